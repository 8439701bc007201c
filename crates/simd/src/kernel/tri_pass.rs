//! The triangle pass of `robust`, `ordered` and `exact`: one sign per canonical triangle and
//! light, for the blocks of 8 triangles of one work item.

use super::filter::{f32_decide, f32_products, f32_stage, filter_f32, filter_f32_det};
use super::filter::{F32Stage, Fallback};
use super::signs::{set_sign_bits, write_one, write_pack, PACK};
use super::{dot3, edge_normal, gather, off_plane, plane, splat4, sub3};
use crate::dispatch::Pass;
use crate::lanes::{Level, F32V, F64V};
use crate::layout::{CanonBlock, Geometry, LANES};
use shadowvol_robust_math::Accuracy;
use std::ops::Range;

/// The triangle pass over the blocks `blocks` of one object: see [`tri_signs`] for what it
/// writes. Its [`Pass::Out`] is the number of (triangle, light) evaluations decided by the
/// scalar exact predicate.
pub(crate) struct TriPass<'a, 'o, G> {
    /// The object's layout.
    pub lay: &'a G,
    /// Blocks of 8 triangles.
    pub blocks: Range<usize>,
    /// The lights, in the object's frame.
    pub lights: &'a [[f32; 4]],
    /// `Robust`, `Ordered` or `Exact` (`Original` is evaluated as `Ordered`).
    pub mode: Accuracy,
    /// `out[l / PACK]`: the sign bytes of the blocks' slots for the lights of pack `l / PACK`.
    pub out: &'a mut [&'o mut [i8]],
}

impl<G: Geometry> Pass for TriPass<'_, '_, G> {
    type Out = u64;
    #[inline(always)]
    fn run<Lv: Level>(self) -> u64 {
        tri_signs::<Lv, G>(self)
    }
}

/// Signs of the canonical triangles in `blocks` (blocks of 8) for every light.
///
/// `out[l / PACK]` receives the signs of this range for light `l`: one byte per triangle slot
/// (`blocks.len() * 8` bytes; padding lanes get 0). With one light the byte is the sign as an
/// `i8`; with several, the byte of pack `p` holds lights `4p .. 4p + 4` as bits ([`PACK`]).
/// Returns the number of (triangle, light) evaluations neither the `f32` nor the `f64` filter
/// could certify (exact mode), which were decided with the scalar exact predicate.
#[inline(always)]
fn tri_signs<Lv: Level, G: Geometry>(pass: TriPass<G>) -> u64 {
    let TriPass {
        lay,
        blocks,
        lights,
        mode,
        out,
    } = pass;
    let mut uncertain = 0u64;
    let b0 = blocks.start;
    assert!(
        blocks.end * LANES <= lay.tri_slots()
            && out.len() == lights.len().div_ceil(PACK)
            && out.iter().all(|o| o.len() == blocks.len() * LANES)
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
    // The f32 stage of each light (exact mode), decided once per call.
    let (mut stage_buf, mut stage_spill) = ([F32Stage::Skip; 8], Vec::new());
    let stages = f32_stages(lay, lights, mode, &mut stage_buf, &mut stage_spill);
    for blk in blocks {
        let t = blk * LANES;
        let valid: u32 = if t + LANES <= lay.tri_count() {
            0xFF
        } else {
            (1u32 << (lay.tri_count() - t)) - 1
        };
        let dst = (blk - b0) * LANES;
        // The block's triangles in canonical order (vertex 0 in the padding lanes).
        let block_ids = lay.canon_block::<Lv>(t);
        let ids: &CanonBlock = &block_ids;
        if let (Accuracy::Ordered | Accuracy::Original, 0xFF, Some(lv)) = (mode, valid, one32) {
            ordered_one_full::<Lv, G>(lay, ids, &lv, &mut out[0][dst..dst + LANES]);
            continue;
        }
        if let (Accuracy::Exact, 0xFF, Some(lv), [F32Stage::Unchecked]) =
            (mode, valid, one32, stages)
        {
            uncertain += exact_one_full::<Lv, G>(lay, ids, &lv, &lights[0], one64, out, dst);
            continue;
        }
        // SAFETY: `ids` are vertices of the table (`Layout::build` checked them).
        let (a, b, o) = unsafe {
            (
                gather::<Lv, G>(lay, &ids[0]),
                gather::<Lv, G>(lay, &ids[1]),
                gather::<Lv, G>(lay, &ids[2]),
            )
        };
        let block = Block {
            ids,
            dst,
            valid,
            a,
            b,
            o,
        };
        match mode {
            Accuracy::Ordered | Accuracy::Original => ordered::<Lv>(&block, lights, out),
            Accuracy::Robust => robust::<Lv>(&block, lights, out),
            Accuracy::Exact if one32.is_none() => {
                uncertain += exact_packs::<Lv, G>(lay, &block, (lights, stages), one64, out);
            }
            Accuracy::Exact => {
                // One light (the arm above takes several), where the one-light path above does
                // not apply (a partial block, a light needing the range check, or `w` other
                // than 0 and 1).
                if let (Some(lv32), [light], [stage]) = (one32, lights, stages) {
                    uncertain +=
                        exact_one::<Lv, G>(lay, &block, (&lv32, light, *stage), one64, out);
                }
            }
        }
    }
    uncertain
}

/// The `f32` filter's stage of each light in exact mode (none in the other modes): in `buf` for
/// up to 8 lights, in `spill` beyond, so that the common case allocates nothing.
#[inline(always)]
pub(super) fn f32_stages<'s, G: Geometry>(
    lay: &G,
    lights: &[[f32; 4]],
    mode: Accuracy,
    buf: &'s mut [F32Stage; 8],
    spill: &'s mut Vec<F32Stage>,
) -> &'s [F32Stage] {
    if mode != Accuracy::Exact {
        &[]
    } else if lights.len() <= buf.len() {
        for (s, light) in buf.iter_mut().zip(lights) {
            *s = f32_stage(lay.coords_in_filter_range(), light);
        }
        &buf[..lights.len()]
    } else {
        spill.extend(
            lights
                .iter()
                .map(|light| f32_stage(lay.coords_in_filter_range(), light)),
        );
        spill
    }
}

