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

use crate::lanes::{or_sign_mask_bits, Level, F32V, F64V};
use crate::layout::coord_in_filter_range;
use crate::layout::{Layout, LANES, ODD};
use shadowvol_robust_math::{
    orient_exact, sign_f32, Accuracy, F32_FILTER_EPS, F32_FILTER_MAX, F32_FILTER_MIN,
    F64_FILTER_EPS,
};
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
    let e = sub3(a, b);
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
    dot3(n, &sub3(o, a))
}

/// `p − q` per coordinate.
#[inline(always)]
fn sub3<F: F32V>(p: &[F; 3], q: &[F; 3]) -> [F; 3] {
    [p[0] - q[0], p[1] - q[1], p[2] - q[2]]
}

/// `(n.x·d.x + n.y·d.y) + n.z·d.z`: the dot product of [`sign_f32`], in its order.
#[inline(always)]
fn dot3<F: F32V>(n: &[F; 3], d: &[F; 3]) -> F {
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

/// The certified `f32` filter of `orient_filter_f32`, eight lanes at a time: the same formula,
/// the same operations in the same order and the same constants ([`F32_FILTER_EPS`], the range
/// [`F32_FILTER_MIN`]`..=`[`F32_FILTER_MAX`]), so each lane makes the scalar filter's decision and
/// a certified lane carries its proof. Returns `(positive, negative, uncertain)` bits.
///
/// The caller checks `L.w ∈ {0, 1}` (one scalar test per light; other lights must not come
/// here). With `RANGE = false` the range check on the nine differences is skipped: only sound
/// when every coordinate of `A`, `B`, `O` and `L.xyz` passes [`coord_in_filter_range`], which
/// proves that every difference passes it.
///
/// The scalar filter's `!perm.is_finite()` test is implied here: a non-finite `perm` makes
/// `bound` infinite or NaN, so `|det| > bound` is false, and `perm == 0` is false, so the lane is
/// uncertain, as in the scalar filter. (A non-finite difference always reaches `perm`: each one
/// is a factor of some term of it, and every term is `>= 0` or NaN.)
#[inline(always)]
fn filter_f32<F: F32V, const RANGE: bool>(
    a: &[F; 3],
    b: &[F; 3],
    l: &[F; 4],
    o: &[F; 3],
) -> (u32, u32, u32) {
    let (pq, bad) = f32_products::<F, RANGE>(a, b, l);
    f32_decide::<F, RANGE>(&pq, a, o, bad)
}

/// The first half of [`filter_f32`]: `E = A - B`, `V = L.xyz - w A`, the range check on them
/// (with `RANGE`; its bits are returned) and the six products `[p1, q1, p2, q2, p3, q3]`.
#[inline(always)]
fn f32_products<F: F32V, const RANGE: bool>(a: &[F; 3], b: &[F; 3], l: &[F; 4]) -> ([F; 6], u32) {
    let e = sub3(a, b);
    let wa = [l[3] * a[0], l[3] * a[1], l[3] * a[2]];
    let v = [l[0] - wa[0], l[1] - wa[1], l[2] - wa[2]];
    let mut bad = 0u32;
    if RANGE {
        for x in e.iter().chain(&v) {
            bad |= x.out_of_range_bits(F32_FILTER_MIN, F32_FILTER_MAX);
        }
    }
    let (p1, q1) = (e[1] * v[2], e[2] * v[1]);
    let (p2, q2) = (e[2] * v[0], e[0] * v[2]);
    let (p3, q3) = (e[0] * v[1], e[1] * v[0]);
    ([p1, q1, p2, q2, p3, q3], bad)
}

/// The second half of [`filter_f32`]: `D = O - A`, its range check (with `RANGE`), `det`,
/// `perm` and the decision, given the products and range bits of [`f32_products`].
#[inline(always)]
fn f32_decide<F: F32V, const RANGE: bool>(
    pq: &[F; 6],
    a: &[F; 3],
    o: &[F; 3],
    bad: u32,
) -> (u32, u32, u32) {
    let (det, perm, bad) = f32_terms::<F, RANGE>(pq, a, o, bad);
    let bound = F::splat(F32_FILTER_EPS) * perm;
    let certified = det.abs().gt_bits(bound) & !bad;
    let pos = certified & det.gt_bits(F::splat(0.0));
    let neg = certified & !pos;
    let zero = perm.zero_bits() & !bad;
    (pos, neg, !(pos | neg | zero) & 0xFF)
}

/// `det`, `perm` and the range bits (those of [`f32_products`] or-ed with those of `D = O − A`,
/// with `RANGE`) of [`f32_decide`].
#[inline(always)]
fn f32_terms<F: F32V, const RANGE: bool>(
    pq: &[F; 6],
    a: &[F; 3],
    o: &[F; 3],
    mut bad: u32,
) -> (F, F, u32) {
    let [p1, q1, p2, q2, p3, q3] = *pq;
    let d = sub3(o, a);
    if RANGE {
        for x in &d {
            bad |= x.out_of_range_bits(F32_FILTER_MIN, F32_FILTER_MAX);
        }
    }
    let det = (p1 - q1) * d[0] + (p2 - q2) * d[1] + (p3 - q3) * d[2];
    let perm = (p1.abs() + q1.abs()) * d[0].abs()
        + (p2.abs() + q2.abs()) * d[1].abs()
        + (p3.abs() + q3.abs()) * d[2].abs();
    (det, perm, bad)
}

/// [`filter_f32`] returning `det` itself with the uncertain bits: in every lane that is not
/// uncertain, the sign of `det` is the filter's decision. (Where `|det| > bound` that is the
/// definition; where the filter certifies a zero, `perm = 0` means every term of `perm`, hence
/// every term of `det`, is 0, so `det` is ±0, whose sign is 0.) The several-light triangle pass
/// turns `det` into sign bytes with vector operations and decides only the uncertain lanes
/// another way.
#[inline(always)]
fn filter_f32_det<F: F32V, const RANGE: bool>(
    a: &[F; 3],
    b: &[F; 3],
    l: &[F; 4],
    o: &[F; 3],
) -> (F, u32) {
    let (pq, bad) = f32_products::<F, RANGE>(a, b, l);
    let (det, perm, bad) = f32_terms::<F, RANGE>(&pq, a, o, bad);
    let bound = F::splat(F32_FILTER_EPS) * perm;
    let decided = det.abs().gt_bits(bound) | perm.zero_bits();
    (det, (!decided | bad) & 0xFF)
}

/// How the `f32` filter stage treats one light in `exact` mode.
#[derive(Clone, Copy, PartialEq, Eq)]
enum F32Stage {
    /// `L.w` is neither 0 nor 1: `orient_filter_f32` is uncertain for every input; go to `f64`.
    Skip,
    /// Run the filter with its range check on the differences.
    Checked,
    /// Run the filter without the range check: the layout's coordinates and the light's pass
    /// [`coord_in_filter_range`], so every difference passes it.
    Unchecked,
}

#[inline(always)]
fn f32_stage(lay: &Layout, light: &[f32; 4]) -> F32Stage {
    if light[3] != 0.0 && light[3] != 1.0 {
        F32Stage::Skip
    } else if lay.coords_in_filter_range && light[..3].iter().all(|&c| coord_in_filter_range(c)) {
        F32Stage::Unchecked
    } else {
        F32Stage::Checked
    }
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

/// Sets the bits of light `k` in the several-light sign bytes `acc[i]`, for the lanes `i` in
/// `lanes`, to the sign given by the disjoint bit masks `pos` / `neg` (bit `k` for `+1`, bit
/// `4 + k` for `-1`, neither for 0).
#[inline(always)]
fn set_sign_bits(acc: &mut [u32; LANES], k: usize, lanes: u32, pos: u32, neg: u32) {
    for (i, a) in acc.iter_mut().enumerate() {
        if lanes >> i & 1 == 1 {
            *a &= !(0x11 << k);
        }
    }
    or_sign_mask_bits(acc, pos & lanes, neg & lanes, k as u32);
}

/// Signs of the canonical triangles in `blocks` (blocks of 8) for every light.
///
/// `out[l / PACK]` receives the signs of this range for light `l`: one byte per triangle slot
/// (`blocks.len() * 8` bytes; padding lanes get 0). With one light the byte is the sign as an
/// `i8`; with several, the byte of pack `p` holds lights `4p .. 4p + 4` as bits ([`PACK`]). Returns the number of (triangle, light) evaluations
/// neither the `f32` nor the `f64` filter could certify (exact mode), which were decided with
/// the scalar exact predicate.
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
            && out.iter().all(|o| o.len() == blocks.len() * LANES)
    );
    let several = lights.len() > 1;
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
    // The f32 stage of each light (exact mode), decided once per call.
    let mut stage_buf = [F32Stage::Skip; 8];
    let stage_vec: Vec<F32Stage>;
    let stages: &[F32Stage] = if mode != Accuracy::Exact {
        &[]
    } else if lights.len() <= stage_buf.len() {
        for (s, light) in stage_buf.iter_mut().zip(lights) {
            *s = f32_stage(lay, light);
        }
        &stage_buf[..lights.len()]
    } else {
        stage_vec = lights.iter().map(|light| f32_stage(lay, light)).collect();
        &stage_vec
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
            // live (O is loaded once N exists), and the 8 signs stored as 8 consecutive bytes
            // (one byte per slot).
            // SAFETY: as below.
            let (a, b) = unsafe {
                (
                    gather::<Lv>(lay, &lay.t0[t..]),
                    gather::<Lv>(lay, &lay.t1[t..]),
                )
            };
            let e = sub3(&a, &b);
            let n = edge_normal(&lv, &a, &e);
            // SAFETY: as below.
            let o = unsafe { gather::<Lv>(lay, &lay.t2[t..]) };
            let m = off_plane(&n, &a, &o).signum0().to_i32();
            for (byte, s) in out[0][dst..dst + LANES].iter_mut().zip(m) {
                *byte = s as i8;
            }
            continue;
        }
        if let (Accuracy::Exact, 0xFF, Some(lv), [F32Stage::Unchecked]) =
            (mode, valid, one32, stages)
        {
            // One light, a full block, no range check: as the ordered path above, `O` is
            // loaded only once the products exist (fewer vectors live).
            // SAFETY: as below.
            let (a, b) = unsafe {
                (
                    gather::<Lv>(lay, &lay.t0[t..]),
                    gather::<Lv>(lay, &lay.t1[t..]),
                )
            };
            let (pq, bad) = f32_products::<Lv::F, false>(&a, &b, &lv);
            // SAFETY: as below.
            let o = unsafe { gather::<Lv>(lay, &lay.t2[t..]) };
            let (mut pos, mut neg, unc) = f32_decide::<Lv::F, false>(&pq, &a, &o, bad);
            uncertain += exact_fallback::<Lv>(
                lay, t, &lights[0], one64, &mut None, unc, &mut pos, &mut neg,
            );
            write_one(out, dst, pos, neg);
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
                // `plane`'s operations with `A − B` and `O − A` made once for all lights.
                let (e, d) = (sub3(&a, &b), sub3(&o, &a));
                if several {
                    // Each pack's sign bytes built in registers, one store.
                    for (pack, chunk) in lights.chunks(PACK).enumerate() {
                        let mut acc = [0u32; LANES];
                        for (k, light) in chunk.iter().enumerate() {
                            let n = edge_normal(&splat4(*light), &a, &e);
                            dot3(&n, &d).or_sign_bits(&mut acc, k as u32);
                        }
                        write_pack(out, pack, dst, &acc, valid);
                    }
                } else {
                    // One light, a partial block.
                    let n = edge_normal(&splat4(lights[0]), &a, &e);
                    let (pos, neg) = dot3(&n, &d).sign_bits();
                    write_one(out, dst, pos & valid, neg & valid);
                }
            }
            Accuracy::Robust if several => {
                // Each pack's sign bytes built in registers, one store.
                for (pack, chunk) in lights.chunks(PACK).enumerate() {
                    let mut acc = [0u32; LANES];
                    for (k, light) in chunk.iter().enumerate() {
                        let lv = splat4(*light);
                        let sa = plane(&a, &b, &lv, &o);
                        let sb = plane(&b, &o, &lv, &a);
                        let sc = plane(&o, &a, &lv, &b);
                        sa.or_sign_bits3(sb, sc, &mut acc, k as u32);
                    }
                    write_pack(out, pack, dst, &acc, valid);
                }
            }
            Accuracy::Robust => {
                // One light.
                let lv = splat4(lights[0]);
                let (pa, na) = plane(&a, &b, &lv, &o).sign_bits();
                let (pb, nb) = plane(&b, &o, &lv, &a).sign_bits();
                let (pc, nc) = plane(&o, &a, &lv, &b).sign_bits();
                write_one(out, dst, pa & pb & pc & valid, na & nb & nc & valid);
            }
            Accuracy::Exact if one32.is_none() => {
                // Several lights: each pack's sign bytes built in registers, one store. The
                // block's points widened to f64, made (by `exact_fallback`) only when some lane
                // needs the f64 filter.
                let mut w64: Option<Widened<Lv>> = None;
                for (pack, chunk) in lights.chunks(PACK).enumerate() {
                    let mut acc = [0u32; LANES];
                    for (k, light) in chunk.iter().enumerate() {
                        // 1. The f32 filter on all 8 lanes; the sign of `det` is its decision
                        // in every lane that is not uncertain.
                        let lv32 = splat4(*light);
                        let (det, unc32) = match stages[pack * PACK + k] {
                            F32Stage::Skip => (Lv::F::splat(0.0), 0xFF),
                            F32Stage::Checked => filter_f32_det::<Lv::F, true>(&a, &b, &lv32, &o),
                            F32Stage::Unchecked => {
                                filter_f32_det::<Lv::F, false>(&a, &b, &lv32, &o)
                            }
                        };
                        det.or_sign_bits(&mut acc, k as u32);
                        let unc = unc32 & valid;
                        if unc != 0 {
                            // 2, 3. The uncertain lanes (rare): their bits replaced.
                            let (mut pos, mut neg) = (0, 0);
                            uncertain += exact_fallback::<Lv>(
                                lay, t, light, one64, &mut w64, unc, &mut pos, &mut neg,
                            );
                            set_sign_bits(&mut acc, k, unc, pos, neg);
                        }
                    }
                    write_pack(out, pack, dst, &acc, valid);
                }
            }
            Accuracy::Exact => {
                // One light (the arm above takes several), where the one-light path above does
                // not apply (a partial block, a light needing the range check, or `w` other
                // than 0 and 1).
                if let (Some(lv32), [light], [stage]) = (one32, lights, stages) {
                    // 1. The f32 filter on all 8 lanes.
                    let (mut pos, mut neg, unc32) = match stage {
                        F32Stage::Skip => (0, 0, 0xFF),
                        F32Stage::Checked => filter_f32::<Lv::F, true>(&a, &b, &lv32, &o),
                        F32Stage::Unchecked => filter_f32::<Lv::F, false>(&a, &b, &lv32, &o),
                    };
                    let unc = unc32 & valid;
                    uncertain += exact_fallback::<Lv>(
                        lay, t, light, one64, &mut None, unc, &mut pos, &mut neg,
                    );
                    write_one(out, dst, pos & valid, neg & valid);
                }
            }
        }
    }
    uncertain
}

