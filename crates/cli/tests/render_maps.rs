//! `shadowvol render --shadows map`: the JSON names the maps' settings, `--reference`,
//! `--frames` and `--explain` work as with volumes, the image is lit as the volumes' is away
//! from the shadows, and bad map flags are refused with a message.

mod common;

use common::run;
use serde_json::Value;
use shadowvol_test_support::{main, Outcome, Skip};

main!(
    map_json_names_the_settings_and_frames_read_nothing_back,
    explain_lists_each_lights_map,
    maps_and_volumes_light_the_scene_alike,
    pcss_names_the_filter_and_each_lights_size,
    bad_map_flags_are_refused
);

fn scratch(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("shadowvol-render-maps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name).display().to_string()
}

/// Runs `render ARGS`; a visible skip (a failure under CI) without an adapter.
fn render(args: &[&str]) -> Result<std::process::Output, Skip> {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    let out = run(&all);
    let stderr = String::from_utf8_lossy(&out.stderr);
    common::no_adapter("render", &stderr)?;
    assert!(out.status.success(), "shadowvol {all:?} failed:\n{stderr}");
    Ok(out)
}

fn json(args: &[&str]) -> Result<Value, Skip> {
    let out = render(&[args, &["--format", "json"]].concat())?;
    Ok(serde_json::from_slice(&out.stdout).expect("JSON on stdout"))
}

fn map_json_names_the_settings_and_frames_read_nothing_back() -> Outcome {
    let png = scratch("map.png");
    let diff = scratch("map-diff.png");
    let v = json(&[
        "hard-light-at-vertex",
        "--backdrop",
        "--size",
        "96x72",
        "--shadows",
        "map",
        "--map-size",
        "1024",
        "--map-filter",
        "hard",
        "--map-bias",
        "0.01,0.5,1",
        "--map-cascades",
        "3",
        "--frames",
        "2",
        "--diff",
        &diff,
        "--out",
        &png,
    ])?;
    assert_eq!(v["shadows"], "map", "{v}");
    let d = image::open(&diff).expect("--diff wrote a PNG").to_rgba8();
    assert_eq!(d.dimensions(), (96, 72));
    assert_eq!(v["pipeline"], "map");
    assert!(v["backend"].is_null());
    assert_eq!(v["map_size"], 1024);
    assert_eq!(v["map_size_point"], 1024);
    assert_eq!(v["map_filter"], "hard");
    assert_eq!(v["map_cascades"], 3);
    for kind in ["directional", "point"] {
        let b = &v["map_bias"][kind];
        assert_eq!(
            (
                b["depth"].as_f64(),
                b["slope"].as_f64(),
                b["normal"].as_f64()
            ),
            (Some(0.01), Some(0.5), Some(1.0)),
            "{v}"
        );
    }
    assert_eq!(v["frame_readback_bytes"], 0);
    assert_eq!(v["frames"]["count"], 2);
    for k in [
        "artifact_pixels",
        "boundary_pixels",
        "undecidable_pixels",
        "reference_shadow_pixels",
    ] {
        assert!(v[k].as_u64().is_some(), "{k}: {v}");
    }
    if let Some(t) = v["gpu_timings_ms"].as_object() {
        assert!(t["shadow_maps"].as_f64().unwrap() > 0.0, "{v}");
        assert_eq!(t["extract"].as_f64(), Some(0.0));
    }
    // Without the map flags: Bevy's defaults; volumes report no map settings.
    let d = json(&[
        "hard-book-3",
        "--size",
        "64x48",
        "--shadows",
        "map",
        "--out",
        &png,
    ])?;
    assert_eq!(
        (d["map_size"].as_u64(), d["map_size_point"].as_u64()),
        (Some(2048), Some(1024))
    );
    assert_eq!(d["map_filter"], "pcf");
    assert_eq!(d["map_cascades"], 1);
    assert_eq!(d["map_bias"]["point"]["depth"].as_f64(), Some(0.08));
    assert_eq!(d["map_bias"]["directional"]["normal"].as_f64(), Some(1.8));
    let vol = json(&["hard-book-3", "--size", "64x48", "--out", &png])?;
    assert_eq!(vol["shadows"], "volumes");
    assert!(
        vol["map_size"].is_null() && vol["map_bias"].is_null(),
        "{vol}"
    );
    if let Some(t) = vol["gpu_timings_ms"].as_object() {
        assert_eq!(t["shadow_maps"].as_f64(), Some(0.0));
    }
    Ok(())
}

fn explain_lists_each_lights_map() -> Outcome {
    let out = render(&[
        "hard-directional-parallel",
        "--size",
        "64x48",
        "--shadows",
        "map",
        "--explain",
        "--out",
        &scratch("explain.png"),
    ])?;
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("map pipeline"), "{text}");
    let maps = text.lines().filter(|l| l.starts_with("light ")).count();
    assert_eq!(maps, 6, "one line per light:\n{text}");
    assert!(text.contains("Directional map 2048x2048"), "{text}");
    Ok(())
}

