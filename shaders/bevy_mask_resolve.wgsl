// shadowvol-bevy: the mask resolve. A triangle that covers the target; its pipeline's stencil
// test (== 0, lit) decides which pixels get the 1 it writes into one layer of the mask.
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}
