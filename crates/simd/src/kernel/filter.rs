//! `exact` mode's certified filters in lanes, and the stages behind them.
//!
//! Stage 1 is the `f32` filter of `orient_filter_f32` on 8 lanes ([`filter_f32`],
//! [`filter_f32_det`]; [`f32_stage`] decides per light whether and how it runs). Stages 2 and 3
//! ([`Fallback`]) take the lanes it leaves uncertain: the `f64` filter of `orient_filter_f64` on
//! the 4-lane halves that hold such lanes ([`filter_f64`]), then the scalar `orient_exact`. Each
//! vector filter evaluates its scalar filter's formula with the same operations in the same
//! order and the same constants, so a lane it certifies carries the scalar filter's proof.

use super::{cross, cross_products, dot3, gather, light_dir, sub3};
use crate::lanes::{Arith, Level, F32V, F64V};
use crate::layout::{coord_in_filter_range, CanonBlock, Geometry};
use shadowvol_robust_math::{
    orient_exact, F32_FILTER_EPS, F32_FILTER_MAX, F32_FILTER_MIN, F64_FILTER_EPS,
};

/// The filters' `det = (E × V)·D` and `perm = (|p1| + |q1|)·|D.x| + (|p2| + |q2|)·|D.y| +
/// (|p3| + |q3|)·|D.z|` from the products of [`cross_products`] and `D = O − A`, in the order
/// of the scalar filters.
#[inline(always)]
fn det_perm<V: Arith>(pq: &[V; 6], d: &[V; 3]) -> (V, V) {
    let det = dot3(&cross(pq), d);
    let sums = [
        pq[0].abs() + pq[1].abs(),
        pq[2].abs() + pq[3].abs(),
        pq[4].abs() + pq[5].abs(),
    ];
    let perm = dot3(&sums, &[d[0].abs(), d[1].abs(), d[2].abs()]);
    (det, perm)
}

