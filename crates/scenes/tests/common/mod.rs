//! Helpers shared by the glTF tests.

/// Builds a GLB from a JSON document and a binary chunk (always written, even if empty).
pub fn glb(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    shadowvol_scenes::glb_container(&serde_json::to_vec(doc).unwrap(), Some(bin)).unwrap()
}
