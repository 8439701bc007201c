//! `shadowvol render` on any mesh, with no flags: OBJ files of every kind a user brings (a
//! scan, a CAD part with flat polygon faces, a quad mesh, an open model, a non-manifold one) and
//! glTF files without lights or camera. Each must exit 0 with its object in view and its shadow
//! on the added ground, and in exact mode agree with the ray-traced reference on all but
//! 0.05 % of the pixels.

mod common;

use common::{run, BIN};
use serde_json::Value;
use shadowvol_test_support::{main, Outcome, Skip};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

main!(
    every_kind_of_obj_renders_with_a_default_light_and_ground,
    gltf_files_without_lights_or_camera_render,
    no_flags_at_all_writes_stem_png_in_the_current_directory,
    flags_override_the_defaults,
    json_report_has_the_contract_keys,
    files_without_triangles_are_refused_and_skipped_geometry_is_noted,
    coordinates_near_the_f32_limit_render_or_fail_clearly,
    a_render_without_a_display_prints_no_error_line
);

/// The size of the compared renders: large enough for a few thousand shadow pixels.
const SIZE: &str = "160x160";
const PIXELS: f64 = 160.0 * 160.0;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "shadowvol-render-any-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An OBJ text from positions and faces (1-based on output).
fn obj(positions: &[[f32; 3]], faces: &[Vec<usize>]) -> String {
    let mut s = String::from("# written by the render_any test\n");
    for p in positions {
        writeln!(s, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for f in faces {
        s.push('f');
        for i in f {
            write!(s, " {}", i + 1).unwrap();
        }
        s.push('\n');
    }
    s
}

/// A lumpy sphere of irregular triangles, as a scanner writes: an icosphere with every vertex
/// pushed in or out by a deterministic amount, off the origin.
fn scan() -> String {
    let m = shadowvol_scenes::procedural::icosphere(320, 3.0);
    let p: Vec<[f32; 3]> = m
        .positions
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let bump = 1.0 + 0.08 * ((i * 7919 % 23) as f32 / 23.0 - 0.5);
            let q = *q * bump;
            [q.x, q.y + 3.2, q.z]
        })
        .collect();
    let f: Vec<Vec<usize>> = m
        .triangles
        .iter()
        .map(|t| t.iter().map(|&i| i as usize).collect())
        .collect();
    obj(&p, &f)
}

/// An L-shaped bracket: two flat L faces written as one 6-gon each, and its sides as quads.
fn cad_bracket() -> String {
    let l = [
        [0., 0.],
        [40., 0.],
        [40., 8.],
        [8., 8.],
        [8., 30.],
        [0., 30.],
    ];
    let mut p = Vec::new();
    for z in [0f32, 20.] {
        for [x, y] in l {
            p.push([x, y, z]);
        }
    }
    // Both L faces fan from the outer corner, as the loader fans polygons: convex pieces only.
    let mut faces = vec![vec![0, 5, 4, 3, 2, 1], (6..12).collect()];
    for i in 0..6 {
        let j = (i + 1) % 6;
        faces.push(vec![i, j, j + 6, i + 6]);
    }
    obj(&p, &faces)
}

/// A box whose faces are 4x4 grids of quads.
fn quad_box() -> String {
    let n = 4usize;
    let mut p = Vec::new();
    let mut faces = Vec::new();
    // Each face: origin, u and v directions (outward normal u x v).
    let sides: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
        ([0., 0., 0.], [0., 1., 0.], [1., 0., 0.]),
        ([0., 0., 1.], [1., 0., 0.], [0., 1., 0.]),
        ([0., 0., 0.], [0., 0., 1.], [0., 1., 0.]),
        ([1., 0., 0.], [0., 1., 0.], [0., 0., 1.]),
        ([0., 0., 0.], [1., 0., 0.], [0., 0., 1.]),
        ([0., 1., 0.], [0., 0., 1.], [1., 0., 0.]),
    ];
    let mut index = std::collections::HashMap::new();
    for (o, u, v) in sides {
        let mut id = |a: usize, b: usize| {
            let q =
                [0, 1, 2].map(|k| o[k] + u[k] * a as f32 / n as f32 + v[k] * b as f32 / n as f32);
            let key = q.map(|c| (c * 1000.0).round() as i64);
            *index.entry(key).or_insert_with(|| {
                p.push(q.map(|c| c * 2.0));
                p.len() - 1
            })
        };
        for a in 0..n {
            for b in 0..n {
                faces.push(vec![id(a, b), id(a + 1, b), id(a + 1, b + 1), id(a, b + 1)]);
            }
        }
    }
    obj(&p, &faces)
}

