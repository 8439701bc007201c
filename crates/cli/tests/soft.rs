//! `render` with lights of a size: the JSON's per-light radius and samples, `--visibility`'s
//! files, a radius 0 that leaves the image byte for byte, every sample's hard shadow without an
//! artifact against the reference on hard-* presets, and bad radii refused with a message.
//! Skips visibly without a GPU adapter.

mod common;

use shadowvol_test_support::{main, Outcome};
use std::path::PathBuf;

main!(
    json_lists_radii_and_samples_and_writes_visibility,
    radius_zero_and_one_sample_leave_the_png_unchanged,
    every_samples_hard_shadow_matches_the_reference,
    visibility_error_of_a_plate_shrinks_with_samples,
    shadow_maps_report_their_fractional_visibility,
    bad_radii_are_refused_with_the_light_named
);

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("shadowvol-soft-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn json_lists_radii_and_samples_and_writes_visibility() -> Outcome {
    let d = dir("json");
    let vis = d.join("vis.png");
    let (v, _) = common::json_ok(&[
        "render",
        "hard-tetrahedron",
        "--light-radius",
        "0.2",
        "--light-samples",
        "8",
        "--size",
        "64x64",
        "--out",
        d.join("t.png").to_str().unwrap(),
        "--visibility",
        vis.to_str().unwrap(),
        "--explain",
        "--format",
        "json",
    ])?;
    let lights = v["lights"].as_array().unwrap().len();
    assert_eq!(lights, 2, "hard-tetrahedron has two lights");
    assert_eq!(v["light_radii"], serde_json::json!([0.2, 0.2]));
    assert_eq!(v["light_samples"], serde_json::json!([8, 8]));
    assert_eq!(v["light_samples_reason"].as_array().unwrap().len(), 2);
    let files = v["visibility_files"].as_array().unwrap();
    assert_eq!(files.len(), 2);
    assert_eq!(files[0], vis.to_str().unwrap());
    assert!(
        files[1].as_str().unwrap().ends_with("vis-1.png"),
        "{files:?}"
    );
    for f in files {
        let bytes = std::fs::read(f.as_str().unwrap()).expect("written");
        assert_eq!(&bytes[1..4], b"PNG");
        // 8-bit grey: colour type 0 in the IHDR chunk.
        assert_eq!((bytes[24], bytes[25]), (8, 0), "8-bit greyscale");
    }
    // The plan: one entry per (scene light, surface), as without a radius.
    assert_eq!(v["plan"].as_array().unwrap().len() % lights, 0);
    assert!(v["plan"]
        .as_array()
        .unwrap()
        .iter()
        .all(|e| e["light"].as_u64() < Some(2)));
    Ok(())
}

fn radius_zero_and_one_sample_leave_the_png_unchanged() -> Outcome {
    let d = dir("zero");
    let render = |name: &str, extra: &[&str]| -> Result<Vec<u8>, shadowvol_test_support::Skip> {
        let out = d.join(name);
        let mut args = vec![
            "render",
            "hard-light-at-vertex",
            "--size",
            "64x64",
            "--out",
            out.to_str().unwrap(),
            "--format",
            "json",
        ];
        args.extend_from_slice(extra);
        common::json_ok(&args)?;
        Ok(std::fs::read(&out).unwrap())
    };
    let plain = render("plain.png", &[])?;
    assert_eq!(plain, render("zero.png", &["--light-radius", "0"])?);
    assert_eq!(
        plain,
        render(
            "one.png",
            &["--light-radius", "0.3", "--light-samples", "1"]
        )?
    );
    Ok(())
}

/// On hard-* presets where exact hard volumes have no artifact, every sample of a light with a
/// size (each a point light) has none either, on both volume pipelines.
fn every_samples_hard_shadow_matches_the_reference() -> Outcome {
    let d = dir("samples");
    for preset in ["hard-tetrahedron", "hard-light-at-vertex", "hard-book-3"] {
        for pipeline in ["host", "gpu"] {
            let (v, _) = common::json_ok(&[
                "render",
                preset,
                "--pipeline",
                pipeline,
                "--light-radius",
                "0.05",
                "--light-samples",
                "4",
                "--size",
                "64x64",
                "--backdrop",
                "--reference",
                "--out",
                d.join("s.png").to_str().unwrap(),
                "--format",
                "json",
            ])?;
            let per = v["sample_artifact_pixels"].as_array().unwrap();
            assert_eq!(per.len(), v["lights"].as_array().unwrap().len());
            for (li, samples) in per.iter().enumerate() {
                let samples = samples.as_array().unwrap();
                assert_eq!(samples.len(), 4, "{preset}: light {li}");
                assert!(
                    samples.iter().all(|n| n == 0),
                    "{preset} ({pipeline}): light {li} samples {samples:?}"
                );
            }
            assert_eq!(v["artifact_pixels"], 0, "{preset} ({pipeline})");
        }
    }
    Ok(())
}

