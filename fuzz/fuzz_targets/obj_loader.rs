//! Arbitrary bytes into the OBJ parser: it must return a mesh that validates, or an error; never
//! panic or hang.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(mesh) = shadowvol_scenes::obj::parse_obj(&text, "fuzz.obj") {
        mesh.validate().expect("a parsed OBJ mesh must validate");
        let _ = shadowvol_mesh_topology::EdgeTable::build(&mesh).expect("valid mesh builds");
    }
});
