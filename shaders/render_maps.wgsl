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
    // (kind: 0 directional, 1 spot, 2 cube, 3 none; filter: 0 hard, 1 PCF 3x3, 2 PCSS; map size
    // in texels; cascades of a directional map).
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
    // PCSS: (Bevy's light size in world units, 0, 0, 0).
    soft: vec4<f32>,
    // PCSS, per cascade of a directional map: (map width, map height in world units; a, b:
    // Bevy's depth of our depth d is a d + b).
    cascade_soft: array<vec4<f32>, 4>,
};

@group(2) @binding(0) var<uniform> mp: MapU;
@group(3) @binding(0) var map_2d: texture_depth_2d_array;
@group(3) @binding(1) var map_cube: texture_depth_cube;
// The frame's comparison sampler: nearest for hard shadows, linear for PCF and PCSS (one
// sampler, as OpenGL samples a texture with one only).
@group(3) @binding(2) var map_cmp: sampler_comparison;
// PCSS only (its own bind group layout): bilinear depth reads for the blocker search.
@group(3) @binding(3) var map_lin: sampler;

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

// Where a surface point is looked up in its light's map.
struct MapLookup {
    // 0: nowhere (no map, or outside the 2-D map: lit); 1: the 2-D map; 2: the cube map.
    at: u32,
    // 2-D: texture coordinates from the top left, and the layer (cascade).
    uv: vec2<f32>,
    layer: u32,
    // The point's reverse-Z depth in the map.
    depth: f32,
    // Cube: the direction from the light to the (biased) point, and the unbiased point's
    // distance from the light along its major axis.
    dir: vec3<f32>,
    dist: f32,
};

fn nowhere() -> MapLookup {
    var k: MapLookup;
    k.at = 0u;
    return k;
}

// The lookup of a clip position in layer `layer` of the 2-D map: nowhere outside the map.
fn at_2d(clip: vec4<f32>, layer: u32) -> MapLookup {
    if (clip.w <= 0.0) {
        return nowhere();
    }
    let ndc = clip.xyz / clip.w;
    if (any(abs(ndc.xy) > vec2<f32>(1.0))) {
        return nowhere();
    }
    var k: MapLookup;
    k.at = 1u;
    k.uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    k.layer = layer;
    k.depth = clamp(ndc.z, 0.0, 1.0);
    return k;
}

// The hard or PCF visibility of a 2-D lookup.
fn filter_2d(k: MapLookup) -> f32 {
    if (mp.mode.y == 0u) {
        return tap_2d(k.uv, k.layer, k.depth);
    }
    let texel = 1.0 / f32(mp.mode.z);
    var sum = 0.0;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            sum += tap_2d(k.uv + vec2<f32>(f32(i), f32(j)) * texel, k.layer, k.depth);
        }
    }
    return sum / 9.0;
}

// The hard or PCF visibility of a cube lookup.
fn filter_cube(k: MapLookup) -> f32 {
    let v = k.dir;
    if (mp.mode.y == 0u) {
        return textureSampleCompareLevel(map_cube, map_cmp, v, k.depth);
    }
    let a = abs(v);
    let major = max(a.x, max(a.y, a.z));
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
            sum += textureSampleCompareLevel(map_cube, map_cmp, d, k.depth);
        }
    }
    return sum / 9.0;
}

// Where a camera-relative surface point with geometric normal `normal` is looked up, offset as
// Bevy offsets it: by the depth bias along the direction to the light and by the normal bias
// along the normal, turned towards the light.
fn map_lookup(world: vec3<f32>, normal: vec3<f32>) -> MapLookup {
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
        return nowhere();
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
        return at_2d(mp.view_proj[c] * vec4<f32>(p, 1.0), c);
    }
    if (mp.mode.x == 1u) {
        let dist = max(dot(-to_light, mp.axis.xyz), 0.0);
        let p = world + mp.bias.x * l + mp.bias.y * dist * n;
        return at_2d(mp.view_proj[0] * vec4<f32>(p, 1.0), 0u);
    }
    let a = abs(to_light);
    let dist = max(a.x, max(a.y, a.z));
    let p = world + mp.bias.x * l + mp.bias.y * dist * n;
    var k: MapLookup;
    k.at = 2u;
    k.dir = p - light_point;
    let b = abs(k.dir);
    k.depth = clamp(mp.bias.z / max(b.x, max(b.y, b.z)), 0.0, 1.0);
    k.dist = dist;
    return k;
}

