// GPU-resident shadow volumes: the draws of the shadow-volume pass, by vertex pulling.
//
// Appended to the renderer's render_raster.wgsl (its Globals, LightU, fragment shaders and attenuation),
// so the host and GPU pipelines light pixels with the same code. Every vertex shader here builds
// positions with `rel` and clips them with `g.view_proj * pos` (@invariant), so a front cap lands
// on exactly the depth the pre-pass wrote from the same triangle.
//
// Sides: one instance per side record (resident_edges), 6 vertices: the quad (p, q, q_inf) +
// (p, q_inf, p_inf), with (p, q) = (b, a) for m > 0 and (a, b) for m < 0 (outward, as
// `volume::build_sides`); x_inf is the direction away from the light (`extrude`). For a directional light p_inf == q_inf,
// so the second triangle is degenerate and draws nothing, and the side is one triangle.
// Caps: per triangle of a z-fail object, read its sign; the front cap is the triangle itself in
// canonical order (sigma = +1 with counter-clockwise front faces, sigma = -1 in the clockwise
// pipeline), the back cap its extrusion with reversed order for sigma = +1. A vertex a draw does
// not need goes to one fixed point, so its triangle is degenerate and rasterizes nothing.

const R_NEGATIVE: u32 = 0x80000000u;
const R_TOUCH: i32 = 2;

// The scene's tables packed as the extraction binds them (`tables` of shaders/silhouette.wgsl,
// shadowvol-gpu's `TablePacking`), each at the word offset `r_at` gives: here object-space
// positions (f32 bits, xyz per global vertex id), edge ends, canonical triangles and the object
// of each vertex, read through `r_position`, `r_edge`, `r_triangle` and `r_vertex_object`.
@group(0) @binding(1) var<storage, read> r_tables: array<u32>;
// shadowvol-gpu's `TableOffsets`, field for field (`TableOffsets` of shaders/silhouette.wgsl).
struct RTables {
    objects: u32,
    positions: u32,
    edges: u32,
    ov_offsets: u32,
    ov_refs: u32,
    tris: u32,
    ov_vertices: u32,
    vertex_objects: u32,
}
@group(0) @binding(9) var<uniform> r_at: RTables;
// Camera-relative world positions per global vertex id, written by `resident_vertices`.
@group(0) @binding(7) var<storage, read> r_world: array<vec4<f32>>;
@group(2) @binding(0) var<storage, read_write> r_world_out: array<vec4<f32>>;
// [light * tri_count + triangle] signs from resident_triangles.
@group(0) @binding(4) var<storage, read> r_signs: array<i32>;
// [light * capacity + slot] side records from resident_edges.
@group(0) @binding(5) var<storage, read> r_records: array<u32>;
// Per (light, object), [2 * (lt.points.x + object)]: the object-space light as the point
// P = L.xyz / w split into f32 hi and lo, (hi, w) then (lo, 0), or for a directional light
// (L.xyz, 0) then 0 (`scene::light_points`, in f64 on the host).
@group(0) @binding(12) var<storage, read> r_light_points: array<vec4<f32>>;
// Per object, 5 words of 4: rows 0-2 of the camera-relative world-from-object transform (f32
// bits), the albedo (f32 bits), (first global triangle, surface + 1, first triangle within the
// surface, first global edge).
@group(0) @binding(6) var<storage, read> r_objects: array<vec4<u32>>;

// Fields of an object's fifth word.
const R_FIRST_TRIANGLE: u32 = 0u;
const R_FIRST_EDGE: u32 = 3u;

