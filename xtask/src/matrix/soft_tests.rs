//! Tests of the soft-shadow table: the render JSON of the CLI with lights of a size (a sample in
//! `testdata/`), the figures taken from it, the radius each light kind gets, and the table, its
//! ratios and verdicts on a fixed record set.

use super::cli::RenderReport;
use super::plan::{SoftRadius, MAP_KEY, SOFT_VOLUMES_KEY};
use super::records::{Data, HostInfo, Key, Record, Render, Results, SoftFields};
use super::soft::radius_for;
use super::soft_table::{groups, plot_points, verdict, Verdict};
use super::tables::tables;
use serde_json::{json, Value};

/// `shadowvol render hard-tetrahedron --backdrop --light=2,3,5,1 --light-radius 0.05
/// --light-samples 4 --reference --frames 2 --size 64x36 --format json`, with `plan` trimmed to
/// one entry. Its `visibility_error` is the CLI's of the time: `[null]`.
const SOFT_JSON: &str = include_str!("testdata/soft.json");

fn error(mean: f64, p99: f64, pixels: usize) -> Value {
    json!({"penumbra_pixels": pixels, "mean": mean, "p99": p99, "max": p99 * 2.0,
           "lit_umbra_mismatches": 1, "reference_bound": 1e-9})
}

#[test]
fn soft_render_json_of_the_cli_parses_and_a_missing_error_is_said() {
    let raw: Value = serde_json::from_str(SOFT_JSON).unwrap();
    let report: RenderReport = serde_json::from_str(SOFT_JSON).unwrap();
    let bounds = report.scene_bounds.expect("scene_bounds");
    assert!(bounds.diagonal() > 0.0);
    assert_eq!(report.frame.light_radii, vec![0.05]);
    let soft = SoftFields::of(&report, 0.05);
    assert_eq!(soft.light_samples_used, Some(4));
    let samples: u64 = raw["sample_artifact_pixels"][0]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_u64().unwrap())
        .sum();
    assert_eq!(soft.sample_artifact_pixels, Some(samples));
    assert_eq!(soft.light_penumbra_px, raw["light_penumbra_px"][0].as_f64());
    // The CLI of the time writes `null` for the light's error: no number, and the reason.
    if raw["visibility_error"][0].is_null() {
        assert_eq!(soft.penumbra_pixels, None);
        assert_eq!(soft.visibility_mean, None);
        assert_eq!(
            soft.missing.as_deref(),
            Some("visibility_error is null for light 0 of radius 0.05000000074505806")
        );
    }
    let mut no_field = raw.clone();
    no_field.as_object_mut().unwrap().remove("visibility_error");
    let r: RenderReport = serde_json::from_value(no_field).unwrap();
    let s = SoftFields::of(&r, 0.05);
    assert_eq!(
        (s.visibility_mean, s.missing.as_deref()),
        (None, Some("the render JSON has no visibility_error"))
    );

    // With the error filled in as the contract says, the figures are read.
    let mut filled = raw;
    filled["visibility_error"] = json!([error(0.02, 0.1, 300)]);
    let r: RenderReport = serde_json::from_value(filled).unwrap();
    let s = SoftFields::of(&r, 0.05);
    assert_eq!(s.missing, None);
    assert_eq!(
        (s.visibility_mean, s.visibility_p99, s.visibility_max),
        (Some(0.02), Some(0.1), Some(0.2))
    );
    assert_eq!(
        (s.penumbra_pixels, s.lit_umbra_mismatches),
        (Some(300), Some(1))
    );
}

