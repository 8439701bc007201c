//! Tests of the typed records against real CLI output (samples captured from the CLI in
//! `testdata/`) and a real matrix run (the committed `docs/results/results.json`), and of the
//! CSV and tables of a small fixed record set.

use super::cli::{frame_ms, BenchReport, CliRecord, RecordList, RenderReport};
use super::csv::to_csv;
use super::records::{Baseline, Bench, Data, HostInfo, Key, ModeErrors, Record, Render, Results};
use super::tables::tables;
use serde_json::{json, Map, Value};

fn value(text: &str) -> Value {
    serde_json::from_str(text).unwrap()
}

fn host() -> HostInfo {
    HostInfo {
        cpu: Some("test cpu".into()),
        cores: Some(2),
        ..HostInfo::default()
    }
}

/// `shadowvol bench --scene sphere-100k --backend cpu,simd --mode exact,original --frames 3
/// --format json`, trimmed to two records (cpu exact, simd original).
const BENCH_JSON: &str = include_str!("testdata/bench.json");
/// `shadowvol render hard-tetrahedron --reference --backdrop --backend cpu --mode exact
/// --size 64x48 --format json`, with `plan` trimmed to one entry.
const RENDER_JSON: &str = include_str!("testdata/render.json");
/// `shadowvol accuracy --backend cpu --mode robust --format json`, trimmed to two records.
const ACCURACY_JSON: &str = include_str!("testdata/accuracy.json");
/// `shadowvol baselines --scene bunny --frames 1 --warmup 0 --format json`, trimmed to a
/// seed's record and one of ours.
const BASELINES_JSON: &str = include_str!("testdata/baselines.json");

/// Every field of the CLI record `raw` is in the record's JSON with the same value (its
/// `details` as `detail_*` columns), and the record adds only the host's and `added` fields.
fn carries_every_field(raw: &Value, rec: &Record, added: &[&str]) {
    let host_fields = serde_json::to_value(HostInfo::default()).unwrap();
    let host_fields = host_fields.as_object().unwrap();
    assert!(host_fields.contains_key("cpu") && host_fields.contains_key("git_rev"));
    let out = rec.to_value().unwrap();
    let out = out.as_object().unwrap();
    let raw = raw.as_object().unwrap();
    let mut expected = Map::new();
    for (k, v) in raw {
        if k == "details" {
            for (dk, dv) in v.as_object().unwrap() {
                expected.insert(format!("detail_{dk}"), dv.clone());
            }
        } else {
            expected.insert(k.clone(), v.clone());
        }
    }
    for (k, v) in &expected {
        assert_eq!(out.get(k), Some(v), "field {k}");
    }
    for k in out.keys() {
        assert!(
            expected.contains_key(k) || added.contains(&k.as_str()) || host_fields.contains_key(k),
            "unexpected field {k}"
        );
    }
}

#[test]
fn bench_json_of_the_cli_parses() {
    let raw = value(BENCH_JSON);
    let report: BenchReport<Bench> = serde_json::from_str(BENCH_JSON).unwrap();
    assert_eq!(report.floor_ms, raw["floor_ms"].as_f64());
    let features: Vec<String> =
        serde_json::from_value(raw["host"]["compile_target_features"].clone()).unwrap();
    assert_eq!(report.host.compile_target_features, features);
    assert_eq!(
        report.host.profile.as_deref(),
        raw["host"]["profile"].as_str()
    );
    assert_eq!(
        report.records.len(),
        raw["records"].as_array().unwrap().len()
    );
    assert!(!report.records.is_empty());
    for (r, v) in report
        .records
        .iter()
        .zip(raw["records"].as_array().unwrap())
    {
        assert_eq!(r.scene, v["scene"].as_str().unwrap());
        assert_eq!(r.backend, v["backend"].as_str().unwrap());
        assert_eq!(r.mode.as_deref(), v["mode"].as_str());
        assert_eq!(r.data.lights, v["lights"].as_u64());
        assert_eq!(r.data.triangles, v["triangles"].as_u64());
        assert_eq!(r.data.median_ms, v["median_ms"].as_f64());
        assert_eq!(r.data.p10_ms, v["p10_ms"].as_f64());
        assert_eq!(r.data.p90_ms, v["p90_ms"].as_f64());
        assert_eq!(r.data.floor_ms, v["floor_ms"].as_f64());
        assert_eq!(
            r.details.simd_level.as_deref(),
            v["details"]["simd_level"].as_str()
        );
        assert!(r.data.median_ms.is_some() && r.data.lights == Some(1));
    }
    let simd = report.records.iter().find(|r| r.backend == "simd");
    assert!(simd.is_some_and(|r| r.details.simd_level.is_some()));
    for (r, v) in report
        .records
        .into_iter()
        .zip(raw["records"].as_array().unwrap())
    {
        let rec = Record::from_cli("table1", r, Data::Bench, "unused", &host());
        carries_every_field(v, &rec, &["experiment"]);
    }
}

