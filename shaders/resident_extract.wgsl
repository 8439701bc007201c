// GPU-resident extraction: the triangle pass and the edge pass of the shadow-volume pass.
//
// Appended to the `wgpu` silhouette backend's module (shaders/silhouette.wgsl, composed by
// `shadowvol_wgpu_compute::shaders::module_source`) and to shaders/exact_int.wgsl, so it shares
// their bindings in group 0 (params, the scene's tables packed as the `wgpu` backend uploads
// them, read through its accessors; lights and signs), their MODE constant
// and their functions (`Invocation`, `load_edge`, `load_triangle`, `triangle_sign_traced`,
// `edge_multiplicity`, with TOUCH_SIGNS set). The CPU twin is `shadowvol_renderer::resident::twin`: keep the two in step.
//
// 1. `resident_reset`: per light two indirect draw records (z-pass and z-fail sides, 6 vertices
//    per instance, 0 instances) and the statistics, zeroed.
// 2. `resident_triangles`: one sign per (light, triangle) in the mode, for the triangle's
//    canonical vertex order (ids ascending). TOUCH marks a triangle with a vertex exactly at the
//    point light: it has no volume (no cap, no contribution to any edge).
//    In exact mode this pipeline is built with DEFER_INT: a pair the certified filter leaves is
//    marked PENDING, and
// 2b. `resident_pending_args` writes the indirect dispatch of `resident_pending`: the triangle
//    grid when any pair is pending, else no workgroup; `resident_pending` decides each PENDING
//    pair with `orient_int` (the same `triangle_sign_traced`, DEFER_INT off), so the integer
//    code runs, and is compiled, only where the filter needs it.
// 3. `resident_edges`: per (light, edge), m from the backend's `edge_multiplicity` (the parity
//    times the sign of each opposite vertex's triangle; `original`: the naive per-(edge, OV)
//    sign instead), then |m| side records appended to the light's z-pass list (from the front
//    of its region) or z-fail list (from the back), by the plan's technique for the edge's
//    object. The append is aggregated per workgroup: one global atomic per workgroup, light and
//    list.
//
// Lights with a size (exact mode): the host passes runs of consecutive lights that sample one
// light (a sharing group, `light_group`) and, per group and object, the box of its object-space
// samples. The triangle pass decides each triangle once per group with `box_sign` (an f32 filter
// certified for every light in the box; robust-math's `box_sign_f32`); a triangle it certifies
// has that sign for every sample, and only the others are decided per sample. The edge pass
// computes m once for the group where every opposite triangle is shared and appends its records
// for every sample of the group in one round; the other edges go per sample, and a workgroup
// with none skips that loop.

struct ResidentParams {
    object_count: u32,
    // Records per light region (at least the opposite-vertex count: sum |m| can't exceed it).
    capacity: u32,
    // Bit 0: count silhouette edges, side quads and cap triangles per (light, object).
    flags: u32,
    _pad: u32,
}

@group(1) @binding(0) var<uniform> rp: ResidentParams;
// [light * object_count + object]: 0 culled, 1 z-pass, 2 z-fail.
@group(1) @binding(3) var<storage, read> technique: array<u32>;
// [light * 8 ..]: z-pass then z-fail DrawIndirectArgs (vertex_count, instance_count, first
// vertex, first instance); then [light_count * 8]: triangles decided by `orient_int`; then,
// with flags bit 0, per (light, object): silhouette edges, side quads, cap triangles.
@group(1) @binding(5) var<storage, read_write> args: array<atomic<u32>>;
// [light * capacity + slot]: global edge, NEGATIVE set when m < 0.
@group(1) @binding(6) var<storage, read_write> records: array<u32>;

// After the (light, object) codes of `technique`, one word per light: NO_GROUP (or ALL_CULLED),
// or its sharing group (bits 0-15), the group's light count (bits 16-23) and its index in the
// group (24-31).
const NO_GROUP: u32 = 0xffffffffu;
// The word of a light outside every group whose objects are all culled: no edge work.
const ALL_CULLED: u32 = 0xfffffffeu;
// A group's triangle that `box_sign` left (shared signs, `signs[light_count * tri_count + group
// * tri_count + t]`, hold -1, 1 or this).
const NOT_SHARED: i32 = 4;
const BOX_INPUT_MAX: f32 = 0x1p39f;
const BOX_PERM_MIN: f32 = 0x1p-60f;

