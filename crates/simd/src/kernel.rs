//! The kernels, generic over the lane [`Level`]. Each is `#[inline(always)]` so that it is
//! compiled inside the per-level entry points of `dispatch.rs` (one of them a
//! `#[target_feature(enable = "avx2")]` function), with every lane operation inlined.
//!
//! Three kernels:
//!
//! * [`tri_signs`]: one sign per canonical triangle and light (`robust`, `ordered`, `exact`).
//!   Because the canonical triangle of every (edge, OV) pair is the triangle itself, its sign
//!   times the pair's permutation parity is exactly `ov_sign` of the reference, so each triangle
//!   is evaluated once instead of once per edge.
//! * [`edge_sums`]: `m(e) = Σ sign(t) · parity` over the triangles of each edge.
//! * [`edge_original`]: `original` mode, per (edge, OV), sharing `V`, `A − B` and `N`
//!   between the two OVs of a manifold edge.

use crate::lanes::{Level, F32V, F64V};
use crate::layout::{Layout, LANES, ODD};
use shadowvol_robust_math::{orient_exact, sign_f32, Accuracy, F64_FILTER_EPS};
use std::ops::Range;

/// Gathers the positions of the 8 vertex ids `idx[..8]` from the SoA arrays.
///
/// # Safety
/// `idx.len() >= 8` and every id is a vertex of `lay` (guaranteed for the layout's own index
/// arrays by `Layout::build`).
#[inline(always)]
unsafe fn gather<Lv: Level>(lay: &Layout, idx: &[u32]) -> [Lv::F; 3] {
    // SAFETY: forwarded from the caller; the position arrays have the vertex count as length.
    unsafe {
        if USE_SOA_GATHER {
            [
                Lv::F::gather(&lay.xs, idx),
                Lv::F::gather(&lay.ys, idx),
                Lv::F::gather(&lay.zs, idx),
            ]
        } else {
            Lv::gather_xyz(&lay.xyz, idx)
        }
    }
}

/// Gather from the three SoA arrays (`true`) or load 16-byte records and transpose (`false`).
const USE_SOA_GATHER: bool = false;

#[inline(always)]
fn splat4<F: F32V>(l: [f32; 4]) -> [F; 4] {
    [
        F::splat(l[0]),
        F::splat(l[1]),
        F::splat(l[2]),
        F::splat(l[3]),
    ]
}

/// `((A − B) × V)·(O − A)` with exactly the operations (and order) of [`sign_f32`]; its sign
/// is `sign_f32(A, B, L, O)` in every lane.
#[inline(always)]
fn plane<F: F32V>(a: &[F; 3], b: &[F; 3], l: &[F; 4], o: &[F; 3]) -> F {
    let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let n = edge_normal(l, a, &e);
    off_plane(&n, a, o)
}

/// `N = (A − B) × V` with `V = L.xyz − L.w·A`, given `E = A − B`: the first operations of
/// [`sign_f32`], in its order (shared by both OVs of an edge in `original`).
#[inline(always)]
fn edge_normal<F: F32V>(lv: &[F; 4], a: &[F; 3], e: &[F; 3]) -> [F; 3] {
    let v = [
        lv[0] - lv[3] * a[0],
        lv[1] - lv[3] * a[1],
        lv[2] - lv[3] * a[2],
    ];
    [
        e[1] * v[2] - e[2] * v[1],
        e[2] * v[0] - e[0] * v[2],
        e[0] * v[1] - e[1] * v[0],
    ]
}

/// `N·(O − A)`: the last operations of [`sign_f32`], in its order.
#[inline(always)]
fn off_plane<F: F32V>(n: &[F; 3], a: &[F; 3], o: &[F; 3]) -> F {
    let d = [o[0] - a[0], o[1] - a[1], o[2] - a[2]];
    (n[0] * d[0] + n[1] * d[1]) + n[2] * d[2]
}

