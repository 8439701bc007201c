// shadowvol-renderer's shadow-map pipeline, appended to render_raster.wgsl (whose Globals,
// LightU, SurfaceIn, SurfaceOut and lambert it uses).
//
// Surface vertices stay in world space on the device; every pass subtracts the eye in the vertex
// shader (the same f32 subtraction the host pipeline does on the host), so the pre-pass, the mask
// pass and the lit pass compute bit-identical clip positions and `depth equal` holds.
//
// Maps are reverse-Z (depth 1 nearest the light, cleared to 0) in Depth32Float, as Bevy's are:
// perspective maps have an infinite far plane, depth = near / distance along the view axis.
// A surface point is lit by the map when its reference depth >= the stored depth.

struct MapU {
    // World-to-clip of each face, camera-relative: 1 face (spot, directional), up to 4
    // (cascaded directional, one per cascade and layer) or 6 (cube, in the layer order +X, -X,
    // +Y, -Y, +Z, -Z).
    view_proj: array<mat4x4<f32>, 6>,
    // The eye in world space (w unused).
    eye: vec4<f32>,
    // (kind: 0 directional, 1 spot, 2 cube, 3 none; filter: 0 hard, 1 PCF 3x3; map size in
    // texels; cascades of a directional map).
    mode: vec4<u32>,
    // (depth bias in world units along the direction to the light; normal bias in world units,
    // already times the texel size (directional) or per unit of distance (spot, cube); the
    // cube's near plane; 0).
    bias: vec4<f32>,
    // Spot: the axis the light shines along; cascaded directional: the camera's forward
    // direction (w unused).
    axis: vec4<f32>,
    // Cascaded directional: each cascade's far end, distance along `axis` from the eye.
    cascade_far: vec4<f32>,
    // Cascaded directional: each cascade's normal offset in world units.
    cascade_offset: vec4<f32>,
};

@group(2) @binding(0) var<uniform> mp: MapU;
@group(3) @binding(0) var map_2d: texture_depth_2d_array;
@group(3) @binding(1) var map_cube: texture_depth_cube;
// The frame's comparison sampler: nearest for hard shadows, linear for PCF (one sampler, as
// OpenGL samples a texture with one only).
@group(3) @binding(2) var map_cmp: sampler_comparison;

@vertex
fn vs_map_surface(v: SurfaceIn) -> SurfaceOut {
    var o: SurfaceOut;
    let rel = vec4<f32>(v.pos.xyz - mp.eye.xyz, 1.0);
    o.clip = g.view_proj * rel;
    o.world = rel.xyz;
    o.normal = v.normal.xyz;
    o.albedo = v.albedo.rgb;
    o.ids = v.ids;
    return o;
}

// The casters into face `instance_index` of the light's map.
@vertex
fn vs_map_depth(v: SurfaceIn, @builtin(instance_index) face: u32) -> @builtin(position) vec4<f32> {
    return mp.view_proj[face] * vec4<f32>(v.pos.xyz - mp.eye.xyz, 1.0);
}

// One comparison of layer `layer` of the 2-D map at `uv` (from the top left, in [0, 1]).
fn tap_2d(uv: vec2<f32>, layer: u32, depth: f32) -> f32 {
    return textureSampleCompareLevel(map_2d, map_cmp, uv, layer, depth);
}

// Layer `layer` of the 2-D map's visibility of a clip position: 1 outside the map.
fn lookup_2d(clip: vec4<f32>, layer: u32) -> f32 {
    if (clip.w <= 0.0) {
        return 1.0;
    }
    let ndc = clip.xyz / clip.w;
    if (any(abs(ndc.xy) > vec2<f32>(1.0))) {
        return 1.0;
    }
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let depth = clamp(ndc.z, 0.0, 1.0);
    if (mp.mode.y == 0u) {
        return tap_2d(uv, layer, depth);
    }
    let texel = 1.0 / f32(mp.mode.z);
    var sum = 0.0;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            sum += tap_2d(uv + vec2<f32>(f32(i), f32(j)) * texel, layer, depth);
        }
    }
    return sum / 9.0;
}

