// GPU-resident extraction: the triangle pass and the edge pass of the shadow-volume pass.
//
// Appended to the `wgpu` silhouette backend's module (shaders/silhouette.wgsl, composed by
// `shadowvol_wgpu_compute::shaders::module_source`) and to shaders/exact_int.wgsl, so it shares
// their bindings in group 0 (params, the scene's tables as the `wgpu` backend uploads them:
// positions, edges, ov_refs, tris, ov_offsets, objects; lights and signs), their MODE constant
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

// The indirect dispatch `resident_pending_args` writes (group 2 of that entry only).
@group(2) @binding(0) var<storage, read_write> pending_dispatch: array<u32, 3>;

// A (light, triangle) sign the deferred triangle pass left to `resident_pending`.
const PENDING: i32 = 3;
// Workgroups per dimension of the pending dispatch (the device's limit).
override PENDING_GROUPS_X: u32 = 65535u;

var<workgroup> wg_count: array<atomic<u32>, 2>;
var<workgroup> wg_base: array<u32, 2>;

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
        signs[li * params.tri_count + t] = s;
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
        let k = li * params.tri_count + t;
        if signs[k] != PENDING {
            continue;
        }
        let s = triangle_sign_traced(tri, object_light(tri.object, li)).x;
        signs[k] = s;
        count_cap(li, tri.object, technique[li * rp.object_count + tri.object], s);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn resident_edges(inv: Invocation) {
    let e = flat_index(inv);
    let lid = inv.lid;
    let valid = e < params.edge_count;
    var edge = Edge(0u, 0u, 0u, 0u);
    var object = 0u;
    var a = vec3<f32>(0.0);
    var b = vec3<f32>(0.0);
    if valid {
        edge = load_edge(e);
        object = object_of(FIRST_EDGE, e);
        a = position(edge.a);
        b = position(edge.b);
    }
    let light_count = params.light_count;
    // Uniform loop: every invocation of the workgroup takes part in the barriers.
    for (var li = 0u; li < light_count; li++) {
        var m = 0;
        var tech = 0u;
        if valid {
            tech = technique[li * rp.object_count + object];
        }
        if tech != 0u {
            m = edge_multiplicity(edge, object, li, a, b);
        }
        let n = u32(abs(m));
        let list = select(0u, 1u, tech == 2u);
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
            let r = e | select(0u, NEGATIVE, m < 0);
            let region = li * rp.capacity;
            let first = wg_base[list] + local;
            for (var j = 0u; j < n; j++) {
                var slot = first + j;
                if list == 1u {
                    slot = rp.capacity - 1u - slot;
                }
                records[region + slot] = r;
            }
        }
        workgroupBarrier();
    }
}