/// A box without its top: an open model with boundary edges, lit from inside as well.
fn open_box() -> String {
    let p: Vec<[f32; 3]> = (0..8)
        .map(|k| {
            [
                if k & 1 == 0 { 0. } else { 2. },
                if k & 2 == 0 { 0. } else { 1.5 },
                if k & 4 == 0 { 0. } else { 2. },
            ]
        })
        .collect();
    let faces = vec![
        vec![0, 1, 5, 4], // bottom
        vec![0, 2, 3, 1], // back
        vec![4, 5, 7, 6], // front
        vec![0, 4, 6, 2], // left
        vec![1, 3, 7, 5], // right
    ];
    obj(&p, &faces)
}

/// Two cubes sharing one edge (four triangles on it) and a fin: a triangle hanging off an edge
/// of the first cube.
fn non_manifold() -> String {
    let mut p: Vec<[f32; 3]> = Vec::new();
    let mut faces = Vec::new();
    for (dx, dy) in [(0f32, 0f32), (1., 1.)] {
        let base = p.len();
        for k in 0..8 {
            p.push([
                dx + if k & 1 == 0 { 0. } else { 1. },
                dy + if k & 2 == 0 { 0. } else { 1. },
                if k & 4 == 0 { 0. } else { 1. },
            ]);
        }
        for q in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            faces.push(q.iter().map(|i| base + i).collect());
        }
    }
    p.push([-0.8, 1.6, 0.5]);
    faces.push(vec![2, 6, 16]);
    // The second cube's corner (1, 1, z) is the first cube's (1, 1, z): weld them by index so
    // the shared edge is one edge of four triangles.
    for f in &mut faces {
        for i in f.iter_mut() {
            if *i >= 8 && *i < 16 {
                let k = *i - 8;
                if k & 1 == 0 && k & 2 == 0 {
                    *i = 3 | (k & 4);
                }
            }
        }
    }
    obj(&p, &faces)
}

fn real(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/tests/data/real")
        .join(name)
        .display()
        .to_string()
}

/// Renders `file` with only `--size`, `--reference` and `--format json`, and checks the
/// result; a skip when there is no GPU adapter (a failure under CI).
fn render_checked(file: &str, out_dir: &Path) -> Result<Value, Skip> {
    let out_png = out_dir.join("out.png");
    let args = [
        "render",
        file,
        "--out",
        out_png.to_str().unwrap(),
        "--size",
        SIZE,
        "--reference",
        "--format",
        "json",
    ];
    let out = run(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        common::no_adapter("render", &stderr)?;
    }
    assert!(out.status.success(), "render {file} failed:\n{stderr}");
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["lights_source"], "default", "{file}: {v}");
    assert_eq!(v["lights"].as_array().unwrap().len(), 1, "{file}");
    assert_eq!(v["ground"]["source"], "auto", "{file}: {v}");
    assert_eq!(v["mode"], "exact");
    let plan = v["plan"].as_array().unwrap();
    let casters: Vec<&Value> = plan
        .iter()
        .filter(|e| e["object_name"] != "ground")
        .collect();
    assert!(!casters.is_empty(), "{file}: no caster in the plan");
    for e in &casters {
        assert_ne!(e["technique"], "culled", "{file}: caster culled: {e}");
        assert!(e["silhouette_edges"].as_u64().unwrap() > 0, "{file}: {e}");
    }
    let covered = v["covered_pixels"].as_f64().unwrap();
    let shadow = v["shadow_pixels"].as_f64().unwrap();
    let reference_shadow = v["reference_shadow_pixels"].as_f64().unwrap();
    let artifacts = v["artifact_pixels"].as_f64().unwrap();
    assert!(
        covered > 0.3 * PIXELS,
        "{file}: only {covered} pixels covered"
    );
    assert!(
        shadow > 0.005 * PIXELS && reference_shadow > 0.005 * PIXELS,
        "{file}: the shadow is not in view ({shadow} raster, {reference_shadow} reference pixels)"
    );
    assert!(
        artifacts <= 0.0005 * PIXELS,
        "{file}: {artifacts} artifact pixels, more than 0.05 % of {PIXELS}: {v}"
    );
    eprintln!(
        "{file}: {shadow} shadow pixels, {artifacts} artifact, {} boundary, {} undecidable",
        v["boundary_pixels"], v["undecidable_pixels"]
    );
    Ok(v)
}