/// `A`, `B` and `O` of a block, lanes 0..4 and 4..8, widened to `f64`.
type Widened<Lv> = [([<Lv as Level>::D; 3], [<Lv as Level>::D; 3]); 3];

/// Stages 2 and 3 of `exact` for the lanes `unc` of the block at triangle `t` that the `f32`
/// filter left uncertain: the `f64` filter on the halves that hold such lanes, then the scalar
/// `orient_exact` for the lanes it leaves uncertain. Their signs are or-ed into `pos` / `neg`;
/// returns the number of lanes decided by `orient_exact`. `w64` caches the block's widened
/// points across lights.
///
/// The points are gathered again from memory rather than widened from the registers of the
/// `f32` stage: a conversion of those registers is loop-invariant and speculatable, so LLVM
/// hoisted it (and its spills) out of the light loop into every block; a gather after the
/// stores of earlier lights cannot be hoisted.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn exact_fallback<Lv: Level>(
    lay: &Layout,
    t: usize,
    light: &[f32; 4],
    one64: Option<[Lv::D; 4]>,
    w64: &mut Option<Widened<Lv>>,
    mut unc: u32,
    pos: &mut u32,
    neg: &mut u32,
) -> u64 {
    if unc == 0 {
        return 0;
    }
    if w64.is_none() {
        // SAFETY: `t + 8 <= t0.len()` (asserted by `tri_signs`), and the layout's ids are in
        // range.
        let (a, b, o) = unsafe {
            (
                gather::<Lv>(lay, &lay.t0[t..]),
                gather::<Lv>(lay, &lay.t1[t..]),
                gather::<Lv>(lay, &lay.t2[t..]),
            )
        };
        *w64 = Some([widen3::<Lv>(&a), widen3::<Lv>(&b), widen3::<Lv>(&o)]);
    }
    if let Some([a64, b64, o64]) = w64 {
        let lv: [Lv::D; 4] =
            one64.unwrap_or_else(|| std::array::from_fn(|c| Lv::D::splat(f64::from(light[c]))));
        let (mut p, mut n, mut u) = (0, 0, 0);
        if unc & 0x0F != 0 {
            (p, n, u) = filter_f64(a64.0, b64.0, lv, o64.0);
        }
        if unc & 0xF0 != 0 {
            let (ph, nh, uh) = filter_f64(a64.1, b64.1, lv, o64.1);
            (p, n, u) = (p | ph << 4, n | nh << 4, u | uh << 4);
        }
        *pos |= p & unc;
        *neg |= n & unc;
        unc &= u;
    }
    // The scalar exact predicate for the lanes neither filter certified.
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
            *pos |= 1 << i;
        } else if s < 0 {
            *neg |= 1 << i;
        }
    }
    u64::from(unc.count_ones())
}

