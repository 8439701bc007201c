//! The Draco reader's memory check, in a test binary of its own because it sets
//! `SHADOWVOL_MEMORY_LIMIT` for the process: a stream whose header and accessors agree on a
//! mesh no memory holds (2^30 triangles) is refused before the decoder sizes its tables.

mod common;
use common::glb;

use serde_json::json;
use shadowvol_scenes::load_gltf_slice;
use std::path::PathBuf;

#[test]
fn a_draco_mesh_beyond_the_memory_is_refused_before_decoding() {
    let b =
        std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/draco.glb"))
            .unwrap();
    let n = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
    let stream = &b[20 + n + 8..20 + n + 8 + 1404];
    // Edgebreaker header: traversal byte at 11, then varints 292 (vertices), 557 (faces).
    assert_eq!(&stream[11..16], &[0, 164, 2, 173, 4]);
    let mut s = stream.to_vec();
    // 2^30 faces as a varint.
    s.splice(14..16, [0x80u8, 0x80, 0x80, 0x80, 0x04]);
    let faces: u64 = 1 << 30;
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_draco_mesh_compression"],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0},
            "indices": 1,
            "extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}
        }]}],
        "buffers": [{"byteLength": s.len()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": s.len()}],
        "accessors": [
            {"componentType": 5126, "type": "VEC3", "count": 292},
            {"componentType": 5125, "type": "SCALAR", "count": 3 * faces}
        ],
    });
    // The only test of this binary: no other thread reads the variable.
    std::env::set_var("SHADOWVOL_MEMORY_LIMIT", (1u64 << 30).to_string());
    let e = load_gltf_slice(&glb(&doc, &s), "t.glb", None)
        .unwrap_err()
        .to_string();
    for needle in [
        "primitive 0, KHR_draco_mesh_compression",
        "decoding 1073741824 triangles and 292 points needs about",
        "more than the 1073741824 bytes available (SHADOWVOL_MEMORY_LIMIT",
    ] {
        assert!(e.contains(needle), "{needle:?} not in: {e}");
    }
}