fn bad_radii_are_refused_with_the_light_named() -> Outcome {
    for (radius, what) in [("-1", "at least 0"), ("nan", "finite"), ("inf", "finite")] {
        let out = common::run(&["render", "hard-tetrahedron", "--light-radius", radius]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "--light-radius {radius} is refused");
        assert!(
            stderr.contains("light 0") && stderr.contains(what),
            "{radius}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    let out = common::run(&["render", "hard-tetrahedron", "--light-samples", "0"]);
    assert!(!out.status.success());
    Ok(())
}

/// The plate scene of [`visibility_error_of_a_plate_shrinks_with_samples`], written to `d`.
fn plate_obj(d: &std::path::Path) -> PathBuf {
    let obj = d.join("plate.obj");
    std::fs::write(
        &obj,
        "v -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\n\
         v -0.5 1 -0.5\nv 0.5 1 -0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n\
         f 1 3 2\nf 1 4 3\nf 5 7 6\nf 5 8 7\n",
    )
    .unwrap();
    obj
}

/// `render` of the plate in `d` under its disk light (radius 0.5, straight above), 160x160,
/// with `--reference` and `extra`: its JSON.
fn render_plate(
    d: &std::path::Path,
    extra: &[&str],
) -> Result<serde_json::Value, shadowvol_test_support::Skip> {
    let obj = plate_obj(d);
    let out = d.join("p.png");
    let mut args = vec![
        "render",
        obj.to_str().unwrap(),
        "--light=0,4,0,1",
        "--light-radius",
        "0.5",
        "--ground",
        "off",
        "--size",
        "160x160",
        "--reference",
        "--out",
        out.to_str().unwrap(),
        "--format",
        "json",
    ];
    args.extend_from_slice(extra);
    Ok(common::json_ok(&args)?.0)
}

/// Shadow maps give the reference their own fractional visibility (the filter's, read back per
/// light), not the mask's 0 or 1: under PCF and PCSS the visibility image has grey levels
/// between 0 and 255, and the JSON measures it against the true visibility.
fn shadow_maps_report_their_fractional_visibility() -> Outcome {
    let d = dir("maps");
    for filter in ["pcf", "pcss"] {
        let vis = d.join(format!("v-{filter}.png"));
        let v = render_plate(
            &d,
            &[
                "--shadows",
                "map",
                "--map-filter",
                filter,
                "--map-size",
                "512",
                "--visibility",
                vis.to_str().unwrap(),
            ],
        )?;
        assert_eq!(v["light_samples"], serde_json::json!([1]));
        let e = &v["visibility_error"][0];
        let mean = e["mean"].as_f64().unwrap();
        assert!(
            e["penumbra_pixels"].as_u64().unwrap() > 60 && mean > 0.0 && mean < 1.0,
            "{e}"
        );
        let grey = image::open(&vis).expect("a PNG").to_luma8();
        let between = grey.pixels().filter(|p| p.0[0] > 0 && p.0[0] < 255).count();
        assert!(
            between > 2,
            "{filter}: {between} pixels between lit and shadowed"
        );
    }
    Ok(())
}

/// A square plate over a floor (an OBJ) under a disk light straight above: the reference's
/// visibility error over the penumbra is under 0.03 at 64 samples and shrinks from 4 to 64, and
/// no lit or umbra pixel differs, on both volume pipelines.
fn visibility_error_of_a_plate_shrinks_with_samples() -> Outcome {
    let d = dir("plate");
    for pipeline in ["host", "gpu"] {
        let mut means = Vec::new();
        for n in ["4", "64"] {
            let v = render_plate(&d, &["--light-samples", n, "--pipeline", pipeline])?;
            let e = &v["visibility_error"][0];
            assert!(e["penumbra_pixels"].as_u64().unwrap() > 60, "{e}");
            assert_eq!(e["lit_umbra_mismatches"], 0, "{pipeline} {n}: {e}");
            assert!(e["reference_bound"].as_f64().unwrap() < 1e-3, "{e}");
            means.push(e["mean"].as_f64().unwrap());
        }
        assert!(
            means[1] < 0.03,
            "{pipeline}: mean error at 64 samples {}",
            means[1]
        );
        assert!(means[1] < means[0], "{pipeline}: {means:?}");
    }
    Ok(())
}
