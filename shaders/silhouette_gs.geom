#version 460
// shadowvol: the paper's geometry-shader path (Pečiva et al. 2013, §3).
//
// Input: one point per (edge, light) from edge_points.vert. For its edge (a, b), a < b, the
// shader reads the opposite vertices (CSR), the positions and the object-space light, computes
// the multiplicity m in the requested accuracy mode, writes it to the result buffer, and, when
// asked to, emits |m| side quads extruded to infinity (w = 0) for the stencil pass.
//
// The sign expressions are exactly those of shadowvol-robust-math (`sign_f32`, `canonical`,
// `orient_filter_f64`, `orient_filter_f32`); every intermediate is `precise`, so no contraction
// or reassociation changes the operation order. Exact mode certifies each sign with an f64 filter
// (or the f32 filter when compiled with SHADOWVOL_NO_F64 for devices without shaderFloat64);
// pairs it cannot certify count 0 here and are appended to the uncertain buffer for the host.
//
// With pass = PASS_CAPS the point is a triangle instead (z-fail): the shader computes the
// triangle's sign in the mode (canonical order) and emits its front cap (the triangle) and, for
// point lights, its back cap at infinity, oriented to close the prisms the side quads bound.
//
// Regenerate the SPIR-V with `cargo xtask shaders`: silhouette_gs.geom.spv (f64 filter),
// silhouette_gs.f32.geom.spv (-DSHADOWVOL_NO_F64), and the extraction-only variants
// silhouette_gs.extract.geom.spv / silhouette_gs.extract.f32.geom.spv (-DSHADOWVOL_EXTRACT_ONLY).

#ifndef SHADOWVOL_NO_F64
#extension GL_ARB_gpu_shader_fp64 : require
#endif

layout(points) in;
// At most MAX_QUADS copies of a side quad per edge; larger |m| is clamped and counted.
#define MAX_QUADS 16
#ifdef SHADOWVOL_EXTRACT_ONLY
// Extraction only (rasterisation discarded): declaring no real output keeps the per-invocation
// output storage minimal, which decides how many invocations a GPU runs at once.
layout(points, max_vertices = 1) out;
#else
layout(triangle_strip, max_vertices = 64) out;
#endif

layout(location = 0) flat in uint v_edge[];
layout(location = 1) flat in uint v_light[];

layout(std430, set = 0, binding = 0) readonly buffer Positions { uint pos_bits[]; };
// shadowvol-silhouette's gpu::SceneLayout: (a, b, first OV slot, object) per edge, global vertex
// ids and OV slots, plus a sentinel whose z is the OV count (edge e's OVs: edges[e].z until
// edges[e + 1].z).
layout(std430, set = 0, binding = 1) readonly buffer Edges { uvec4 edges[]; };
layout(std430, set = 0, binding = 2) readonly buffer Ovs { uint ovs[]; };
// Object-space lights (bits of x, y, z, w), index object * light_count + light.
layout(std430, set = 0, binding = 3) readonly buffer Lights { uvec4 light_bits[]; };
// Per object: clip_from_anchor = view_proj * world_from_object * translate(anchor), composed in
// f64 on the host and rounded once; object-space positions are taken relative to the anchor
// (near the object) before the transform, so large coordinates (1e4 offsets) keep their precision.
struct ObjectXform {
    mat4 clip_from_anchor;
    vec4 anchor;
};
layout(std430, set = 0, binding = 4) readonly buffer Xforms { ObjectXform xf[]; };
// Multiplicities, index light * edge_count + edge.
layout(std430, set = 0, binding = 5) buffer Mult { int m_out[]; };
layout(std430, set = 0, binding = 6) buffer Uncertain {
    uint uncertain_count;
    uint clamped_count;
    uint pad0;
    uint pad1;
    uvec4 uncertain[]; // (edge, global OV index, light, 0)
};

layout(std430, set = 0, binding = 7) readonly buffer VertexObject { uint vertex_obj[]; };
layout(std430, set = 0, binding = 8) readonly buffer TriangleCorners { uint corners[]; };
// Exact triangle signs for one light (host-computed; exact-mode caps only).
layout(std430, set = 0, binding = 9) readonly buffer TriangleSigns { int tri_sign[]; };