/// The certified `f64` filter of `orient_filter_f64`, four lanes at a time: the same formula,
/// the same evaluation order and the same constant [`F64_FILTER_EPS`], so each certified lane
/// carries the proof of the scalar filter. Returns `(positive, negative, uncertain)` bits.
#[inline(always)]
fn filter_f64<D: F64V>(a: [D; 3], b: [D; 3], l: [D; 4], o: [D; 3]) -> (u32, u32, u32) {
    let (ax, ay, az) = (a[0], a[1], a[2]);
    let lw = l[3];
    let ex = ax - b[0];
    let ey = ay - b[1];
    let ez = az - b[2];
    let vx = l[0] - lw * ax;
    let vy = l[1] - lw * ay;
    let vz = l[2] - lw * az;
    let dx = o[0] - ax;
    let dy = o[1] - ay;
    let dz = o[2] - az;
    let (p1, q1) = (ey * vz, ez * vy);
    let (p2, q2) = (ez * vx, ex * vz);
    let (p3, q3) = (ex * vy, ey * vx);
    let det = (p1 - q1) * dx + (p2 - q2) * dy + (p3 - q3) * dz;
    let perm = (p1.abs() + q1.abs()) * dx.abs()
        + (p2.abs() + q2.abs()) * dy.abs()
        + (p3.abs() + q3.abs()) * dz.abs();
    let bound = D::splat(F64_FILTER_EPS) * perm;
    // |det| > bound with bound >= 0: det > bound (positive) or -det > bound (negative).
    let pos = det.gt_bits(bound);
    let neg = (D::splat(0.0) - det).gt_bits(bound);
    let zero = perm.zero_bits();
    (pos, neg, !(pos | neg | zero) & 0xF)
}

/// Byte `i` = 1 where bit `i` of the index is set (sign bytes of positive lanes).
const POS_BYTES: [u64; 256] = {
    let mut t = [0u64; 256];
    let mut i = 0;
    while i < 256 {
        let mut b = 0;
        while b < 8 {
            if i & (1 << b) != 0 {
                t[i] |= 1 << (8 * b);
            }
            b += 1;
        }
        i += 1;
    }
    t
};

/// Per-lane `i8` signs from disjoint positive / negative bit masks.
#[inline(always)]
fn sign_bytes(pos: u32, neg: u32) -> [u8; 8] {
    // Negative lanes become 0xFF (= -1i8) = 0xFF * 1.
    (POS_BYTES[(pos & 0xFF) as usize] | (POS_BYTES[(neg & 0xFF) as usize] * 0xFF)).to_le_bytes()
}

