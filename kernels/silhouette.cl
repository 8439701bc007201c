// shadowvol: silhouette multiplicities for every edge of every object and every light, in one
// enqueue. OpenCL C 1.2 (core atomics only). Built at run time by crates/opencl.
//
// Convention (see crates/robust-math): light L = (x, y, z, w); for an edge (a, b), a < b, and an
// opposite vertex O,
//     V = L.xyz - L.w * A,  s(a, b, o) = sgn(((A - B) x V) . (O - A)),  m(a, b) = sum_o s(a, b, o).
//
// Layout (built once by the host at prepare, all objects concatenated):
//   pos       3 floats per vertex; vertex ids are global (object's base + compact id)
//   edges     4 uints per edge (a, b, first OV slot, object), a < b, global vertex ids, plus a
//             sentinel whose third value is the OV count (edge e's OVs are slots
//             edges[4e + 2] .. edges[4e + 6]); shadowvol-silhouette's gpu::SceneLayout
//   ovs       opposite vertices (global vertex ids)
//   lights    4 floats per (object, light): object-space light, index obj * num_lights + l
// Outputs:
//   counts    counts[0] = uncertain records appended, counts[1] = silhouette entries appended
//   sil       the compact silhouette list of all lights: (l * num_edges + e, m) int pairs, in any
//             order; the first counts[1] are filled (capacity num_edges * num_lights, the most
//             there can be). The index is light-major like the host's multiplicity array, so one
//             read brings back every light's silhouette.
//   unc       (edge, ov slot, light, 0) uint records that the exact filter could not certify;
//             only the first unc_capacity are stored, counts[0] counts them all
//
// Build options: -DSHADOWVOL_EXACT_F64=1 selects the f64 filter for exact mode (needs
// cl_khr_fp64); without it exact mode uses the f32 filter.

// No fused multiply-add: robust and ordered must evaluate exactly the expression written.
#pragma OPENCL FP_CONTRACT OFF

#if defined(SHADOWVOL_EXACT_F64)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif

// The mode codes of shadowvol_silhouette::gpu::mode_code.
#define MODE_ORIGINAL 0u
#define MODE_ROBUST 1u
#define MODE_ORDERED 2u
#define MODE_EXACT 3u

// Returned by the filters when the sign is not certified.
#define SV_UNCERTAIN 2

// Constants of crates/robust-math (F32_FILTER_EPS = 2^-19, F32_FILTER_MIN/MAX = 2^-40 / 2^40).
#define SV_F32_FILTER_EPS 0x1.0p-19f
#define SV_F32_FILTER_MIN 0x1.0p-40f
#define SV_F32_FILTER_MAX 0x1.0p40f
// Guards against flush-to-zero devices (not in the CPU filter; they only add uncertain records):
// an underflowing product w * a, and a permanent so small that a flushed intermediate could
// exceed the slack of the error bound.
#define SV_F32_PRODUCT_MIN 0x1.0p-100f
#define SV_F32_PERM_MIN 0x1.0p-96f

int sv_sgn32(float x) {
    return x > 0.0f ? 1 : (x < 0.0f ? -1 : 0);
}

// 1 when x is a subnormal float (tested on the bits: a flush-to-zero device compares it as 0).
int sv_is_subnormal(float x) {
    uint u = as_uint(x);
    return (u & 0x7f800000u) == 0u && (u & 0x007fffffu) != 0u;
}

float3 sv_load(__global const float* pos, uint i) {
    return vload3(i, pos);
}

// ((A - B) x V) . (O - A) in f32; exactly robust-math's `sign_f32` op order.
int sv_sign_f32(float3 a, float3 b, float4 l, float3 o) {
    float vx = l.x - l.w * a.x;
    float vy = l.y - l.w * a.y;
    float vz = l.z - l.w * a.z;
    float ex = a.x - b.x;
    float ey = a.y - b.y;
    float ez = a.z - b.z;
    float nx = ey * vz - ez * vy;
    float ny = ez * vx - ex * vz;
    float nz = ex * vy - ey * vx;
    float dx = o.x - a.x;
    float dy = o.y - a.y;
    float dz = o.z - a.z;
    return sv_sgn32((nx * dx + ny * dy) + nz * dz);
}

