// The f64 certified filter of shadowvol-wgpu-compute's exact mode (needs SHADER_F64).
//
// Appended to shaders/silhouette.wgsl by the host, which then calls `filter_f64` where the
// kernel's `exact_filter` is marked `@exact-filter`. Self-contained, so it validates on its own.
//
// The same formula as robust-math's `orient_filter_f64`, operation for operation: f32 -> f64 is
// exact, `L.w * A` is exact in f64, so only the differences and the remaining products and sums
// round. The bound is 8x robust-math's F64_FILTER_EPS (1e-15, itself above the 9u that the
// straight evaluation needs): WGSL cannot forbid FMA contraction or reassociation, which remove
// roundings but do not add any, and the extra factor leaves room for them. Intermediates never
// leave the normal f64 range (products of f32 values stay above 2^-596), so flushing f64
// subnormals cannot occur; subnormal f32 inputs are rejected by the caller.

const GPU_F64_FILTER_EPS: f64 = 8e-15lf;
const UNCERTAIN_F64: i32 = 2;

fn filter_f64(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>, o: vec3<f32>) -> i32 {
    let ax = f64(a.x);
    let ay = f64(a.y);
    let az = f64(a.z);
    let lw = f64(l.w);
    let ex = ax - f64(b.x);
    let ey = ay - f64(b.y);
    let ez = az - f64(b.z);
    let vx = f64(l.x) - lw * ax;
    let vy = f64(l.y) - lw * ay;
    let vz = f64(l.z) - lw * az;
    let dx = f64(o.x) - ax;
    let dy = f64(o.y) - ay;
    let dz = f64(o.z) - az;
    let p1 = ey * vz;
    let q1 = ez * vy;
    let p2 = ez * vx;
    let q2 = ex * vz;
    let p3 = ex * vy;
    let q3 = ey * vx;
    let det = ((p1 - q1) * dx + (p2 - q2) * dy) + (p3 - q3) * dz;
    let perm = ((abs(p1) + abs(q1)) * abs(dx) + (abs(p2) + abs(q2)) * abs(dy)) + (abs(p3) + abs(q3)) * abs(dz);
    if abs(det) > GPU_F64_FILTER_EPS * perm {
        return select(-1, 1, det > 0.0lf);
    }
    if perm == 0.0lf {
        return 0;
    }
    return UNCERTAIN_F64;
}
