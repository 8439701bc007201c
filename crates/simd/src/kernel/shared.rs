//! `exact` with several lights of one `w`: each triangle classified once against the box of the
//! lights ([`LightBox`]), so that only the triangles whose plane cuts the box are evaluated per
//! light.
//!
//! [`SharedTriPass`] runs [`LightBox::filter`]'s operations on four `f64` lanes at a time
//! ([`box_filter`]), decides the lanes it leaves uncertain with the scalar
//! [`LightBox::sign_at_corners`], and writes one byte per triangle slot: the sign the whole box
//! shares, or [`NOT_SHARED`]. A block of 8 triangles with a cut one gets every light's sign
//! bytes ([`PACK`]) from the per-light filters of the triangle pass; the other blocks get none
//! (the edge pass takes a shared triangle's sign from its shared byte). The edge pass then
//! computes an edge whose triangles are all shared once for every light.

use super::filter::{widen3, F32Stage};
use super::gather;
use super::signs::{NOT_SHARED, PACK};
use super::tri_pass::{exact_packs, f32_stages, Block};
use crate::dispatch::Pass;
use crate::lanes::{Level, F64V};
use crate::layout::{CanonBlock, Geometry, LANES};
use shadowvol_robust_math::{BoxFilter, LightBox, BOX_FILTER_EPS};
use std::ops::Range;

/// Fewest lights for which the shared pass runs: the box filter costs about as much as two or
/// three lights' filters, so with fewer lights it cannot pay.
pub(crate) const SHARE_MIN_LIGHTS: usize = 4;

/// Blocks of 8 triangles [`worth_sharing`] samples, spread over the object.
const SAMPLE_BLOCKS: usize = 8;

/// Whether the shared pass pays on `lay` for the box `bx`: at least half of a sample of its
/// triangles (the triangles of up to [`SAMPLE_BLOCKS`] blocks spread over the object) have one
/// sign for the whole box by the filter. Lights spread around an object (a box as large as the
/// object) cut most planes; then every triangle would be evaluated per light after the box
/// filter, for nothing.
pub(crate) fn worth_sharing<G: Geometry>(lay: &G, bx: &LightBox) -> bool {
    let blocks = lay.tri_slots() / LANES;
    let (mut shared, mut seen) = (0, 0);
    for k in 0..SAMPLE_BLOCKS.min(blocks) {
        let blk = k * blocks / SAMPLE_BLOCKS.min(blocks);
        let t = blk * LANES;
        let ids = lay.canon_block::<crate::lanes::Wide>(t);
        for i in 0..LANES.min(lay.tri_count() - t) {
            let p = |c: usize| lay.pos(ids[c][i]);
            seen += 1;
            shared += usize::from(matches!(bx.filter(p(0), p(1), p(2)), BoxFilter::Shared(_)));
        }
    }
    2 * shared >= seen
}

/// A [`LightBox`]'s terms in lanes.
#[derive(Clone, Copy)]
pub(super) struct BoxLanes<D> {
    centre: [D; 3],
    half: [D; 3],
    reach: [D; 3],
    w: D,
}

impl<D: F64V> BoxLanes<D> {
    /// The terms of `bx` splatted.
    #[inline(always)]
    pub(super) fn new(bx: &LightBox) -> Self {
        let s = |v: [f64; 3]| v.map(D::splat);
        Self {
            centre: s(bx.centre()),
            half: s(bx.half()),
            reach: s(bx.reach()),
            w: D::splat(f64::from(bx.w())),
        }
    }
}