/// Signs of the canonical triangles in `blocks` (blocks of 8) for every light.
///
/// `out[l / PACK]` receives the signs of this range for light `l` (`blocks.len() * 8` records of
/// [`PACK`] bytes; padding lanes get 0). Returns the number of (triangle, light) evaluations the `f64` filter could not
/// certify (exact mode), which were decided with the scalar exact predicate.
#[inline(always)]
pub(crate) fn tri_signs<Lv: Level>(
    lay: &Layout,
    blocks: Range<usize>,
    lights: &[[f32; 4]],
    mode: Accuracy,
    out: &mut [&mut [i8]],
) -> u64 {
    let mut uncertain = 0u64;
    let b0 = blocks.start;
    assert!(
        blocks.end * LANES <= lay.t0.len()
            && out.len() == lights.len().div_ceil(PACK)
            && out.iter().all(|o| o.len() == blocks.len() * LANES * PACK)
    );
    // One light: its lanes made once per call rather than once per block (no allocation).
    let one32 = match lights {
        [light] => Some(splat4::<Lv::F>(*light)),
        _ => None,
    };
    let one64: Option<[Lv::D; 4]> = match lights {
        [light] if mode == Accuracy::Exact => {
            Some(std::array::from_fn(|c| Lv::D::splat(f64::from(light[c]))))
        }
        _ => None,
    };
    for blk in blocks {
        let t = blk * LANES;
        let valid: u32 = if t + LANES <= lay.tri_count {
            0xFF
        } else {
            (1u32 << (lay.tri_count - t)) - 1
        };
        let dst = (blk - b0) * LANES;
        if let (Accuracy::Ordered | Accuracy::Original, 0xFF, Some(lv)) = (mode, valid, one32) {
            // One light, a full block (the common case): `plane`'s operations with fewer vectors
            // live (O is loaded once N exists), and the signs stored as one vector of
            // `i32` records: byte 0 of each 4-byte record is the sign, the other three bytes
            // (lights 1-3 of the pack) are unused with one light.
            // SAFETY: as below.
            let (a, b) = unsafe {
                (
                    gather::<Lv>(lay, &lay.t0[t..]),
                    gather::<Lv>(lay, &lay.t1[t..]),
                )
            };
            let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            let n = edge_normal(&lv, &a, &e);
            // SAFETY: as below.
            let o = unsafe { gather::<Lv>(lay, &lay.t2[t..]) };
            let m = off_plane(&n, &a, &o).signum0().to_i32();
            let pack = &mut out[0][dst * PACK..(dst + LANES) * PACK];
            for (record, s) in pack.chunks_exact_mut(PACK).zip(m) {
                for (byte, x) in record.iter_mut().zip(s.to_le_bytes()) {
                    *byte = x as i8;
                }
            }
            continue;
        }
        // SAFETY: `t + 8 <= t0.len()` (asserted above), and the layout's ids are in range.
        let (a, b, o) = unsafe {
            (
                gather::<Lv>(lay, &lay.t0[t..]),
                gather::<Lv>(lay, &lay.t1[t..]),
                gather::<Lv>(lay, &lay.t2[t..]),
            )
        };
        match mode {
            Accuracy::Ordered | Accuracy::Original => {
                for (l, light) in lights.iter().enumerate() {
                    let (pos, neg) = plane(&a, &b, &splat4(*light), &o).sign_bits();
                    write_signs(out, l, dst, pos & valid, neg & valid);
                }
            }
            Accuracy::Robust => {
                for (l, light) in lights.iter().enumerate() {
                    let lv = splat4(*light);
                    let (pa, na) = plane(&a, &b, &lv, &o).sign_bits();
                    let (pb, nb) = plane(&b, &o, &lv, &a).sign_bits();
                    let (pc, nc) = plane(&o, &a, &lv, &b).sign_bits();
                    write_signs(out, l, dst, pa & pb & pc & valid, na & nb & nc & valid);
                }
            }
            Accuracy::Exact => {
                let (a, b, o) = (widen3::<Lv>(&a), widen3::<Lv>(&b), widen3::<Lv>(&o));
                for (l, light) in lights.iter().enumerate() {
                    let lv: [Lv::D; 4] = one64.unwrap_or_else(|| {
                        std::array::from_fn(|c| Lv::D::splat(f64::from(light[c])))
                    });
                    let (p_lo, n_lo, u_lo) = filter_f64(a.0, b.0, lv, o.0);
                    let (p_hi, n_hi, u_hi) = filter_f64(a.1, b.1, lv, o.1);
                    let (mut pos, mut neg) = (p_lo | p_hi << 4, n_lo | n_hi << 4);
                    let unc = (u_lo | u_hi << 4) & valid;
                    if unc != 0 {
                        uncertain += u64::from(unc.count_ones());
                        let mut bits = unc;
                        while bits != 0 {
                            let i = bits.trailing_zeros() as usize;
                            bits &= bits - 1;
                            let s = orient_exact(
                                lay.pos(lay.t0[t + i]),
                                lay.pos(lay.t1[t + i]),
                                *light,
                                lay.pos(lay.t2[t + i]),
                            );
                            if s > 0 {
                                pos |= 1 << i;
                            } else if s < 0 {
                                neg |= 1 << i;
                            }
                        }
                    }
                    write_signs(out, l, dst, pos & valid, neg & valid);
                }
            }
        }
    }
    uncertain
}

/// Lanes 0..4 and 4..8 of a point vector, widened to `f64`. (A function, not a closure: closures
/// are not `#[inline(always)]`, and an intrinsic left in a non-inlined closure is not inlined.)
#[inline(always)]
fn widen3<Lv: Level>(p: &[Lv::F; 3]) -> ([Lv::D; 3], [Lv::D; 3]) {
    let (x, y, z) = (Lv::widen(p[0]), Lv::widen(p[1]), Lv::widen(p[2]));
    ([x.0, y.0, z.0], [x.1, y.1, z.1])
}