layout(push_constant) uniform Push {
    uint mode;
    uint edge_count; // primitives of this draw: edges (sides pass) or triangles (caps pass)
    uint light_count;
    uint uncertain_capacity;
    uint emit;
    uint pass;
} pc;

const uint PASS_SIDES = 0u;
const uint PASS_CAPS = 1u;

const uint MODE_ORIGINAL = 0u;
const uint MODE_ROBUST = 1u;
const uint MODE_ORDERED = 2u;
const uint MODE_EXACT = 3u;
const uint MODE_PRECOMPUTED = 4u;
const int UNCERTAIN = 2;

vec3 position(uint v) {
    return uintBitsToFloat(uvec3(pos_bits[3u * v], pos_bits[3u * v + 1u], pos_bits[3u * v + 2u]));
}

uvec3 position_bits(uint v) {
    return uvec3(pos_bits[3u * v], pos_bits[3u * v + 1u], pos_bits[3u * v + 2u]);
}

// The renderer's convention for a point light at a vertex: a triangle with a vertex p for which
// p * L.w == L.xyz in f32 casts no volume (its shadow has no volume). Render passes only.
bool touches_light(vec3 p, vec4 l) {
    precise vec3 q = p * l.w;
    return l.w != 0.0 && all(equal(q, l.xyz));
}

// robust-math `sign_f32`: ((A - B) x V) . (O - A) in f32, in exactly this operation order.
int sign_f32(vec3 a, vec3 b, vec4 l, vec3 o) {
    precise float vx = l.x - l.w * a.x;
    precise float vy = l.y - l.w * a.y;
    precise float vz = l.z - l.w * a.z;
    precise float ex = a.x - b.x;
    precise float ey = a.y - b.y;
    precise float ez = a.z - b.z;
    precise float nx = ey * vz - ez * vy;
    precise float ny = ez * vx - ex * vz;
    precise float nz = ex * vy - ey * vx;
    precise float dx = o.x - a.x;
    precise float dy = o.y - a.y;
    precise float dz = o.z - a.z;
    precise float d = (nx * dx + ny * dy) + nz * dz;
    return d > 0.0 ? 1 : (d < 0.0 ? -1 : 0);
}

#ifndef SHADOWVOL_NO_F64
// Exact conversion of f32 bits to f64 (subnormal f32 included, whatever the f32 denorm mode).
double f64_of_bits(uint bits) {
    uint sgn = bits & 0x80000000u;
    uint ex = (bits >> 23) & 0xFFu;
    uint man = bits & 0x7FFFFFu;
    if (ex == 0u) {
        if (man == 0u) {
            return packDouble2x32(uvec2(0u, sgn));
        }
        int msb = findMSB(man); // 0..22
        man = (man << uint(23 - msb)) & 0x7FFFFFu;
        ex = uint(msb - 149 + 1023);
    } else {
        ex = ex - 127u + 1023u;
    }
    return packDouble2x32(uvec2(man << 29, sgn | (ex << 20) | (man >> 3)));
}

// robust-math `orient_filter_f64` (F64_FILTER_EPS = 1e-15): 1, -1, 0 or UNCERTAIN.
int orient_filter(uvec3 a_bits, uvec3 b_bits, uvec4 l_bits, uvec3 o_bits) {
    double ax = f64_of_bits(a_bits.x);
    double ay = f64_of_bits(a_bits.y);
    double az = f64_of_bits(a_bits.z);
    double lw = f64_of_bits(l_bits.w);
    precise double ex = ax - f64_of_bits(b_bits.x);
    precise double ey = ay - f64_of_bits(b_bits.y);
    precise double ez = az - f64_of_bits(b_bits.z);
    precise double vx = f64_of_bits(l_bits.x) - lw * ax;
    precise double vy = f64_of_bits(l_bits.y) - lw * ay;
    precise double vz = f64_of_bits(l_bits.z) - lw * az;
    precise double dx = f64_of_bits(o_bits.x) - ax;
    precise double dy = f64_of_bits(o_bits.y) - ay;
    precise double dz = f64_of_bits(o_bits.z) - az;
    precise double p1 = ey * vz;
    precise double q1 = ez * vy;
    precise double p2 = ez * vx;
    precise double q2 = ex * vz;
    precise double p3 = ex * vy;
    precise double q3 = ey * vx;
    precise double det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    precise double perm = ((abs(p1) + abs(q1)) * abs(dx) + (abs(p2) + abs(q2)) * abs(dy))
        + (abs(p3) + abs(q3)) * abs(dz);
    precise double bound = 1.0e-15LF * perm;
    if (abs(det) > bound) {
        return det > 0.0LF ? 1 : -1;
    }
    if (perm == 0.0LF) {
        return 0;
    }
    return UNCERTAIN;
}
#else
bool f32_bits_subnormal(uint bits) {
    return (bits & 0x7F800000u) == 0u && (bits & 0x7FFFFFu) != 0u;
}