#[test]
fn accuracy_and_baselines_json_of_the_cli_parse() {
    let raw = value(ACCURACY_JSON);
    let list: RecordList<ModeErrors> = serde_json::from_str(ACCURACY_JSON).unwrap();
    assert_eq!(list.records.len(), 2);
    for (r, v) in list
        .records
        .into_iter()
        .zip(raw["records"].as_array().unwrap())
    {
        assert_eq!(r.data.open_vertices, v["open_vertices"].as_u64());
        assert_eq!(r.data.sign_diff_vs_exact, v["sign_diff_vs_exact"].as_u64());
        assert_eq!(r.data.uncertain, v["uncertain"].as_u64());
        assert!(r.data.open_vertices.is_some() && r.device.is_none());
        let rec = Record::from_cli("accuracy", r, Data::ModeErrors, "the cpu", &host());
        assert_eq!(rec.device, "the cpu");
        carries_every_field(v, &rec, &["experiment", "device"]);
    }

    let raw = value(BASELINES_JSON);
    let list: RecordList<Baseline> = serde_json::from_str(BASELINES_JSON).unwrap();
    assert_eq!(list.records.len(), 2);
    assert!(list.records[0].mode.is_none() && list.records[1].mode.is_some());
    for (r, v) in list
        .records
        .into_iter()
        .zip(raw["records"].as_array().unwrap())
    {
        assert_eq!(r.data.silhouette_edges, v["silhouette_edges"].as_u64());
        assert_eq!(r.data.agrees_with_exact, v["agrees_with_exact"].as_bool());
        assert_eq!(r.data.median_ms, v["median_ms"].as_f64());
        assert!(r.data.silhouette_edges.is_some());
        let rec = Record::from_cli("toywars", r, Data::Baseline, "unused", &host());
        carries_every_field(v, &rec, &["experiment"]);
    }
}

#[test]
fn render_json_of_the_cli_parses() {
    let raw = value(RENDER_JSON);
    let report: RenderReport = serde_json::from_str(RENDER_JSON).unwrap();
    let n = |v: Option<usize>| v.map(|x| x as u64);
    assert_eq!(n(report.artifact_pixels), raw["artifact_pixels"].as_u64());
    assert_eq!(
        Some(report.shadow_pixels as u64),
        raw["shadow_pixels"].as_u64()
    );
    assert_eq!(
        n(report.reference_shadow_pixels),
        raw["reference_shadow_pixels"].as_u64()
    );
    assert_eq!(n(report.covered_pixels), raw["covered_pixels"].as_u64());
    assert_eq!(Some(report.frame.adapter.as_str()), raw["adapter"].as_str());
    assert!(report.artifact_pixels.is_some() && report.reference_shadow_pixels.is_some());
    let t = report.frame.timings;
    let rt = &raw["timings"];
    assert_eq!(Some(t.total_ms), rt["total_ms"].as_f64());
    assert_eq!(Some(t.prepare_ms), rt["prepare_ms"].as_f64());
    assert_eq!(t.reference_ms, rt["reference_ms"].as_f64());
    let frame = rt["total_ms"].as_f64().unwrap() - rt["prepare_ms"].as_f64().unwrap();
    // Written back: the same fields, and the same report when read again.
    let back = serde_json::to_value(&report).unwrap();
    let keys = |v: &Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
    assert_eq!(keys(&back), keys(&raw));
    assert_eq!(
        serde_json::from_value::<RenderReport>(back).unwrap(),
        report
    );
    let r = Render::new(report, "64x48", "x.png".into());
    assert_eq!(r.frame_ms, Some(frame));
    // Every timing is a `timing_*` column.
    for (k, v) in rt.as_object().unwrap() {
        assert_eq!(r.timing.get(&format!("timing_{k}")), Some(v), "timing {k}");
    }
}

