// Exact sign of det4(A, B, L, O) = | A 1 ; B 1 ; L ; O 1 | with u32 integer arithmetic only.
//
// Part of shadowvol-wgpu-compute. The CPU twin is `orient_int` in
// crates/wgpu-compute/src/twin.rs: keep the two in step, statement for statement.
//
// Why integers: WGSL compilers may contract (FMA) and reassociate float math, so no float
// operation here may influence the result. Every input is read as its bit pattern; every
// operation below is an exact (or intentionally wrapping, mod 2^32) u32 operation.
//
// Method: every finite f32 is (-1)^s * m * 2^(e - 150), m < 2^24 an integer (the hidden bit
// added for a normal number; a subnormal has exponent field 0 and is decoded as field 1 without
// the hidden bit). The determinant is the signed sum of 24 monomials, cofactor expansion along
// the light's row (XI_TERMS): 18 products of 3 inputs (l0, l1, l2 times two coordinates) and 6 of
// 4 (l3 times three coordinates); the 1s of the matrix are exact. Each product of mantissas is an
// integer below 2^96 (3 limbs), multiplied with 16-bit halves (WGSL has no u64). It is added to
// or subtracted from a two's complement fixed-point accumulator of 35 u32 limbs whose least
// significant bit is 2^-596 (the smallest exponent of a product of four f32s), at bit position
// sum(e) - 4; a 3-factor product gets the exact factor 1 = 1 * 2^(150 - 150) as its fourth.
// The carry (borrow) runs only as far as it propagates.
//
// Width: a product of four f32s is below 2^512 and of three below 2^384, so |det| < 2^515 and
// |det| * 2^596 < 2^1111: 1112 bits hold it in two's complement, 35 limbs = 1120 bits do. Every
// shifted product ends below bit 1108 (limb 34), so no write leaves the array; the arithmetic is
// mod 2^1120, and the final sum, hence its sign, is exact.
//
// The convention is robust-math's: the result is sgn(((A - B) x V) . (O - A)), V = L.xyz - L.w A,
// the same value as `orient_exact`, for every finite input (subnormals, zeros, f32::MAX, any w).
// For NaN or infinite inputs the result is unspecified, but every index stays in bounds.

// Pipeline-overridable: true leaves `orient_int` out of the pipeline (the host's fallback line
// returns UNCERTAIN first), so a kernel that reaches it only for rare pairs can run it in a
// separate dispatch: compiled in, it slows the whole kernel even where no invocation reaches it.
override DEFER_INT: bool = false;

const XI_LIMBS: u32 = 35u;
// Index of the pseudo-input "exact 1" (mantissa 1, exponent field 150) in the decoded arrays.
const XI_ONE: u32 = 13u;

// The 24 monomials of det4: bits 0-3, 4-7, 8-11, 12-15 are the factors (inputs a0 a1 a2 = 0 1 2,
// b = 3 4 5, o = 6 7 8, l = 9 10 11 12, XI_ONE = 13), bit 16 set means subtract.
// det4 = l0 C0 - l1 C1 + l2 C2 - l3 det3(A, B, O), C_k the 3x3 minors of |A 1; B 1; O 1|.
const XI_TERMS = array<u32, 24>(
    0x0d519u, // + l0 a1 b2
    0x1d429u, // - l0 a2 b1
    0x1d819u, // - l0 a1 o2
    0x0d729u, // + l0 a2 o1
    0x0d849u, // + l0 b1 o2
    0x1d759u, // - l0 b2 o1
    0x1d50au, // - l1 a0 b2
    0x0d32au, // + l1 a2 b0
    0x0d80au, // + l1 a0 o2
    0x1d62au, // - l1 a2 o0
    0x1d83au, // - l1 b0 o2
    0x0d65au, // + l1 b2 o0
    0x0d40bu, // + l2 a0 b1
    0x1d31bu, // - l2 a1 b0
    0x1d70bu, // - l2 a0 o1
    0x0d61bu, // + l2 a1 o0
    0x0d73bu, // + l2 b0 o1
    0x1d64bu, // - l2 b1 o0
    0x1840cu, // - l3 a0 b1 o2
    0x0750cu, // + l3 a0 b2 o1
    0x0831cu, // + l3 a1 b0 o2
    0x1651cu, // - l3 a1 b2 o0
    0x1732cu, // - l3 a2 b0 o1
    0x0642cu, // + l3 a2 b1 o0
);

// The exact 64-bit product a * b as (low, high) u32s, from 16-bit halves (Hacker's Delight
// mulhu): no partial sum can exceed 2^32 - 1.
fn xi_mul32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let t = a1 * b0 + (p00 >> 16u);
    let w = (t & 0xffffu) + a0 * b1;
    let hi = a1 * b1 + (t >> 16u) + (w >> 16u);
    let lo = (w << 16u) | (p00 & 0xffffu);
    return vec2<u32>(lo, hi);
}