#[inline(always)]
fn write_signs(out: &mut [&mut [i8]], l: usize, dst: usize, pos: u32, neg: u32) {
    let bytes = sign_bytes(pos, neg);
    let pack = &mut out[l / PACK][dst * PACK..(dst + LANES) * PACK];
    for (i, b) in bytes.into_iter().enumerate() {
        pack[i * PACK + l % PACK] = b as i8;
    }
}

/// Lights per sign pack: the sign of triangle slot `t` for light `l` is byte `l % 4` of the
/// 4-byte record `t` in pack `l / 4`, so one 32-bit load (or gather) serves four lights.
pub(crate) const PACK: usize = 4;

/// `±s` by the parity bit of a triangle reference.
#[inline(always)]
fn signed(s: i8, tref: u32) -> i32 {
    let k = (tref >> 31) as i32; // 1 for odd parity
    (i32::from(s) ^ -k) + k
}

/// Pushes `base + i` for the non-zero lanes of `m`.
#[inline(always)]
fn push_nonzero(sil: &mut Vec<u32>, m: &[i32; LANES], base: usize) {
    if *m != [0; LANES] {
        for (i, &mi) in m.iter().enumerate() {
            if mi != 0 {
                sil.push((base + i) as u32);
            }
        }
    }
}

/// Pushes `base + i` for the set bits `i` of `bits`.
#[inline(always)]
fn push_bits(sil: &mut Vec<u32>, mut bits: u32, base: usize) {
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        sil.push((base + i) as u32);
    }
}

/// Multiplicities of the edges in `blocks` from the triangle signs (`robust`, `ordered`,
/// `exact`), scalar. Light `l`'s sign of this object's triangle slot `t` is
/// `signs[bases[l / PACK] + t * PACK + l % PACK]`; `out[l]` receives this range's
/// multiplicities; `sil[l]` collects `edge_base + e` for `m != 0`.
///
/// # Panics
/// If a slice is shorter than described.
pub(crate) fn edge_sums(
    lay: &Layout,
    blocks: Range<usize>,
    signs: &[i8],
    bases: &[usize],
    out: &mut [&mut [i32]],
    sil: &mut [Vec<u32>],
    edge_base: usize,
) {
    let e_start = blocks.start * LANES;
    // Every triangle reference of the layout is < tri_count.
    assert!(bases
        .iter()
        .all(|&b| b + lay.tri_count * PACK <= signs.len()));
    assert!(bases.len() == out.len().div_ceil(PACK));
    for blk in blocks {
        let e0 = blk * LANES;
        if lay.block_fast[blk] {
            // Block-outer, light-inner: the block's triangle references are read once.
            let (ta, tb) = (&lay.tri_a[e0..e0 + LANES], &lay.tri_b[e0..e0 + LANES]);
            for (l, out) in out.iter_mut().enumerate() {
                let base = bases[l / PACK] + l % PACK;
                let s = &signs[base..base + (lay.tri_count - 1) * PACK + 1];
                let dst = &mut out[e0 - e_start..e0 - e_start + LANES];
                let mut any = 0;
                for ((d, &t1), &t2) in dst.iter_mut().zip(ta).zip(tb) {
                    let (i1, i2) = ((t1 & !ODD) as usize * PACK, (t2 & !ODD) as usize * PACK);
                    debug_assert!(i1 < s.len() && i2 < s.len());
                    // SAFETY: `Layout::build` stores only triangle slots < tri_count, and
                    // `s` covers slot tri_count - 1 (asserted above).
                    let (s1, s2) = unsafe { (*s.get_unchecked(i1), *s.get_unchecked(i2)) };
                    let m = signed(s1, t1) + signed(s2, t2);
                    *d = m;
                    any |= m;
                }
                if any != 0 {
                    for (i, &m) in dst.iter().enumerate() {
                        if m != 0 {
                            sil[l].push((edge_base + e0 + i) as u32);
                        }
                    }
                }
            }
        } else {
            edge_sums_general(lay, e0, signs, bases, out, sil, edge_base, e_start);
        }
    }
}

