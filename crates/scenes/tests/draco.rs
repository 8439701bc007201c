//! `KHR_draco_mesh_compression` beyond the real corpus: the Draco stream of
//! `tests/data/real/draco.glb` (glTF Transform's encoder) placed in documents built here, to check
//! that the stream replaces the accessors' data, and that every malformed case (a stream cut
//! short or corrupted, a wrong attribute id, counts that disagree, a missing view) is an error
//! naming the primitive, never a panic.

mod common;
use common::glb;
#[path = "common/draco.rs"]
mod draco_common;
use draco_common::{doc, real, stream_of};

use serde_json::json;

use shadowvol_scenes::{load_gltf_slice, Scene};

/// The Draco stream of `draco.glb`, its decoded point count and its triangle count.
fn stream() -> (Vec<u8>, u64, u64) {
    stream_of("draco.glb")
}

fn load(
    d: &serde_json::Value,
    bin: &[u8],
) -> Result<std::sync::Arc<shadowvol_mesh_topology::EdgeTable>, String> {
    load_gltf_slice(&glb(d, bin), "t.glb", None)
        .and_then(|s| s.baked_table())
        .map_err(|e| e.to_string())
}

fn expect_err(d: &serde_json::Value, bin: &[u8], needles: &[&str]) {
    let m = load(d, bin).expect_err("must be refused");
    for n in needles {
        assert!(m.contains(n), "{n:?} not in: {m}");
    }
}

#[test]
fn the_stream_replaces_the_accessors_data_under_the_node_transform() {
    let (s, points, tris) = stream();
    let file = Scene::load(real("draco.glb"))
        .unwrap()
        .baked_table()
        .unwrap();
    let m = load(&doc(&s, points, tris), &s).unwrap();
    assert_eq!(m.triangles, file.triangles);
    assert_eq!(m.positions.len(), file.positions.len());
    let t = glam::Vec3::new(1.0, 2.0, 3.0);
    for (a, b) in m.positions.iter().zip(&file.positions) {
        assert_eq!(*a, *b + t);
    }
    // Used but not required, with fallback data in the accessors (zeros): the stream wins.
    let mut d = doc(&s, points, tris);
    d["extensionsRequired"] = json!([]);
    let fallback = (12 * points + 4 * 3 * tris) as usize;
    let mut bin = s.clone();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let off = bin.len();
    bin.resize(off + fallback, 0);
    d["buffers"][0]["byteLength"] = json!(bin.len());
    d["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteOffset": off, "byteLength": fallback}));
    d["accessors"][0]["bufferView"] = json!(1);
    d["accessors"][1]["bufferView"] = json!(1);
    d["accessors"][1]["byteOffset"] = json!(12 * points);
    assert_eq!(load(&d, &bin).unwrap().triangles, file.triangles);
}

#[test]
fn malformed_draco_primitives_are_errors_naming_the_primitive() {
    let (s, points, tris) = stream();
    let at = "node 0, mesh 0, primitive 0, KHR_draco_mesh_compression";
    // Not a Draco stream.
    let junk = vec![0xA5u8; s.len()];
    expect_err(&doc(&junk, points, tris), &junk, &[at, "cannot be decoded"]);
    // The attribute id is not in the stream.
    let mut d = doc(&s, points, tris);
    d["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["attributes"]
        ["POSITION"] = json!(7);
    expect_err(&d, &s, &[at, "Draco attribute 7", "holds attributes [0"]);
    // Counts that disagree with the stream.
    expect_err(&doc(&s, points + 1, tris), &s, &[at, "declares count"]);
    expect_err(&doc(&s, points, tris - 1), &s, &[at, "3 per triangle"]);
    // Header counts that disagree with the accessors are refused before the decoder sizes its
    // tables from them: edgebreaker's encoded vertices made about 2^61 (the varint after the
    // traversal byte at offset 11), and a sequential stream's point count against a POSITION
    // accessor one larger.
    assert_eq!(
        &s[11..14],
        &[0, 164, 2],
        "traversal 0, then 292 encoded vertices"
    );
    let mut huge = s.clone();
    huge.splice(12..14, [255u8, 255, 255, 255, 255, 255, 255, 255, 164, 2]);
    expect_err(
        &doc(&huge, points, tris),
        &huge,
        &[
            at,
            "declares 2666130979403333631 encoded vertices",
            "count 292",
        ],
    );
    let (q, qpoints, qtris) = stream_of("draco-sequential.glb");
    expect_err(
        &doc(&q, qpoints + 1, qtris),
        &q,
        &[
            at,
            &format!("declares {qpoints} points"),
            "the stream is corrupted",
        ],
    );
    expect_err(
        &doc(&s, points, tris + 1),
        &s,
        &[at, "declares 557 triangles"],
    );
    // The view is missing, or absent from the extension.
    let mut d = doc(&s, points, tris);
    d["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["bufferView"] =
        json!(3);
    expect_err(&d, &s, &[at, "bufferView 3 does not exist"]);
    let mut d = doc(&s, points, tris);
    d["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"] =
        json!({"attributes": {"POSITION": 0}});
    expect_err(&d, &s, &[at, "\"bufferView\" is missing"]);
}

#[test]
fn a_cut_or_corrupted_stream_never_panics() {
    let (s, points, tris) = stream();
    // Every prefix: a decode error, or (for none of them but the whole) a mesh.
    for len in 0..s.len() {
        let cut = &s[..len];
        let r = std::panic::catch_unwind(|| load(&doc(cut, points, tris), cut));
        let r = r.unwrap_or_else(|_| panic!("a stream cut to {len} bytes panicked"));
        assert!(
            r.is_err(),
            "a stream cut to {len} of {} bytes loaded",
            s.len()
        );
    }
    // Each byte changed in turn (three ways): an error or a mesh, never a panic.
    for i in 0..s.len() {
        for x in [0x01u8, 0x80, 0xFF] {
            let mut c = s.clone();
            c[i] ^= x;
            let r = std::panic::catch_unwind(|| load(&doc(&c, points, tris), &c));
            assert!(r.is_ok(), "byte {i} ^ {x:#04x} panicked");
        }
    }
}
