//! `shadowvol scenes`, `shadowvol scene export`, and `shadowvol silhouette` on glTF files and
//! preset names, checked against the scenes crate and the cpu backend directly.

mod common;

use common::{json_of, run};
use serde_json::Value;
use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::{extract_once, Accuracy, TopologyScene};
use std::path::PathBuf;

fn fails(args: &[&str]) -> (i32, String) {
    let out = run(args);
    assert!(!out.status.success(), "shadowvol {args:?} should fail");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("shadowvol-cli-{}-{name}", std::process::id()))
}

#[test]
fn scenes_json_lists_every_preset_with_its_size() {
    let rows = json_of(&["scenes", "--format", "json"]);
    let rows = rows.as_array().expect("an array");
    let presets = shadowvol_scenes::presets();
    assert_eq!(rows.len(), presets.len());
    for (row, info) in rows.iter().zip(&presets) {
        let obj = row.as_object().unwrap();
        let mut keys: Vec<_> = obj.keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(keys, ["lights", "name", "objects", "triangles"]);
        assert_eq!(row["name"], info.name.as_str());
        // Sizes checked against the library only for the small presets (the big ones are
        // checked in crates/scenes/tests/presets.rs).
        if info.name.starts_with("hard-") || info.name == "spheres-100x1k" {
            let s = shadowvol_scenes::preset(&info.name).unwrap();
            assert_eq!(row["objects"], s.geometry.objects.len());
            assert_eq!(row["triangles"], s.triangle_count());
            assert_eq!(row["lights"], s.lights.len());
        }
    }
    // The largest presets are listed with their size, not generated (10^7 and 10^8
    // triangles: icospheres are exact for even counts; Loop subdivision quadruples).
    for (name, t) in [
        ("sphere-10m", 10_000_000u64),
        ("sphere-100m", 100_000_000),
        ("bunny-10m", 3_674 * 4u64.pow(6)),
    ] {
        let row = rows.iter().find(|r| r["name"] == name).unwrap();
        assert_eq!(
            (
                row["objects"].as_u64(),
                row["triangles"].as_u64(),
                row["lights"].as_u64()
            ),
            (Some(1), Some(t), Some(1)),
            "{row}"
        );
    }
    let town = rows.iter().find(|r| r["name"] == "town").unwrap();
    let t = town["triangles"].as_u64().unwrap();
    assert!((558_600..=581_400).contains(&t), "town: {t}");
    let text = run(&["scenes"]);
    assert!(text.status.success());
    assert!(String::from_utf8_lossy(&text.stdout).contains("sphere-1m"));
}

/// Exact silhouette of a preset's baked mesh, computed here with the cpu backend, as
/// `[a, b, m]` triples named by input vertex index.
fn reference_edges(name: &str, light: [f32; 4]) -> Vec<[i64; 3]> {
    let table = shadowvol_scenes::preset(name)
        .unwrap()
        .baked_table()
        .unwrap();
    let scene = TopologyScene::one("baked", table);
    let l = shadowvol_silhouette::Light::new(light[0], light[1], light[2], light[3]).unwrap();
    let (m, _) = extract_once(&mut CpuBackend::new(), &scene, &[l], Accuracy::Exact).unwrap();
    let t = &scene.objects[0].table;
    let mut out: Vec<[i64; 3]> = t
        .edges
        .iter()
        .zip(m.values(0))
        .filter(|(_, &v)| v != 0)
        .map(|(&[a, b], &v)| {
            [
                i64::from(t.vertex_names.get(a as usize)),
                i64::from(t.vertex_names.get(b as usize)),
                i64::from(v),
            ]
        })
        .collect();
    out.sort_unstable();
    out
}

fn edges_of(report: &Value) -> Vec<[i64; 3]> {
    report["lights"][0]["edges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| [0, 1, 2].map(|k| e[k].as_i64().unwrap()))
        .collect()
}

#[test]
fn exported_glb_and_preset_name_give_the_reference_silhouette() {
    let name = "hard-multi-object-transforms";
    let path = temp("multi.glb");
    let p = path.to_str().unwrap();
    let summary = json_of(&["scene", "export", name, p, "--format", "json"]);
    assert_eq!(summary["objects"], 4);
    let loaded = shadowvol_scenes::load_gltf(&path).unwrap();
    let original = shadowvol_scenes::preset(name).unwrap();
    assert_eq!(
        loaded.baked_table().unwrap(),
        original.baked_table().unwrap()
    );

    let light = "0.5,3,2,1";
    let from_glb = json_of(&["silhouette", p, "--light", light, "--format", "json"]);
    let from_name = json_of(&["silhouette", name, "--light", light, "--format", "json"]);
    std::fs::remove_file(&path).ok();
    assert_eq!(from_glb["mesh"], from_name["mesh"]);
    assert_eq!(from_glb["lights"], from_name["lights"]);
    let reference = reference_edges(name, [0.5, 3.0, 2.0, 1.0]);
    assert!(!reference.is_empty());
    assert_eq!(edges_of(&from_glb), reference);
    assert_eq!(from_glb["lights"][0]["open_vertices"], 0);

    // Without --light, the scene's own lights are used.
    let own = json_of(&["silhouette", name, "--format", "json"]);
    assert_eq!(
        own["lights"].as_array().unwrap().len(),
        original.lights.len()
    );
}

#[test]
fn bad_scene_arguments_fail_clearly() {
    let (code, err) = fails(&["scene", "export", "town", temp("x.gltf").to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(".glb"), "{err}");
    let (code, err) = fails(&[
        "scene",
        "export",
        "no-such-preset",
        temp("y.glb").to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("unknown scene 'no-such-preset'"), "{err}");
    let bad = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/tests/data/index_out_of_range.gltf"
    );
    let (code, err) = fails(&["silhouette", bad, "--light", "0,0,1,1"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("accessor 1 (indices)") && err.contains("index_out_of_range.gltf"),
        "{err}"
    );
}