#[test]
fn two_lights_pool_their_penumbrae_and_a_point_light_takes_no_part() {
    let report = |errors: Value, radii: Value| -> RenderReport {
        serde_json::from_value(json!({
            "mode": "exact",
            "lights": [[0, 5, 0, 1], [3, 5, 0, 1], [0, 9, 0, 1]],
            "light_radii": radii,
            "light_samples": [16, 16, 1],
            "light_penumbra_px": [12.5, 30.0, 0.0],
            "sample_artifact_pixels": [[1, 0], [2, 3], [4]],
            "visibility_error": errors,
        }))
        .unwrap()
    };
    let r = report(
        json!([error(0.1, 0.3, 100), error(0.4, 0.5, 300), null]),
        json!([0.2, 0.2, 0.0]),
    );
    let s = SoftFields::of(&r, 0.2);
    // (0.1 * 100 + 0.4 * 300) / 400; the largest p99 and max; the point light left out.
    assert_eq!(s.visibility_mean, Some(0.325));
    assert_eq!((s.visibility_p99, s.visibility_max), (Some(0.5), Some(1.0)));
    assert_eq!(
        (s.penumbra_pixels, s.lit_umbra_mismatches),
        (Some(400), Some(2))
    );
    assert_eq!(
        (
            s.light_samples_used,
            s.light_penumbra_px,
            s.sample_artifact_pixels
        ),
        (Some(16), Some(30.0), Some(10))
    );
    // No penumbra pixel at all: the lights' means, unweighted.
    let r = report(
        json!([error(0.1, 0.3, 0), error(0.3, 0.5, 0), null]),
        json!([0.2, 0.2, 0.0]),
    );
    assert!((SoftFields::of(&r, 0.2).visibility_mean.unwrap() - 0.2).abs() < 1e-12);
    // A light with a size and no error: none, and which.
    let r = report(
        json!([error(0.1, 0.3, 100), null, null]),
        json!([0.2, 0.2, 0.0]),
    );
    let s = SoftFields::of(&r, 0.2);
    assert_eq!(s.visibility_mean, None);
    assert_eq!(
        s.missing.as_deref(),
        Some("visibility_error is null for light 1 of radius 0.20000000298023224")
    );
}

#[test]
fn the_quick_form_is_short_and_the_steps_count_every_render() {
    use super::plan::SoftPlan;
    let quick = SoftPlan::new(true);
    assert_eq!(quick.scenes.len() * quick.radii.len(), 1);
    assert_eq!(
        (quick.samples.as_slice(), quick.plan_choice),
        (&[1, 16][..], false)
    );
    assert_eq!(
        (quick.pcss_sizes.as_slice(), quick.steps()),
        (&[2048][..], 4)
    );
    let full = SoftPlan::new(false);
    assert_eq!(full.renders_per_radius(), 7);
    assert_eq!(full.steps(), 4 * (1 + 3 * 7));
}

#[test]
fn a_scene_that_mixes_light_kinds_keeps_its_point_lights() {
    use super::soft::point_lights_of_a_mix;
    let sun = [1.0, 2.0, 3.0, 0.0];
    let point = [2.0, 3.0, 5.0, 1.0];
    assert_eq!(point_lights_of_a_mix(&[point, sun]), Some(vec![point]));
    assert_eq!(point_lights_of_a_mix(&[point, point]), None);
    assert_eq!(point_lights_of_a_mix(&[sun]), None);
}

#[test]
fn each_light_kind_gets_its_radius() {
    let r = SoftRadius {
        fraction: 0.03,
        radians: 0.02,
    };
    let sun = [[0.0, 1.0, 0.0, 0.0]];
    let point = [[0.0, 5.0, 0.0, 1.0], [1.0, 5.0, 0.0, 2.0]];
    assert_eq!(radius_for(r, &sun, None), Ok((0.02, None)));
    let (radius, fraction) = radius_for(r, &point, Some(10.0)).unwrap();
    assert!((radius - 0.3).abs() < 1e-12 && fraction == Some(0.03));
    let e = radius_for(r, &point, None).unwrap_err();
    assert!(e.contains("scene_bounds"), "{e}");
    let mixed = [sun[0], point[0]];
    assert!(radius_for(r, &mixed, Some(10.0))
        .unwrap_err()
        .contains("mix"));
    assert!(radius_for(r, &[], Some(10.0)).is_err());
}

fn host() -> HostInfo {
    HostInfo {
        cpu: Some("test cpu".into()),
        ..HostInfo::default()
    }
}