// The indirect dispatch `resident_pending_args` writes (group 2 of that entry only).
@group(2) @binding(0) var<storage, read_write> pending_dispatch: array<u32, 3>;

// A (light, triangle) sign the deferred triangle pass left to `resident_pending`.
const PENDING: i32 = 3;
// Workgroups per dimension of the pending dispatch (the device's limit).
override PENDING_GROUPS_X: u32 = 65535u;

var<workgroup> wg_count: array<atomic<u32>, 2>;
var<workgroup> wg_base: array<u32, 2>;

fn light_group(li: u32) -> u32 {
    return technique[params.light_count * rp.object_count + li];
}

// Row of group `g`'s shared signs in `signs`.
fn shared_row(g: u32) -> u32 {
    return (params.light_count + g) * params.tri_count;
}

fn box_input_ok(x: f32) -> bool {
    let m = abs(x);
    return x == 0.0 || (m >= F32_FILTER_MIN && m <= BOX_INPUT_MAX);
}

fn box_inputs_ok(v: vec3<f32>) -> bool {
    return box_input_ok(v.x) && box_input_ok(v.y) && box_input_ok(v.z);
}

fn box_diff_ok(x: f32) -> bool {
    return x == 0.0 || abs(x) >= F32_FILTER_MIN;
}

// The sign every light of group `g`'s box gives `tri` (canonical order), or NOT_SHARED:
// robust-math's `box_sign_f32`, operation for operation. The box is (centre, w) and
// (half-extent, 1 when valid) after the lights in `lights`.
fn box_sign(tri: Triangle, g: u32) -> i32 {
    let k = params.light_count * rp.object_count + 2u * (g * rp.object_count + tri.object);
    let cw = lights[k];
    let hv = lights[k + 1u];
    let c = cw.xyz;
    let h = hv.xyz;
    let w = cw.w;
    let a = tri.p0;
    let b = tri.p1;
    let o = tri.p2;
    if hv.w != 1.0 || (w != 0.0 && w != 1.0) {
        return NOT_SHARED;
    }
    if !(box_inputs_ok(a) && box_inputs_ok(b) && box_inputs_ok(o) && box_inputs_ok(c) && box_inputs_ok(h)) {
        return NOT_SHARED;
    }
    let ex = a.x - b.x;
    let ey = a.y - b.y;
    let ez = a.z - b.z;
    let dx = o.x - a.x;
    let dy = o.y - a.y;
    let dz = o.z - a.z;
    let vx = c.x - w * a.x;
    let vy = c.y - w * a.y;
    let vz = c.z - w * a.z;
    if !(box_diff_ok(ex) && box_diff_ok(ey) && box_diff_ok(ez) && box_diff_ok(dx) && box_diff_ok(dy)
        && box_diff_ok(dz) && box_diff_ok(vx) && box_diff_ok(vy) && box_diff_ok(vz)) {
        return NOT_SHARED;
    }
    let p1 = dy * ez;
    let q1 = dz * ey;
    let p2 = dz * ex;
    let q2 = dx * ez;
    let p3 = dx * ey;
    let q3 = dy * ex;
    let nx = p1 - q1;
    let ny = p2 - q2;
    let nz = p3 - q3;
    let mx = abs(p1) + abs(q1);
    let my = abs(p2) + abs(q2);
    let mz = abs(p3) + abs(q3);
    let gx = h.x + abs(c.x);
    let gy = h.y + abs(c.y);
    let gz = h.z + abs(c.z);
    let f = (nx * vx + ny * vy) + nz * vz;
    let r = (abs(nx) * h.x + abs(ny) * h.y) + abs(nz) * h.z;
    let p = (mx * (abs(vx) + gx) + my * (abs(vy) + gy)) + mz * (abs(vz) + gz);
    if p < BOX_PERM_MIN {
        return NOT_SHARED;
    }
    let bound = F32_FILTER_EPS * p;
    if f - r > bound || -(f + r) > bound {
        return sgn(f);
    }
    return NOT_SHARED;
}

fn stats_base() -> u32 {
    return params.light_count * 8u;
}

fn count_slot(li: u32, obj: u32) -> u32 {
    return stats_base() + 1u + 3u * (li * rp.object_count + obj);
}