/// [`LightBox::filter`] on four lanes: the same operations in the same order and the same
/// constant [`BOX_FILTER_EPS`], so a lane it decides carries the scalar filter's proof. Returns
/// the `(positive, negative, zero, cut)` bits of the shared signs and the cut planes; a lane in
/// none of them is uncertain.
#[inline(always)]
pub(super) fn box_filter<D: F64V>(
    a: &[D; 3],
    b: &[D; 3],
    o: &[D; 3],
    bx: &BoxLanes<D>,
) -> (u32, u32, u32, u32) {
    let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let d = [o[0] - a[0], o[1] - a[1], o[2] - a[2]];
    let pq = [
        d[1] * e[2],
        d[2] * e[1],
        d[2] * e[0],
        d[0] * e[2],
        d[0] * e[1],
        d[1] * e[0],
    ];
    let n = [pq[0] - pq[1], pq[2] - pq[3], pq[4] - pq[5]];
    let m = [
        pq[0].abs() + pq[1].abs(),
        pq[2].abs() + pq[3].abs(),
        pq[4].abs() + pq[5].abs(),
    ];
    let (c, h, g, w) = (&bx.centre, &bx.half, &bx.reach, bx.w);
    let v = [c[0] - w * a[0], c[1] - w * a[1], c[2] - w * a[2]];
    let f = (n[0] * v[0] + n[1] * v[1]) + n[2] * v[2];
    let r = (n[0].abs() * h[0] + n[1].abs() * h[1]) + n[2].abs() * h[2];
    let p = (m[0] * (v[0].abs() + g[0]) + m[1] * (v[1].abs() + g[1])) + m[2] * (v[2].abs() + g[2]);
    let bound = D::splat(BOX_FILTER_EPS) * p;
    let zero = D::splat(0.0);
    let (low, high) = (f - r, f + r);
    let pos = low.gt_bits(bound);
    let neg = (zero - high).gt_bits(bound);
    let flat = p.zero_bits() & !(pos | neg);
    let cut = (zero - low).gt_bits(bound) & high.gt_bits(bound) & !(pos | neg | flat);
    (pos, neg, flat, cut)
}

/// The shared triangle pass over the blocks `blocks` of one object (see the module
/// documentation). Its [`Pass::Out`] is the number of (triangle, light) evaluations decided by
/// the scalar exact predicate (the corner tests are not counted).
pub(crate) struct SharedTriPass<'a, 'o, G> {
    /// The object's layout.
    pub lay: &'a G,
    /// Blocks of 8 triangles.
    pub blocks: Range<usize>,
    /// The lights, in the object's frame (at least two, one `w`).
    pub lights: &'a [[f32; 4]],
    /// Their box.
    pub bx: &'a LightBox,
    /// `out[l / PACK]`: the sign bytes of the blocks' slots for the lights of pack `l / PACK`
    /// (written for the blocks with a cut triangle only).
    pub out: &'a mut [&'o mut [i8]],
    /// The blocks' shared bytes: the box's sign, or [`NOT_SHARED`] (padding slots get 0).
    pub shared: &'a mut [i8],
}

impl<G: Geometry> Pass for SharedTriPass<'_, '_, G> {
    type Out = u64;
    #[inline(always)]
    fn run<Lv: Level>(self) -> u64 {
        shared_signs::<Lv, G>(self)
    }
}