/// Where no shadow falls, maps and volumes add the same light: the images differ only near
/// shadows.
fn maps_and_volumes_light_the_scene_alike() -> Outcome {
    let (a, b) = (scratch("alike-map.png"), scratch("alike-vol.png"));
    let args = ["bunny", "--size", "96x96", "--map-filter", "hard"];
    let map = json(
        &[
            &args[..],
            &["--shadows", "map", "--map-size", "4096", "--out", &a],
        ]
        .concat(),
    )?;
    let vol = json(&[&args[..], &["--out", &b]].concat())?;
    let total = 96 * 96;
    let (m, v) = (
        map["shadow_pixels"].as_u64().unwrap(),
        vol["shadow_pixels"].as_u64().unwrap(),
    );
    assert!(
        m.abs_diff(v) * 20 <= v,
        "shadow pixels {m} (map) against {v} (volumes)"
    );
    let p = image::open(&a).unwrap().to_rgba8();
    let q = image::open(&b).unwrap().to_rgba8();
    let differ = p
        .pixels()
        .zip(q.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 3))
        .count();
    assert!(
        differ * 100 <= total * 3,
        "{differ} of {total} pixels differ"
    );
    Ok(())
}

/// `--map-filter pcss`: the JSON names the filter and each map's PCSS size (Bevy's
/// `soft_shadow_size`: the radius of a point light, more than `tan θ` for a directional one);
/// with every radius 0 a note says the maps are read with pcf, and the image is pcf's.
fn pcss_names_the_filter_and_each_lights_size() -> Outcome {
    let help = run(&["render", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("pcss") && help.contains("blocker"), "{help}");
    let png = scratch("pcss.png");
    let args = ["hard-book-3", "--size", "64x48", "--shadows", "map"];
    let v = json(
        &[
            &args[..],
            &[
                "--map-filter",
                "pcss",
                "--light-radius",
                "0.05",
                "--out",
                &png,
            ],
        ]
        .concat(),
    )?;
    assert_eq!(v["map_filter"], "pcss", "{v}");
    let maps = v["shadow_maps"].as_array().expect("shadow_maps");
    assert_eq!(maps.len(), 6);
    for m in maps {
        let size = m["soft_shadow_size"].as_f64().expect("soft_shadow_size");
        match m["kind"].as_str() {
            Some("cube") => assert!((size - 0.05).abs() < 1e-6, "{m}"),
            Some("directional") => assert!(size > 0.05f64.tan(), "{m}"),
            other => panic!("{other:?}"),
        }
    }
    let (a, b) = (scratch("pcss0.png"), scratch("pcf0.png"));
    let out = render(&[&args[..], &["--map-filter", "pcss", "--out", &a]].concat())?;
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("every light has radius 0"), "{e}");
    render(&[&args[..], &["--out", &b]].concat())?;
    assert!(
        image::open(&a).unwrap().to_rgba8() == image::open(&b).unwrap().to_rgba8(),
        "pcss with radius 0 differs from pcf"
    );
    Ok(())
}

fn bad_map_flags_are_refused() -> Outcome {
    let png = scratch("bad.png");
    for (args, says) in [
        (
            vec!["--shadows", "map", "--pipeline", "gpu"],
            "leave out --pipeline and --backend",
        ),
        (
            vec!["--shadows", "map", "--backend", "simd"],
            "leave out --pipeline and --backend",
        ),
        (
            vec!["--shadows", "map", "--map-bias", "1,2"],
            "expected DEPTH,SLOPE,NORMAL",
        ),
        (
            vec!["--shadows", "map", "--map-bias", "nan,0,0"],
            "must be finite",
        ),
        (vec!["--shadows", "map", "--map-size", "0"], "--map-size"),
        (
            vec!["--shadows", "map", "--map-size", "20000"],
            "--map-size",
        ),
        (vec!["--shadows", "maps"], "--shadows"),
        (
            vec!["--shadows", "map", "--map-cascades", "5"],
            "--map-cascades",
        ),
    ] {
        let all = [&["render", "hard-book-3", "--out", &png][..], &args].concat();
        let out = run(&all);
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{all:?} succeeded");
        assert!(e.contains(says), "{all:?}: {e}");
        assert!(!e.contains("panicked"), "{all:?}: {e}");
    }
    Ok(())
}