/// One block of 8 canonical triangles: their vertex ids, where its sign bytes go (`dst`), the
/// lanes that are triangles (`valid`), and its corners.
pub(super) struct Block<'i, F> {
    /// The canonical triangles' vertex ids.
    pub ids: &'i CanonBlock,
    /// Where the block's sign bytes go in each pack.
    pub dst: usize,
    /// The lanes that are triangles.
    pub valid: u32,
    /// The first corners.
    pub a: [F; 3],
    /// The second corners.
    pub b: [F; 3],
    /// The third corners.
    pub o: [F; 3],
}

/// `ordered` with one light on a full block (the common case): `plane`'s operations with fewer
/// vectors live (O is loaded once N exists), and the 8 signs stored as 8 consecutive bytes
/// (one byte per slot) into `out`.
#[inline(always)]
fn ordered_one_full<Lv: Level, G: Geometry>(
    lay: &G,
    ids: &CanonBlock,
    lv: &[Lv::F; 4],
    out: &mut [i8],
) {
    // SAFETY: `ids` are vertices of the table (`Layout::build` checked them).
    let (a, b) = unsafe { (gather::<Lv, G>(lay, &ids[0]), gather::<Lv, G>(lay, &ids[1])) };
    let e = sub3(&a, &b);
    let n = edge_normal(lv, &a, &e);
    // SAFETY: as above.
    let o = unsafe { gather::<Lv, G>(lay, &ids[2]) };
    let m = off_plane(&n, &a, &o).signum0().to_i32();
    for (byte, s) in out.iter_mut().zip(m) {
        *byte = s as i8;
    }
}

/// `exact` with one light (`lv`, `light`, `one64`) on a full block, without the range check: as
/// [`ordered_one_full`], `O` is loaded only once the products exist (fewer vectors live).
/// Returns the evaluations decided by the scalar exact predicate.
#[inline(always)]
fn exact_one_full<Lv: Level, G: Geometry>(
    lay: &G,
    ids: &CanonBlock,
    lv: &[Lv::F; 4],
    light: &[f32; 4],
    one64: Option<[Lv::D; 4]>,
    out: &mut [&mut [i8]],
    dst: usize,
) -> u64 {
    // SAFETY: `ids` are vertices of the table (`Layout::build` checked them).
    let (a, b) = unsafe { (gather::<Lv, G>(lay, &ids[0]), gather::<Lv, G>(lay, &ids[1])) };
    let (pq, bad) = f32_products::<Lv::F, false>(&a, &b, lv);
    // SAFETY: as above.
    let o = unsafe { gather::<Lv, G>(lay, &ids[2]) };
    let (mut pos, mut neg, unc) = f32_decide::<Lv::F, false>(&pq, &a, &o, bad);
    let uncertain = Fallback::<Lv, G>::new(lay, ids).decide(light, one64, unc, &mut pos, &mut neg);
    write_one(out, dst, pos, neg);
    uncertain
}

/// `ordered` (and `original`, evaluated as `ordered`): `plane`'s operations with `A − B` and
/// `O − A` made once for all lights.
#[inline(always)]
fn ordered<Lv: Level>(block: &Block<'_, Lv::F>, lights: &[[f32; 4]], out: &mut [&mut [i8]]) {
    let Block {
        dst,
        valid,
        a,
        b,
        o,
        ..
    } = block;
    let (e, d) = (sub3(a, b), sub3(o, a));
    if lights.len() > 1 {
        // Each pack's sign bytes built in registers, one store.
        for (pack, chunk) in lights.chunks(PACK).enumerate() {
            let mut acc = [0u32; LANES];
            for (k, light) in chunk.iter().enumerate() {
                let n = edge_normal(&splat4(*light), a, &e);
                dot3(&n, &d).or_sign_bits(&mut acc, k as u32);
            }
            write_pack(out, pack, *dst, &acc, *valid);
        }
    } else {
        // One light, a partial block.
        let n = edge_normal(&splat4(lights[0]), a, &e);
        let (pos, neg) = dot3(&n, &d).sign_bits();
        write_one(out, *dst, pos & valid, neg & valid);
    }
}