fn every_kind_of_obj_renders_with_a_default_light_and_ground() -> Outcome {
    let dir = scratch("obj");
    let meshes = [
        ("scan", scan()),
        ("cad-bracket", cad_bracket()),
        ("quad-box", quad_box()),
        ("open-box", open_box()),
        ("non-manifold", non_manifold()),
    ];
    for (name, text) in meshes {
        let path = dir.join(format!("{name}.obj"));
        std::fs::write(&path, text).unwrap();
        render_checked(path.to_str().unwrap(), &dir)?;
    }
    render_checked(&real("reference.obj"), &dir)?;
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

fn gltf_files_without_lights_or_camera_render() -> Outcome {
    let dir = scratch("gltf");
    for f in ["obj2gltf.glb", "gltfpack.glb", "gltfpack-c.glb"] {
        render_checked(&real(f), &dir)?;
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

/// With no flag at all, the PNG goes to `STEM.png` in the current directory.
fn no_flags_at_all_writes_stem_png_in_the_current_directory() -> Outcome {
    let dir = scratch("bare");
    std::fs::write(dir.join("part.obj"), cad_bracket()).unwrap();
    let out = Command::new(BIN)
        .current_dir(&dir)
        .args(["render", "part.obj"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        common::no_adapter("render", &stderr)?;
    }
    assert!(out.status.success(), "{stderr}");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("-> part.png"), "{text}");
    assert!(text.contains("default key light"), "{text}");
    assert!(text.contains("nothing lies below the casters"), "{text}");
    assert_eq!(&std::fs::read(dir.join("part.png")).unwrap()[1..4], b"PNG");
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

/// `--light` replaces the default, `--ground off` removes the plane, and a preset keeps its own
/// receivers under `auto`.
fn flags_override_the_defaults() -> Outcome {
    let dir = scratch("flags");
    let path = dir.join("box.obj");
    std::fs::write(&path, quad_box()).unwrap();
    let png = dir.join("o.png");
    let base = [
        "render",
        path.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
        "--size",
        "48x48",
        "--format",
        "json",
    ];
    let mut args = base.to_vec();
    args.extend(["--light", "1,10,2,1", "--ground", "off"]);
    let out = run(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        common::no_adapter("render", &stderr)?;
    }
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["lights_source"], "flags");
    assert_eq!(v["lights"][0], serde_json::json!([1.0, 10.0, 2.0, 1.0]));
    assert!(v["ground"].is_null(), "{v}");
    assert!(v["plan"]
        .as_array()
        .unwrap()
        .iter()
        .all(|e| e["object_name"] != "ground"));

    let mut args = base.to_vec();
    args.extend(["--ground", "on"]);
    let v: Value = serde_json::from_slice(&run(&args).stdout).expect("JSON");
    assert_eq!(v["ground"]["source"], "flags");
    assert_eq!(v["lights_source"], "default");

    // A hard-* preset declares no ground and keeps none under auto; its lights are the file's.
    let mut args = base.to_vec();
    args[1] = "hard-book-3";
    let v: Value = serde_json::from_slice(&run(&args).stdout).expect("JSON");
    assert!(v["ground"].is_null(), "{v}");
    assert_eq!(v["lights_source"], "file");
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

/// `shadowvol render --format json` keeps the contract's keys; `--diff` writes a PNG. (On the
/// binary, so that it can skip visibly without an adapter: a unit test cannot.)
fn json_report_has_the_contract_keys() -> Outcome {
    let dir = std::env::temp_dir().join(format!("shadowvol-cli-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out_png = dir.join("r.png");
    let diff_png = dir.join("d.png");
    let (v, _) = common::json_ok(&[
        "render",
        "hard-double-sided-sheet",
        "--out",
        out_png.to_str().unwrap(),
        "--size",
        "64x48",
        "--backdrop",
        "--diff",
        diff_png.to_str().unwrap(),
        "--format",
        "json",
    ])?;
    for key in ["artifact_pixels", "shadow_pixels", "plan", "timings"] {
        assert!(v.get(key).is_some(), "missing {key}: {v}");
    }
    assert!(v["artifact_pixels"].as_u64().is_some());
    assert!(v["geometric_artifact_pixels"].as_u64().is_some());
    assert!(v["undecidable_pixels"].as_u64().is_some());
    assert!(v["boundary_pixels"].as_u64().is_some());
    let footprint = v["footprint_boundary_pixels"].as_u64().unwrap();
    assert!(footprint <= v["boundary_pixels"].as_u64().unwrap());
    assert!(v["geometric_footprint_boundary_pixels"].as_u64().is_some());
    assert!(v["shadow_pixels"].as_u64().unwrap() > 0);
    let plan = v["plan"].as_array().unwrap();
    assert!(!plan.is_empty());
    for key in [
        "light",
        "object",
        "technique",
        "silhouette",
        "side_quads",
        "reason",
    ] {
        assert!(plan[0].get(key).is_some(), "plan entry without {key}");
    }
    assert!(
        v["timings"]["raster_ms"].as_f64().is_some(),
        "timings without raster_ms"
    );
    // Host-side times exist where the host does the work: on the GPU pipeline extraction and
    // volumes run on the device, and no backend runs.
    let host = v["pipeline"] == "host";
    for key in ["silhouette_ms", "side_building_ms"] {
        let t = &v["timings"][key];
        assert!(
            if host {
                t.as_f64().is_some()
            } else {
                t.is_null()
            },
            "{} pipeline: timings.{key} is {t}",
            v["pipeline"]
        );
    }
    assert_eq!(
        v["backend"].is_null(),
        !host,
        "backend on the {} pipeline",
        v["pipeline"]
    );
    let unit = if host {
        "edge-opposite-vertex-light"
    } else {
        "triangle-light"
    };
    assert_eq!(v["uncertain_unit"], unit);
    let png = std::fs::read(&out_png).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert_eq!(&std::fs::read(&diff_png).unwrap()[1..4], b"PNG");
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

/// A file with only lines and points is an error (no PNG), the same as `silhouette`'s; a file
/// with faces and lines renders, with a note for the lines, which `silhouette` reports too.
fn files_without_triangles_are_refused_and_skipped_geometry_is_noted() -> Outcome {
    let dir = scratch("wire");
    let wire = dir.join("wire.obj");
    std::fs::write(&wire, "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\np 3\n").unwrap();
    let wire = wire.to_str().unwrap();
    let png = dir.join("wire.png");
    let first_error = |out: &std::process::Output| {
        assert_eq!(out.status.code(), Some(1), "{out:?}");
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        stderr
            .lines()
            .find(|l| l.starts_with("error: "))
            .unwrap_or_else(|| panic!("no error line in:\n{stderr}"))
            .to_owned()
    };
    let rendered = first_error(&run(&["render", wire, "--out", png.to_str().unwrap()]));
    for part in [
        "wire.obj: no triangles found",
        "2 line (l) statements skipped, the first at line 4",
        "1 point (p) statement skipped, the first at line 6",
    ] {
        assert!(rendered.contains(part), "expected {part:?} in: {rendered}");
    }
    assert!(
        !png.exists(),
        "a PNG was written for a file with no triangles"
    );
    let extracted = first_error(&run(&["silhouette", wire, "--light", "0,0,5,1"]));
    assert_eq!(rendered, extracted, "render and silhouette disagree");

    let mixed = dir.join("mixed.obj");
    std::fs::write(&mixed, format!("{}l 1 2\n", cad_bracket())).unwrap();
    let mixed = mixed.to_str().unwrap();
    let note = "mixed.obj: 1 line (l) statement skipped";
    let v = common::json_of(&[
        "silhouette",
        mixed,
        "--light",
        "0,0,50,1",
        "--format",
        "json",
    ]);
    let notes = v["notes"].as_array().expect("notes in the silhouette JSON");
    assert!(
        notes.iter().any(|n| n.as_str().unwrap().contains(note)),
        "{notes:?}"
    );
    let out = run(&[
        "render",
        mixed,
        "--out",
        png.to_str().unwrap(),
        "--size",
        "64x64",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        common::no_adapter("render", &stderr)?;
    }
    assert!(out.status.success(), "render {mixed} failed:\n{stderr}");
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("note: ") && l.contains(note)),
        "no note for the skipped line in:\n{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

/// Coordinates near `f32::MAX` are valid positions, but no camera frames them and no ring of
/// generated lights fits around them: `render` and `bench` say so and exit 1 (they used to panic
/// on a non-finite light). Far from the origin but small, a model still renders.
fn coordinates_near_the_f32_limit_render_or_fail_clearly() -> Outcome {
    let dir = scratch("huge");
    let tetrahedron = |s: &str| {
        format!(
            "v -{s} -{s} -{s}\nv {s} -{s} -{s}\nv 0 {s} -{s}\nv 0 0 {s}\n\
             f 1 2 3\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"
        )
    };
    let big = dir.join("big.obj");
    std::fs::write(&big, tetrahedron("3e38")).unwrap();
    let big = big.to_str().unwrap();
    let png = dir.join("big.png");
    let refused = |args: &[&str], what: &str| {
        let out = run(args);
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
        assert_eq!(out.status.code(), Some(1), "{args:?}:\n{stderr}");
        let line = stderr.lines().find(|l| l.starts_with("error: ")).unwrap();
        for part in [
            "big.obj: the scene's bounds ([-3e38, -3e38, -3e38] to",
            what,
        ] {
            assert!(line.contains(part), "expected {part:?} in: {line}");
        }
        assert_eq!(line.matches("big.obj").count(), 1, "{line}");
    };
    let out = png.to_str().unwrap();
    for pipeline in ["gpu", "host"] {
        refused(
            &["render", big, "--out", out, "--pipeline", pipeline],
            "too large for a camera that frames them in f32",
        );
    }
    assert!(!png.exists(), "a PNG was written for an unframable scene");
    refused(
        &["bench", "--scene", big, "--backend", "cpu", "--lights", "2"],
        "too large for the ring of generated lights in f32",
    );

    // A triangle 1e23 wide at 1e30 from the origin: framing and lighting stay finite.
    let far = dir.join("far.obj");
    std::fs::write(
        &far,
        "v 1e30 1e30 1e30\nv 1.0000001e30 1e30 1e30\nv 1e30 1.0000001e30 1e30\nf 1 2 3\n",
    )
    .unwrap();
    let far_png = dir.join("far.png");
    let args = [
        "render",
        far.to_str().unwrap(),
        "--out",
        far_png.to_str().unwrap(),
        "--size",
        "64x64",
        "--pipeline",
        "host",
        "--backend",
        "cpu",
    ];
    let out = run(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    if !out.status.success() {
        common::no_adapter("render", &stderr)?;
    }
    assert!(out.status.success(), "{args:?} failed:\n{stderr}");
    assert!(far_png.exists(), "no PNG for the far triangle");
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

/// Without a display (no `DISPLAY`, no `WAYLAND_DISPLAY`), a render that succeeds prints no line
/// starting with `error`: Mesa's device-select layer used to print
/// `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` twice while probing for a
/// display.
fn a_render_without_a_display_prints_no_error_line() -> Outcome {
    let png = scratch("quiet").join("quiet.png");
    let out = std::process::Command::new(common::BIN)
        .args(["render", "hard-tetrahedron", "--size", "48x48", "--out"])
        .arg(&png)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .expect("run shadowvol");
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        common::no_adapter("render", &stderr)?;
    }
    assert!(out.status.success(), "{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert!(errors.is_empty(), "a successful render printed: {errors:?}");
    Ok(())
}
