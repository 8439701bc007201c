// shadowvol-renderer: depth pre-pass with ambient, stencil shadow volumes, additive Lambert.
//
// Every pass computes the clip position with the same expression `g.view_proj * pos` from a
// vec4 vertex attribute and marks it @invariant, so a z-fail front cap drawn from the same
// vertices lands on exactly the depth the pre-pass wrote.

struct Globals {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    ambient: vec4<f32>,
};

struct LightU {
    // (x, y, z, w): w = 1 point light, w = 0 directional (towards the light).
    pos: vec4<f32>,
    color: vec4<f32>,
    // (inverse square 0/1, 1 / range or 0, cone scale, cone offset): glTF's attenuation.
    emit: vec4<f32>,
    // (axis the spot shines along, 1 for a spot light).
    spot: vec4<f32>,
    // GPU-resident pass only (resident_draw.wgsl): (record region start, region size, first sign of
    // this light, 1 when it has a back cap). Zero in the host pipeline.
    draw: vec4<u32>,
    // GPU-resident pass only: (first light point of this light, 1 + the first shared sign of its
    // sharing group or 0, 0, 0), see `r_light_points` and `cap_sign`. Zero in the host pipeline.
    points: vec4<u32>,
};

@group(0) @binding(0) var<uniform> g: Globals;
@group(1) @binding(0) var<uniform> lt: LightU;

struct SurfaceIn {
    @location(0) pos: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    @location(3) ids: vec2<u32>,
};

struct SurfaceOut {
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) normal: vec3<f32>,
    @location(2) @interpolate(flat) albedo: vec3<f32>,
    @location(3) @interpolate(flat) ids: vec2<u32>,
};

@vertex
fn vs_surface(v: SurfaceIn) -> SurfaceOut {
    var o: SurfaceOut;
    o.clip = g.view_proj * v.pos;
    o.world = v.pos.xyz;
    o.normal = v.normal.xyz;
    o.albedo = v.albedo.rgb;
    o.ids = v.ids;
    return o;
}

struct VolumeOut {
    @invariant @builtin(position) clip: vec4<f32>,
};

// Shadow-volume vertices: w = 1 on the caster, w = 0 extruded to infinity.
@vertex
fn vs_volume(@location(0) pos: vec4<f32>) -> VolumeOut {
    var o: VolumeOut;
    o.clip = g.view_proj * pos;
    return o;
}

struct PrepassOut {
    @location(0) color: vec4<f32>,
    @location(1) ids: vec2<u32>,
};

@fragment
fn fs_prepass(i: SurfaceOut) -> PrepassOut {
    var o: PrepassOut;
    o.color = vec4<f32>(i.albedo * g.ambient.x, 1.0);
    o.ids = i.ids;
    return o;
}

// glTF KHR_lights_punctual: saturate(1 - (d / range)^4) / d^2, times the cone's
// saturate(cos * scale + offset)^2; 1 for unit and directional lights. The same formulas as
// shadowvol_scenes::Emission in f64.
fn attenuation(world: vec3<f32>) -> f32 {
    if (lt.emit.x == 0.0 || lt.pos.w == 0.0) {
        return 1.0;
    }
    let v = world - lt.pos.xyz / lt.pos.w;
    let d2 = max(dot(v, v), 1e-30);
    var a = 1.0 / d2;
    if (lt.emit.y > 0.0) {
        let q = d2 * lt.emit.y * lt.emit.y;
        a = a * clamp(1.0 - q * q, 0.0, 1.0);
    }
    if (lt.spot.w > 0.0) {
        let c = dot(v * inverseSqrt(d2), lt.spot.xyz);
        let s = clamp(c * lt.emit.z + lt.emit.w, 0.0, 1.0);
        a = a * s * s;
    }
    return a;
}

// The light's Lambert term at a surface fragment, the normal turned towards the eye.
fn lambert(i: SurfaceOut) -> vec3<f32> {
    let len = length(i.normal);
    if (len <= 0.0) {
        return vec3<f32>(0.0);
    }
    var n = i.normal / len;
    if (dot(n, g.eye.xyz - i.world) < 0.0) {
        n = -n;
    }
    let l = normalize(lt.pos.xyz - lt.pos.w * i.world);
    let k = max(dot(n, l), 0.0) * attenuation(i.world);
    return i.albedo * lt.color.rgb * k;
}

@fragment
fn fs_lit(i: SurfaceOut) -> @location(0) vec4<f32> {
    return vec4<f32>(lambert(i), 0.0);
}

// The pre-pass for a colour target alone (embedders without an ids target).
@fragment
fn fs_prepass_color(i: SurfaceOut) -> @location(0) vec4<f32> {
    return vec4<f32>(i.albedo * g.ambient.x, 1.0);
}