// The object of global triangle (R_FIRST_TRIANGLE) or edge (R_FIRST_EDGE) `id`: the last object
// whose first one is at most `id` (binary search, as the extraction's `object_of`).
fn r_object_of(field: u32, id: u32) -> u32 {
    var lo = 0u;
    var hi = arrayLength(&r_objects) / 5u;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if r_objects[mid * 5u + 4u][field] <= id {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// The canonical vertex ids of global triangle `t`.
fn r_triangle(t: u32) -> vec3<u32> {
    let k = r_at.tris + 3u * t;
    return vec3<u32>(r_tables[k], r_tables[k + 1u], r_tables[k + 2u]);
}

// The ends (a, b) of global edge `e`.
fn r_edge(e: u32) -> vec2<u32> {
    let k = r_at.edges + 2u * e;
    return vec2<u32>(r_tables[k], r_tables[k + 1u]);
}

// The object of global vertex `v`.
fn r_vertex_object(v: u32) -> u32 {
    return r_tables[r_at.vertex_objects + v];
}

// The object-space position of global vertex `id`.
fn r_position(id: u32) -> vec3<f32> {
    let k = r_at.positions + 3u * id;
    return vec3<f32>(bitcast<f32>(r_tables[k]), bitcast<f32>(r_tables[k + 1u]), bitcast<f32>(r_tables[k + 2u]));
}

// The camera-relative world position of global vertex `id` of object `obj`, once per vertex and
// frame: every draw then reads the same stored value, so shared vertices are bit-identical.
fn transform(obj: u32, id: u32) -> vec3<f32> {
    let p = r_position(id);
    let r0 = bitcast<vec4<f32>>(r_objects[obj * 5u]);
    let r1 = bitcast<vec4<f32>>(r_objects[obj * 5u + 1u]);
    let r2 = bitcast<vec4<f32>>(r_objects[obj * 5u + 2u]);
    return vec3<f32>(
        ((r0.x * p.x + r0.y * p.y) + r0.z * p.z) + r0.w,
        ((r1.x * p.x + r1.y * p.y) + r1.z * p.z) + r1.w,
        ((r2.x * p.x + r2.y * p.y) + r2.z * p.z) + r2.w,
    );
}

@compute @workgroup_size(256)
fn resident_vertices(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let v = gid.x + gid.y * nwg.x * 256u;
    if v >= arrayLength(&r_world_out) {
        return;
    }
    r_world_out[v] = vec4<f32>(transform(r_vertex_object(v), v), 1.0);
}

// The host pipeline's SurfaceVertex (gpu.rs), 3 per triangle, for `vs_surface`.
struct SurfaceV {
    pos: vec4<f32>,
    normal: vec4<f32>,
    albedo: vec4<f32>,
    ids: vec2<u32>,
    pad: vec2<u32>,
};

// One chunk of the surface vertices (a binding holds at most max_storage_buffer_binding_size):
// triangles [first, first + count).
struct SurfaceChunk {
    first: u32,
    count: u32,
    pad: vec2<u32>,
};

@group(2) @binding(1) var<storage, read_write> r_surface_out: array<SurfaceV>;
@group(2) @binding(2) var<uniform> r_chunk: SurfaceChunk;

// Per triangle, its 3 surface vertices in canonical order, with the flat normal, albedo and ids
// (after `resident_vertices`, from the same stored positions every draw reads).
@compute @workgroup_size(256)
fn resident_surfaces(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = gid.x + gid.y * nwg.x * 256u;
    if k >= r_chunk.count || 3u * k + 2u >= arrayLength(&r_surface_out) {
        return;
    }
    let t = r_chunk.first + k;
    let tr = r_triangle(t);
    let obj = r_object_of(R_FIRST_TRIANGLE, t);
    let p0 = rel(tr.x);
    let p1 = rel(tr.y);
    let p2 = rel(tr.z);
    let n = vec4<f32>(cross(p1 - p0, p2 - p0), 0.0);
    let albedo = bitcast<vec4<f32>>(r_objects[obj * 5u + 3u]);
    let ids = surface_ids(obj, t);
    r_surface_out[3u * k] = SurfaceV(vec4<f32>(p0, 1.0), n, albedo, ids, vec2<u32>(0u));
    r_surface_out[3u * k + 1u] = SurfaceV(vec4<f32>(p1, 1.0), n, albedo, ids, vec2<u32>(0u));
    r_surface_out[3u * k + 2u] = SurfaceV(vec4<f32>(p2, 1.0), n, albedo, ids, vec2<u32>(0u));
}

// The pixel ids `[surface + 1, triangle]` of global triangle `t` of `object`: the object's
// record holds its first global triangle (x), its surface + 1 (y) and the index of its first
// triangle within that surface (z; not 0 where a surface is drawn in parts).
fn surface_ids(object: u32, t: u32) -> vec2<u32> {
    let r = r_objects[object * 5u + 4u];
    return vec2<u32>(r.y, t - r.x + r.z);
}

fn rel(id: u32) -> vec3<f32> {
    return r_world[id].xyz;
}

// The point at infinity of global vertex `id` of object `obj` away from the light: in object
// space (p - hi) - lo, whose first difference is exact where p is near the light (Sterbenz),
// then turned by the object's linear part and scaled to a largest component of 1, as the host
// pipeline's `volume::extrude` (0 when p is at the light).
fn extrude(id: u32, obj: u32) -> vec4<f32> {
    let k = 2u * (lt.points.x + obj);
    let a = r_light_points[k];
    var d = -a.xyz;
    if a.w != 0.0 {
        let p = r_position(id);
        d = (p - a.xyz) - r_light_points[k + 1u].xyz;
    }
    let r0 = bitcast<vec4<f32>>(r_objects[obj * 5u]).xyz;
    let r1 = bitcast<vec4<f32>>(r_objects[obj * 5u + 1u]).xyz;
    let r2 = bitcast<vec4<f32>>(r_objects[obj * 5u + 2u]).xyz;
    let wd = vec3<f32>(dot(r0, d), dot(r1, d), dot(r2, d));
    let m = max(max(abs(wd.x), abs(wd.y)), abs(wd.z));
    if m == 0.0 {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(wd / m, 0.0);
}

fn clip(pos: vec4<f32>) -> VolumeOut {
    var o: VolumeOut;
    o.clip = g.view_proj * pos;
    return o;
}

fn degenerate() -> VolumeOut {
    return clip(vec4<f32>(0.0, 0.0, 0.0, 1.0));
}

@vertex
fn vs_resident_surface(@builtin(vertex_index) vi: u32) -> SurfaceOut {
    let t = vi / 3u;
    let tr = r_triangle(t);
    let obj = r_object_of(R_FIRST_TRIANGLE, t);
    let p0 = rel(tr.x);
    let p1 = rel(tr.y);
    let p2 = rel(tr.z);
    var p = p0;
    let c = vi % 3u;
    if c == 1u {
        p = p1;
    } else if c == 2u {
        p = p2;
    }
    var o: SurfaceOut;
    o.clip = g.view_proj * vec4<f32>(p, 1.0);
    o.world = p;
    o.normal = cross(p1 - p0, p2 - p0);
    o.albedo = bitcast<vec4<f32>>(r_objects[obj * 5u + 3u]).rgb;
    o.ids = surface_ids(obj, t);
    return o;
}

fn side_vertex(record: u32, v: u32) -> VolumeOut {
    let e = record & ~R_NEGATIVE;
    let er = r_edge(e);
    var p = er.y;
    var q = er.x;
    if (record & R_NEGATIVE) != 0u {
        let t = p;
        p = q;
        q = t;
    }
    switch v {
        case 0u, 3u: {
            return clip(vec4<f32>(rel(p), 1.0));
        }
        case 1u: {
            return clip(vec4<f32>(rel(q), 1.0));
        }
        case 2u, 4u: {
            return clip(extrude(q, r_object_of(R_FIRST_EDGE, e)));
        }
        default: {
            return clip(extrude(p, r_object_of(R_FIRST_EDGE, e)));
        }
    }
}

// Z-pass sides: the light's records from the front of its region.
@vertex
fn vs_resident_side_zpass(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> VolumeOut {
    return side_vertex(r_records[lt.draw.x + i], v);
}

// Z-fail sides: the light's records from the back of its region.
@vertex
fn vs_resident_side_zfail(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> VolumeOut {
    return side_vertex(r_records[lt.draw.x + lt.draw.y - 1u - i], v);
}

// A shared sign the triangle pass left (NOT_SHARED in resident_extract.wgsl).
const R_NOT_SHARED: i32 = 4;

// The light's sign of triangle `t`: its sharing group's where the group has one (the triangle
// pass writes no per-light sign there), else its own.
fn cap_sign(t: u32) -> i32 {
    if lt.points.y != 0u {
        let s = r_signs[lt.points.y - 1u + t];
        if s != R_NOT_SHARED {
            return s;
        }
    }
    return r_signs[lt.draw.z + t];
}

// 6 vertices per triangle: the sigma = +1 front cap, then the back cap (sigma != 0, point lights).
@vertex
fn vs_resident_cap_ccw(@builtin(vertex_index) vi: u32) -> VolumeOut {
    let t = vi / 6u;
    let k = vi % 6u;
    let s = cap_sign(t);
    if s == 0 || s == R_TOUCH {
        return degenerate();
    }
    let tr = r_triangle(t);
    if k < 3u {
        if s != 1 {
            return degenerate();
        }
        return clip(vec4<f32>(rel(tr[k]), 1.0));
    }
    if lt.draw.w == 0u {
        return degenerate();
    }
    // Back cap, outward: (inf0, inf2, inf1) for sigma = +1, (inf0, inf1, inf2) for sigma = -1.
    var c = k - 3u;
    if s == 1 && c != 0u {
        c = 3u - c;
    }
    return clip(extrude(tr[c], r_object_of(R_FIRST_TRIANGLE, t)));
}

// 3 vertices per triangle: the sigma = -1 front cap (drawn with clockwise front faces).
@vertex
fn vs_resident_cap_cw(@builtin(vertex_index) vi: u32) -> VolumeOut {
    let t = vi / 3u;
    if cap_sign(t) != -1 {
        return degenerate();
    }
    let tr = r_triangle(t);
    return clip(vec4<f32>(rel(tr[vi % 3u]), 1.0));
}