// A difference the f32 filter may use: in [2^-40, 2^40] or zero, and not a non-zero difference
// flushed to zero by the device's denormal mode.
bool diff_ok(float x, float y, float d) {
    float m = abs(d);
    if (m == 0.0) {
        return x == y;
    }
    return m >= 9.094947017729282e-13 && m <= 1099511627776.0;
}

// robust-math `orient_filter_f32` (F32_FILTER_EPS = 2^-19): 1, -1, 0 or UNCERTAIN.
int orient_filter(uvec3 a_bits, uvec3 b_bits, uvec4 l_bits, uvec3 o_bits) {
    for (int i = 0; i < 3; i++) {
        if (f32_bits_subnormal(a_bits[i]) || f32_bits_subnormal(b_bits[i])
            || f32_bits_subnormal(o_bits[i]) || f32_bits_subnormal(l_bits[i])) {
            return UNCERTAIN;
        }
    }
    if (f32_bits_subnormal(l_bits.w)) {
        return UNCERTAIN;
    }
    // For w other than 0 or 1, w*A is rounded, and when it cancels against L.xyz the error of V
    // is relative to |w*A|, not to |V|: the bound would not hold (robust-math's rule).
    if (l_bits.w != 0u && l_bits.w != 0x80000000u && l_bits.w != 0x3f800000u) {
        return UNCERTAIN;
    }
    vec3 a = uintBitsToFloat(a_bits);
    vec3 b = uintBitsToFloat(b_bits);
    vec4 l = uintBitsToFloat(l_bits);
    vec3 o = uintBitsToFloat(o_bits);
    precise float ex = a.x - b.x;
    precise float ey = a.y - b.y;
    precise float ez = a.z - b.z;
    precise float lax = l.w * a.x;
    precise float lay = l.w * a.y;
    precise float laz = l.w * a.z;
    precise float vx = l.x - lax;
    precise float vy = l.y - lay;
    precise float vz = l.z - laz;
    precise float dx = o.x - a.x;
    precise float dy = o.y - a.y;
    precise float dz = o.z - a.z;
    if (!diff_ok(a.x, b.x, ex) || !diff_ok(a.y, b.y, ey) || !diff_ok(a.z, b.z, ez)
        || !diff_ok(l.x, lax, vx) || !diff_ok(l.y, lay, vy) || !diff_ok(l.z, laz, vz)
        || !diff_ok(o.x, a.x, dx) || !diff_ok(o.y, a.y, dy) || !diff_ok(o.z, a.z, dz)) {
        return UNCERTAIN;
    }
    // l.w * a must stay in the normal range (an underflowed or flushed product has an absolute,
    // not a relative, error): leave such inputs to the host, as orient_filter_f32 does.
    const float FLT_MIN_NORMAL = 1.17549435e-38;
    if (l.w != 0.0 && ((a.x != 0.0 && abs(lax) < FLT_MIN_NORMAL)
                       || (a.y != 0.0 && abs(lay) < FLT_MIN_NORMAL)
                       || (a.z != 0.0 && abs(laz) < FLT_MIN_NORMAL))) {
        return UNCERTAIN;
    }
    if (isinf(lax) || isinf(lay) || isinf(laz)) {
        return UNCERTAIN;
    }
    precise float p1 = ey * vz;
    precise float q1 = ez * vy;
    precise float p2 = ez * vx;
    precise float q2 = ex * vz;
    precise float p3 = ex * vy;
    precise float q3 = ey * vx;
    precise float det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    precise float perm = ((abs(p1) + abs(q1)) * abs(dx) + (abs(p2) + abs(q2)) * abs(dy))
        + (abs(p3) + abs(q3)) * abs(dz);
    if (isinf(perm) || isnan(perm) || isnan(det)) {
        return UNCERTAIN;
    }
    precise float bound = 1.9073486328125e-06 * perm; // 2^-19
    if (abs(det) > bound) {
        return det > 0.0 ? 1 : -1;
    }
    if (perm == 0.0) {
        return 0;
    }
    return UNCERTAIN;
}
#endif

