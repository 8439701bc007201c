//! Arbitrary bytes as the KHR_draco_mesh_compression stream of a one-primitive GLB (view-less
//! POSITION and indices accessors whose counts come from the first 4 bytes, the rest as the
//! stream): a mesh that validates, or an error naming the primitive; never a panic that
//! escapes the loader, a hang or an unbounded allocation in the decoder.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

/// A GLB of one node and one Draco primitive over `stream` (buffer view 0).
fn glb(stream: &[u8], points: u32, indices: u32) -> Vec<u8> {
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"extensions":{{"KHR_draco_mesh_compression":{{"bufferView":0,"attributes":{{"POSITION":0}}}}}}}}]}}],"buffers":[{{"byteLength":{n}}}],"bufferViews":[{{"buffer":0,"byteLength":{n}}}],"accessors":[{{"componentType":5126,"type":"VEC3","count":{points}}},{{"componentType":5125,"type":"SCALAR","count":{indices}}}]}}"#,
        n = stream.len()
    );
    shadowvol_scenes::glb_container(doc.as_bytes(), Some(stream)).expect("a small GLB")
}

fuzz_target!(|data: &[u8]| {
    common::tolerate_guarded_panics();
    if data.len() < 4 {
        return;
    }
    let points = u32::from(u16::from_le_bytes([data[0], data[1]])).max(1);
    let indices = 3 * u32::from(u16::from_le_bytes([data[2], data[3]])).max(1);
    let stream = &data[4..];
    if stream.is_empty() {
        return;
    }
    match shadowvol_scenes::load_gltf_slice(&glb(stream, points, indices), "fuzz.glb", None) {
        Ok(scene) => {
            common::check_loaded(&scene, "a loaded Draco scene");
        }
        Err(e) => {
            let m = e.to_string();
            assert!(m.contains("primitive 0"), "the error names the primitive: {m}");
        }
    }
});
