//! The real-exporter corpus (`tests/data/real/`, made by `make.sh` with obj2gltf, gltfpack,
//! glTF Transform, trimesh and plyfile from one OBJ): every file gives the OBJ's triangles by
//! position, and the OBJ's exact silhouettes edge for edge by position (cpu backend); the
//! meshopt-compressed files give the uncompressed quantized file's triangles and silhouettes;
//! the Draco-compressed files give, vertex for vertex and triangle for triangle, what Google's
//! own decoder gives (its `-decoded.glb` twins, written by `make_draco.mjs`), in its point order
//! where the stream has only positions, and by position where attribute seams split points.

use glam::Vec3;
use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_scenes::Scene;
use shadowvol_silhouette::{extract_once, Accuracy, Light, TopologyScene};
use std::path::PathBuf;
use std::sync::Arc;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(name)
}

fn load(name: &str) -> Arc<EdgeTable> {
    let (scene, notes) = Scene::load_with_notes(data(name)).unwrap_or_else(|e| panic!("{e}"));
    assert!(notes.is_empty(), "{name}: {notes:?}");
    scene.baked_table().unwrap()
}

/// The weld key of a position: its coordinates' bits, `-0` as `+0`.
fn key(p: Vec3) -> [u32; 3] {
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

/// Triangles as position triples, rotated so the smallest key comes first (winding kept), sorted.
fn triangles_by_position(m: &EdgeTable) -> Vec<[[u32; 3]; 3]> {
    let mut out: Vec<[[u32; 3]; 3]> = m
        .triangles
        .iter()
        .map(|t| {
            let k = t.map(|i| key(m.positions[i as usize]));
            let r = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
            [k[r], k[(r + 1) % 3], k[(r + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}

/// Silhouette edges with `m != 0` for each light, as (position, position, m) with the smaller
/// key first (m negated when the edge is turned around), sorted.
/// A silhouette edge by position: (smaller key, larger key, multiplicity from the first).
type EdgeByPosition = ([u32; 3], [u32; 3], i32);

fn silhouettes_by_position(m: &EdgeTable, lights: &[Light]) -> Vec<Vec<EdgeByPosition>> {
    let table = m.clone();
    let positions = table.positions.clone();
    let edges = table.edges.clone();
    let scene = TopologyScene::single(table);
    let (mult, _) = extract_once(&mut CpuBackend::new(), &scene, lights, Accuracy::Exact).unwrap();
    (0..lights.len())
        .map(|l| {
            let mut out: Vec<_> = mult
                .values(l)
                .iter()
                .zip(&edges)
                .filter(|(&v, _)| v != 0)
                .map(|(&v, e)| {
                    let (a, b) = (key(positions[e[0] as usize]), key(positions[e[1] as usize]));
                    if a <= b {
                        (a, b, v)
                    } else {
                        (b, a, -v)
                    }
                })
                .collect();
            out.sort_unstable();
            out
        })
        .collect()
}

fn lights(reference: &EdgeTable) -> Vec<Light> {
    let p = reference.positions[0];
    vec![
        Light::point(Vec3::new(9000.0, 20000.0, 9000.0)),
        Light::point(Vec3::new(-5000.0, 1000.0, 30000.0)),
        // In the planes x = p.x and z = p.z of a vertex: many faces edge-on or nearly.
        Light::point(Vec3::new(p.x, 50000.0, p.z)),
        Light::new(1.0, 2.0, 3.0, 0.0).unwrap(),
        Light::new(-0.3, 1.0, 0.2, 0.0).unwrap(),
    ]
}

const FILES: [&str; 12] = [
    "obj2gltf.glb",
    "gltfpack.glb",
    "gltfpack-c.glb",
    "gltfpack-cc.glb",
    "gltfpack-noq.glb",
    "sparse.glb",
    "reference-ascii.stl",
    "reference-binary.stl",
    "reference-ascii.ply",
    "reference-binary-le.ply",
    "reference-binary-be.ply",
    "reference.obj",
];

#[test]
fn every_file_has_the_obj_triangles_and_its_exact_silhouettes() {
    let reference = load("reference.obj");
    assert_eq!(reference.triangles.len(), 557);
    let lights = lights(&reference);
    let tris = triangles_by_position(&reference);
    let sil = silhouettes_by_position(&reference, &lights);
    assert!(
        sil.iter().all(|s| s.len() > 20),
        "every light sees a silhouette"
    );
    for name in FILES {
        let m = load(name);
        assert_eq!(m.triangles.len(), 557, "{name}");
        assert_eq!(
            triangles_by_position(&m),
            tris,
            "{name}: triangles by position"
        );
        assert_eq!(
            silhouettes_by_position(&m, &lights),
            sil,
            "{name}: silhouettes"
        );
    }
}

#[test]
fn meshopt_compressed_files_decode_to_the_uncompressed_quantized_file() {
    let quantized = load("gltfpack.glb");
    let lights = lights(&quantized);
    let silhouettes = silhouettes_by_position(&quantized, &lights);
    // meshoptimizer's index codec keeps each triangle's winding but may rotate its corners.
    let rotated = |t: [u32; 3]| {
        let r = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
        [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
    };
    // -c: the same vertex stream bit for bit, the same triangles in the same order.
    let c = load("gltfpack-c.glb");
    assert_eq!(c.positions, quantized.positions);
    assert_eq!(c.triangles.len(), quantized.triangles.len());
    for (a, b) in c.triangles.iter().zip(&quantized.triangles) {
        assert_eq!(rotated(*a), rotated(*b));
    }
    // -cc also reorders vertices for its codec: the same triangles and silhouettes by position.
    for name in ["gltfpack-c.glb", "gltfpack-cc.glb"] {
        let m = load(name);
        assert_eq!(
            triangles_by_position(&m),
            triangles_by_position(&quantized),
            "{name}"
        );
        assert_eq!(silhouettes_by_position(&m, &lights), silhouettes, "{name}");
    }
}

/// glTF Transform's Draco encodings of `obj2gltf.glb` (edgebreaker at the default speed,
/// sequential, edgebreaker at speed 0: the strongest predictions), each with the same file as
/// decoded by Google's decoder (draco3dgltf).
const DRACO: [(&str, &str); 3] = [
    ("draco.glb", "draco-decoded.glb"),
    ("draco-sequential.glb", "draco-sequential-decoded.glb"),
    ("draco-speed0.glb", "draco-speed0-decoded.glb"),
];

#[test]
fn draco_files_decode_exactly_as_googles_decoder_decodes_them() {
    let obj = load("reference.obj");
    let lights = lights(&obj);
    let bits = |m: &EdgeTable| -> Vec<[u32; 3]> {
        m.positions
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    // Draco quantizes positions to 14 bits of the mesh's extent: each decoded vertex lies within
    // half a step (per axis) of a vertex of the OBJ.
    let (lo, hi) = obj
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let step = (hi - lo).max_element() / 16383.0;
    for (name, reference) in DRACO {
        let m = load(name);
        let r = load(reference);
        assert_eq!(m.triangles.len(), 557, "{name}");
        assert_eq!(bits(&m), bits(&r), "{name}: positions, bit for bit");
        assert_eq!(m.triangles, r.triangles, "{name}: triangles, in order");
        assert_eq!(
            silhouettes_by_position(&m, &lights),
            silhouettes_by_position(&r, &lights),
            "{name}: silhouettes"
        );
        for (i, p) in m.positions.iter().enumerate() {
            let d = obj
                .positions
                .iter()
                .map(|q| (*p - *q).abs().max_element())
                .fold(f32::INFINITY, f32::min);
            assert!(
                d <= 0.5001 * step,
                "{name}: vertex {i} is {d} from the OBJ's"
            );
        }
    }
}

#[test]
fn a_draco_scene_of_several_objects_decodes_as_googles_decoder_decodes_it() {
    // `shadowvol scene export hard-multi-object-transforms` (four objects under their own
    // transforms, a non-manifold book among them, four lights), through glTF Transform's `draco`.
    let load_scene = |name: &str| {
        let (scene, notes) = Scene::load_with_notes(data(name)).unwrap_or_else(|e| panic!("{e}"));
        assert!(notes.is_empty(), "{name}: {notes:?}");
        scene
    };
    let d = load_scene("scene-draco.glb");
    let r = load_scene("scene-draco-decoded.glb");
    assert_eq!(d.geometry.objects.len(), 4);
    assert_eq!(d.geometry.objects.len(), r.geometry.objects.len());
    for (a, b) in d.geometry.objects.iter().zip(&r.geometry.objects) {
        assert_eq!(a.world_from_object, b.world_from_object, "{}", a.name);
        assert_eq!(a.table.triangles, b.table.triangles, "{}", a.name);
        let bits = |m: &EdgeTable| -> Vec<[u32; 3]> {
            m.positions
                .iter()
                .map(|p| p.to_array().map(f32::to_bits))
                .collect()
        };
        assert_eq!(bits(&a.table), bits(&b.table), "{}", a.name);
    }
    assert_eq!(d.lights.len(), 4);
    assert_eq!(d.lights, r.lights);
    let (dm, rm) = (d.baked_table().unwrap(), r.baked_table().unwrap());
    let sil = silhouettes_by_position(&dm, &d.light_positions());
    assert!(sil.iter().all(|s| !s.is_empty()));
    assert_eq!(sil, silhouettes_by_position(&rm, &r.light_positions()));
}

#[test]
fn a_draco_mesh_with_attribute_seams_gives_googles_geometry_in_its_own_point_order() {
    // make_uv_sphere.py: POSITION, NORMAL and TEXCOORD_0, the u = 0/1 seam and the poles
    // duplicating vertices. With seams to carry, draco-oxide numbers the split points in
    // another order than Google's decoder: the same positions bit for bit as a multiset, the
    // same triangles and the same exact silhouettes by position.
    let d = load("uv-sphere-draco.glb");
    let r = load("uv-sphere-draco-decoded.glb");
    let sorted_bits = |m: &EdgeTable| {
        let mut v: Vec<[u32; 3]> = m
            .positions
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect();
        v.sort_unstable();
        v
    };
    assert_eq!(d.triangles.len(), 528);
    assert_eq!(d.positions.len(), r.positions.len());
    assert_eq!(sorted_bits(&d), sorted_bits(&r));
    assert_eq!(triangles_by_position(&d), triangles_by_position(&r));
    let lights = lights(&r);
    let sil = silhouettes_by_position(&d, &lights);
    assert!(sil.iter().all(|s| s.len() > 10));
    assert_eq!(sil, silhouettes_by_position(&r, &lights));
    let json = |name: &str| -> serde_json::Value {
        let b = std::fs::read(data(name)).unwrap();
        let n = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
        serde_json::from_slice(&b[20..20 + n]).unwrap()
    };
    let attrs = &json("uv-sphere-draco.glb")["meshes"][0]["primitives"][0]["extensions"]
        ["KHR_draco_mesh_compression"]["attributes"];
    for a in ["POSITION", "NORMAL", "TEXCOORD_0"] {
        assert!(attrs.get(a).is_some(), "the stream carries {a}");
    }
}

#[test]
fn the_corpus_uses_what_it_is_meant_to_test() {
    let json = |name: &str| -> serde_json::Value {
        let b = std::fs::read(data(name)).unwrap();
        let n = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
        serde_json::from_slice(&b[20..20 + n]).unwrap()
    };
    let q = json("gltfpack.glb");
    assert_eq!(q["extensionsRequired"][0], "KHR_mesh_quantization");
    assert_eq!(q["accessors"][0]["componentType"], 5123, "u16 positions");
    for name in ["gltfpack-c.glb", "gltfpack-cc.glb"] {
        let c = json(name);
        assert!(c["extensionsRequired"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e == "EXT_meshopt_compression"));
        assert_eq!(
            c["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"],
            true
        );
    }
    // Draco: required, accessors without data, the stream's header names its method
    // (byte 8: 0 sequential, 1 edgebreaker); the decoded twins carry no Draco.
    for ((name, reference), method) in DRACO.into_iter().zip([1u8, 0, 1]) {
        let d = json(name);
        assert_eq!(d["extensionsRequired"][0], "KHR_draco_mesh_compression");
        let prim = &d["meshes"][0]["primitives"][0];
        let view = prim["extensions"]["KHR_draco_mesh_compression"]["bufferView"]
            .as_u64()
            .unwrap() as usize;
        let pos = prim["attributes"]["POSITION"].as_u64().unwrap() as usize;
        assert!(d["accessors"][pos].get("bufferView").is_none(), "{name}");
        let b = std::fs::read(data(name)).unwrap();
        let n = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
        let start =
            20 + n + 8 + d["bufferViews"][view]["byteOffset"].as_u64().unwrap_or(0) as usize;
        assert_eq!(&b[start..start + 5], b"DRACO", "{name}");
        assert_eq!(b[start + 8], method, "{name}: encoder method");
        let r = json(reference);
        assert!(r.get("extensionsUsed").is_none(), "{reference}");
    }
    let s = json("sparse.glb");
    assert!(s["accessors"][0].get("bufferView").is_none());
    assert!(s["accessors"][0].get("sparse").is_some());
    let ply = std::fs::read(data("reference-binary-be.ply")).unwrap();
    assert!(ply.starts_with(b"ply\nformat binary_big_endian 1.0\n"));
}
