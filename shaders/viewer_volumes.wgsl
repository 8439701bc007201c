// shadowvol-viewer: the shadow volumes drawn over the frame.

struct Volumes {
    view_proj: mat4x4<f32>,
    color: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Volumes;

// Volume vertices relative to the eye; w = 0 is extruded to infinity, as in the renderer.
@vertex
fn vs_volume(@location(0) pos: vec4<f32>) -> @builtin(position) vec4<f32> {
    return u.view_proj * pos;
}

@fragment
fn fs_volume() -> @location(0) vec4<f32> {
    return u.color;
}
