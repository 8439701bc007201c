//! The Draco reader's memory check, in a test binary of its own because it sets
//! `SHADOWVOL_MEMORY_LIMIT` for the process: a stream whose header and accessors agree on a
//! mesh no memory holds (2^30 triangles) is refused before the decoder sizes its tables.

mod common;
use common::glb;
#[path = "common/draco.rs"]
mod draco_common;
use draco_common::{doc, stream_of};

use shadowvol_scenes::load_gltf_slice;

#[test]
fn a_draco_mesh_beyond_the_memory_is_refused_before_decoding() {
    let (stream, points, _) = stream_of("draco.glb");
    assert_eq!(points, 292);
    // Edgebreaker header: traversal byte at 11, then varints 292 (vertices), 557 (faces).
    assert_eq!(&stream[11..16], &[0, 164, 2, 173, 4]);
    let mut s = stream;
    // 2^30 faces as a varint.
    s.splice(14..16, [0x80u8, 0x80, 0x80, 0x80, 0x04]);
    let doc = doc(&s, points, 1 << 30);
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