#[test]
fn added_fields_are_accepted_and_missing_ones_are_none() {
    let mut raw = value(BENCH_JSON);
    raw["new_top_level"] = json!({"a": 1});
    raw["records"][0]["new_field"] = json!([1, 2]);
    raw["host"]["new_host_field"] = json!("x");
    let report: BenchReport<Bench> = serde_json::from_value(raw).unwrap();
    assert_eq!(report.records[0].data.extra["new_field"], json!([1, 2]));

    let mut raw = value(RENDER_JSON);
    raw["new_field"] = json!(3);
    raw["timings"]["new_stage_ms"] = json!(0.5);
    let report: RenderReport = serde_json::from_value(raw).unwrap();
    assert_eq!(report, serde_json::from_str(RENDER_JSON).unwrap());

    let r: CliRecord<Bench> =
        serde_json::from_value(json!({"scene": "s", "backend": "b"})).unwrap();
    assert_eq!(
        (r.mode, r.data.median_ms, r.data.lights),
        (None, None, None)
    );
    let r: RenderReport = serde_json::from_value(json!({"mode": "exact"})).unwrap();
    assert_eq!(
        (r.artifact_pixels, r.frames, r.frame.plan.len()),
        (None, None, 0)
    );
}

#[test]
fn a_wrong_shape_is_an_error_naming_the_field() {
    let e = serde_json::from_value::<BenchReport<Bench>>(json!({"records": [{"scene": 1}]}))
        .unwrap_err()
        .to_string();
    assert!(e.contains("invalid type"), "{e}");
    let e = serde_json::from_str::<BenchReport<Bench>>(r#"{"records": [{"backend": "cpu"}]}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing field `scene`"), "{e}");
}

#[test]
fn frame_time_leaves_the_upload_out() {
    let t = shadowvol_report::Timings {
        silhouette_ms: Some(1.0),
        prepare_ms: 2.0,
        total_ms: 5.0,
        reference_ms: Some(9.0),
        ..shadowvol_report::Timings::default()
    };
    assert_eq!(frame_ms(&t), 3.0);
}

#[test]
fn results_json_of_a_real_run_round_trips() {
    let path = crate::project_root().join("docs/results/results.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let raw = value(&text);
    let results: Results = serde_json::from_str(&text).unwrap();
    let raw_records = raw["records"].as_array().unwrap();
    assert_eq!(results.records.len(), raw_records.len());
    assert!(results.records.len() > 100);
    for (r, v) in results.records.iter().zip(raw_records) {
        assert_eq!(&r.to_value().unwrap(), v, "{} {:?}", r.experiment, r.key);
    }
    // Each experiment holds its kind of measurement.
    for r in &results.records {
        let ok = match r.experiment.as_str() {
            "accuracy" => r.mode_errors().is_some(),
            "artifacts" | "table1-frame" | "frames" => r.render().is_some(),
            "toywars" => r.baseline().is_some(),
            _ => r.bench().is_some(),
        };
        assert!(ok, "{}", r.experiment);
    }
    assert_eq!(serde_json::to_value(&results).unwrap(), raw);
}

fn bench(exp: &str, scene: &str, mode: &str, lights: u64, ms: f64) -> Record {
    let mut extra = Map::new();
    extra.insert("detail_note".into(), json!("a,\"b\""));
    Record {
        host: host(),
        experiment: exp.into(),
        reused_from: None,
        key: Key {
            scene: scene.into(),
            backend: "cpu".into(),
            mode: Some(mode.into()),
        },
        device: "cpu device".into(),
        data: Data::Bench(Bench {
            lights: Some(lights),
            triangles: Some(1000),
            median_ms: Some(ms),
            p10_ms: Some(ms * 0.5),
            p90_ms: Some(ms * 2.0),
            floor_ms: Some(0.5),
            extra,
        }),
    }
}

fn fixed_records() -> Vec<Record> {
    let mut seed = Record {
        host: host(),
        experiment: "toywars".into(),
        reused_from: None,
        key: Key {
            scene: "bunny".into(),
            backend: "classic".into(),
            mode: None,
        },
        device: String::new(),
        data: Data::Baseline(Baseline {
            triangles: Some(70),
            median_ms: Some(12.5),
            silhouette_edges: Some(9),
            agrees_with_exact: Some(false),
            ..Baseline::default()
        }),
    };
    if let Data::Baseline(b) = &mut seed.data {
        b.extra.insert("kind".into(), json!("seed"));
    }
    vec![
        bench("table1", "sphere-1m", "original", 1, 2.0),
        bench("table1", "sphere-1m", "robust", 1, 3.0),
        bench("lights", "sphere-100k", "robust", 4, 8.0),
        seed,
    ]
}

#[test]
fn csv_has_the_union_of_fields_sorted_and_quoted() {
    let csv = to_csv(&fixed_records()).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    // The host fields the fixture leaves unknown are empty cells.
    assert_eq!(
        lines[0],
        "agrees_with_exact,backend,compile_target_features,cores,cpu,detail_note,device,error,\
         experiment,flags,floor_ms,git_rev,host,kind,lights,median_ms,mode,os,p10_ms,p90_ms,\
         profile,rustc,rustflags,scene,silhouette_edges,simd_level,triangles"
    );
    assert_eq!(lines.len(), 5);
    assert_eq!(
        lines[1],
        ",cpu,,2,test cpu,\"a,\"\"b\"\"\",cpu device,,table1,,0.5,,,,1,2.0,original,,1.0,4.0,,,,\
         sphere-1m,,,1000"
    );
    assert_eq!(
        lines[4],
        "false,classic,,2,test cpu,,,,toywars,,,,,seed,,12.5,,,,,,,,bunny,9,,70"
    );
}

#[test]
fn tables_of_a_fixed_record_set() {
    let results = Results {
        host: host(),
        command: "cargo xtask matrix --quick".into(),
        warmup: Some(1),
        quick: true,
        frames: 5,
        elapsed_s: 12.0,
        backends: vec!["cpu".into()],
        devices: [("cpu".to_owned(), "cpu device".to_owned())].into(),
        records: fixed_records(),
        ..Results::default()
    };
    let modes = vec!["original".to_owned(), "robust".to_owned()];
    let t = tables(&results, &modes);
    let has = |line: &str| assert!(t.lines().any(|l| l == line), "no line {line:?} in\n{t}");
    has("Command: `cargo xtask matrix --quick` (1 warm-up and 5 timed frames per measurement; 12 s in all).");
    has("**This machine**: test cpu (2 cores), ?, ?, git ?, RUSTFLAGS=`?`.");
    has("| cpu | cpu device |");
    // Table 1: silhouette / frame ms, ratio to original, floor.
    has("| backend | original | robust | floor |");
    has("|---|---|---|---|");
    has("| cpu | 2.00 / n/a (1.00x) | 3.00 / n/a (1.50x) | 0.50 |");
    // Accuracy: the time ratio, no accuracy or artifact records.
    has("| cpu | robust | 1.50 | n/a | n/a | n/a | n/a |");
    // Lights: one column per light count measured.
    has("| backend | mode | 4 |");
    has("| cpu | robust | 8.00 |");
    has("| cpu | original | n/a |");
    // Toy Wars: the seed's row, its mode a dash.
    has("| algorithm | mode | bunny (70 tri.) ms | silhouette edges | = exact |");
    has("| classic | - | 12.5 (n/a-n/a) | 9 | **no** |");
    assert!(!t.contains("## Failures"));
}

/// A `frames` record of the frame table from a `render --frames` report.
fn frames_record(backend: &str, pipeline: &str, median: f64, bytes: u64) -> Record {
    let report: RenderReport = serde_json::from_value(json!({
        "pipeline": pipeline,
        "frames": {"count": 10, "median_ms": median, "p10_ms": median * 0.9, "p90_ms": median * 1.5},
        "frame_readback_bytes": bytes,
        "adapter": "llvmpipe",
        "mode": "exact",
        "timings": {"total_ms": 3.0, "prepare_ms": 1.0},
    }))
    .unwrap();
    Record {
        host: host(),
        experiment: "frames".into(),
        reused_from: None,
        key: Key {
            scene: "sphere-1m".into(),
            backend: backend.into(),
            mode: Some("exact".into()),
        },
        device: "llvmpipe".into(),
        data: Data::Render(Render::new(report, "160x120", "f.png".into())),
    }
}

#[test]
fn frame_table_compares_the_pipelines_of_one_run() {
    let results = Results {
        host: host(),
        records: vec![
            frames_record("simd", "host", 40.0, 4_000_000),
            frames_record("gpu-pipeline", "gpu", 30.0, 0),
        ],
        ..Results::default()
    };
    let r = results.records[1].render().unwrap();
    assert_eq!(r.pipeline.as_deref(), Some("gpu"));
    assert_eq!(
        (r.frames_median_ms, r.frame_readback_bytes),
        (Some(30.0), Some(0))
    );
    let t = tables(&results, &["exact".to_owned()]);
    let line = "| sphere-1m | 40.0 (36.0-60.0) | 30.0 (27.0-45.0) | 0.75x | 4000000 / 0 |";
    assert!(t.lines().any(|l| l == line), "no line {line:?} in\n{t}");
    // The records round-trip through results.json's shape.
    let text = serde_json::to_string(&results.records[0]).unwrap();
    assert!(text.contains("\"frames_median_ms\":40.0"), "{text}");
}

/// A record of the volumes-against-maps table: `backend` `gpu-pipeline`, `simd` or `map`;
/// `map` = (size, filter, bias) for the map pipeline; `frames` = median ms (timed) or `None`
/// (a sweep render).
fn maps_record(
    backend: &str,
    mode: Option<&str>,
    map: Option<(u64, &str, &str)>,
    frames: Option<f64>,
    artifacts: u64,
) -> Record {
    let mut report = json!({
        "artifact_pixels": artifacts,
        "boundary_pixels": 7,
        "shadow_pixels": 500,
        "reference_shadow_pixels": 510,
        "adapter": "llvmpipe",
        "mode": "exact",
        "pipeline": if map.is_some() { "map" } else { "gpu" },
        "shadows": if map.is_some() { "map" } else { "volumes" },
        "gpu_timings_ms": {"shadow_maps": 1.5, "lighting": 2.0},
    });
    if let Some(ms) = frames {
        report["frames"] =
            json!({"count": 5, "median_ms": ms, "p10_ms": ms * 0.9, "p90_ms": ms * 1.2});
    }
    if let Some((size, filter, _)) = map {
        report["map_size"] = json!(size);
        report["map_filter"] = json!(filter);
    }
    let report: RenderReport = serde_json::from_value(report).unwrap();
    let mut render = Render::new(report, "100x100", "m.png".into());
    render.map_bias = map.map(|(_, _, b)| b.to_owned());
    Record {
        host: host(),
        experiment: if frames.is_some() {
            "maps"
        } else {
            "maps-sweep"
        }
        .into(),
        reused_from: None,
        key: Key {
            scene: "s".into(),
            backend: backend.into(),
            mode: mode.map(str::to_owned),
        },
        device: "llvmpipe".into(),
        data: Data::Render(render),
    }
}

#[test]
fn maps_table_picks_the_best_swept_bias_and_the_first_map_as_good_as_exact() {
    let results = Results {
        host: host(),
        records: vec![
            maps_record("gpu-pipeline", Some("exact"), None, Some(10.0), 0),
            maps_record("simd", Some("exact"), None, Some(40.0), 0),
            maps_record("map", None, Some((512, "pcf", "default")), Some(5.0), 100),
            maps_record("map", None, Some((512, "pcf", "0.3,0,4")), None, 20),
            maps_record("map", None, Some((512, "pcf", "0.005,0,0.3")), None, 60),
            maps_record("map", None, Some((2048, "pcf", "default")), Some(8.0), 0),
        ],
        ..Results::default()
    };
    let r = results.records[2].render().unwrap();
    assert_eq!(r.gpu_shadow_maps_ms, Some(1.5));
    assert_eq!(
        results.records[0].render().unwrap().gpu_shadow_maps_ms,
        None
    );
    let t = tables(&results, &["exact".to_owned()]);
    for line in [
        "| s | volumes, GPU pipeline, exact | 10.0 (9.00-12.0) | 1.00 | 0 | 7 | 500 (510) |",
        "| s | volumes, host pipeline (simd), exact | 40.0 (36.0-48.0) | 4.00 | 0 | 7 | 500 (510) |",
        "| s | map 512 pcf, Bevy's bias | 5.00 (4.50-6.00) | 0.50 | 100 | 7 | 500 (510) |",
        "| s | map 512 pcf, tuned with hindsight (bias 0.3,0,4) | 5.00 (4.50-6.00) | 0.50 | 20 | 7 | 500 (510) |",
        "| s | map 2048 pcf, tuned with hindsight (bias default) | 8.00 (7.20-9.60) | 0.80 | 0 | 7 | 500 (510) |",
        "| s | 10.0, 0 | map 2048 pcf, Bevy's bias | 8.00 | 1.25 | 0 |",
    ] {
        assert!(t.lines().any(|l| l == line), "no line {line:?} in\n{t}");
    }
    let pts = super::maps_table::plot_points(&results.records);
    let tuned_512 = pts
        .iter()
        .find(|p| p.0 == "map 512 pcf, tuned with hindsight")
        .expect("a tuned point");
    assert_eq!((tuned_512.1, tuned_512.2), ("map tuned", 5.0));
    assert!((tuned_512.3 - 20.0 / 10_000.0).abs() < 1e-12);
    assert_eq!(pts.len(), 6);
}

#[test]
fn memory_table_shows_bytes_per_triangle_and_round_trips() {
    use super::records::Memory;
    let m = Memory {
        triangles: Some(1_000_000),
        peak_rss_bytes: Some(172_000_000),
        table_bytes: Some(129_000_000),
        topology_bytes: Some(66_000_000),
        host_bytes: Some(63_000_000),
        device_bytes: Some(0),
        wall_s: Some(1.5),
        ..Memory::default()
    };
    let results = Results {
        host: host(),
        records: vec![
            Record {
                host: host(),
                experiment: "memory".into(),
                reused_from: None,
                key: Key {
                    scene: "sphere-1m".into(),
                    backend: "simd".into(),
                    mode: Some("exact".into()),
                },
                device: "cpu".into(),
                data: Data::Memory(m),
            },
            Record {
                host: host(),
                experiment: "memory".into(),
                reused_from: None,
                key: Key {
                    scene: "sphere-10m".into(),
                    backend: "build".into(),
                    mode: None,
                },
                device: "cpu".into(),
                data: Data::Memory(Memory {
                    triangles: Some(10_000_000),
                    build_ms: Some(900.0),
                    build_read_ms: Some(7.0),
                    build_threads: Some(2),
                    ..Memory::default()
                }),
            },
        ],
        skips: vec!["memory: sphere-100m on simd skipped: needs about 18.4 GB".into()],
        ..Results::default()
    };
    let line = "| sphere-1m | 1000000 | simd | 172 | 129 | 66 | 63 | 0 | 172 | 1.5 |";
    let t = tables(&results, &["exact".to_owned()]);
    assert!(t.lines().any(|l| l == line), "no line {line:?} in\n{t}");
    // A run left out says so, under its own heading.
    let skip = "- memory: sphere-100m on simd skipped: needs about 18.4 GB";
    assert!(
        t.contains("\n## Left out\n\n") && t.lines().any(|l| l == skip),
        "{t}"
    );
    // `--replot` reads results.json back into the same record.
    let text = serde_json::to_string(&serde_json::to_value(&results).unwrap()).unwrap();
    let back: Results = serde_json::from_str(&text).unwrap();
    assert_eq!(back.records, results.records);
    assert_eq!(back.skips, results.skips);
    let points = super::memory_table::plot_points(&back.records);
    assert_eq!(points["simd"], vec![(1e6, 172.0)]);
    // The build timing is its own table, not a memory row or a plotted point.
    let build = "| sphere-10m | 10000000 | 900 | 7.00 | 129 | 2 |";
    assert!(t.lines().any(|l| l == build), "no line {build:?} in\n{t}");
    assert!(!points.contains_key("build") && !t.contains("| sphere-10m | 10000000 | build |"));
}