// 1 when the difference d = x - y is acceptable to the f32 filter: x == y (then d is exactly 0),
// or |d| within [MIN, MAX]. On a device without flush-to-zero this equals the CPU rule
// "d == 0 or |d| in range"; with flush-to-zero a flushed non-zero difference is rejected.
int sv_diff_ok(float x, float y, float d) {
    if (x == y) {
        return 1;
    }
    float m = fabs(d);
    return m >= SV_F32_FILTER_MIN && m <= SV_F32_FILTER_MAX;
}

// robust-math's `orient_filter_f32` (same expression, same bound) plus the flush-to-zero guards.
// Returns -1, 0, 1, or SV_UNCERTAIN.
int sv_filter_f32(float3 a, float3 b, float4 l, float3 o) {
    if (sv_is_subnormal(a.x) || sv_is_subnormal(a.y) || sv_is_subnormal(a.z) ||
        sv_is_subnormal(b.x) || sv_is_subnormal(b.y) || sv_is_subnormal(b.z) ||
        sv_is_subnormal(o.x) || sv_is_subnormal(o.y) || sv_is_subnormal(o.z) ||
        sv_is_subnormal(l.x) || sv_is_subnormal(l.y) || sv_is_subnormal(l.z) ||
        sv_is_subnormal(l.w)) {
        return SV_UNCERTAIN;
    }
    // For w other than 0 or 1, w*A is rounded, and when it cancels against L.xyz the error of V
    // is relative to |w*A|, not to |V|: the bound below would not hold (robust-math's rule).
    if (l.w != 0.0f && l.w != 1.0f) {
        return SV_UNCERTAIN;
    }
    float ex = a.x - b.x;
    float ey = a.y - b.y;
    float ez = a.z - b.z;
    float wx = l.w * a.x;
    float wy = l.w * a.y;
    float wz = l.w * a.z;
    if (l.w != 0.0f && ((a.x != 0.0f && fabs(wx) < SV_F32_PRODUCT_MIN) ||
                        (a.y != 0.0f && fabs(wy) < SV_F32_PRODUCT_MIN) ||
                        (a.z != 0.0f && fabs(wz) < SV_F32_PRODUCT_MIN))) {
        return SV_UNCERTAIN;
    }
    float vx = l.x - wx;
    float vy = l.y - wy;
    float vz = l.z - wz;
    float dx = o.x - a.x;
    float dy = o.y - a.y;
    float dz = o.z - a.z;
    if (!(sv_diff_ok(a.x, b.x, ex) && sv_diff_ok(a.y, b.y, ey) && sv_diff_ok(a.z, b.z, ez) &&
          sv_diff_ok(l.x, wx, vx) && sv_diff_ok(l.y, wy, vy) && sv_diff_ok(l.z, wz, vz) &&
          sv_diff_ok(o.x, a.x, dx) && sv_diff_ok(o.y, a.y, dy) && sv_diff_ok(o.z, a.z, dz))) {
        return SV_UNCERTAIN;
    }
    float p1 = ey * vz, q1 = ez * vy;
    float p2 = ez * vx, q2 = ex * vz;
    float p3 = ex * vy, q3 = ey * vx;
    float det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    float perm = ((fabs(p1) + fabs(q1)) * fabs(dx) + (fabs(p2) + fabs(q2)) * fabs(dy)) +
                 (fabs(p3) + fabs(q3)) * fabs(dz);
    if (!isfinite(perm)) {
        return SV_UNCERTAIN;
    }
    if (perm == 0.0f) {
        // Every term is exactly zero (no flushed term can reach 0: each is >= 2^-120).
        return 0;
    }
    if (perm < SV_F32_PERM_MIN) {
        return SV_UNCERTAIN;
    }
    if (fabs(det) > SV_F32_FILTER_EPS * perm) {
        return det > 0.0f ? 1 : -1;
    }
    return SV_UNCERTAIN;
}