/// `robust`: the three sides of each triangle; the sign where all three agree, else 0.
#[inline(always)]
fn robust<Lv: Level>(block: &Block<'_, Lv::F>, lights: &[[f32; 4]], out: &mut [&mut [i8]]) {
    let Block {
        dst,
        valid,
        a,
        b,
        o,
        ..
    } = block;
    if lights.len() > 1 {
        // Each pack's sign bytes built in registers, one store.
        for (pack, chunk) in lights.chunks(PACK).enumerate() {
            let mut acc = [0u32; LANES];
            for (k, light) in chunk.iter().enumerate() {
                let lv = splat4(*light);
                let sa = plane(a, b, &lv, o);
                let sb = plane(b, o, &lv, a);
                let sc = plane(o, a, &lv, b);
                sa.or_sign_bits3(sb, sc, &mut acc, k as u32);
            }
            write_pack(out, pack, *dst, &acc, *valid);
        }
    } else {
        // One light.
        let lv = splat4(lights[0]);
        let (pa, na) = plane(a, b, &lv, o).sign_bits();
        let (pb, nb) = plane(b, o, &lv, a).sign_bits();
        let (pc, nc) = plane(o, a, &lv, b).sign_bits();
        write_one(out, *dst, pa & pb & pc & valid, na & nb & nc & valid);
    }
}

/// `exact` with several lights (and their `stages`): each pack's sign bytes built in registers,
/// one store. The block's points are widened to f64 (by `fallback`) only when some lane needs
/// the f64 filter. Returns the evaluations decided by the scalar exact predicate.
#[inline(always)]
pub(super) fn exact_packs<Lv: Level, G: Geometry>(
    lay: &G,
    block: &Block<'_, Lv::F>,
    (lights, stages): (&[[f32; 4]], &[F32Stage]),
    one64: Option<[Lv::D; 4]>,
    out: &mut [&mut [i8]],
) -> u64 {
    let Block {
        ids,
        dst,
        valid,
        a,
        b,
        o,
    } = block;
    let mut uncertain = 0;
    let mut fallback = Fallback::<Lv, G>::new(lay, ids);
    for (pack, chunk) in lights.chunks(PACK).enumerate() {
        let mut acc = [0u32; LANES];
        for (k, light) in chunk.iter().enumerate() {
            // 1. The f32 filter on all 8 lanes; the sign of `det` is its decision in every lane
            // that is not uncertain.
            let lv32 = splat4(*light);
            let (det, unc32) = match stages[pack * PACK + k] {
                F32Stage::Skip => (Lv::F::splat(0.0), 0xFF),
                F32Stage::Checked => filter_f32_det::<Lv::F, true>(a, b, &lv32, o),
                F32Stage::Unchecked => filter_f32_det::<Lv::F, false>(a, b, &lv32, o),
            };
            det.or_sign_bits(&mut acc, k as u32);
            let unc = unc32 & valid;
            if unc != 0 {
                // 2, 3. The uncertain lanes (rare): their bits replaced.
                let (mut pos, mut neg) = (0, 0);
                uncertain += fallback.decide(light, one64, unc, &mut pos, &mut neg);
                set_sign_bits(&mut acc, k, unc, pos, neg);
            }
        }
        write_pack(out, pack, *dst, &acc, *valid);
    }
    uncertain
}

/// `exact` with one light (`lv32`, `light`, `stage`) on a block the one-light fast path does not
/// take. Returns the evaluations decided by the scalar exact predicate.
#[inline(always)]
fn exact_one<Lv: Level, G: Geometry>(
    lay: &G,
    block: &Block<'_, Lv::F>,
    (lv32, light, stage): (&[Lv::F; 4], &[f32; 4], F32Stage),
    one64: Option<[Lv::D; 4]>,
    out: &mut [&mut [i8]],
) -> u64 {
    let Block {
        ids,
        dst,
        valid,
        a,
        b,
        o,
    } = block;
    // 1. The f32 filter on all 8 lanes.
    let (mut pos, mut neg, unc32) = match stage {
        F32Stage::Skip => (0, 0, 0xFF),
        F32Stage::Checked => filter_f32::<Lv::F, true>(a, b, lv32, o),
        F32Stage::Unchecked => filter_f32::<Lv::F, false>(a, b, lv32, o),
    };
    let unc = unc32 & valid;
    let uncertain = Fallback::<Lv, G>::new(lay, ids).decide(light, one64, unc, &mut pos, &mut neg);
    write_one(out, *dst, pos & valid, neg & valid);
    uncertain
}