/// The general (CSR) path of [`edge_sums`] for the block starting at edge `e0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn edge_sums_general(
    lay: &Layout,
    e0: usize,
    signs: &[i8],
    bases: &[usize],
    out: &mut [&mut [i32]],
    sil: &mut [Vec<u32>],
    edge_base: usize,
    e_start: usize,
) {
    for e in e0..(e0 + LANES).min(lay.edge_count) {
        let r = lay.ov_offsets[e] as usize..lay.ov_offsets[e + 1] as usize;
        for (l, out) in out.iter_mut().enumerate() {
            let base = bases[l / PACK] + l % PACK;
            let m: i32 = lay.ov_tri[r.clone()]
                .iter()
                .map(|&t| signed(signs[base + (t & !ODD) as usize * PACK], t))
                .sum();
            out[e - e_start] = m;
            if m != 0 {
                sil[l].push((edge_base + e) as u32);
            }
        }
    }
}

/// [`edge_sums`] with 8 edges per AVX2 vector: per block, two 32-bit gathers per pack of four
/// lights fetch the signs of both triangles of 8 edges for all four lights. Identical results.
///
/// # Safety
/// The CPU must support AVX2, and `signs.len()` must be below `i32::MAX`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn edge_sums_avx2(
    lay: &Layout,
    blocks: Range<usize>,
    signs: &[i8],
    bases: &[usize],
    out: &mut [&mut [i32]],
    sil: &mut [Vec<u32>],
    edge_base: usize,
) {
    use std::arch::x86_64::*;
    let e_start = blocks.start * LANES;
    assert!(signs.len() < i32::MAX as usize);
    assert!(bases
        .iter()
        .all(|&b| b + lay.tri_count * PACK <= signs.len()));
    assert!(bases.len() == out.len().div_ceil(PACK));
    let mask = _mm256_set1_epi32(!ODD as i32);
    if let ([base], [out0], [sil0]) = (bases, &mut *out, &mut *sil) {
        // One light (the common case): the loop below without the pack and lane loops, so the
        // gathers of consecutive blocks overlap. Byte 0 of each record is the sign.
        let b = _mm256_set1_epi32(*base as i32);
        for blk in blocks.clone() {
            let e0 = blk * LANES;
            if !lay.block_fast[blk] {
                let mut one = [&mut **out0];
                edge_sums_general(
                    lay,
                    e0,
                    signs,
                    bases,
                    &mut one,
                    std::slice::from_mut(sil0),
                    edge_base,
                    e_start,
                );
                continue;
            }
            // SAFETY: fast blocks are full, so e0 + 8 <= tri_a.len() = tri_b.len(); every index
            // is base + 4 * slot with slot < tri_count, inside `signs` (asserted above).
            let (g1, g2, k1, k2) = unsafe {
                let t1 = _mm256_loadu_si256(lay.tri_a[e0..e0 + LANES].as_ptr().cast());
                let t2 = _mm256_loadu_si256(lay.tri_b[e0..e0 + LANES].as_ptr().cast());
                let i1 = _mm256_add_epi32(b, _mm256_slli_epi32::<2>(_mm256_and_si256(t1, mask)));
                let i2 = _mm256_add_epi32(b, _mm256_slli_epi32::<2>(_mm256_and_si256(t2, mask)));
                let p = signs.as_ptr().cast::<i32>();
                (
                    _mm256_i32gather_epi32::<1>(p, i1),
                    _mm256_i32gather_epi32::<1>(p, i2),
                    _mm256_srai_epi32::<31>(t1),
                    _mm256_srai_epi32::<31>(t2),
                )
            };
            let s1 = _mm256_srai_epi32::<24>(_mm256_slli_epi32::<24>(g1));
            let s2 = _mm256_srai_epi32::<24>(_mm256_slli_epi32::<24>(g2));
            let s1 = _mm256_sub_epi32(_mm256_xor_si256(s1, k1), k1);
            let s2 = _mm256_sub_epi32(_mm256_xor_si256(s2, k2), k2);
            let m = _mm256_add_epi32(s1, s2);
            let dst = &mut out0[e0 - e_start..e0 - e_start + LANES];
            // SAFETY: `dst` holds 8 i32 (written once, not read back here).
            unsafe { crate::lanes::stream_i32x8(dst.as_mut_ptr().cast(), m) };
            let zero = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
                m,
                _mm256_setzero_si256(),
            ))) as u32;
            push_bits(sil0, !zero & 0xFF, edge_base + e0);
        }
        _mm_sfence();
        return;
    }
    for blk in blocks {
        let e0 = blk * LANES;
        if lay.block_fast[blk] {
            // SAFETY: fast blocks are full, so e0 + 8 <= tri_a.len() = tri_b.len().
            let (t1, t2) = unsafe {
                (
                    _mm256_loadu_si256(lay.tri_a[e0..e0 + LANES].as_ptr().cast()),
                    _mm256_loadu_si256(lay.tri_b[e0..e0 + LANES].as_ptr().cast()),
                )
            };
            // Parity masks: -1 for odd (bit 31 set), 0 for even. Byte offsets of the records.
            let (k1, k2) = (_mm256_srai_epi32::<31>(t1), _mm256_srai_epi32::<31>(t2));
            let i1 = _mm256_slli_epi32::<2>(_mm256_and_si256(t1, mask));
            let i2 = _mm256_slli_epi32::<2>(_mm256_and_si256(t2, mask));
            for (pack, &base) in bases.iter().enumerate() {
                let b = _mm256_set1_epi32(base as i32);
                // SAFETY: every index is base + 4 * slot with slot < tri_count, and the 4-byte
                // record there is inside `signs` (asserted above); gathers need no alignment.
                let (g1, g2) = unsafe {
                    let p = signs.as_ptr().cast::<i32>();
                    (
                        _mm256_i32gather_epi32::<1>(p, _mm256_add_epi32(b, i1)),
                        _mm256_i32gather_epi32::<1>(p, _mm256_add_epi32(b, i2)),
                    )
                };
                let lights = (out.len() - pack * PACK).min(PACK);
                for lane in 0..lights {
                    let l = pack * PACK + lane;
                    // Byte `lane` of each record, sign-extended.
                    let shift = _mm_cvtsi32_si128((24 - 8 * lane) as i32);
                    let s1 = _mm256_srai_epi32::<24>(_mm256_sll_epi32(g1, shift));
                    let s2 = _mm256_srai_epi32::<24>(_mm256_sll_epi32(g2, shift));
                    // Negate where the parity is odd.
                    let s1 = _mm256_sub_epi32(_mm256_xor_si256(s1, k1), k1);
                    let s2 = _mm256_sub_epi32(_mm256_xor_si256(s2, k2), k2);
                    let m = _mm256_add_epi32(s1, s2);
                    let dst = &mut out[l][e0 - e_start..e0 - e_start + LANES];
                    // SAFETY: `dst` holds 8 i32; unaligned store. (Not a streaming store: with
                    // several lights' rows, half a cache line each per block, those thrash the
                    // write-combining buffers.)
                    unsafe { _mm256_storeu_si256(dst.as_mut_ptr().cast(), m) };
                    let zero = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
                        m,
                        _mm256_setzero_si256(),
                    ))) as u32;
                    push_bits(&mut sil[l], !zero & 0xFF, edge_base + e0);
                }
            }
        } else {
            edge_sums_general(lay, e0, signs, bases, out, sil, edge_base, e_start);
        }
    }
    // The streaming stores above are weakly ordered: make them visible before the caller
    // (another thread, after rayon's join) reads the output.
    _mm_sfence();
}