// The light's visibility at a camera-relative surface point, hard or PCF.
fn map_visibility(world: vec3<f32>, normal: vec3<f32>) -> f32 {
    let k = map_lookup(world, normal);
    if (k.at == 1u) {
        return filter_2d(k);
    }
    if (k.at == 2u) {
        return filter_cube(k);
    }
    return 1.0;
}

// Percentage-closer soft shadows as Bevy 0.20 ships them (experimental_pbr_pcss): a blocker
// search sized by the light, a penumbra estimate from the mean blocker depth, and a filter sized
// by it. Constants and what they mean: crates/renderer/src/maps/pcss.rs (a unit test keeps
// these lines equal to it). Used only for lights whose size is above 0 (the host reads the
// others with PCF, as Bevy reads lights without a soft shadow size with its normal filter).
const PCSS_MIN_BLUR: f32 = 0.5;
const PCSS_SPOT_TEXEL: f32 = 0.013427734;
const PCSS_POINT_SCALE: f32 = 0.003;
const PCSS_POINT_OFFSET_SCALE: f32 = 0.5;
const PCSS_FILTER_TEXELS: vec2<f32> = vec2<f32>(0.00390625, 0.022949219);
const PCSS_FILTER_SCALES: vec2<f32> = vec2<f32>(0.015, 0.035);
// The blocker search's points, in eighths: Direct3D's standard 8x multisample positions.
const PCSS_SEARCH: array<vec2<f32>, 8> = array<vec2<f32>, 8>(vec2<f32>(1.0, -3.0), vec2<f32>(-1.0, 3.0), vec2<f32>(5.0, 1.0), vec2<f32>(-3.0, -5.0), vec2<f32>(-5.0, 5.0), vec2<f32>(-7.0, -1.0), vec2<f32>(3.0, 7.0), vec2<f32>(7.0, -7.0));

// Search point `i`, in units of the search size.
fn pcss_search(i: u32) -> vec2<f32> {
    var points = PCSS_SEARCH;
    return points[i] / 8.0;
}

// Bevy's scale of the 2-D filter for a map of `texel` world units a texel.
fn pcss_filter_scale(texel: f32) -> f32 {
    let t = PCSS_FILTER_TEXELS;
    let f = PCSS_FILTER_SCALES;
    return f.x + (texel - t.x) * (f.y - f.x) / (t.y - t.x);
}

// The filter's turn at the pixel whose centre is `frag`: interleaved gradient noise (Jimenez
// 2014) at frame 1, as Bevy's non-temporal filter, so that every image is reproducible.
fn pcss_turn(frag: vec2<f32>) -> f32 {
    let p = frag + vec2<f32>(5.588238);
    return 6.2831855 * fract(52.982918 * fract(0.06711056 * p.x + 0.00583715 * p.y));
}

// Tap `i` of the filter's spiral turned by `turn`: radius (8 - i) / 8, each tap 135 degrees on
// from the one before (Jimenez 2014, as Bevy's).
fn pcss_spiral(i: u32, turn: f32) -> vec2<f32> {
    let t = turn + f32(i + 1u) * 2.3561945;
    return vec2<f32>(cos(t), sin(t)) * (f32(8u - i) / 8.0);
}

// The mean depth of the searched blockers (Bevy's depth `to_bevy.x d + to_bevy.y`, at most 1,
// as Bevy's map clamps casters above its range), 0 where none is nearer the light than `k`.
fn pcss_blockers_2d(k: MapLookup, step: vec2<f32>, to_bevy: vec2<f32>) -> f32 {
    var sum = 0.0;
    var n = 0.0;
    for (var i = 0u; i < 8u; i++) {
        let uv = k.uv + pcss_search(i) * step;
        let z = textureSampleLevel(map_2d, map_lin, uv, k.layer, 0);
        if (z >= k.depth) {
            sum += min(to_bevy.x * z + to_bevy.y, 1.0);
            n += 1.0;
        }
    }
    if (n == 0.0) {
        return 0.0;
    }
    return sum / n;
}

