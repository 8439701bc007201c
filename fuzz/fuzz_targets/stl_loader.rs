//! Arbitrary bytes into the STL loader (ASCII or binary): a mesh that validates and builds an
//! edge table, or an error; never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = shadowvol_scenes::stl::parse_stl(data, "fuzz.stl") {
        mesh.validate().expect("a loaded STL mesh must validate");
        assert_eq!(mesh.positions.len(), 3 * mesh.triangles.len());
        let _ = shadowvol_mesh_topology::EdgeTable::build(&mesh);
    }
});