void emit_quads(uint obj, uint a, uint b, vec4 l, int m) {
    mat4 clip = xf[obj].clip_from_anchor;
    vec3 c = xf[obj].anchor.xyz;
    precise vec3 ra = position(a) - c;
    precise vec3 rb = position(b) - c;
    // The light relative to the anchor: L.xyz - c * L.w.
    precise vec3 lr = l.xyz - c * l.w;
    precise vec4 ca = clip * vec4(ra, 1.0);
    precise vec4 cb = clip * vec4(rb, 1.0);
    // Points at infinity away from the light: X * w - L.xyz, homogeneous w = 0.
    precise vec4 ia = clip * vec4(ra * l.w - lr, 0.0);
    precise vec4 ib = clip * vec4(rb * l.w - lr, 0.0);
    int n = abs(m);
    if (n > MAX_QUADS) {
        atomicAdd(clamped_count, 1u);
        n = MAX_QUADS;
    }
    for (int i = 0; i < n; i++) {
        if (m > 0) {
            gl_Position = ca; EmitVertex();
            gl_Position = cb; EmitVertex();
            gl_Position = ia; EmitVertex();
            gl_Position = ib; EmitVertex();
        } else {
            gl_Position = cb; EmitVertex();
            gl_Position = ca; EmitVertex();
            gl_Position = ib; EmitVertex();
            gl_Position = ia; EmitVertex();
        }
        EndPrimitive();
    }
}

// z-fail caps of triangle t (global index) for light li.
void emit_caps(uint t, uint li) {
    uint g0 = corners[3u * t];
    uint g1 = corners[3u * t + 1u];
    uint g2 = corners[3u * t + 2u];
    uint obj = vertex_obj[g0];
    vec4 l = uintBitsToFloat(light_bits[obj * pc.light_count + li]);
    // Canonical order i0 < i1 < i2.
    uint i0 = min(g0, min(g1, g2));
    uint i2 = max(g0, max(g1, g2));
    uint i1 = g0 + g1 + g2 - i0 - i2;
    vec3 p0 = position(i0);
    vec3 p1 = position(i1);
    vec3 p2 = position(i2);
    int s;
    if (pc.mode == MODE_EXACT || pc.mode == MODE_PRECOMPUTED) {
        s = tri_sign[t];
    } else if (touches_light(p0, l) || touches_light(p1, l) || touches_light(p2, l)) {
        s = 0;
    } else {
        // Original has no triangle sign of its own: its caps use ordered's.
        s = sign_f32(p0, p1, l, p2);
        if (pc.mode == MODE_ROBUST) {
            int s1 = sign_f32(p1, p2, l, p0);
            int s2 = sign_f32(p2, p0, l, p1);
            if (s != s1 || s1 != s2) {
                s = 0;
            }
        }
    }
    if (s == 0) {
        return;
    }
    mat4 clip = xf[obj].clip_from_anchor;
    vec3 c = xf[obj].anchor.xyz;
    precise vec3 r0 = p0 - c;
    precise vec3 r1 = p1 - c;
    precise vec3 r2 = p2 - c;
    precise vec4 c0 = clip * vec4(r0, 1.0);
    precise vec4 c1 = clip * vec4(r1, 1.0);
    precise vec4 c2 = clip * vec4(r2, 1.0);
    // The sides of a triangle with sign s > 0 run i0 -> i1 -> i2 along it and back at infinity;
    // the caps run the other way: front (i0, i2, i1), back (i0∞, i1∞, i2∞). Reversed for s < 0.
    gl_Position = c0; EmitVertex();
    gl_Position = s > 0 ? c2 : c1; EmitVertex();
    gl_Position = s > 0 ? c1 : c2; EmitVertex();
    EndPrimitive();
    if (l.w != 0.0) {
        precise vec3 lr = l.xyz - c * l.w;
        precise vec4 j0 = clip * vec4(r0 * l.w - lr, 0.0);
        precise vec4 j1 = clip * vec4(r1 * l.w - lr, 0.0);
        precise vec4 j2 = clip * vec4(r2 * l.w - lr, 0.0);
        gl_Position = j0; EmitVertex();
        gl_Position = s > 0 ? j1 : j2; EmitVertex();
        gl_Position = s > 0 ? j2 : j1; EmitVertex();
        EndPrimitive();
    }
}

