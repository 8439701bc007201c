// Silhouette multiplicities for every edge of a prepared scene, for many lights, in one dispatch
// per step.
//
// Part of shadowvol-wgpu-compute (crates/wgpu-compute). The CPU twin of these kernels is
// `shadowvol_wgpu_compute::twin`: keep the two in step. The renderer's GPU-resident pass appends
// its own kernels to this module and reuses its bindings and functions.
//
// Two steps (the thesis' method):
// 1. `triangles` (robust, ordered, exact): one invocation per global triangle; for each light of
//    the dispatch, the sign of the triangle in its canonical vertex order (ids ascending) goes to
//    `signs[light * tri_count + triangle]`.
//    In exact mode with the integer fallback deferred, `resolve_uncertain` then decides the
//    pairs the filter left, on the device, before the edge step.
// 2. `extract`: one invocation per global edge; for each light, m = the sum over the edge's
//    opposite vertices (OVs) of the parity times the sign of that OV's triangle (`original`: the
//    naive per-(edge, OV) sign instead, with no triangle step). It writes m to
//    `mult[light * edge_count + edge]` and appends `(edge, m)` to the light's compact silhouette
//    list when m != 0 (atomic append; the list order is unspecified).
// Every triangle is evaluated once, in one order, for all its edges: robust and ordered close
// their chains by construction.
//
// Sign convention (crates/robust-math): for an edge (a, b), a < b, and an OV o,
//   V = L.xyz - L.w * A,  s = sgn( ((A - B) x V) . (O - A) ).
// MODE (pipeline-overridable): 0 original, 1 robust, 2 ordered, 3 exact.
//
// Exact mode uses a certified filter (`exact_filter`). What it cannot certify goes to
// `device_exact`: by default `orient_int` decides it on the device (inline, or, with DEFER_INT,
// in `resolve_uncertain` over the appended pairs); otherwise (the module as it
// stands) the (triangle, light) pair's sign is 0 here and the pair is appended to `uncertain`;
// the host decides it exactly and patches `mult` and the compact lists. For devices with
// SHADER_F64 the host builds this module with the call marked `@exact-filter` replaced by
// `filter_f64` and appends shaders/exact_f64.wgsl.
//
// WGSL cannot forbid FMA contraction or reassociation; the f32 modes may therefore differ from
// the CPU in the last bits (only exact mode is required to be bit-identical), and the filter
// bounds leave margin for it (see the crate documentation).

override MODE: u32 = 0u;

// True in the renderer's resident pass, whose triangle step marks triangles with a vertex exactly
// at a point light as TOUCH: `edge_multiplicity` skips them in every mode.
override TOUCH_SIGNS: bool = false;

// True in the `wgpu` backend's `original` edge step for scenes whose OV vertex list is bound
// (`ov_vertices`): it reads each OV in one step instead of through its triangle.
override OV_VERTICES: bool = false;

// True in the `wgpu` backend's pipelines for scenes of one object: `object_of` is 0 at compile
// time (a search the compiler cannot remove costs lavapipe up to a tenth of a frame).
override SINGLE_OBJECT: bool = false;

const WORKGROUP_SIZE: u32 = 256u;
const UNCERTAIN: i32 = 2;
// A triangle sign that is not a sign: the triangle touches the light and has no volume.
const TOUCH: i32 = 2;
// Set on a side record of the renderer's resident pass for m < 0.
const NEGATIVE: u32 = 0x80000000u;
// Fields of an `objects` entry.
const FIRST_EDGE: u32 = 0u;
const FIRST_TRIANGLE: u32 = 1u;

// robust-math's F32_FILTER_EPS (2^-19), F32_FILTER_MIN (2^-40), F32_FILTER_MAX (2^40).
const F32_FILTER_EPS: f32 = 0x1p-19f;
const F32_FILTER_MIN: f32 = 0x1p-40f;
const F32_FILTER_MAX: f32 = 0x1p40f;
// GPU-only guards of the f32 filter (`shaders::GPU_F32_INPUT_MAX`, `GPU_F32_PERM_MIN`): every input
// magnitude at most 2^39 (so no difference or product can overflow), and a non-zero permanent at
// least 2^-60 (so flushing a subnormal intermediate to zero moves det by far less than the bound).
const F32_INPUT_MAX_BITS: u32 = 0x53000000u; // bits of 2^39
const F32_PERM_MIN: f32 = 0x1p-60f;