/// Lanes 0..4 and 4..8 of a point vector, widened to `f64`. (A function, not a closure: closures
/// are not `#[inline(always)]`, and an intrinsic left in a non-inlined closure is not inlined.)
#[inline(always)]
fn widen3<Lv: Level>(p: &[Lv::F; 3]) -> ([Lv::D; 3], [Lv::D; 3]) {
    let (x, y, z) = (Lv::widen(p[0]), Lv::widen(p[1]), Lv::widen(p[2]));
    ([x.0, y.0, z.0], [x.1, y.1, z.1])
}

/// Writes one light's signs of the block at slot `dst` (one light: `i8` signs, one byte per
/// slot).
#[inline(always)]
fn write_one(out: &mut [&mut [i8]], dst: usize, pos: u32, neg: u32) {
    for (d, b) in out[0][dst..dst + LANES]
        .iter_mut()
        .zip(sign_bytes(pos, neg))
    {
        *d = b as i8;
    }
}

/// Writes the several-light sign bytes `acc` (byte of lane `i` = `acc[i]`, see [`PACK`]) of
/// the block at slot `dst` into pack `pack`; lanes outside `valid` (padding) get 0.
#[inline(always)]
fn write_pack(out: &mut [&mut [i8]], pack: usize, dst: usize, acc: &[u32; LANES], valid: u32) {
    for (i, (d, a)) in out[pack][dst..dst + LANES].iter_mut().zip(acc).enumerate() {
        *d = if valid >> i & 1 == 1 {
            *a as u8 as i8
        } else {
            0
        };
    }
}

