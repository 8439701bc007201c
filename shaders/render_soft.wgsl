// shadowvol-renderer's lights with a size: each sample's stencil counted into a visibility
// target, then the light's unshadowed lit pass scaled by the visible share.
//
// Passes of one light of N samples: per sample, its stencil pass, then `fs_count` adds 1 where
// the stencil is 0 (the pipeline's stencil test), so the target ends with the integer k of
// samples the pixel sees (exact in R16Float up to 2048); after the last sample, the light's own
// lit pass draws into the light target with the stencil cleared (no shadow), and
// `fs_composite` adds light × k / N into the colour, N given as the draw's instance (so no
// buffer is needed; the division is in the shader because a unorm target clamps the
// fragment's output before blending).

// Vertex i of the triangle (-1, -1), (3, -1), (-1, 3), which covers the whole viewport.
fn corner(i: u32) -> vec4<f32> {
    let x = f32((i & 1u) << 2u) - 1.0;
    let y = f32((i & 2u) << 1u) - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    return corner(i);
}

// One sample that sees the pixel.
@fragment
fn fs_count() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.0, 0.0, 0.0);
}

@group(0) @binding(0) var visibility: texture_2d<f32>;
@group(0) @binding(1) var unshadowed: texture_2d<f32>;

struct CompositeOut {
    @builtin(position) clip: vec4<f32>,
    // The light's samples N.
    @location(0) @interpolate(flat) samples: u32,
};

// The full-screen triangle, carrying N from the instance index.
@vertex
fn vs_composite(
    @builtin(vertex_index) i: u32,
    @builtin(instance_index) samples: u32,
) -> CompositeOut {
    var o: CompositeOut;
    o.clip = corner(i);
    o.samples = samples;
    return o;
}

// The light's unshadowed contribution times the share k / N of the samples that see the pixel.
@fragment
fn fs_composite(i: CompositeOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(i.clip.xy);
    let k = textureLoad(visibility, p, 0).r;
    let light = textureLoad(unshadowed, p, 0);
    return vec4<f32>(light.rgb * (k / f32(max(i.samples, 1u))), 0.0);
}
