//! Helpers shared by the Draco tests: a corpus file's Draco stream, and a document around one.

use serde_json::json;
use std::path::PathBuf;

/// The path of the real-corpus file `name`.
pub fn real(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(name)
}

/// The Draco stream of the corpus file `name`, its point count and its triangle count.
pub fn stream_of(name: &str) -> (Vec<u8>, u64, u64) {
    let b = std::fs::read(real(name)).unwrap();
    let n = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&b[20..20 + n]).unwrap();
    let prim = &doc["meshes"][0]["primitives"][0];
    let view = &doc["bufferViews"][prim["extensions"]["KHR_draco_mesh_compression"]["bufferView"]
        .as_u64()
        .unwrap() as usize];
    let start = 20 + n + 8 + view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let len = view["byteLength"].as_u64().unwrap() as usize;
    let pos = prim["attributes"]["POSITION"].as_u64().unwrap() as usize;
    let idx = prim["indices"].as_u64().unwrap() as usize;
    (
        b[start..start + len].to_vec(),
        doc["accessors"][pos]["count"].as_u64().unwrap(),
        doc["accessors"][idx]["count"].as_u64().unwrap() / 3,
    )
}

/// A document whose one primitive is the Draco stream `s` (buffer view 0), with view-less
/// POSITION and indices accessors of `points` and `3 * triangles` elements, on a node
/// translated by (1, 2, 3).
pub fn doc(s: &[u8], points: u64, triangles: u64) -> serde_json::Value {
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_draco_mesh_compression"],
        "nodes": [{"mesh": 0, "translation": [1.0, 2.0, 3.0]}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0},
            "indices": 1,
            "extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}
        }]}],
        "buffers": [{"byteLength": s.len()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": s.len()}],
        "accessors": [
            {"componentType": 5126, "type": "VEC3", "count": points},
            {"componentType": 5125, "type": "SCALAR", "count": 3 * triangles}
        ],
    })
}
