//! `shadowvol silhouette` on STL, PLY and quantized/compressed glTF from real exporters
//! (`crates/scenes/tests/data/real/`): the JSON lists the OBJ's exact silhouette edge for edge,
//! compared by position (the vertex numbering differs between formats); `--help` names the
//! formats; a glTF of lines only is refused with the skipped primitive named; Draco-compressed
//! glTF gives the JSON of the same file decoded by Google's decoder.

mod common;

use common::{json_of, run};
use serde_json::Value;
use std::path::PathBuf;

fn real(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/tests/data/real")
        .join(name)
        .display()
        .to_string()
}

/// Silhouette edges of the JSON's first light as (position, position, m), the smaller position
/// (by bits) first, m negated when turned around; sorted.
type EdgeByPosition = ([u32; 3], [u32; 3], i64);

fn edges_by_position(file: &str, json: &Value) -> Vec<EdgeByPosition> {
    let table = shadowvol_scenes::Scene::load(file)
        .unwrap()
        .baked_table()
        .unwrap();
    // The JSON names a vertex by the smallest input index of its weld group.
    let by_name: std::collections::HashMap<u64, glam::Vec3> = table
        .vertex_names
        .iter()
        .zip(&table.positions)
        .map(|(n, &p)| (u64::from(n), p))
        .collect();
    let key = |i: u64| {
        let p = by_name[&i];
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ]
    };
    let mut out: Vec<_> = json["lights"][0]["edges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let (a, b, m) = (
                key(e[0].as_u64().unwrap()),
                key(e[1].as_u64().unwrap()),
                e[2].as_i64().unwrap(),
            );
            if a <= b {
                (a, b, m)
            } else {
                (b, a, -m)
            }
        })
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn stl_ply_and_compressed_gltf_give_the_obj_silhouette_by_position() {
    let light = "--light=9000,20000,-3000,1";
    let silhouette = |f: &str| {
        let file = real(f);
        let json = json_of(&[
            "silhouette",
            &file,
            light,
            "--mode",
            "exact",
            "--format",
            "json",
        ]);
        assert_eq!(json["lights"][0]["open_vertices"], 0, "{f}");
        assert!(json.get("notes").is_none(), "{f}");
        (json["mesh"].clone(), edges_by_position(&file, &json))
    };
    let (obj_mesh, obj) = silhouette("reference.obj");
    assert!(obj.len() > 20);
    for f in [
        "reference-ascii.stl",
        "reference-binary.stl",
        "reference-ascii.ply",
        "reference-binary-le.ply",
        "reference-binary-be.ply",
        "gltfpack.glb",
        "gltfpack-c.glb",
        "gltfpack-cc.glb",
        "sparse.glb",
    ] {
        let (mesh, edges) = silhouette(f);
        assert_eq!(edges, obj, "{f}");
        assert_eq!(mesh["welded_vertices"], obj_mesh["welded_vertices"], "{f}");
        assert_eq!(mesh["edges"], obj_mesh["edges"], "{f}");
    }
    // STL is a soup: 3 input vertices per facet, welded to the OBJ's.
    let (stl_mesh, _) = silhouette("reference-binary.stl");
    assert_eq!(stl_mesh["vertices"], 3 * 557);
}

#[test]
fn draco_gltf_gives_the_silhouettes_of_googles_decoding() {
    // The scene's own four lights (KHR_lights_punctual survives the Draco transcoding).
    for (f, reference) in [
        ("draco.glb", "draco-decoded.glb"),
        ("scene-draco.glb", "scene-draco-decoded.glb"),
    ] {
        let args = |file: &str| -> Vec<String> {
            let mut a = vec!["silhouette".to_owned(), real(file)];
            if !file.starts_with("scene") {
                a.push("--light=9000,20000,-3000,1".to_owned());
            }
            a.extend(["--mode", "exact", "--format", "json"].map(str::to_owned));
            a
        };
        let run_json = |file: &str| {
            let a = args(file);
            json_of(&a.iter().map(String::as_str).collect::<Vec<_>>())
        };
        let (d, r) = (run_json(f), run_json(reference));
        assert!(d.get("notes").is_none(), "{f}");
        assert!(!d["lights"].as_array().unwrap().is_empty(), "{f}");
        assert_eq!(
            d["lights"], r["lights"],
            "{f}: every light's edges and open vertices"
        );
        assert_eq!(d["mesh"]["edges"], r["mesh"]["edges"], "{f}");
    }
}

#[test]
fn help_lists_the_input_formats() {
    let out = run(&["--help"]);
    let text = String::from_utf8_lossy(&out.stdout);
    for ext in [
        ".gltf",
        ".glb",
        ".obj",
        ".stl",
        ".ply",
        "KHR_mesh_quantization",
        "EXT_meshopt_compression",
        "KHR_draco_mesh_compression",
    ] {
        assert!(text.contains(ext), "--help does not name {ext}:\n{text}");
    }
    let out = run(&["silhouette", "--help"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(".stl") && text.contains(".ply"), "{text}");
}

#[test]
fn a_gltf_of_lines_only_is_refused_naming_the_skipped_primitive() {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/tests/data/lines_mode.gltf")
        .display()
        .to_string();
    let out = run(&["silhouette", &file, "--light=0,10,0,1"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no triangles") && err.contains("primitive 0") && err.contains("Lines"),
        "{err}"
    );
}