struct Params {
    edge_count: u32,
    light_count: u32,
    uncertain_capacity: u32,
    tri_count: u32,
    // Entries of each light's compact list in `silhouettes`.
    list_capacity: u32,
    // Objects of the scene (`objects` has one more entry, the sentinel).
    object_count: u32,
    _pad1: u32,
    _pad2: u32,
}

// One record per uncertain (triangle, light): global triangle, light index within this dispatch.
struct Uncertain {
    triangle: u32,
    light: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
// The scene's edge tables (silhouette's `gpu::TableBuffer`), packed into one buffer of words
// (shadowvol-gpu's `TablePacking`: one storage binding for all of them, so that every pipeline
// stays within WebGPU's 8 storage buffers per stage), each table at the word offset
// `table_at` gives, with global ids:
// - positions: object-space xyz (f32 bits) per global vertex id;
// - edges: per global edge, its ends (a, b), a < b global vertex ids;
// - ov_offsets: per global edge, its first OV slot; one sentinel at the end: the OV count;
// - ov_refs: per OV slot, 4 t + r, the global triangle t whose vertex r (canonical order) is
//   the OV;
// - tris: per global triangle, its global vertex ids in ascending (canonical) order;
// - objects: per object (first edge, first triangle, first vertex, first OV slot), plus a
//   sentinel;
// - ov_vertices: with OV_VERTICES, per OV slot, the OV's global vertex id (else absent, never
//   read);
// - vertex_objects: the renderer's resident pass only, per global vertex its object.
// Read them only through the accessors below (`position`, `load_edge`, `ov_ref`,
// `tri_vertex`, `object_base`, `ov_vertex`); their CPU twin is shadowvol-gpu's `PackedView`.
@group(0) @binding(1) var<storage, read> tables: array<u32>;
// Word offsets of the tables in `tables` (shadowvol-gpu's `TableOffsets`, field for field).
struct TableOffsets {
    objects: u32,
    positions: u32,
    edges: u32,
    ov_offsets: u32,
    ov_refs: u32,
    tris: u32,
    ov_vertices: u32,
    vertex_objects: u32,
}
@group(0) @binding(2) var<uniform> table_at: TableOffsets;
// Object-space lights, [object * light_count + light].
@group(0) @binding(4) var<storage, read> lights: array<vec4<f32>>;
// Multiplicities, [light * edge_count + edge].
@group(0) @binding(5) var<storage, read_write> mult: array<i32>;
// [light]: length of the light's compact list; [light_count]: number of uncertain records.
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;
// Compact lists: light l owns [l * c, (l + 1) * c), c = params.list_capacity; entries (edge,
// bitcast m). A light's counter may pass c: the entries past it are not written, and the host
// runs the dispatch again with longer lists.
@group(0) @binding(7) var<storage, read_write> silhouettes: array<vec2<u32>>;
@group(0) @binding(8) var<storage, read_write> uncertain: array<Uncertain>;
// [light * tri_count + triangle]: -1, 0, 1 (TOUCH in the resident pass).
@group(0) @binding(11) var<storage, read_write> signs: array<i32>;

// The builtins of one invocation of a triangle or edge kernel (every kernel of the module and of
// the renderer's resident pass takes them so).
struct Invocation {
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
}

// The global invocation index of a 1-D dispatch folded into a 2-D grid of workgroups.
fn flat_index(inv: Invocation) -> u32 {
    return (inv.wid.x + inv.wid.y * inv.nwg.x) * WORKGROUP_SIZE + inv.lid;
}

fn position(id: u32) -> vec3<f32> {
    let k = table_at.positions + 3u * id;
    return vec3<f32>(bitcast<f32>(tables[k]), bitcast<f32>(tables[k + 1u]), bitcast<f32>(tables[k + 2u]));
}

// Field `field` (FIRST_EDGE, FIRST_TRIANGLE, ...) of object `obj`'s entry (the sentinel at
// `object_count`).
fn object_base(obj: u32, field: u32) -> u32 {
    return tables[table_at.objects + 4u * obj + field];
}

// OV slot `k`'s reference, 4 t + r.
fn ov_ref(k: u32) -> u32 {
    return tables[table_at.ov_refs + k];
}

// Vertex `r` (canonical order) of global triangle `t`.
fn tri_vertex(t: u32, r: u32) -> u32 {
    return tables[table_at.tris + 3u * t + r];
}

// With OV_VERTICES: OV slot `k`'s global vertex.
fn ov_vertex(k: u32) -> u32 {
    return tables[table_at.ov_vertices + k];
}

// Light `li` of the dispatch in object `obj`'s space.
fn object_light(obj: u32, li: u32) -> vec4<f32> {
    return lights[obj * params.light_count + li];
}

// The object of global id `id` (an edge for FIRST_EDGE, a triangle for FIRST_TRIANGLE): the
// last object whose first id is at most `id` (binary search; silhouette's `gpu::object_of`).
fn object_of(field: u32, id: u32) -> u32 {
    if SINGLE_OBJECT {
        return 0u;
    }
    // A uniform branch, for the pipelines built without SINGLE_OBJECT.
    if params.object_count <= 1u {
        return 0u;
    }
    var lo = 0u;
    var hi = params.object_count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if object_base(mid, field) <= id {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// Global edge `e`: its ends' ids and its OV slots [ov_begin, ov_end) (its object, where needed,
// is `object_of(FIRST_EDGE, e)`).
struct Edge {
    a: u32,
    b: u32,
    ov_begin: u32,
    ov_end: u32,
}

fn load_edge(e: u32) -> Edge {
    let k = table_at.edges + 2u * e;
    let o = table_at.ov_offsets + e;
    return Edge(tables[k], tables[k + 1u], tables[o], tables[o + 1u]);
}

// Global triangle `t`: its canonical (ascending) vertices' positions and its object.
struct Triangle {
    p0: vec3<f32>,
    p1: vec3<f32>,
    p2: vec3<f32>,
    object: u32,
}

fn load_triangle(t: u32) -> Triangle {
    return Triangle(
        position(tri_vertex(t, 0u)),
        position(tri_vertex(t, 1u)),
        position(tri_vertex(t, 2u)),
        object_of(FIRST_TRIANGLE, t),
    );
}

fn sgn(x: f32) -> i32 {
    return select(select(0, -1, x < 0.0), 1, x > 0.0);
}

// robust-math's `sign_f32`, operation for operation (no cross()/dot(): their order is unspecified).
fn sign_f32(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>, o: vec3<f32>) -> i32 {
    let vx = l.x - l.w * a.x;
    let vy = l.y - l.w * a.y;
    let vz = l.z - l.w * a.z;
    let ex = a.x - b.x;
    let ey = a.y - b.y;
    let ez = a.z - b.z;
    let nx = ey * vz - ez * vy;
    let ny = ez * vx - ex * vz;
    let nz = ex * vy - ey * vx;
    let dx = o.x - a.x;
    let dy = o.y - a.y;
    let dz = o.z - a.z;
    return sgn((nx * dx + ny * dy) + nz * dz);
}

fn is_subnormal(x: f32) -> bool {
    let m = bitcast<u32>(x) & 0x7fffffffu;
    return m != 0u && m < 0x00800000u;
}

fn any_subnormal3(v: vec3<f32>) -> bool {
    return is_subnormal(v.x) || is_subnormal(v.y) || is_subnormal(v.z);
}

fn too_large(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > F32_INPUT_MAX_BITS;
}

fn any_too_large3(v: vec3<f32>) -> bool {
    return too_large(v.x) || too_large(v.y) || too_large(v.z);
}

fn out_of_range(x: f32) -> bool {
    let m = abs(x);
    return m != 0.0 && (m < F32_FILTER_MIN || m > F32_FILTER_MAX);
}

// robust-math's `orient_filter_f32` with the GPU guards above. Returns -1, 0, 1 or UNCERTAIN.
fn filter_f32(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>, o: vec3<f32>) -> i32 {
    if any_too_large3(a) || any_too_large3(b) || any_too_large3(o) || any_too_large3(l.xyz) || too_large(l.w) {
        return UNCERTAIN;
    }
    let ex = a.x - b.x;
    let ey = a.y - b.y;
    let ez = a.z - b.z;
    // Only w = 0 and w = 1 make L.w * A exact in f32; for any other w its rounding is relative
    // to |w A|, not to |V|, and V = L.xyz - w A may cancel (robust-math's rule).
    if l.w != 0.0 && l.w != 1.0 {
        return UNCERTAIN;
    }
    let vx = l.x - l.w * a.x;
    let vy = l.y - l.w * a.y;
    let vz = l.z - l.w * a.z;
    let dx = o.x - a.x;
    let dy = o.y - a.y;
    let dz = o.z - a.z;
    if out_of_range(ex) || out_of_range(ey) || out_of_range(ez) || out_of_range(vx) || out_of_range(vy)
        || out_of_range(vz) || out_of_range(dx) || out_of_range(dy) || out_of_range(dz) {
        return UNCERTAIN;
    }
    let p1 = ey * vz;
    let q1 = ez * vy;
    let p2 = ez * vx;
    let q2 = ex * vz;
    let p3 = ex * vy;
    let q3 = ey * vx;
    let det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    let perm = ((abs(p1) + abs(q1)) * abs(dx) + (abs(p2) + abs(q2)) * abs(dy)) + (abs(p3) + abs(q3)) * abs(dz);
    if perm == 0.0 {
        return 0;
    }
    if perm < F32_PERM_MIN {
        return UNCERTAIN;
    }
    if abs(det) > F32_FILTER_EPS * perm {
        return sgn(det);
    }
    return UNCERTAIN;
}

// The certified sign of det4(A, B, L, O), or UNCERTAIN. Subnormal inputs are never certified:
// a device may flush them when loading or converting.
fn exact_filter(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>, o: vec3<f32>) -> i32 {
    if any_subnormal3(a) || any_subnormal3(b) || any_subnormal3(o) || any_subnormal3(l.xyz) || is_subnormal(l.w) {
        return UNCERTAIN;
    }
    return filter_f32(a, b, l, o); // @exact-filter
}

// What the filter leaves: decided here, or UNCERTAIN to leave it to the host. The host builds the
// module with the call marked @exact-int switched to `orient_int` (shaders/exact_int.wgsl,
// integer arithmetic on the f32 bits, exact for every finite input) and that file appended,
// unless WgpuOptions::exact_on_device is false.
fn device_exact(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>, o: vec3<f32>) -> i32 {
    return UNCERTAIN; // @exact-int
}

// The sign of the canonical triangle `tri` (ids ascending) for light `l` in the mode (robust,
// ordered or exact; robust-math's `triangle_sign`), and 1 in y when exact mode needed
// `device_exact` (the filter could not certify it). x is UNCERTAIN when `device_exact` leaves it
// to the host.
fn triangle_sign_traced(tri: Triangle, l: vec4<f32>) -> vec2<i32> {
    let p0 = tri.p0;
    let p1 = tri.p1;
    let p2 = tri.p2;
    if MODE == 3u {
        let f = exact_filter(p0, p1, l, p2);
        if f != UNCERTAIN {
            return vec2<i32>(f, 0);
        }
        return vec2<i32>(device_exact(p0, p1, l, p2), 1);
    }
    let s0 = sign_f32(p0, p1, l, p2);
    if MODE == 1u {
        let s1 = sign_f32(p1, p2, l, p0);
        let s2 = sign_f32(p2, p0, l, p1);
        if s0 != s1 || s1 != s2 {
            return vec2<i32>(0, 0);
        }
    }
    return vec2<i32>(s0, 0);
}

// m of `edge` of object `object` (`a`, `b` its ends' positions; both loaded once by the caller,
// the object only for `original`, which alone reads it) for light `li`:
// `original` evaluates every (edge, OV) naively; the other modes sum the parity times the signs
// of the OVs' triangles (a reference's rank 1 is the odd permutation). TOUCH triangles
// contribute nothing.
fn edge_multiplicity(edge: Edge, object: u32, li: u32, a: vec3<f32>, b: vec3<f32>) -> i32 {
    let row = li * params.tri_count;
    var m = 0;
    if MODE == 0u {
        let l = object_light(object, li);
        for (var k = edge.ov_begin; k < edge.ov_end; k++) {
            // Nested, not `&&`: WGSL's `&&` may be compiled without short-circuit, and the
            // backend's `original` must not read the sign buffers.
            if TOUCH_SIGNS {
                if signs[row + (ov_ref(k) >> 2u)] == TOUCH {
                    continue;
                }
            }
            var o = 0u;
            if OV_VERTICES {
                o = ov_vertex(k);
            } else {
                let r = ov_ref(k);
                o = tri_vertex(r >> 2u, r & 3u);
            }
            m += sign_f32(a, b, l, position(o));
        }
    } else {
        for (var k = edge.ov_begin; k < edge.ov_end; k++) {
            let r = ov_ref(k);
            let s = signs[row + (r >> 2u)];
            if s != TOUCH {
                m += select(s, -s, (r & 3u) == 1u);
            }
        }
    }
    return m;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn triangles(inv: Invocation) {
    let t = flat_index(inv);
    if t >= params.tri_count {
        return;
    }
    let tri = load_triangle(t);
    let light_count = params.light_count;
    for (var li = 0u; li < light_count; li++) {
        var s = triangle_sign_traced(tri, object_light(tri.object, li)).x;
        if s == UNCERTAIN {
            let slot = atomicAdd(&counters[light_count], 1u);
            if slot < params.uncertain_capacity {
                uncertain[slot] = Uncertain(t, li, 0u, 0u);
            }
            s = 0;
        }
        signs[li * params.tri_count + t] = s;
    }
}

// Exact mode with the integer fallback deferred (the triangle step built with DEFER_INT): decides
// each (triangle, light) pair the step appended to `uncertain` with the same
// `triangle_sign_traced`, `orient_int` compiled in, and writes its sign. A grid-stride loop, so
// the host sizes the grid from the list's capacity; records past the capacity are not read (the
// host then grows the list and runs the dispatch again).
@compute @workgroup_size(WORKGROUP_SIZE)
fn resolve_uncertain(inv: Invocation) {
    let n = min(atomicLoad(&counters[params.light_count]), params.uncertain_capacity);
    let stride = inv.nwg.x * inv.nwg.y * WORKGROUP_SIZE;
    for (var i = flat_index(inv); i < n; i += stride) {
        let r = uncertain[i];
        let tri = load_triangle(r.triangle);
        let s = triangle_sign_traced(tri, object_light(tri.object, r.light)).x;
        signs[r.light * params.tri_count + r.triangle] = s;
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn extract(inv: Invocation) {
    let e = flat_index(inv);
    let edge_count = params.edge_count;
    if e >= edge_count {
        return;
    }
    let edge = load_edge(e);
    let a = position(edge.a);
    let b = position(edge.b);
    let capacity = params.list_capacity;
    var object = 0u;
    if MODE == 0u {
        object = object_of(FIRST_EDGE, e);
    }
    for (var li = 0u; li < params.light_count; li++) {
        let m = edge_multiplicity(edge, object, li, a, b);
        mult[li * edge_count + e] = m;
        if m != 0 {
            let slot = atomicAdd(&counters[li], 1u);
            if slot < capacity {
                silhouettes[li * capacity + slot] = vec2<u32>(e, bitcast<u32>(m));
            }
        }
    }
}