void main() {
#ifndef SHADOWVOL_EXTRACT_ONLY
    if (pc.pass == PASS_CAPS) {
        if (v_edge[0] < pc.edge_count && v_light[0] < pc.light_count) {
            emit_caps(v_edge[0], v_light[0]);
        }
        return;
    }
#endif
    uint e = v_edge[0];
    uint li = v_light[0];
    if (e >= pc.edge_count || li >= pc.light_count) {
        return;
    }
    uvec4 ed = edges[e];
    uint a = ed.x;
    uint b = ed.y;
    uint obj = ed.w;
    uint ov_end = edges[e + 1u].z;
    uvec4 lb = light_bits[obj * pc.light_count + li];
    vec4 l = uintBitsToFloat(lb);
    uint out_index = li * pc.edge_count + e;
    int m = 0;
    if (pc.mode == MODE_PRECOMPUTED) {
        m = m_out[out_index];
    } else {
        vec3 pa = position(a);
        vec3 pb = position(b);
        bool edge_touches = pc.emit != 0u && (touches_light(pa, l) || touches_light(pb, l));
        for (uint k = ed.z; k < ov_end; k++) {
            uint o = ovs[k];
            if (pc.emit != 0u && (edge_touches || touches_light(position(o), l))) {
                continue; // rendering: triangles touching a point light cast no volume
            }
            int s = 0;
            if (pc.mode == MODE_ORIGINAL) {
                s = sign_f32(pa, pb, l, position(o));
            } else if (pc.mode == MODE_EXACT) {
                s = orient_filter(position_bits(a), position_bits(b), lb, position_bits(o));
                if (s == UNCERTAIN) {
                    uint slot = atomicAdd(uncertain_count, 1u);
                    if (slot < pc.uncertain_capacity) {
                        uncertain[slot] = uvec4(e, k, li, 0u);
                    }
                    s = 0;
                }
            } else {
                // robust-math `canonical`: sorted ids and the permutation parity.
                uint i0, i1, i2;
                int parity;
                if (o > b) {
                    i0 = a; i1 = b; i2 = o; parity = 1;
                } else if (o < a) {
                    i0 = o; i1 = a; i2 = b; parity = 1;
                } else {
                    i0 = a; i1 = o; i2 = b; parity = -1;
                }
                vec3 p0 = position(i0);
                vec3 p1 = position(i1);
                vec3 p2 = position(i2);
                int t = sign_f32(p0, p1, l, p2);
                if (pc.mode == MODE_ROBUST) {
                    int t1 = sign_f32(p1, p2, l, p0);
                    int t2 = sign_f32(p2, p0, l, p1);
                    if (t != t1 || t1 != t2) {
                        t = 0;
                    }
                }
                s = t * parity;
            }
            m += s;
        }
        m_out[out_index] = m;
    }
#ifndef SHADOWVOL_EXTRACT_ONLY
    if (pc.emit != 0u && m != 0) {
        emit_quads(obj, a, b, l, m);
    }
#endif
}