/// `original` mode for the edges in `blocks`: per (edge, OV) `sign_f32(A, B, L, O)`, 8 edges per
/// vector in fast blocks. Output as in [`edge_sums`].
#[inline(always)]
pub(crate) fn edge_original<Lv: Level>(
    lay: &Layout,
    blocks: Range<usize>,
    lights: &[[f32; 4]],
    out: &mut [&mut [i32]],
    sil: &mut [Vec<u32>],
    edge_base: usize,
) {
    if let ([light], [out0], [sil0]) = (lights, &mut *out, &mut *sil) {
        edge_original_one::<Lv>(lay, blocks, *light, out0, sil0, edge_base);
        return;
    }
    let e_start = blocks.start * LANES;
    for blk in blocks {
        let e0 = blk * LANES;
        if lay.block_fast[blk] {
            // Fast blocks are full: e0 + 8 <= edge_count = ea.len() (and eb, eo1, eo2).
            let idx =
                |v: &[u32]| -> [u32; LANES] { v[e0..e0 + LANES].try_into().unwrap_or([0; LANES]) };
            let (ia, ib, i1, i2) = (idx(&lay.ea), idx(&lay.eb), idx(&lay.eo1), idx(&lay.eo2));
            // SAFETY: 8 ids each, all vertices of the layout (`Layout::build`).
            let (a, b, o1, o2) = unsafe {
                (
                    gather::<Lv>(lay, &ia),
                    gather::<Lv>(lay, &ib),
                    gather::<Lv>(lay, &i1),
                    gather::<Lv>(lay, &i2),
                )
            };
            let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            for (l, light) in lights.iter().enumerate() {
                let lv = splat4::<Lv::F>(*light);
                // The operations of `sign_f32`, with V, A - B and N shared by both OVs.
                let n = edge_normal(&lv, &a, &e);
                let d1 = off_plane(&n, &a, &o1);
                let d2 = off_plane(&n, &a, &o2);
                let m = (d1.signum0() + d2.signum0()).to_i32();
                out[l][e0 - e_start..e0 - e_start + LANES].copy_from_slice(&m);
                push_nonzero(&mut sil[l], &m, edge_base + e0);
            }
        } else {
            original_general_block(lay, e0, lights, out, sil, edge_base, e_start);
        }
    }
}

