#version 460
// shadowvol: the paper's geometry-shader path (Pečiva et al. 2013, §3), extraction only.
//
// Input: one point per (edge, light) from edge_points.vert. For its edge (a, b), a < b, the
// shader reads the opposite vertices (CSR), the positions and the object-space light, computes
// the multiplicity m in the requested accuracy mode and writes it to the result buffer.
// Rasterisation is discarded: nothing is emitted.
//
// The sign expressions are exactly those of shadowvol-robust-math (`sign_f32`, `canonical`,
// `orient_filter_f64`, `orient_filter_f32`); every intermediate is `precise`, so no contraction
// or reassociation changes the operation order. Exact mode certifies each sign with an f64 filter
// (or the f32 filter when compiled with SHADOWVOL_NO_F64 for devices without shaderFloat64);
// pairs it cannot certify count 0 here and are appended to the uncertain buffer for the host.
//
// Regenerate the SPIR-V with `cargo xtask shaders`: silhouette_gs.geom.spv (f64 filter) and
// silhouette_gs.f32.geom.spv (-DSHADOWVOL_NO_F64).

#ifndef SHADOWVOL_NO_F64
#extension GL_ARB_gpu_shader_fp64 : require
#endif

layout(points) in;
// Declaring no real output keeps the per-invocation output storage minimal, which decides how
// many invocations a GPU runs at once.
layout(points, max_vertices = 1) out;

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
// Multiplicities, index light * edge_count + edge.
layout(std430, set = 0, binding = 4) buffer Mult { int m_out[]; };
layout(std430, set = 0, binding = 5) buffer Uncertain {
    uint uncertain_count;
    uint pad0;
    uint pad1;
    uint pad2;
    uvec4 uncertain[]; // (edge, global OV index, light, 0)
};

layout(push_constant) uniform Push {
    uint mode;
    uint edge_count;
    uint light_count;
    uint uncertain_capacity;
} pc;

// The mode codes of shadowvol_silhouette::gpu::mode_code.
const uint MODE_ORIGINAL = 0u;
const uint MODE_ROBUST = 1u;
const uint MODE_ORDERED = 2u;
const uint MODE_EXACT = 3u;
const int UNCERTAIN = 2;

vec3 position(uint v) {
    return uintBitsToFloat(uvec3(pos_bits[3u * v], pos_bits[3u * v + 1u], pos_bits[3u * v + 2u]));
}

uvec3 position_bits(uint v) {
    return uvec3(pos_bits[3u * v], pos_bits[3u * v + 1u], pos_bits[3u * v + 2u]);
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

void main() {
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
    vec3 pa = position(a);
    vec3 pb = position(b);
    int m = 0;
    for (uint k = ed.z; k < ov_end; k++) {
        uint o = ovs[k];
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
    m_out[li * pc.edge_count + e] = m;
}