// The cube map's visibility in direction `v` from the light.
fn lookup_cube(v: vec3<f32>) -> f32 {
    let a = abs(v);
    let major = max(a.x, max(a.y, a.z));
    let depth = clamp(mp.bias.z / major, 0.0, 1.0);
    if (mp.mode.y == 0u) {
        return textureSampleCompareLevel(map_cube, map_cmp, v, depth);
    }
    // 3x3 taps in the plane of the major face, one texel (2 major / size) apart.
    var u = vec3<f32>(0.0, 1.0, 0.0);
    var w = vec3<f32>(0.0, 0.0, 1.0);
    if (a.y >= a.x && a.y >= a.z) {
        u = vec3<f32>(1.0, 0.0, 0.0);
    } else if (a.z >= a.x) {
        u = vec3<f32>(1.0, 0.0, 0.0);
        w = vec3<f32>(0.0, 1.0, 0.0);
    }
    let step = 2.0 * major / f32(mp.mode.z);
    var sum = 0.0;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let d = v + (f32(i) * u + f32(j) * w) * step;
            sum += textureSampleCompareLevel(map_cube, map_cmp, d, depth);
        }
    }
    return sum / 9.0;
}

// The light's visibility at a camera-relative surface point with geometric normal `normal`, by
// the map, with Bevy's depth bias (along the direction to the light) and normal bias (along the
// normal, turned towards the light).
fn map_visibility(world: vec3<f32>, normal: vec3<f32>) -> f32 {
    let len = length(normal);
    // Towards the light: its direction, or the vector to its point xyz / w (any w != 0, as the
    // reference reads a homogeneous light).
    var light_point = vec3<f32>(0.0);
    var to_light = lt.pos.xyz;
    if (lt.pos.w != 0.0) {
        light_point = lt.pos.xyz / lt.pos.w;
        to_light = light_point - world;
    }
    var n = vec3<f32>(0.0);
    if (len > 0.0) {
        n = normal / len;
        if (dot(n, to_light) < 0.0) {
            n = -n;
        }
    }
    let l = normalize(to_light);
    if (mp.mode.x == 3u) {
        return 1.0;
    }
    if (mp.mode.x == 0u) {
        // The first cascade whose slice of the view holds the point (the last one beyond).
        var c = 0u;
        let view_depth = dot(world, mp.axis.xyz);
        for (var k = 0u; k + 1u < mp.mode.w; k++) {
            if (view_depth > mp.cascade_far[k]) {
                c = k + 1u;
            }
        }
        let p = world + mp.bias.x * l + mp.cascade_offset[c] * n;
        return lookup_2d(mp.view_proj[c] * vec4<f32>(p, 1.0), c);
    }
    if (mp.mode.x == 1u) {
        let dist = max(dot(-to_light, mp.axis.xyz), 0.0);
        let p = world + mp.bias.x * l + mp.bias.y * dist * n;
        return lookup_2d(mp.view_proj[0] * vec4<f32>(p, 1.0), 0u);
    }
    let a = abs(to_light);
    let dist = max(a.x, max(a.y, a.z));
    let p = world + mp.bias.x * l + mp.bias.y * dist * n;
    return lookup_cube(p - light_point);
}

// The mask pass: the stencil is set (reference 1, replace) where the map shadows the point
// (visibility below one half), so the frame's stencil and the reference metric read maps as
// they read volumes.
@fragment
fn fs_map_mask(i: SurfaceOut) {
    if (map_visibility(i.world, i.normal) >= 0.5) {
        discard;
    }
}

// The lit pass: fs_lit's Lambert term times the map's visibility (fractional under PCF).
@fragment
fn fs_map_lit(i: SurfaceOut) -> @location(0) vec4<f32> {
    return vec4<f32>(lambert(i) * map_visibility(i.world, i.normal), 0.0);
}