/// `original` for the block starting at edge `e0` through the general (CSR) path, scalar: any
/// number of OVs per edge. Output as in [`edge_original`].
#[inline(always)]
fn original_general_block(
    lay: &Layout,
    e0: usize,
    lights: &[[f32; 4]],
    out: &mut [&mut [i32]],
    sil: &mut [Vec<u32>],
    edge_base: usize,
    e_start: usize,
) {
    for e in e0..(e0 + LANES).min(lay.edge_count) {
        let [a, b] = lay.edges[e];
        let (pa, pb) = (lay.pos(a), lay.pos(b));
        let ovs = &lay.ovs[lay.ov_offsets[e] as usize..lay.ov_offsets[e + 1] as usize];
        for (l, light) in lights.iter().enumerate() {
            let m: i32 = ovs
                .iter()
                .map(|&o| i32::from(sign_f32(pa, pb, *light, lay.pos(o))))
                .sum();
            out[l][e - e_start] = m;
            if m != 0 {
                sil[l].push((edge_base + e) as u32);
            }
        }
    }
}

/// [`edge_original`] for one light (the common case): the same operations as the general
/// loop, ordered so that fewer vectors are live at once (the OVs are loaded only once `N`
/// exists, which spares the general loop's register spills), with the light's lanes made
/// once and the output written with streaming stores (one output row, written once).
#[inline(always)]
fn edge_original_one<Lv: Level>(
    lay: &Layout,
    blocks: Range<usize>,
    light: [f32; 4],
    out: &mut [i32],
    sil: &mut Vec<u32>,
    edge_base: usize,
) {
    let e_start = blocks.start * LANES;
    let lv = splat4::<Lv::F>(light);
    for blk in blocks {
        let e0 = blk * LANES;
        if !lay.block_fast[blk] {
            original_general_block(
                lay,
                e0,
                &[light],
                &mut [&mut *out],
                std::slice::from_mut(sil),
                edge_base,
                e_start,
            );
            continue;
        }
        // Fast blocks are full: e0 + 8 <= edge_count = ea.len() (and eb, eo1, eo2).
        let idx =
            |v: &[u32]| -> [u32; LANES] { v[e0..e0 + LANES].try_into().unwrap_or([0; LANES]) };
        // SAFETY: 8 ids each, all vertices of the layout (`Layout::build`).
        let (a, b) = unsafe {
            (
                gather::<Lv>(lay, &idx(&lay.ea)),
                gather::<Lv>(lay, &idx(&lay.eb)),
            )
        };
        let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let n = edge_normal(&lv, &a, &e);
        // SAFETY: as above.
        let o1 = unsafe { gather::<Lv>(lay, &idx(&lay.eo1)) };
        let d1 = off_plane(&n, &a, &o1);
        // SAFETY: as above.
        let o2 = unsafe { gather::<Lv>(lay, &idx(&lay.eo2)) };
        let d2 = off_plane(&n, &a, &o2);
        let nz =
            (d1.signum0() + d2.signum0()).store_i32(&mut out[e0 - e_start..e0 - e_start + LANES]);
        push_bits(sil, nz, edge_base + e0);
    }
    // Streaming stores (`store_i32`) are weakly ordered: make them visible before the caller
    // (another thread, after rayon's join) reads the output.
    Lv::store_fence();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::Wide;
    use shadowvol_robust_math::orient_filter_f64;

    /// The 4-lane filter makes exactly the decisions of the scalar `orient_filter_f64`
    /// (certified sign, certified zero, or uncertain) on random and on coplanar inputs.
    #[test]
    fn vector_filter_mirrors_scalar_filter() {
        let mut x = 0x9E37_79B9u32;
        let mut rnd = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        let mut uncertain_seen = 0;
        for round in 0..4000 {
            let mut lanes = [([0f32; 3], [0f32; 3], [0f32; 3]); 4];
            let l: [f32; 4] = if round % 2 == 0 {
                [0.25, -0.5, 0.75, 1.0]
            } else {
                [1.0, -0.5, 0.0, 0.0]
            };
            for lane in &mut lanes {
                let mut p = || {
                    if round % 3 == 0 {
                        // Random small lattice points in the plane y = -(x + z) / 2.
                        let (a, c) = ((rnd() % 9) as f32, (rnd() % 9) as f32);
                        [a, -(a + c) * 0.5, c]
                    } else {
                        let f = |r: u32| (r % 20001) as f32 / 1000.0 - 10.0;
                        [f(rnd()), f(rnd()), f(rnd())]
                    }
                };
                *lane = (p(), p(), p());
            }
            let wd =
                |f: &dyn Fn(usize) -> f32| <Wide as Level>::D::from_f32([f(0), f(1), f(2), f(3)]);
            let a = std::array::from_fn(|c| wd(&|i| lanes[i].0[c]));
            let b = std::array::from_fn(|c| wd(&|i| lanes[i].1[c]));
            let o = std::array::from_fn(|c| wd(&|i| lanes[i].2[c]));
            let lv = std::array::from_fn(|c| <Wide as Level>::D::splat(f64::from(l[c])));
            let (pos, neg, unc) = filter_f64(a, b, lv, o);
            for (i, (pa, pb, po)) in lanes.iter().enumerate() {
                let expect = orient_filter_f64(*pa, *pb, l, *po);
                let got = if unc >> i & 1 == 1 {
                    uncertain_seen += 1;
                    None
                } else if pos >> i & 1 == 1 {
                    Some(1)
                } else if neg >> i & 1 == 1 {
                    Some(-1)
                } else {
                    Some(0)
                };
                assert_eq!(got, expect, "lane {i}: {pa:?} {pb:?} {l:?} {po:?}");
            }
        }
        assert!(
            uncertain_seen > 0,
            "the coplanar rounds must produce uncertain lanes"
        );
    }

    #[test]
    fn sign_bytes_encode_lanes() {
        assert_eq!(
            sign_bytes(0b0000_0101, 0b1000_0010).map(|b| b as i8),
            [1, -1, 1, 0, 0, 0, 0, -1]
        );
    }
}