/// The certified `f64` filter of `orient_filter_f64`, four lanes at a time: the same formula,
/// the same evaluation order and the same constant [`F64_FILTER_EPS`], so each certified lane
/// carries the proof of the scalar filter. Returns `(positive, negative, uncertain)` bits.
#[inline(always)]
pub(super) fn filter_f64<D: F64V>(a: [D; 3], b: [D; 3], l: [D; 4], o: [D; 3]) -> (u32, u32, u32) {
    let pq = cross_products(&sub3(&a, &b), &light_dir(&l, &a));
    let (det, perm) = det_perm(&pq, &sub3(&o, &a));
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
pub(super) fn filter_f32<F: F32V, const RANGE: bool>(
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
pub(super) fn f32_products<F: F32V, const RANGE: bool>(
    a: &[F; 3],
    b: &[F; 3],
    l: &[F; 4],
) -> ([F; 6], u32) {
    let e = sub3(a, b);
    let v = light_dir(l, a);
    let mut bad = 0u32;
    if RANGE {
        for x in e.iter().chain(&v) {
            bad |= x.out_of_range_bits(F32_FILTER_MIN, F32_FILTER_MAX);
        }
    }
    (cross_products(&e, &v), bad)
}

/// The second half of [`filter_f32`]: `D = O - A`, its range check (with `RANGE`), `det`,
/// `perm` and the decision, given the products and range bits of [`f32_products`].
#[inline(always)]
pub(super) fn f32_decide<F: F32V, const RANGE: bool>(
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
    let d = sub3(o, a);
    if RANGE {
        for x in &d {
            bad |= x.out_of_range_bits(F32_FILTER_MIN, F32_FILTER_MAX);
        }
    }
    let (det, perm) = det_perm(pq, &d);
    (det, perm, bad)
}

/// [`filter_f32`] returning `det` itself with the uncertain bits: in every lane that is not
/// uncertain, the sign of `det` is the filter's decision. (Where `|det| > bound` that is the
/// definition; where the filter certifies a zero, `perm = 0` means every term of `perm`, hence
/// every term of `det`, is 0, so `det` is ±0, whose sign is 0.) The several-light triangle pass
/// turns `det` into sign bytes with vector operations and decides only the uncertain lanes
/// another way.
#[inline(always)]
pub(super) fn filter_f32_det<F: F32V, const RANGE: bool>(
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
pub(super) enum F32Stage {
    /// `L.w` is neither 0 nor 1: `orient_filter_f32` is uncertain for every input; go to `f64`.
    Skip,
    /// Run the filter with its range check on the differences.
    Checked,
    /// Run the filter without the range check: the layout's coordinates and the light's pass
    /// [`coord_in_filter_range`], so every difference passes it.
    Unchecked,
}

/// The [`F32Stage`] of `light` on an object whose coordinates all pass
/// [`coord_in_filter_range`] (`coords_ok`) or not.
#[inline(always)]
pub(super) fn f32_stage(coords_ok: bool, light: &[f32; 4]) -> F32Stage {
    if light[3] != 0.0 && light[3] != 1.0 {
        F32Stage::Skip
    } else if coords_ok && light[..3].iter().all(|&c| coord_in_filter_range(c)) {
        F32Stage::Unchecked
    } else {
        F32Stage::Checked
    }
}

/// `A`, `B` and `O` of a block, lanes 0..4 and 4..8, widened to `f64`.
type Widened<Lv> = [([<Lv as Level>::D; 3], [<Lv as Level>::D; 3]); 3];

/// Stages 2 and 3 of `exact` for one block of 8 canonical triangles: the lanes the `f32`
/// filter left uncertain, for each light in turn.
///
/// The block's points are gathered again from memory (once per block, on first use, and kept
/// across lights) rather than widened from the registers of the `f32` stage: a conversion of
/// those registers is loop-invariant and speculatable, so LLVM would hoist it (and its spills)
/// out of the light loop into every block; a gather after the stores of earlier lights cannot
/// be hoisted.
pub(super) struct Fallback<'a, Lv: Level, G> {
    lay: &'a G,
    /// The block's canonical triangles.
    ids: &'a CanonBlock,
    /// The block's points widened to `f64`, once some lane needed them.
    w64: Option<Widened<Lv>>,
}

impl<'a, Lv: Level, G: Geometry> Fallback<'a, Lv, G> {
    /// The block of canonical triangles `ids` (vertices of `lay`'s table).
    #[inline(always)]
    pub(super) fn new(lay: &'a G, ids: &'a CanonBlock) -> Self {
        Self {
            lay,
            ids,
            w64: None,
        }
    }

    /// Decides the lanes `unc` for `light` (`one64`: its `f64` lanes when made already): the
    /// `f64` filter on the halves that hold such lanes, then the scalar `orient_exact` for the
    /// lanes it leaves uncertain. Their signs are or-ed into `pos` / `neg`; returns the number
    /// of lanes decided by `orient_exact`.
    #[inline(always)]
    pub(super) fn decide(
        &mut self,
        light: &[f32; 4],
        one64: Option<[Lv::D; 4]>,
        mut unc: u32,
        pos: &mut u32,
        neg: &mut u32,
    ) -> u64 {
        if unc == 0 {
            return 0;
        }
        let (lay, ids) = (self.lay, self.ids);
        if self.w64.is_none() {
            // SAFETY: `ids` are vertices of the table (see `new`).
            let (a, b, o) = unsafe {
                (
                    gather::<Lv, G>(lay, &ids[0]),
                    gather::<Lv, G>(lay, &ids[1]),
                    gather::<Lv, G>(lay, &ids[2]),
                )
            };
            self.w64 = Some([widen3::<Lv>(&a), widen3::<Lv>(&b), widen3::<Lv>(&o)]);
        }
        if let Some([a64, b64, o64]) = &self.w64 {
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
                lay.pos(ids[0][i]),
                lay.pos(ids[1][i]),
                *light,
                lay.pos(ids[2][i]),
            );
            if s > 0 {
                *pos |= 1 << i;
            } else if s < 0 {
                *neg |= 1 << i;
            }
        }
        u64::from(unc.count_ones())
    }
}

/// Lanes 0..4 and 4..8 of a point vector, widened to `f64`. (A function, not a closure: closures
/// are not `#[inline(always)]`, and an intrinsic left in a non-inlined closure is not inlined.)
#[inline(always)]
pub(super) fn widen3<Lv: Level>(p: &[Lv::F; 3]) -> ([Lv::D; 3], [Lv::D; 3]) {
    let (x, y, z) = (Lv::widen(p[0]), Lv::widen(p[1]), Lv::widen(p[2]));
    ([x.0, y.0, z.0], [x.1, y.1, z.1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::splat4;
    use crate::kernel::xorshift;
    use crate::lanes::Wide;
    use crate::layout::COORD_MAX;
    use shadowvol_robust_math::{orient_filter_f32, orient_filter_f64};

    /// The 4-lane filter makes exactly the decisions of the scalar `orient_filter_f64`
    /// (certified sign, certified zero, or uncertain) on random and on coplanar inputs.
    #[test]
    fn vector_filter_mirrors_scalar_filter() {
        let mut rnd = xorshift(0x9E37_79B9u32);
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
        let mut rnd = xorshift(0x2545_F491u32);
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
                            if rnd().is_multiple_of(2) {
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
        let ok = [1.0f32, 2.0, 0.0].iter().all(|&c| coord_in_filter_range(c));
        assert!(f32_stage(ok, &[1.0, 2.0, 3.0, 0.5]) == F32Stage::Skip);
        assert!(orient_filter_f32(
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [1.0, 2.0, 3.0, 0.5],
            [0.0, 1.0, 0.0]
        )
        .is_none());
        assert!(f32_stage(ok, &[1.0, 2.0, 3.0, 1.0]) == F32Stage::Unchecked);
        assert!(f32_stage(ok, &[1.0, 2.0, 3.0, 0.0]) == F32Stage::Unchecked);
        assert!(f32_stage(ok, &[1e-30, 2.0, 3.0, 1.0]) == F32Stage::Checked);
        let tiny = [1e-30f32, 1.0, 1.0]
            .iter()
            .all(|&c| coord_in_filter_range(c));
        assert!(f32_stage(tiny, &[1.0, 2.0, 3.0, 1.0]) == F32Stage::Checked);
    }
}