// PCSS on the 2-D map: directional maps in world units across the map, spot maps with Bevy's
// fixed spot texel size.
fn pcss_2d(k: MapLookup, frag: vec2<f32>) -> f32 {
    let size = mp.soft.x;
    var per_world: vec2<f32>;
    var texel = PCSS_SPOT_TEXEL;
    var to_bevy = vec2<f32>(1.0, 0.0);
    if (mp.mode.x == 0u) {
        let c = mp.cascade_soft[k.layer];
        per_world = 1.0 / c.xy;
        texel = max(c.x, c.y) / f32(mp.mode.z);
        to_bevy = c.zw;
    } else {
        per_world = vec2<f32>(1.0 / (PCSS_SPOT_TEXEL * f32(mp.mode.z)));
    }
    let receiver = to_bevy.x * k.depth + to_bevy.y;
    let blocker = pcss_blockers_2d(k, size * per_world, to_bevy);
    let blur = max((blocker - receiver) * size / receiver, PCSS_MIN_BLUR);
    let step = pcss_filter_scale(texel) * blur * per_world;
    let turn = pcss_turn(frag);
    var sum = 0.0;
    for (var i = 0u; i < 8u; i++) {
        sum += tap_2d(k.uv + pcss_spiral(i, turn) * step, k.layer, k.depth);
    }
    return sum / 8.0;
}

// Two unit vectors perpendicular to the unit vector `n` and to each other (Duff et al. 2017).
fn pcss_basis(n: vec3<f32>) -> mat2x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return mat2x3<f32>(
        vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        vec3<f32>(b, s + n.y * n.y * a, -n.y),
    );
}

// PCSS on the cube map: the search and the filter move the lookup direction across itself, by
// Bevy's size (search) and by its point-light filter scale (filter), times the distance.
fn pcss_cube(k: MapLookup, frag: vec2<f32>) -> f32 {
    let size = mp.soft.x;
    let basis = pcss_basis(normalize(k.dir));
    let search = basis * (size * k.dist);
    var sum = 0.0;
    var n = 0.0;
    for (var i = 0u; i < 8u; i++) {
        let z = textureSampleLevel(map_cube, map_lin, k.dir + search * pcss_search(i), 0);
        if (z >= k.depth) {
            sum += z;
            n += 1.0;
        }
    }
    var blocker = 0.0;
    if (n > 0.0) {
        blocker = sum / n;
    }
    let blur = max((blocker - k.depth) * size / k.depth, PCSS_MIN_BLUR);
    let spread = basis * (PCSS_POINT_SCALE * blur * k.dist * PCSS_POINT_OFFSET_SCALE);
    let turn = pcss_turn(frag);
    var vis = 0.0;
    for (var i = 0u; i < 8u; i++) {
        let d = k.dir + spread * pcss_spiral(i, turn);
        vis += textureSampleCompareLevel(map_cube, map_cmp, d, k.depth);
    }
    return vis / 8.0;
}

// The light's visibility at a camera-relative surface point under PCSS, at the pixel `frag`.
fn map_visibility_pcss(world: vec3<f32>, normal: vec3<f32>, frag: vec2<f32>) -> f32 {
    let k = map_lookup(world, normal);
    if (k.at == 1u) {
        return pcss_2d(k, frag);
    }
    if (k.at == 2u) {
        return pcss_cube(k, frag);
    }
    return 1.0;
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

// The visibility pass (a frame read back): the map's visibility of the surface point, for the
// reference's soft metric (`FrameImage::visibility`).
@fragment
fn fs_map_visibility(i: SurfaceOut) -> @location(0) vec4<f32> {
    return vec4<f32>(map_visibility(i.world, i.normal), 0.0, 0.0, 0.0);
}

// The visibility pass under PCSS.
@fragment
fn fs_map_visibility_pcss(i: SurfaceOut) -> @location(0) vec4<f32> {
    return vec4<f32>(map_visibility_pcss(i.world, i.normal, i.clip.xy), 0.0, 0.0, 0.0);
}

// The mask pass under PCSS.
@fragment
fn fs_map_mask_pcss(i: SurfaceOut) {
    if (map_visibility_pcss(i.world, i.normal, i.clip.xy) >= 0.5) {
        discard;
    }
}

// The lit pass under PCSS.
@fragment
fn fs_map_lit_pcss(i: SurfaceOut) -> @location(0) vec4<f32> {
    return vec4<f32>(lambert(i) * map_visibility_pcss(i.world, i.normal, i.clip.xy), 0.0);
}