// With flags bit 0: counts a decided front cap of a z-fail object (technique 2).
fn count_cap(li: u32, obj: u32, tech: u32, s: i32) {
    if (rp.flags & 1u) != 0u && tech == 2u && (s == 1 || s == -1) {
        atomicAdd(&args[count_slot(li, obj) + 2u], 1u);
    }
}

@compute @workgroup_size(64)
fn resident_reset(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let n_args = params.light_count * 8u;
    let total = n_args + 1u + 3u * params.light_count * rp.object_count;
    if i >= total {
        return;
    }
    var v = 0u;
    if i < n_args && i % 4u == 0u {
        v = 6u;
    }
    atomicStore(&args[i], v);
}

// x as (odd integer, exponent): x = odd * 2^exponent, for x != 0 (subnormals included).
fn odd_part(x: f32) -> vec2<i32> {
    let b = bitcast<u32>(x);
    let e = (b >> 23u) & 0xffu;
    var m = b & 0x7fffffu;
    var ex = -149;
    if e != 0u {
        m = m | 0x800000u;
        ex = i32(e) - 150;
    }
    let tz = countTrailingZeros(m);
    return vec2<i32>(i32(m >> tz), ex + i32(tz));
}

// p * w == l exactly (not only after rounding), in integers: the odd parts multiply and the
// exponents add, with the signs, so no f32 product is formed.
fn exact_product_is(p: f32, w: f32, l: f32) -> bool {
    if p == 0.0 || w == 0.0 || l == 0.0 {
        return (p == 0.0 || w == 0.0) && l == 0.0;
    }
    if ((p < 0.0) != (w < 0.0)) != (l < 0.0) {
        return false;
    }
    let a = odd_part(p);
    let b = odd_part(w);
    let c = odd_part(l);
    if a.y + b.y != c.y {
        return false;
    }
    // Odd parts below 2^24: their product fits in u32 when the bit lengths add to at most 32,
    // and is at least 2^24 (so not c.x) when they add to more than 25.
    let bits = (32u - countLeadingZeros(u32(a.x))) + (32u - countLeadingZeros(u32(b.x)));
    if bits > 25u {
        return false;
    }
    return u32(a.x) * u32(b.x) == u32(c.x);
}

