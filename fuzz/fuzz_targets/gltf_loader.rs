//! Arbitrary bytes into the glTF/GLB loader (embedded buffers only): a scene whose meshes
//! validate, or an error; never a panic (the Draco decoder's panics are the loader's to catch).
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::tolerate_guarded_panics();
    if let Ok(scene) = shadowvol_scenes::load_gltf_slice(data, "fuzz.glb", None) {
        for o in &scene.objects {
            o.mesh.validate().expect("a loaded glTF mesh must validate");
        }
        let _ = scene.topology();
    }
});