#if defined(SHADOWVOL_EXACT_F64)
// robust-math's `orient_filter_f64`: same expression, same bound (F64_FILTER_EPS = 1e-15).
// Subnormal f32 inputs are left to the host (a flush-to-zero device may flush them on conversion).
int sv_filter_f64(float3 a32, float3 b32, float4 l32, float3 o32) {
    if (sv_is_subnormal(a32.x) || sv_is_subnormal(a32.y) || sv_is_subnormal(a32.z) ||
        sv_is_subnormal(b32.x) || sv_is_subnormal(b32.y) || sv_is_subnormal(b32.z) ||
        sv_is_subnormal(o32.x) || sv_is_subnormal(o32.y) || sv_is_subnormal(o32.z) ||
        sv_is_subnormal(l32.x) || sv_is_subnormal(l32.y) || sv_is_subnormal(l32.z) ||
        sv_is_subnormal(l32.w)) {
        return SV_UNCERTAIN;
    }
    double ax = (double)a32.x, ay = (double)a32.y, az = (double)a32.z;
    double lw = (double)l32.w;
    double ex = ax - (double)b32.x;
    double ey = ay - (double)b32.y;
    double ez = az - (double)b32.z;
    double vx = (double)l32.x - lw * ax;
    double vy = (double)l32.y - lw * ay;
    double vz = (double)l32.z - lw * az;
    double dx = (double)o32.x - ax;
    double dy = (double)o32.y - ay;
    double dz = (double)o32.z - az;
    double p1 = ey * vz, q1 = ez * vy;
    double p2 = ez * vx, q2 = ex * vz;
    double p3 = ex * vy, q3 = ey * vx;
    double det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    double perm = ((fabs(p1) + fabs(q1)) * fabs(dx) + (fabs(p2) + fabs(q2)) * fabs(dy)) +
                  (fabs(p3) + fabs(q3)) * fabs(dz);
    double bound = 1.0e-15 * perm;
    if (fabs(det) > bound) {
        return det > 0.0 ? 1 : -1;
    }
    if (perm == 0.0) {
        return 0;
    }
    return SV_UNCERTAIN;
}
#endif

int sv_filter(float3 a, float3 b, float4 l, float3 o) {
#if defined(SHADOWVOL_EXACT_F64)
    return sv_filter_f64(a, b, l, o);
#else
    return sv_filter_f32(a, b, l, o);
#endif
}

__kernel void silhouette(__global const float* restrict pos,
                         __global const uint* restrict edges,
                         __global const uint* restrict ovs,
                         __global const float* restrict lights,
                         const uint num_edges,
                         const uint num_lights,
                         const uint mode,
                         __global volatile uint* counts,
                         __global int* sil,
                         __global uint* unc,
                         const uint unc_capacity) {
    const uint e = (uint)get_global_id(0);
    const uint l = (uint)get_global_id(1);
    if (e >= num_edges || l >= num_lights) {
        return;
    }
    const size_t rec = 4 * (size_t)e;
    const size_t li = ((size_t)edges[rec + 3] * num_lights + l) * 4;
    const float4 light = (float4)(lights[li], lights[li + 1], lights[li + 2], lights[li + 3]);
    const uint ia = edges[rec];
    const uint ib = edges[rec + 1];
    const float3 pa = sv_load(pos, ia);
    const float3 pb = sv_load(pos, ib);
    const uint begin = edges[rec + 2];
    const uint end = edges[rec + 6];
    int m = 0;
    for (uint k = begin; k < end; ++k) {
        const uint io = ovs[k];
        const float3 po = sv_load(pos, io);
        int s;
        if (mode == MODE_ORIGINAL) {
            s = sv_sign_f32(pa, pb, light, po);
        } else if (mode == MODE_EXACT) {
            s = sv_filter(pa, pb, light, po);
            if (s == SV_UNCERTAIN) {
                const uint slot = atomic_inc(&counts[0]);
                if (slot < unc_capacity) {
                    unc[4 * (size_t)slot] = e;
                    unc[4 * (size_t)slot + 1] = k;
                    unc[4 * (size_t)slot + 2] = l;
                    unc[4 * (size_t)slot + 3] = 0u;
                }
                s = 0;
            }
        } else {
            // Canonical order (ascending ids) and the parity of the permutation from (a, b, o).
            float3 p0, p1, p2;
            int parity;
            if (io > ib) {
                p0 = pa; p1 = pb; p2 = po; parity = 1;
            } else if (io < ia) {
                p0 = po; p1 = pa; p2 = pb; parity = 1;
            } else {
                p0 = pa; p1 = po; p2 = pb; parity = -1;
            }
            const int s0 = sv_sign_f32(p0, p1, light, p2);
            if (mode == MODE_ROBUST) {
                const int s1 = sv_sign_f32(p1, p2, light, p0);
                const int s2 = sv_sign_f32(p2, p0, light, p1);
                s = (s0 == s1 && s1 == s2) ? s0 : 0;
            } else {
                s = s0;
            }
            s *= parity;
        }
        m += s;
    }
    if (m != 0) {
        const uint slot = atomic_inc(&counts[1]);
        const size_t at = 2 * (size_t)slot;
        sil[at] = (int)(l * num_edges + e);
        sil[at + 1] = m;
    }
}