// The vertex is exactly at the point light: p * w == L.xyz exactly (`volume::at_light`).
fn touches(p: vec3<f32>, l: vec4<f32>) -> bool {
    return l.w != 0.0 && exact_product_is(p.x, l.w, l.x) && exact_product_is(p.y, l.w, l.y)
        && exact_product_is(p.z, l.w, l.z);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn resident_triangles(inv: Invocation) {
    let t = flat_index(inv);
    if t >= params.tri_count {
        return;
    }
    let tri = load_triangle(t);
    for (var li = 0u; li < params.light_count; li++) {
        let tech = technique[li * rp.object_count + tri.object];
        signs[li * params.tri_count + t] = triangle_light(li, tri, tech);
    }
}

// Light `li`'s sign of `tri` (0 for a culled object, TOUCH, PENDING for the integer pass), and
// its cap counted.
fn triangle_light(li: u32, tri: Triangle, tech: u32) -> i32 {
    var s = 0;
    if tech != 0u {
        let l = object_light(tri.object, li);
        if touches(tri.p0, l) || touches(tri.p1, l) || touches(tri.p2, l) {
            s = TOUCH;
        } else {
            let traced = triangle_sign_traced(tri, l);
            s = select(traced.x, PENDING, traced.x == UNCERTAIN);
            if traced.y != 0 {
                atomicAdd(&args[stats_base()], 1u);
            }
        }
        count_cap(li, tri.object, tech, s);
    }
    return s;
}

// `resident_triangles` for a frame with sharing groups (exact mode): per group, `box_sign` on
// the group's box; where it certifies a sign, that is every light's, else each light decides.
@compute @workgroup_size(WORKGROUP_SIZE)
fn resident_triangles_shared(inv: Invocation) {
    let t = flat_index(inv);
    if t >= params.tri_count {
        return;
    }
    let tri = load_triangle(t);
    var li = 0u;
    while li < params.light_count {
        let tech = technique[li * rp.object_count + tri.object];
        let group = light_group(li);
        if group >= ALL_CULLED {
            signs[li * params.tri_count + t] = triangle_light(li, tri, tech);
            li += 1u;
            continue;
        }
        // A group's lights are consecutive and have the same techniques.
        let g = group & 0xffffu;
        let count = max((group >> 16u) & 0xffu, 1u);
        var s = NOT_SHARED;
        if tech != 0u {
            s = box_sign(tri, g);
        }
        signs[shared_row(g) + t] = s;
        if s != NOT_SHARED {
            // No per-light sign: the edge pass, the pending pass and the caps read the group's.
            if (rp.flags & 1u) != 0u {
                for (var j = 0u; j < count; j++) {
                    count_cap(li + j, tri.object, tech, s);
                }
            }
        } else {
            for (var j = 0u; j < count; j++) {
                signs[(li + j) * params.tri_count + t] = triangle_light(li + j, tri, tech);
            }
        }
        li += count;
    }
}

@compute @workgroup_size(1)
fn resident_pending_args() {
    let groups = max((params.tri_count + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE, 1u);
    let x = min(groups, PENDING_GROUPS_X);
    let any = atomicLoad(&args[stats_base()]) != 0u;
    pending_dispatch[0] = select(0u, x, any);
    pending_dispatch[1] = (groups + x - 1u) / x;
    pending_dispatch[2] = 1u;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn resident_pending(inv: Invocation) {
    let t = flat_index(inv);
    if t >= params.tri_count {
        return;
    }
    let tri = load_triangle(t);
    for (var li = 0u; li < params.light_count; li++) {
        // A triangle its group shares has no per-light sign of this frame.
        let group = light_group(li);
        if group < ALL_CULLED {
            if signs[shared_row(group & 0xffffu) + t] != NOT_SHARED {
                continue;
            }
        }
        let k = li * params.tri_count + t;
        if signs[k] != PENDING {
            continue;
        }
        let s = triangle_sign_traced(tri, object_light(tri.object, li)).x;
        signs[k] = s;
        count_cap(li, tri.object, technique[li * rp.object_count + tri.object], s);
    }
}

// One light's side records for this invocation's edge: `n` records of `m`'s sign in list
// `list`, placed after one global atomic per workgroup and list. Called in uniform control flow
// by every invocation of the workgroup (`n` = 0 where there is nothing to append).
fn append_light(li: u32, lid: u32, e: u32, object: u32, m: i32, list: u32) {
    let n = u32(abs(m));
    if lid == 0u {
        atomicStore(&wg_count[0], 0u);
        atomicStore(&wg_count[1], 0u);
    }
    workgroupBarrier();
    var local = 0u;
    if n != 0u {
        local = atomicAdd(&wg_count[list], n);
        if (rp.flags & 1u) != 0u {
            let c = count_slot(li, object);
            atomicAdd(&args[c], 1u);
            atomicAdd(&args[c + 1u], n);
        }
    }
    workgroupBarrier();
    if lid == 0u {
        let zp = atomicLoad(&wg_count[0]);
        let zf = atomicLoad(&wg_count[1]);
        if zp != 0u {
            wg_base[0] = atomicAdd(&args[li * 8u + 1u], zp);
        }
        if zf != 0u {
            wg_base[1] = atomicAdd(&args[li * 8u + 5u], zf);
        }
    }
    workgroupBarrier();
    if n != 0u {
        write_records(li, e, m, list, wg_base[list] + local);
    }
    workgroupBarrier();
}

// |m| records of edge `e` into light `li`'s list `list` from its slot `first`.
fn write_records(li: u32, e: u32, m: i32, list: u32, first: u32) {
    let r = e | select(0u, NEGATIVE, m < 0);
    let region = li * rp.capacity;
    for (var j = 0u; j < u32(abs(m)); j++) {
        var slot = first + j;
        if list == 1u {
            slot = rp.capacity - 1u - slot;
        }
        records[region + slot] = r;
    }
}

// m of `edge` for sharing group `g` when every opposite triangle has a shared sign (x), and
// whether one has not (y = 1): then each light of the group computes its own.
fn shared_multiplicity(edge: Edge, g: u32) -> vec2<i32> {
    let row = shared_row(g);
    var m = 0;
    for (var k = edge.ov_begin; k < edge.ov_end; k++) {
        let r = ov_ref(k);
        let s = signs[row + (r >> 2u)];
        if s == NOT_SHARED {
            return vec2<i32>(0, 1);
        }
        m += select(s, -s, (r & 3u) == 1u);
    }
    return vec2<i32>(m, 0);
}

// Light `li`'s `|m|` records of edge `e` in list `list`, placed with one global atomic (the
// shared edge pass has no workgroup barrier: a silhouette edge is rare, and a device that runs
// a workgroup's invocations as coroutines, as lavapipe does, pays for every barrier).
fn append_global(li: u32, e: u32, object: u32, m: i32, list: u32) {
    let n = u32(abs(m));
    if n == 0u {
        return;
    }
    if (rp.flags & 1u) != 0u {
        let c = count_slot(li, object);
        atomicAdd(&args[c], 1u);
        atomicAdd(&args[c + 1u], n);
    }
    let slot = atomicAdd(&args[li * 8u + 1u + 4u * list], n);
    write_records(li, e, m, list, slot);
}

// The records of a sharing group's lights `first .. first + count` (same techniques): m once
// for the group where every opposite triangle is shared, else each light's own.
fn append_group(first: u32, count: u32, g: u32, e: u32, it: EdgeItem) {
    let tech = technique[first * rp.object_count + it.object];
    if tech == 0u {
        return;
    }
    let list = select(0u, 1u, tech == 2u);
    let sm = shared_multiplicity(it.edge, g);
    if sm.y == 0 {
        if sm.x != 0 {
            for (var j = 0u; j < count; j++) {
                append_global(first + j, e, it.object, sm.x, list);
            }
        }
        return;
    }
    for (var j = 0u; j < count; j++) {
        append_global(first + j, e, it.object, group_multiplicity(it.edge, first + j, g), list);
    }
}

// m of `edge` for light `li` of sharing group `g` (exact mode): each opposite triangle's sign is
// the group's where it has one, else the light's own.
fn group_multiplicity(edge: Edge, li: u32, g: u32) -> i32 {
    let row = li * params.tri_count;
    let group_row = shared_row(g);
    var m = 0;
    for (var k = edge.ov_begin; k < edge.ov_end; k++) {
        let r = ov_ref(k);
        var s = signs[group_row + (r >> 2u)];
        if s == NOT_SHARED {
            s = signs[row + (r >> 2u)];
        }
        if s != TOUCH {
            m += select(s, -s, (r & 3u) == 1u);
        }
    }
    return m;
}

// The invocation's edge, its object and its ends' positions (zeros past the last edge).
struct EdgeItem {
    valid: bool,
    edge: Edge,
    object: u32,
    a: vec3<f32>,
    b: vec3<f32>,
}

fn edge_item(e: u32) -> EdgeItem {
    var it = EdgeItem(false, Edge(0u, 0u, 0u, 0u), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    if e < params.edge_count {
        it.valid = true;
        it.edge = load_edge(e);
        it.object = object_of(FIRST_EDGE, e);
        it.a = position(it.edge.a);
        it.b = position(it.edge.b);
    }
    return it;
}

// Light `li`'s records of the invocation's edge, aggregated per workgroup (`append_light`).
fn edge_light(li: u32, lid: u32, e: u32, it: EdgeItem) {
    var m = 0;
    var tech = 0u;
    if it.valid {
        tech = technique[li * rp.object_count + it.object];
    }
    if tech != 0u {
        m = edge_multiplicity(it.edge, it.object, li, it.a, it.b);
    }
    append_light(li, lid, e, it.object, m, select(0u, 1u, tech == 2u));
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn resident_edges(inv: Invocation) {
    let e = flat_index(inv);
    let it = edge_item(e);
    // Uniform loop: every invocation of the workgroup takes part in the barriers.
    for (var li = 0u; li < params.light_count; li++) {
        edge_light(li, inv.lid, e, it);
    }
}

// `resident_edges` for a frame with sharing groups (exact mode): a group's lights together, and
// every record placed with a global atomic (no barrier).
@compute @workgroup_size(WORKGROUP_SIZE)
fn resident_edges_shared(inv: Invocation) {
    let e = flat_index(inv);
    if e >= params.edge_count {
        return;
    }
    let it = edge_item(e);
    var li = 0u;
    while li < params.light_count {
        let group = light_group(li);
        if group < ALL_CULLED {
            let count = max((group >> 16u) & 0xffu, 1u);
            append_group(li, count, group & 0xffffu, e, it);
            li += count;
            continue;
        }
        let tech = technique[li * rp.object_count + it.object];
        if group == NO_GROUP && tech != 0u {
            let m = edge_multiplicity(it.edge, it.object, li, it.a, it.b);
            append_global(li, e, it.object, m, select(0u, 1u, tech == 2u));
        }
        li += 1u;
    }
}