/// A `soft` record of `scene` at `radius` (`fraction` of the box for point lights): volumes
/// with `--light-samples` `samples` (`plan`: the plan's choice, which drew `used`), or PCSS of
/// `map` texels; `err` = the mean error (`None`: the CLI gave none), `ms` the median frame time.
#[allow(clippy::too_many_arguments)]
fn soft_record(
    scene: &str,
    radius: f64,
    fraction: Option<f64>,
    samples: Option<(&str, u32)>,
    map: Option<u64>,
    err: Option<f64>,
    ms: f64,
) -> Record {
    let used = samples.map_or(1, |s| s.1);
    let mut report = json!({
        "mode": "exact",
        "adapter": "llvmpipe",
        "pipeline": if map.is_some() { "map" } else { "gpu" },
        "shadows": if map.is_some() { "map" } else { "volumes" },
        "lights": [[0, 5, 0, 1]],
        "light_radii": [radius],
        "light_samples": [used],
        "light_penumbra_px": [20.0],
        "frames": {"count": 5, "median_ms": ms, "p10_ms": ms * 0.9, "p90_ms": ms * 1.2},
        "visibility_error": [err.map(|e| error(e, e * 3.0, 500))],
    });
    if map.is_none() {
        report["sample_artifact_pixels"] = json!([vec![0; used as usize]]);
    } else {
        report["map_size"] = json!(map);
        report["map_filter"] = json!("pcf");
    }
    let report: RenderReport = serde_json::from_value(report).unwrap();
    let soft = SoftFields::of(&report, radius);
    let mut render = Render::new(report, "320x180", "s.png".into());
    render.set_soft(soft, fraction, samples.map(|s| s.0.to_owned()));
    Record {
        host: host(),
        experiment: "soft".into(),
        reused_from: None,
        key: Key {
            scene: scene.into(),
            backend: if map.is_some() {
                MAP_KEY
            } else {
                SOFT_VOLUMES_KEY
            }
            .into(),
            mode: map.is_none().then(|| "exact".to_owned()),
        },
        device: "llvmpipe".into(),
        data: Data::Render(render),
    }
}

/// Scene `a` (a point light at 0.03 of its box): PCSS 2048 is reached only by the plan's N, at
/// twice PCSS's time (PCSS wins); PCSS 4096's error is N=4's exactly (equal counts), at half
/// its time (volumes). Scene `town` (the sun): no volume N reaches either PCSS size; one is
/// faster than N=1 as well. Scene `c`: PCSS without an error; `d`: no PCSS render.
fn soft_records() -> Vec<Record> {
    let vol = |scene, r, f, n: &'static str, used, err, ms| {
        soft_record(scene, r, f, Some((n, used)), None, Some(err), ms)
    };
    let pcss = |scene, r, f, size, err, ms| soft_record(scene, r, f, None, Some(size), err, ms);
    let (ra, fa) = (0.15, Some(0.03));
    vec![
        vol("a", ra, fa, "1", 1, 0.2, 5.0),
        vol("a", ra, fa, "4", 4, 0.1, 10.0),
        vol("a", ra, fa, "16", 16, 0.05, 30.0),
        vol("a", ra, fa, "64", 64, 0.01, 90.0),
        vol("a", ra, fa, "plan", 12, 0.06, 24.0),
        pcss("a", ra, fa, 2048, Some(0.08), 12.0),
        pcss("a", ra, fa, 4096, Some(0.1), 20.0),
        vol("town", 0.02, None, "1", 1, 0.3, 5.0),
        vol("town", 0.02, None, "16", 16, 0.2, 30.0),
        pcss("town", 0.02, None, 2048, Some(0.01), 8.0),
        pcss("town", 0.02, None, 4096, Some(0.01), 4.0),
        vol("c", 0.5, Some(0.1), "1", 1, 0.3, 5.0),
        pcss("c", 0.5, Some(0.1), 2048, None, 8.0),
        vol("d", 0.04, Some(0.01), "1", 1, 0.3, 5.0),
    ]
}

