//! Arbitrary bytes into the PLY loader (ASCII, binary little- and big-endian): a mesh that
//! validates and builds an edge table, or an error; never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = shadowvol_scenes::ply::parse_ply(data, "fuzz.ply") {
        mesh.validate().expect("a loaded PLY mesh must validate");
        let _ = shadowvol_mesh_topology::EdgeTable::build(&mesh);
    }
});