/// See [`SharedTriPass`].
#[inline(always)]
fn shared_signs<Lv: Level, G: Geometry>(pass: SharedTriPass<G>) -> u64 {
    let SharedTriPass {
        lay,
        blocks,
        lights,
        bx,
        out,
        shared,
    } = pass;
    assert!(
        lights.len() > 1
            && blocks.end * LANES <= lay.tri_slots()
            && shared.len() == blocks.len() * LANES
            && out.len() == lights.len().div_ceil(PACK)
            && out.iter().all(|o| o.len() == blocks.len() * LANES)
    );
    let lanes = BoxLanes::<Lv::D>::new(bx);
    let (mut stage_buf, mut stage_spill) = ([F32Stage::Skip; 8], Vec::new());
    let stages = f32_stages(
        lay,
        lights,
        shadowvol_robust_math::Accuracy::Exact,
        &mut stage_buf,
        &mut stage_spill,
    );
    let b0 = blocks.start;
    let mut uncertain = 0;
    for blk in blocks {
        let t = blk * LANES;
        let valid: u32 = if t + LANES <= lay.tri_count() {
            0xFF
        } else {
            (1u32 << (lay.tri_count() - t)) - 1
        };
        let dst = (blk - b0) * LANES;
        let block_ids = lay.canon_block::<Lv>(t);
        let ids: &CanonBlock = &block_ids;
        // SAFETY: `ids` are vertices of the table (`Layout::build` checked them).
        let (a, b, o) = unsafe {
            (
                gather::<Lv, G>(lay, &ids[0]),
                gather::<Lv, G>(lay, &ids[1]),
                gather::<Lv, G>(lay, &ids[2]),
            )
        };
        let (pos, neg, flat, cut) = {
            let (a64, b64, o64) = (widen3::<Lv>(&a), widen3::<Lv>(&b), widen3::<Lv>(&o));
            let lo = box_filter(&a64.0, &b64.0, &o64.0, &lanes);
            let hi = box_filter(&a64.1, &b64.1, &o64.1, &lanes);
            (
                lo.0 | hi.0 << 4,
                lo.1 | hi.1 << 4,
                lo.2 | hi.2 << 4,
                lo.3 | hi.3 << 4,
            )
        };
        let (mut pos, mut neg, mut flat) = (pos & valid, neg & valid, flat & valid);
        // The lanes the filter leaves uncertain: the exact predicate at the box's corners.
        let mut unc = valid & !(pos | neg | flat | cut);
        while unc != 0 {
            let i = unc.trailing_zeros() as usize;
            unc &= unc - 1;
            let s = bx.sign_at_corners(lay.pos(ids[0][i]), lay.pos(ids[1][i]), lay.pos(ids[2][i]));
            match s {
                Some(1) => pos |= 1 << i,
                Some(-1) => neg |= 1 << i,
                Some(_) => flat |= 1 << i,
                None => {}
            }
        }
        let is_shared = pos | neg | flat;
        for (i, byte) in shared[dst..dst + LANES].iter_mut().enumerate() {
            *byte = if pos >> i & 1 == 1 {
                1
            } else if neg >> i & 1 == 1 {
                -1
            } else if is_shared >> i & 1 == 1 || valid >> i & 1 == 0 {
                0
            } else {
                NOT_SHARED
            };
        }
        if is_shared != valid {
            // A cut triangle in the block: every light's signs of the block, as the triangle
            // pass makes them (the shared lanes come out equal to their shared sign).
            let block = Block {
                ids,
                dst,
                valid,
                a,
                b,
                o,
            };
            uncertain += exact_packs::<Lv, G>(lay, &block, (lights, stages), None, out);
        }
    }
    uncertain
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::xorshift;
    use crate::lanes::Wide;

    /// The 4-lane box filter makes exactly the decisions of the scalar `LightBox::filter` on
    /// random boxes and triangles, boxes touching a plane at a vertex, and flat boxes.
    #[test]
    fn box_filter_lanes_mirror_the_scalar_filter() {
        type D = <Wide as Level>::D;
        let mut rnd = xorshift(0x5EED_1234);
        let mut f = move || (rnd() % 20001) as f32 / 1000.0 - 10.0;
        let mut seen = [0usize; 4];
        for round in 0..4000u32 {
            let w = [1.0, 0.0, 2.0][(round % 3) as usize];
            let tris: [([f32; 3], [f32; 3], [f32; 3]); 4] =
                std::array::from_fn(|_| ([f(), f(), f()], [f(), f(), f()], [f(), f(), f()]));
            let size = [0.0, 0.01, 1.0, 5.0][(round / 3 % 4) as usize];
            let mut lo = [f(), f(), f()];
            if round % 7 == 0 {
                // A corner at the first triangle's vertex B (w = 1: on its plane).
                lo = tris[0].1;
            }
            let mut tris = tris;
            if round % 11 == 0 {
                // A degenerate triangle: every determinant is 0.
                tris[1].1 = tris[1].0;
            }
            let hi = lo.map(|x| x + size);
            let bx = LightBox::from_bounds(lo, hi, w);
            let wd = |g: &dyn Fn(usize) -> f32| D::from_f32([g(0), g(1), g(2), g(3)]);
            let a = std::array::from_fn(|c| wd(&|i| tris[i].0[c]));
            let b = std::array::from_fn(|c| wd(&|i| tris[i].1[c]));
            let o = std::array::from_fn(|c| wd(&|i| tris[i].2[c]));
            let (pos, neg, flat, cut) = box_filter(&a, &b, &o, &BoxLanes::<D>::new(&bx));
            for (i, (ta, tb, to)) in tris.iter().enumerate() {
                let bit = |m: u32| m >> i & 1 == 1;
                let got = match (bit(pos), bit(neg), bit(flat), bit(cut)) {
                    (true, false, false, false) => BoxFilter::Shared(1),
                    (false, true, false, false) => BoxFilter::Shared(-1),
                    (false, false, true, false) => BoxFilter::Shared(0),
                    (false, false, false, true) => BoxFilter::Cut,
                    (false, false, false, false) => BoxFilter::Uncertain,
                    bits => panic!("lane {i}: overlapping bits {bits:?}"),
                };
                let want = bx.filter(*ta, *tb, *to);
                assert_eq!(got, want, "lane {i}: {ta:?} {tb:?} {to:?} {bx:?}");
                seen[match want {
                    BoxFilter::Shared(0) => 0,
                    BoxFilter::Shared(_) => 1,
                    BoxFilter::Cut => 2,
                    BoxFilter::Uncertain => 3,
                }] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n > 0), "{seen:?}");
    }
}