// The exact product p * m for p < 2^72 (3 limbs, least significant first) and m < 2^24: it is
// below 2^96, so the top limb p.z * m + carries cannot wrap.
fn xi_mul96(p: vec3<u32>, m: u32) -> vec3<u32> {
    let x = xi_mul32(p.x, m);
    let y = xi_mul32(p.y, m);
    let r1 = x.y + y.x;
    let c = select(0u, 1u, r1 < y.x);
    return vec3<u32>(x.x, r1, y.y + p.z * m + c);
}

// The exact sign of det4(A, B, L, O): -1, 0 or +1, equal to robust-math's `orient_exact`.
fn orient_int(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>, o: vec3<f32>) -> i32 {
    var bits = array<u32, 13>(
        bitcast<u32>(a.x), bitcast<u32>(a.y), bitcast<u32>(a.z),
        bitcast<u32>(b.x), bitcast<u32>(b.y), bitcast<u32>(b.z),
        bitcast<u32>(o.x), bitcast<u32>(o.y), bitcast<u32>(o.z),
        bitcast<u32>(l.x), bitcast<u32>(l.y), bitcast<u32>(l.z), bitcast<u32>(l.w),
    );
    // Decode: value = (-1)^sg * man * 2^(ex - 150); subnormals (field 0) use ex = 1, no hidden bit.
    var man = array<u32, 14>();
    var ex = array<u32, 14>();
    var sg = array<u32, 14>();
    for (var i = 0u; i < 13u; i++) {
        let u = bits[i];
        let field = (u >> 23u) & 0xffu;
        man[i] = (u & 0x7fffffu) | select(0u, 0x800000u, field != 0u);
        ex[i] = max(field, 1u);
        sg[i] = u >> 31u;
    }
    man[XI_ONE] = 1u;
    ex[XI_ONE] = 150u;
    sg[XI_ONE] = 0u;

    var terms = XI_TERMS;
    // Two's complement accumulator, little-endian limbs; bit 0 is worth 2^-596.
    var acc = array<u32, 35>();
    for (var t = 0u; t < 24u; t++) {
        let code = terms[t];
        let i0 = code & 15u;
        let i1 = (code >> 4u) & 15u;
        let i2 = (code >> 8u) & 15u;
        let i3 = (code >> 12u) & 15u;
        if man[i0] == 0u || man[i1] == 0u || man[i2] == 0u || man[i3] == 0u {
            continue;
        }
        // The mantissa product, < 2^96.
        var p = xi_mul96(vec3<u32>(xi_mul32(man[i0], man[i1]), 0u), man[i2]);
        if i3 != XI_ONE {
            p = xi_mul96(p, man[i3]);
        }
        // Its place in the accumulator: 2^(sum ex - 600) = 2^-596 * 2^pos.
        let pos = ex[i0] + ex[i1] + ex[i2] + ex[i3] - 4u;
        let k = pos >> 5u;
        let sh = pos & 31u;
        let r = 31u - sh; // (x >> 1) >> r is x >> (32 - sh), also for sh = 0
        var s = array<u32, 4>(
            p.x << sh,
            (p.y << sh) | ((p.x >> 1u) >> r),
            (p.z << sh) | ((p.y >> 1u) >> r),
            (p.z >> 1u) >> r,
        );
        let neg = ((code >> 16u) ^ sg[i0] ^ sg[i1] ^ sg[i2] ^ sg[i3]) != 0u;
        var c = 0u;
        for (var j = 0u; j < 4u; j++) {
            let x = acc[k + j];
            let q = s[j];
            if neg {
                let d = x - q;
                acc[k + j] = d - c;
                c = select(0u, 1u, x < q || d < c);
            } else {
                let d = x + q;
                let e = d + c;
                acc[k + j] = e;
                c = select(0u, 1u, d < q || e < c);
            }
        }
        // The carry (borrow) runs only as far as it propagates.
        var i = k + 4u;
        while c != 0u && i < XI_LIMBS {
            let x = acc[i];
            if neg {
                acc[i] = x - 1u;
                c = select(0u, 1u, x == 0u);
            } else {
                acc[i] = x + 1u;
                c = select(0u, 1u, x == 0xffffffffu);
            }
            i++;
        }
    }

    if (acc[XI_LIMBS - 1u] >> 31u) != 0u {
        return -1;
    }
    var nz = 0u;
    for (var i = 0u; i < XI_LIMBS; i++) {
        nz |= acc[i];
    }
    return select(0, 1, nz != 0u);
}
