//! `original` mode: per (edge, OV) `sign_f32(A, B, L, O)`, 8 edges per vector in the fast
//! (manifold) blocks, with `V`, `A − B` and `N` shared by the two OVs of an edge; the general
//! (CSR) blocks are scalar.

use super::{dot3, edge_normal, gather, off_plane, push_bits, splat4, store_part, sub3, EdgeOut};
use crate::dispatch::Pass;
use crate::lanes::{Level, F32V};
use crate::layout::{Geometry, LANES};
use shadowvol_robust_math::sign_f32;
use std::ops::Range;

/// `original` over the blocks `blocks` of one object: `out.rows[l]` receives the range's
/// multiplicities for light `l`, `out.sil[l]` collects `edge_base + e` where `m != 0`.
pub(crate) struct EdgeOriginal<'a, 'r, G> {
    /// The object's layout.
    pub lay: &'a G,
    /// Blocks of 8 edges.
    pub blocks: Range<usize>,
    /// The lights, in the object's frame.
    pub lights: &'a [[f32; 4]],
    /// Where the results go.
    pub out: EdgeOut<'a, 'r>,
}

impl<G: Geometry> Pass for EdgeOriginal<'_, '_, G> {
    type Out = ();
    #[inline(always)]
    fn run<Lv: Level>(self) {
        edge_original::<Lv, G>(self);
    }
}

/// [`EdgeOriginal`] at level `Lv`.
#[inline(always)]
fn edge_original<Lv: Level, G: Geometry>(pass: EdgeOriginal<G>) {
    let EdgeOriginal {
        lay,
        blocks,
        lights,
        mut out,
    } = pass;
    let edge_base = out.edge_base;
    if let ([light], [out0], [sil0]) = (lights, &mut *out.rows, &mut *out.sil) {
        edge_original_one::<Lv, G>(lay, blocks, *light, out0, sil0, edge_base);
        return;
    }
    let e_start = blocks.start * LANES;
    for blk in blocks {
        let e0 = blk * LANES;
        if lay.block_fast(blk) {
            let [ia, ib, i1, i2] = lay.fast_ends_and_ovs(blk);
            // SAFETY: 8 ids each, all vertices of the table (`Layout::build`).
            let (a, b, o1, o2) = unsafe {
                (
                    gather::<Lv, G>(lay, &ia),
                    gather::<Lv, G>(lay, &ib),
                    gather::<Lv, G>(lay, &i1),
                    gather::<Lv, G>(lay, &i2),
                )
            };
            // The operations of `sign_f32`: `A − B` and both `O − A` made once for all lights,
            // `V` and `N` once per light for both OVs.
            let (e, d1, d2) = (sub3(&a, &b), sub3(&o1, &a), sub3(&o2, &a));
            for (l, light) in lights.iter().enumerate() {
                let n = edge_normal(&splat4::<Lv::F>(*light), &a, &e);
                let m = dot3(&n, &d1).signum0() + dot3(&n, &d2).signum0();
                let dst = &mut out.rows[l][e0 - e_start..];
                let nz = if dst.len() >= LANES {
                    m.store_i32_cached(dst)
                } else {
                    store_part(m, dst)
                };
                push_bits(&mut out.sil[l], nz, edge_base + e0);
            }
        } else {
            original_general_block(lay, e0, e_start, lights, &mut out);
        }
    }
}

/// `original` for the block starting at edge `e0` through the general (CSR) path, scalar: any
/// number of OVs per edge; `out.rows` start at edge `e_start`.
#[inline(always)]
fn original_general_block<G: Geometry>(
    lay: &G,
    e0: usize,
    e_start: usize,
    lights: &[[f32; 4]],
    out: &mut EdgeOut,
) {
    for e in e0..(e0 + LANES).min(lay.edge_count()) {
        let [a, b] = lay.general_ends(e);
        let (pa, pb) = (lay.pos(a), lay.pos(b));
        for (l, light) in lights.iter().enumerate() {
            let m: i32 = lay
                .general_ovs(e)
                .map(|o| i32::from(sign_f32(pa, pb, *light, lay.pos(o))))
                .sum();
            out.rows[l][e - e_start] = m;
            if m != 0 {
                out.sil[l].push((out.edge_base + e) as u32);
            }
        }
    }
}

/// [`edge_original`] for one light (the common case): the same operations as the general
/// loop, ordered so that fewer vectors are live at once (the OVs are loaded only once `N`
/// exists, which spares the general loop's register spills), with the light's lanes made
/// once and the output written with streaming stores (one output row, written once).
#[inline(always)]
fn edge_original_one<Lv: Level, G: Geometry>(
    lay: &G,
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
        if !lay.block_fast(blk) {
            let mut rest = EdgeOut {
                rows: &mut [&mut *out],
                sil: std::slice::from_mut(sil),
                edge_base,
            };
            original_general_block(lay, e0, e_start, &[light], &mut rest);
            continue;
        }
        let ids = lay.fast_ends_and_ovs(blk);
        // SAFETY: 8 ids each, all vertices of the table (`Layout::build`).
        let (a, b) = unsafe { (gather::<Lv, G>(lay, &ids[0]), gather::<Lv, G>(lay, &ids[1])) };
        let e = sub3(&a, &b);
        let n = edge_normal(&lv, &a, &e);
        // SAFETY: as above.
        let o1 = unsafe { gather::<Lv, G>(lay, &ids[2]) };
        let d1 = off_plane(&n, &a, &o1);
        // SAFETY: as above.
        let o2 = unsafe { gather::<Lv, G>(lay, &ids[3]) };
        let d2 = off_plane(&n, &a, &o2);
        let m = d1.signum0() + d2.signum0();
        let dst = &mut out[e0 - e_start..];
        let nz = if dst.len() >= LANES {
            m.store_i32(dst)
        } else {
            store_part(m, dst)
        };
        push_bits(sil, nz, edge_base + e0);
    }
    // Streaming stores (`store_i32`) are weakly ordered: make them visible before the caller
    // (another thread, after rayon's join) reads the output.
    Lv::store_fence();
}
