//! Helpers shared by the glTF tests.

/// Builds a GLB from a JSON document and a binary chunk.
pub fn glb(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut js = serde_json::to_vec(doc).unwrap();
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut out = Vec::new();
    for w in [
        0x4654_6C67u32,
        2,
        (28 + js.len() + bin.len()) as u32,
        js.len() as u32,
        0x4E4F_534A,
    ] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&js);
    for w in [bin.len() as u32, 0x004E_4942] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&bin);
    out
}