#[test]
fn soft_table_finds_the_cheapest_volumes_at_pcss_error_and_says_who_wins() {
    let records = soft_records();
    let g = groups(&records);
    assert_eq!(g.len(), 4);
    assert_eq!((g[0].scene, g[0].rows.len()), ("a", 7));
    let volumes: Vec<_> = g[0].rows.iter().filter(|r| !r.pcss).copied().collect();
    let pcss: Vec<_> = g[0].rows.iter().filter(|r| r.pcss).copied().collect();
    let (v, row) = verdict(&pcss[0], &volumes);
    assert_eq!(
        v,
        Verdict::Reached {
            volumes: "volumes, plan's N (12)".to_owned(),
            ratio: 2.0
        }
    );
    assert_eq!(row.unwrap().render.light_samples_used, Some(12));
    assert!(v.pcss_wins());
    let (v, _) = verdict(&pcss[1], &volumes);
    assert_eq!(
        v,
        Verdict::Reached {
            volumes: "volumes N=4".to_owned(),
            ratio: 0.5
        }
    );
    assert!(!v.pcss_wins());

    let results = Results {
        host: host(),
        records,
        failures: vec!["soft: c r0 pcss-2048: no visibility error: ...".into()],
        ..Results::default()
    };
    let t = tables(&results, &["exact".to_owned()]);
    for line in [
        "| a | 0.03 of the box (0.150) | PCSS 2048 | 0.0800, 12.0 | volumes, plan's N (12) | 0.0600, 24.0 | 2.00 | **PCSS wins** on time: every volume setting as fast has a larger error; equal or lower error costs 2.00x |",
        "| a | 0.03 of the box (0.150) | PCSS 4096 | 0.1000, 20.0 | volumes N=4 | 0.1000, 10.0 | 0.50 | volumes win: equal or lower error at 0.50x PCSS's time |",
        "| town | 0.02 rad | PCSS 2048 | 0.0100, 8.00 | none | n/a | n/a | no volume N reaches PCSS's error (some are faster) |",
        "| town | 0.02 rad | PCSS 4096 | 0.0100, 4.00 | none | n/a | n/a | **PCSS wins**: lower error and lower time than every volume N |",
        "| c | 0.1 of the box (0.500) | PCSS 2048 | n/a, 8.00 | none | n/a | n/a | n/a: PCSS's error or time missing |",
        "| d | 0.01 of the box (0.040) | PCSS | n/a | none | n/a | n/a | n/a: no PCSS render (see the failures) |",
        "| a | 0.03 of the box (0.150) | volumes N=16 | 16 | 0.0500 | 0.1500 | 0 | 500 | 30.0 (27.0-36.0) |",
        "| a | 0.03 of the box (0.150) | volumes, plan's N | 12 | 0.0600 | 0.1800 | 0 | 500 | 24.0 (21.6-28.8) |",
        "| town | 0.02 rad | PCSS 4096 | - | 0.0100 | 0.0300 | n/a | 500 | 4.00 (3.60-4.80) |",
        "| c | 0.1 of the box (0.500) | PCSS 2048 | - | n/a | n/a | n/a | n/a | 8.00 (7.20-9.60) |",
    ] {
        assert!(t.lines().any(|l| l == line), "no line {line:?} in\n{t}");
    }
    assert!(t.contains("## Soft shadows: volumes against PCSS") && t.contains("## Failures"));
    assert!(
        !t.contains("## Table 1"),
        "--only soft shows its table alone"
    );

    // `--replot` reads results.json back into the same table.
    let text = serde_json::to_string(&serde_json::to_value(&results).unwrap()).unwrap();
    let back: Results = serde_json::from_str(&text).unwrap();
    assert_eq!(tables(&back, &["exact".to_owned()]), t);

    // The plot: a series per technique, volumes first; PCSS 2048 at a, town (c has no error).
    let pts = plot_points(&back.records);
    let labels: Vec<&str> = pts.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(
        labels,
        [
            "volumes N=1",
            "volumes N=4",
            "volumes N=16",
            "volumes N=64",
            "volumes, plan's N",
            "PCSS 2048",
            "PCSS 4096"
        ]
    );
    assert_eq!(pts[5].2, vec![(12.0, 0.08), (8.0, 0.01)]);
    assert_eq!(pts[0].2.len(), 4);
}