/// Lights per sign pack. Every pack holds one byte per triangle slot. With one light the byte
/// is the sign as an `i8` (`1`, `0`, `-1`). With several, the byte of slot `t` in pack `l / 4`
/// holds light `l`'s sign as bits: bit `l % 4` set for `+1`, bit `4 + l % 4` set for `-1`
/// (neither for 0), so one byte load serves four lights and the array is as small as with one
/// light (see [`pack_sign`]).
pub(crate) const PACK: usize = 4;

/// Light `l`'s sign from its slot byte `b` in a call with `lights` lights (see [`PACK`]).
#[inline(always)]
pub(crate) fn pack_sign(b: i8, lights: usize, l: usize) -> i8 {
    if lights == 1 {
        b
    } else {
        let (b, k) = (b as u8, l % PACK);
        (b >> k & 1) as i8 - (b >> (4 + k) & 1) as i8
    }
}

/// `±s` by the parity bit of a triangle reference.
#[inline(always)]
fn signed(s: i8, tref: u32) -> i32 {
    let k = (tref >> 31) as i32; // 1 for odd parity
    (i32::from(s) ^ -k) + k
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
/// [`pack_sign`]`(signs[bases[l / PACK] + t], out.len(), l)`; `out[l]` receives this range's
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
    let nl = out.len();
    // Every triangle reference of the layout is < tri_count.
    assert!(bases.iter().all(|&b| b + lay.tri_count <= signs.len()));
    assert!(bases.len() == nl.div_ceil(PACK));
    for blk in blocks {
        let e0 = blk * LANES;
        if lay.block_fast[blk] {
            // Block-outer, light-inner: the block's triangle references are read once.
            let (ta, tb) = (&lay.tri_a[e0..e0 + LANES], &lay.tri_b[e0..e0 + LANES]);
            for (l, out) in out.iter_mut().enumerate() {
                let base = bases[l / PACK];
                let s = &signs[base..base + lay.tri_count];
                let dst = &mut out[e0 - e_start..e0 - e_start + LANES];
                let mut any = 0;
                for ((d, &t1), &t2) in dst.iter_mut().zip(ta).zip(tb) {
                    let i1 = (t1 & !ODD) as usize;
                    let i2 = (t2 & !ODD) as usize;
                    debug_assert!(i1 < s.len() && i2 < s.len());
                    // SAFETY: `Layout::build` stores only triangle slots < tri_count, and
                    // `s` covers slot tri_count - 1 (asserted above).
                    let (s1, s2) = unsafe { (*s.get_unchecked(i1), *s.get_unchecked(i2)) };
                    let m = signed(pack_sign(s1, nl, l), t1) + signed(pack_sign(s2, nl, l), t2);
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

/// The general (CSR) path of [`edge_sums`] for the block starting at edge `e0` (same sign
/// layout).
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
    let nl = out.len();
    for e in e0..(e0 + LANES).min(lay.edge_count) {
        let r = lay.ov_offsets[e] as usize..lay.ov_offsets[e + 1] as usize;
        for (l, out) in out.iter_mut().enumerate() {
            let base = bases[l / PACK];
            let m: i32 = lay.ov_tri[r.clone()]
                .iter()
                .map(|&t| signed(pack_sign(signs[base + (t & !ODD) as usize], nl, l), t))
                .sum();
            out[e - e_start] = m;
            if m != 0 {
                sil[l].push((edge_base + e) as u32);
            }
        }
    }
}

/// The sign bytes of the 8 triangle slots `ta[..8]` and of `tb[..8]` (parity bit cleared) in
/// the pack at `sp`, sign-extended to 32-bit lanes: 16 scalar byte loads, which measured faster
/// than two `vpgatherdd` on Zen 3 (PERFORMANCE.md).
///
/// # Safety
/// AVX2 present (the caller is compiled with it); `ta` and `tb` point to 8 readable `u32` each,
/// and every slot `t & !ODD` they hold is inside the pack at `sp`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn sign_bytes_of_block(
    sp: *const i8,
    ta: *const u32,
    tb: *const u32,
) -> (std::arch::x86_64::__m256i, std::arch::x86_64::__m256i) {
    use std::arch::x86_64::_mm256_setr_epi32;
    // SAFETY: forwarded from the caller.
    unsafe {
        let ld =
            |t: *const u32, i: usize| -> i32 { i32::from(*sp.add((*t.add(i) & !ODD) as usize)) };
        (
            _mm256_setr_epi32(
                ld(ta, 0),
                ld(ta, 1),
                ld(ta, 2),
                ld(ta, 3),
                ld(ta, 4),
                ld(ta, 5),
                ld(ta, 6),
                ld(ta, 7),
            ),
            _mm256_setr_epi32(
                ld(tb, 0),
                ld(tb, 1),
                ld(tb, 2),
                ld(tb, 3),
                ld(tb, 4),
                ld(tb, 5),
                ld(tb, 6),
                ld(tb, 7),
            ),
        )
    }
}

/// [`edge_sums`] with 8 edges per AVX2 vector: per block and pack of four lights, 16 scalar
/// byte loads fetch the signs of both triangles of 8 edges for all four lights (see [`PACK`]).
/// Identical results.
///
/// # Safety
/// The CPU must support AVX2.
///
/// # Panics
/// If a slice is shorter than described.
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
    assert!(bases.iter().all(|&b| b + lay.tri_count <= signs.len()));
    assert!(bases.len() == out.len().div_ceil(PACK));
    if let ([base], [out0], [sil0]) = (bases, &mut *out, &mut *sil) {
        // One light (the common case): the loop below without the pack and lane loops. The
        // 16 signs of a block are read with scalar byte loads rather than two `vpgatherdd`:
        // measured faster on Zen 3 (ordered 0.81x and 0.93x, exact 0.88x and 0.90x in two paired
        // A/B runs; PERFORMANCE.md).
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
            // SAFETY: fast blocks are full, so e0 + 8 <= tri_a.len() = tri_b.len(); every byte
            // read is signs[base + slot] with slot < tri_count, and base + tri_count <=
            // signs.len() (asserted above).
            let (g1, g2, k1, k2) = unsafe {
                let ta = lay.tri_a.as_ptr().add(e0);
                let tb = lay.tri_b.as_ptr().add(e0);
                let t1 = _mm256_loadu_si256(ta.cast());
                let t2 = _mm256_loadu_si256(tb.cast());
                let (g1, g2) = sign_bytes_of_block(signs.as_ptr().add(*base), ta, tb);
                (
                    g1,
                    g2,
                    _mm256_srai_epi32::<31>(t1),
                    _mm256_srai_epi32::<31>(t2),
                )
            };
            // The loads sign-extended each byte already.
            let s1 = _mm256_sub_epi32(_mm256_xor_si256(g1, k1), k1);
            let s2 = _mm256_sub_epi32(_mm256_xor_si256(g2, k2), k2);
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
            // Parity masks: -1 for odd (bit 31 set), 0 for even.
            let (k1, k2) = (_mm256_srai_epi32::<31>(t1), _mm256_srai_epi32::<31>(t2));
            for (pack, &base) in bases.iter().enumerate() {
                // The 16 sign bytes of the block's triangles, as in the one-light loop.
                // SAFETY: e0 + 8 <= tri_a.len() = tri_b.len(); every byte read is
                // signs[base + slot] with slot < tri_count, and base + tri_count <= signs.len()
                // (asserted above).
                let (g1, g2) = unsafe {
                    sign_bytes_of_block(
                        signs.as_ptr().add(base),
                        lay.tri_a.as_ptr().add(e0),
                        lay.tri_b.as_ptr().add(e0),
                    )
                };
                // Each byte holds four lights' signs as bits (`PACK`; the loads sign-extended
                // it, the shuffle reads byte 0 only). Copy it to the four
                // bytes of its lane, and make byte `j` the sign of light `4 pack + j`: `+1`
                // where bit `j` is set, `-1` where bit `4 + j` is.
                let bcast = _mm256_setr_epi8(
                    0, 0, 0, 0, 4, 4, 4, 4, 8, 8, 8, 8, 12, 12, 12, 12, 0, 0, 0, 0, 4, 4, 4, 4, 8,
                    8, 8, 8, 12, 12, 12, 12,
                );
                let pos_bit = _mm256_set1_epi32(0x0804_0201);
                let neg_bit = _mm256_set1_epi32(0x8040_2010_u32 as i32);
                let (x1, x2) = (
                    _mm256_shuffle_epi8(g1, bcast),
                    _mm256_shuffle_epi8(g2, bcast),
                );
                // -1 where the bit is set, so `neg - pos` is the sign.
                let sign = |x: __m256i| {
                    _mm256_sub_epi8(
                        _mm256_cmpeq_epi8(_mm256_and_si256(x, neg_bit), neg_bit),
                        _mm256_cmpeq_epi8(_mm256_and_si256(x, pos_bit), pos_bit),
                    )
                };
                let (g1, g2) = (sign(x1), sign(x2));
                // Negate every byte where the parity is odd (`k` is 0 or all ones in each
                // 32-bit lane, so `(g ^ k) - k` per byte) and add the two triangles: byte `j`
                // of lane `i` is then `m` of edge `e0 + i` for light `4 pack + j`, in
                // `-2 ..= 2`.
                let s1 = _mm256_sub_epi8(_mm256_xor_si256(g1, k1), k1);
                let s2 = _mm256_sub_epi8(_mm256_xor_si256(g2, k2), k2);
                let m = _mm256_add_epi8(s1, s2);
                let lights = (out.len() - pack * PACK).min(PACK);
                // Bit `4 i + j` set where that byte is non-zero, for this pack's lights only
                // (the bytes of absent lights are not read).
                let zero = _mm256_movemask_epi8(_mm256_cmpeq_epi8(m, _mm256_setzero_si256()));
                let nz = !(zero as u32) & (0x1111_1111u32 * ((1 << lights) - 1));
                // Byte `j` of each lane, sign-extended to i32.
                let rows = [
                    _mm256_srai_epi32::<24>(_mm256_slli_epi32::<24>(m)),
                    _mm256_srai_epi32::<24>(_mm256_slli_epi32::<16>(m)),
                    _mm256_srai_epi32::<24>(_mm256_slli_epi32::<8>(m)),
                    _mm256_srai_epi32::<24>(m),
                ];
                let pack_out = &mut out[pack * PACK..pack * PACK + lights];
                for (row, dst) in rows.iter().zip(pack_out.iter_mut()) {
                    let dst = &mut dst[e0 - e_start..e0 - e_start + LANES];
                    // SAFETY: `dst` holds 8 i32; unaligned store. (Not a streaming store: with
                    // several lights' rows, half a cache line each per block, those thrash the
                    // write-combining buffers.)
                    unsafe { _mm256_storeu_si256(dst.as_mut_ptr().cast(), *row) };
                }
                if nz != 0 {
                    // Silhouette edges in this block (rare): the lanes of each light.
                    for (j, row) in rows.iter().enumerate().take(lights) {
                        let z = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
                            *row,
                            _mm256_setzero_si256(),
                        ))) as u32;
                        push_bits(&mut sil[pack * PACK + j], !z & 0xFF, edge_base + e0);
                    }
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
            // The operations of `sign_f32`: `A − B` and both `O − A` made once for all lights,
            // `V` and `N` once per light for both OVs.
            let (e, d1, d2) = (sub3(&a, &b), sub3(&o1, &a), sub3(&o2, &a));
            for (l, light) in lights.iter().enumerate() {
                let n = edge_normal(&splat4::<Lv::F>(*light), &a, &e);
                let m = dot3(&n, &d1).signum0() + dot3(&n, &d2).signum0();
                let nz = m.store_i32_cached(&mut out[l][e0 - e_start..e0 - e_start + LANES]);
                push_bits(&mut sil[l], nz, edge_base + e0);
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
        let e = sub3(&a, &b);
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
    use crate::layout::COORD_MAX;
    use shadowvol_robust_math::{orient_filter_f32, orient_filter_f64};

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
            let bits = filter_f64(a, b, lv, o);
            for (i, (pa, pb, po)) in lanes.iter().enumerate() {
                let expect = orient_filter_f64(*pa, *pb, l, *po);
                let got = decision(bits, i);
                uncertain_seen += usize::from(got.is_none());
                assert_eq!(got, expect, "lane {i}: {pa:?} {pb:?} {l:?} {po:?}");
            }
        }
        assert!(
            uncertain_seen > 0,
            "the coplanar rounds must produce uncertain lanes"
        );
    }

    /// Lane `i`'s decision from a filter's `(positive, negative, uncertain)` bits, as the scalar
    /// filters return it: `None` for uncertain, else the certified sign (0 when neither bit).
    fn decision((pos, neg, unc): (u32, u32, u32), i: usize) -> Option<i8> {
        if unc >> i & 1 == 1 {
            None
        } else if pos >> i & 1 == 1 {
            Some(1)
        } else if neg >> i & 1 == 1 {
            Some(-1)
        } else {
            Some(0)
        }
    }

    /// One 8-lane input set of `filter_f32`: per lane `(A, B, O)`.
    type Lanes8 = [([f32; 3], [f32; 3], [f32; 3]); 8];

    /// Runs `filter_f32` at level `Lv` (both range variants where the unchecked one is sound) and
    /// asserts each lane's decision equals `orient_filter_f32`'s. Returns the uncertain count.
    fn check_f32_lanes<Lv: Level>(lanes: &Lanes8, l: [f32; 4]) -> usize {
        let ld = |f: &dyn Fn(usize) -> f32| -> Lv::F {
            let v: [f32; 8] = std::array::from_fn(f);
            // SAFETY: 8 in-range indices into `v` (lane i = v[i]).
            unsafe { Lv::F::gather(&v, &[0, 1, 2, 3, 4, 5, 6, 7]) }
        };
        let a = std::array::from_fn(|c| ld(&|i| lanes[i].0[c]));
        let b = std::array::from_fn(|c| ld(&|i| lanes[i].1[c]));
        let o = std::array::from_fn(|c| ld(&|i| lanes[i].2[c]));
        let lv = splat4::<Lv::F>(l);
        let checked = filter_f32::<Lv::F, true>(&a, &b, &lv, &o);
        let in_range = |p: &[f32]| p.iter().all(|&c| coord_in_filter_range(c));
        let unchecked_sound = in_range(&l[..3])
            && lanes
                .iter()
                .all(|(pa, pb, po)| in_range(pa) && in_range(pb) && in_range(po));
        let unchecked = filter_f32::<Lv::F, false>(&a, &b, &lv, &o);
        let mut unc = 0;
        for (i, (pa, pb, po)) in lanes.iter().enumerate() {
            let expect = orient_filter_f32(*pa, *pb, l, *po);
            assert_eq!(
                decision(checked, i),
                expect,
                "lane {i}: {pa:?} {pb:?} {l:?} {po:?}"
            );
            if unchecked_sound {
                assert_eq!(
                    decision(unchecked, i),
                    expect,
                    "unchecked, lane {i}: {pa:?} {pb:?} {l:?} {po:?}"
                );
            }
            unc += usize::from(expect.is_none());
        }
        // `filter_f32_det`: the sign of `det` where it says certain, the same decisions.
        for (range, (det, unc_bits)) in [
            (true, filter_f32_det::<Lv::F, true>(&a, &b, &lv, &o)),
            (false, filter_f32_det::<Lv::F, false>(&a, &b, &lv, &o)),
        ] {
            if !range && !unchecked_sound {
                continue;
            }
            let signs = det.signum0().to_i32();
            for (i, (pa, pb, po)) in lanes.iter().enumerate() {
                let got = (unc_bits >> i & 1 == 0).then_some(signs[i] as i8);
                assert_eq!(
                    got,
                    orient_filter_f32(*pa, *pb, l, *po),
                    "filter_f32_det (range check {range}), lane {i}: {pa:?} {pb:?} {l:?} {po:?}"
                );
            }
        }
        unc
    }

    /// The 8-lane `f32` filter makes exactly the decisions of the scalar `orient_filter_f32`
    /// (certified sign, certified zero, or uncertain) on random, coplanar, near-degenerate and
    /// huge / tiny inputs (range checks), with `w = 0` and `w = 1`, at every available level;
    /// and without its range check wherever [`coord_in_filter_range`] holds for every input.
    #[test]
    fn vector_f32_filter_mirrors_scalar_filter() {
        let mut x = 0x2545_F491u32;
        let mut rnd = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        let (mut uncertain, mut range_rejects, mut zeros, mut unchecked_rounds) = (0, 0, 0, 0);
        for round in 0..6000u32 {
            let kind = round % 6;
            let l: [f32; 4] = match round % 4 {
                0 => [0.25, -0.5, 0.75, 1.0],
                1 => [1.0, -0.5, 0.0, 0.0],
                2 => [3.0, 7.0, -2.0, 1.0],
                _ => [0.0, 0.0, 1.0, 0.0],
            };
            let mut lanes: Lanes8 = [([0f32; 3], [0f32; 3], [0f32; 3]); 8];
            for lane in &mut lanes {
                let mut p = || -> [f32; 3] {
                    let f = |r: u32| (r % 20001) as f32 / 1000.0 - 10.0;
                    match kind {
                        // Random small lattice points in the plane y = -(x + z) / 2.
                        0 => {
                            let (a, c) = ((rnd() % 9) as f32, (rnd() % 9) as f32);
                            [a, -(a + c) * 0.5, c]
                        }
                        // Random points.
                        1 => [f(rnd()), f(rnd()), f(rnd())],
                        // Near-degenerate: almost on the plane x + y + z = 1.
                        2 => {
                            let (a, c) = (f(rnd()), f(rnd()));
                            let y = 1.0 - a - c;
                            let nudge = [0.0, 1e-7, -1e-7, 1e-6][(rnd() % 4) as usize];
                            [a, y + nudge, c]
                        }
                        // Huge and tiny magnitudes around the range limits, and zeros.
                        3 => std::array::from_fn(|_| {
                            let m = [
                                0.0,
                                1.0,
                                F32_FILTER_MIN,
                                F32_FILTER_MAX,
                                1e-13,
                                3e12,
                                f32::MIN_POSITIVE,
                                1e-45,
                                1e30,
                                1.5 * F32_FILTER_MIN,
                                COORD_MAX,
                            ][(rnd() % 11) as usize];
                            if rnd() % 2 == 0 {
                                m
                            } else {
                                -m * (1.0 + (rnd() % 4) as f32 * 0.25)
                            }
                        }),
                        // Axis-aligned points (exact zeros: perm = 0 in some lanes).
                        4 => {
                            let mut q = [0.0; 3];
                            q[(rnd() % 3) as usize] = (rnd() % 5) as f32;
                            q
                        }
                        // Scaled random points: tiny or huge differences.
                        _ => {
                            let s = [1e-12, 1e-6, 1e6, 1e11, 1e20][(rnd() % 5) as usize];
                            [f(rnd()) * s, f(rnd()) * s, f(rnd()) * s]
                        }
                    }
                };
                *lane = (p(), p(), p());
            }
            let unc = check_f32_lanes::<Wide>(&lanes, l);
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") {
                check_avx2(&lanes, l);
            }
            uncertain += unc;
            for (pa, pb, po) in &lanes {
                let e = |u: [f32; 3], v: [f32; 3]| [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
                let v = [0, 1, 2].map(|c| l[c] - l[3] * pa[c]);
                let diffs = [e(*pa, *pb), v, e(*po, *pa)];
                if diffs
                    .iter()
                    .flatten()
                    .any(|&d| d != 0.0 && !(F32_FILTER_MIN..=F32_FILTER_MAX).contains(&d.abs()))
                {
                    range_rejects += 1;
                }
                zeros += usize::from(orient_filter_f32(*pa, *pb, l, *po) == Some(0));
            }
            let all_in = lanes.iter().all(|(pa, pb, po)| {
                [pa, pb, po]
                    .iter()
                    .all(|p| p.iter().all(|&c| coord_in_filter_range(c)))
            });
            unchecked_rounds += usize::from(all_in);
        }
        assert!(uncertain > 0, "coplanar rounds must give uncertain lanes");
        assert!(range_rejects > 0, "the range check must be exercised");
        assert!(zeros > 0, "certified zeros must occur");
        assert!(
            unchecked_rounds > 1000,
            "the unchecked variant must be compared"
        );
    }

    /// `check_f32_lanes` at the AVX2 level, entered with the feature enabled.
    #[cfg(target_arch = "x86_64")]
    fn check_avx2(lanes: &Lanes8, l: [f32; 4]) {
        #[target_feature(enable = "avx2")]
        unsafe fn run(lanes: &Lanes8, l: [f32; 4]) -> usize {
            check_f32_lanes::<crate::lanes::Avx2>(lanes, l)
        }
        // SAFETY: only called after `is_x86_feature_detected!("avx2")`.
        unsafe {
            run(lanes, l);
        }
    }

    /// `coord_in_filter_range` on both operands implies the range check on their difference
    /// (the argument of the unchecked `f32` stage), on values at and near the limits.
    #[test]
    fn coordinate_range_implies_difference_range() {
        let step = F32_FILTER_MIN; // 2^-40
        let mut vals = vec![
            0.0f32,
            step,
            3.0 * step,
            2.0f32.powi(-24),
            1.0,
            0.1,
            COORD_MAX,
        ];
        vals.extend([
            1.0 - 0.999_999_94f32,
            7.629_394_5e-6,
            COORD_MAX - 65536.0,
            12345.678,
        ]);
        vals.extend(vals.clone().iter().map(|v| -v));
        assert!(vals.iter().all(|&v| coord_in_filter_range(v)), "{vals:?}");
        for bad in [
            1.5 * step,
            f32::MIN_POSITIVE,
            1e-45,
            2.0 * COORD_MAX,
            f32::NAN,
            f32::INFINITY,
        ] {
            assert!(!coord_in_filter_range(bad), "{bad}");
        }
        for &x in &vals {
            for &y in &vals {
                for w in [0.0f32, 1.0] {
                    let d = x - w * y;
                    let m = d.abs();
                    assert!(
                        m == 0.0 || (F32_FILTER_MIN..=F32_FILTER_MAX).contains(&m),
                        "{x} - {w} * {y} = {d}"
                    );
                }
            }
        }
    }

    /// `w` outside `{0, 1}` is left to the f64 stage, like `orient_filter_f32` (always `None`).
    #[test]
    fn f32_stage_skips_lights_with_other_w() {
        let lay = |p: [f32; 3]| Layout {
            coords_in_filter_range: p.iter().all(|&c| coord_in_filter_range(c)),
            ..empty_layout()
        };
        let ok = lay([1.0, 2.0, 0.0]);
        assert!(f32_stage(&ok, &[1.0, 2.0, 3.0, 0.5]) == F32Stage::Skip);
        assert!(orient_filter_f32(
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [1.0, 2.0, 3.0, 0.5],
            [0.0, 1.0, 0.0]
        )
        .is_none());
        assert!(f32_stage(&ok, &[1.0, 2.0, 3.0, 1.0]) == F32Stage::Unchecked);
        assert!(f32_stage(&ok, &[1.0, 2.0, 3.0, 0.0]) == F32Stage::Unchecked);
        assert!(f32_stage(&ok, &[1e-30, 2.0, 3.0, 1.0]) == F32Stage::Checked);
        let tiny = lay([1e-30, 1.0, 1.0]);
        assert!(f32_stage(&tiny, &[1.0, 2.0, 3.0, 1.0]) == F32Stage::Checked);
    }

    fn empty_layout() -> Layout {
        Layout {
            xs: vec![],
            ys: vec![],
            zs: vec![],
            xyz: vec![],
            t0: vec![],
            t1: vec![],
            t2: vec![],
            tri_count: 0,
            edge_count: 0,
            block_fast: vec![],
            ea: vec![],
            eb: vec![],
            eo1: vec![],
            eo2: vec![],
            tri_a: vec![],
            tri_b: vec![],
            edges: vec![],
            ov_offsets: vec![],
            ovs: vec![],
            ov_tri: vec![],
            coords_in_filter_range: true,
        }
    }

    #[test]
    fn set_sign_bits_replaces_one_light_of_the_chosen_lanes() {
        // Light 2 (bits 2 and 6) of lanes 1, 2 and 6: lane 1 negative, lane 2 zero, lane 6
        // positive; the positive bit of lane 0 is outside `lanes` and ignored. The other bits
        // are kept.
        let mut acc = [0xFFu32; LANES];
        set_sign_bits(&mut acc, 2, 0b0100_0110, 0b0100_0001, 0b0000_0010);
        let mut want = [0xFFu32; LANES];
        want[1] = 0xFF & !0x04;
        want[2] = 0xFF & !0x44;
        want[6] = 0xFF & !0x40;
        assert_eq!(acc, want);
    }

    #[test]
    fn pack_signs_decode_every_light() {
        // One light: the i8 itself.
        for b in [-1i8, 0, 1] {
            assert_eq!(pack_sign(b, 1, 0), b);
        }
        // Several: light k of the pack is +1 with bit k, -1 with bit 4 + k.
        let byte = (0b0010_1001u8) as i8; // light 0: +1, light 1: -1, light 2: 0, light 3: +1
        let want = [1i8, -1, 0, 1];
        for lights in [2usize, 4, 7] {
            for l in 0..lights {
                assert_eq!(pack_sign(byte, lights, l), want[l % PACK], "{lights} {l}");
            }
        }
    }

    #[test]
    fn sign_bytes_encode_lanes() {
        assert_eq!(
            sign_bytes(0b0000_0101, 0b1000_0010).map(|b| b as i8),
            [1, -1, 1, 0, 0, 0, 0, -1]
        );
    }
}
