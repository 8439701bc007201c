//! Tests of the typed records against a real matrix run (the committed
//! `docs/results/results.json`), and of the CSV and tables of a small fixed record set.

use super::cli::RenderTimings;
use super::csv::to_csv;
use super::records::{Baseline, Bench, Data, HostInfo, Key, Record, Results};
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

#[test]
fn frame_time_prefers_total() {
    let t = |v: Value| {
        serde_json::from_value::<RenderTimings>(v)
            .unwrap()
            .frame_ms()
    };
    assert_eq!(t(json!({"silhouette_ms": 1.0, "raster_ms": 2.0})), 3.0);
    assert_eq!(t(json!({"silhouette_ms": 1.0, "total_ms": 5.0})), 5.0);
    assert_eq!(
        t(json!({"silhouette_ms": 1.0, "prepare_ms": 2.0, "total_ms": 5.0, "reference_ms": 9.0})),
        3.0
    );
    assert_eq!(
        t(json!({"silhouette_ms": 1.0, "prepare_ms": 2.0, "raster_ms": 4.0})),
        5.0
    );
    assert_eq!(
        t(json!({"silhouette_ms": 1.0, "new_ms": 4.0, "reference_x_ms": 8.0, "n": 16.0})),
        5.0
    );
}

/// The committed matrix run: every record reads back into its typed form and writes out to the
/// same JSON, field for field.
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
            "accuracy" => r.accuracy().is_some(),
            "artifacts" | "table1-frame" => r.render().is_some(),
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
