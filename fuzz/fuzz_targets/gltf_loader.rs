//! Arbitrary bytes into the glTF/GLB loader (embedded buffers only): a scene whose meshes
//! build edge tables, or an error; never a panic (the Draco decoder's panics are the loader's to catch).
#![no_main]
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::tolerate_guarded_panics();
    if let Ok(scene) = shadowvol_scenes::load_gltf_slice(data, "fuzz.glb", None) {
        common::check_loaded(&scene, "a loaded glTF scene");
    }
});
