//! Arbitrary bytes into the EXT_meshopt_compression view decoder (mode, filter, stride and
//! count from the first bytes, the rest as the compressed stream): exactly `count * stride`
//! bytes or an error, never a panic or an abort in meshoptimizer; and a vertex stream encoded
//! by meshoptimizer decodes back to itself.
#![no_main]
use libfuzzer_sys::fuzz_target;
use shadowvol_scenes::meshopt_view::{decode, Filter, Mode};

fuzz_target!(|data: &[u8]| {
    if data.len() < 4 {
        return;
    }
    let mode = [Mode::Attributes, Mode::Triangles, Mode::Indices][usize::from(data[0] % 3)];
    let filter = [
        Filter::None,
        Filter::Octahedral,
        Filter::Quaternion,
        Filter::Exponential,
        Filter::Color,
    ][usize::from(data[1] % 5)];
    // Strides 1..=260 include invalid ones on purpose; counts up to 4095.
    let stride = usize::from(data[2]) + 1 + usize::from(data[3] & 3);
    let count = usize::from(u16::from_le_bytes([data[3], data.get(4).copied().unwrap_or(0)]) >> 4);
    let encoded = &data[data.len().min(5)..];
    if let Ok(bytes) = decode(encoded, count, stride, mode, filter) {
        assert_eq!(bytes.len(), count * stride);
    }
    // Round trip: the input as a vertex stream of 12-byte vertices.
    let verts: Vec<[u8; 12]> = encoded
        .chunks_exact(12)
        .map(|c| c.try_into().expect("12 bytes"))
        .collect();
    if !verts.is_empty() {
        let enc = meshopt::encode_vertex_buffer(&verts).expect("encodes");
        let dec = decode(&enc, verts.len(), 12, Mode::Attributes, Filter::None).expect("decodes");
        assert_eq!(dec, verts.concat());
    }
});
