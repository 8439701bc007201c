// shadowvol-viewer: the rendered frame copied to the window.

@group(0) @binding(0) var frame: texture_2d<f32>;

@vertex
fn vs_blit(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle that covers the viewport.
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs_blit(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = textureDimensions(frame);
    let xy = min(vec2<u32>(p.xy), size - vec2<u32>(1u));
    return vec4<f32>(textureLoad(frame, xy, 0).rgb, 1.0);
}
