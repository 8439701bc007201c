// The stencil of a frame copied into an 8-bit colour target, for devices that cannot copy a
// stencil aspect to a buffer (wgpu's DEPTH_TEXTURE_AND_BUFFER_COPIES; OpenGL). One draw per bit
// of the stencil: a full-screen triangle whose fragments pass the stencil test where the bit is
// set (the pipeline's read mask and reference) and add the bit's value, so the target ends with
// the stencil value itself in every pixel.

// The bit this pipeline copies (0 to 7).
override BIT: u32 = 0u;

// Vertex i of the triangle (-1, -1), (3, -1), (-1, 3), which covers the whole viewport.
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i & 1u) << 2u) - 1.0;
    let y = f32((i & 2u) << 1u) - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

// The bit's value in unorm8: (1 << BIT) / 255 stores as exactly 1 << BIT, and the additive
// blend of distinct bits sums them exactly.
@fragment
fn fs_stencil_bit() -> @location(0) vec4<f32> {
    return vec4<f32>(f32(1u << BIT) / 255.0, 0.0, 0.0, 0.0);
}
