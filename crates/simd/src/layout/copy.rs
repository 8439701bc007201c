//! A copy of one edge table laid out for the kernels' speed.
//!
//! * Vertices are *stored* in the order of their first reference when walking the edges (and
//!   their OVs) in table order, so the vertices one block of edges touches sit close together
//!   (a Cuthill-McKee-like renumbering); canonical order and parity still use the table's ids.
//! * Positions as 16-byte records `[x, y, z, 0]`: one aligned load per vertex.
//! * Triangles in canonical vertex order (ascending ids), sorted, as three columns, so the
//!   triangle pass walks the vertices roughly front to back, in the order of the edges (which
//!   the table sorts by their smaller vertex). A triangle's slot is its place in this order.
//! * Edges keep the table's order (global edge index = output slot), in blocks of [`LANES`]. A
//!   fast block (all edges manifold) keeps per edge `a`, `b` and the two OVs for `original`
//!   and its two references `4 s + r` (slot `s`, rank 1 or 0 for the parity) for the other
//!   modes. Every other block keeps CSR records in [`GeneralBlocks`].

use super::LANES;
use super::{
    check_table, fast_blocks, positions_in_filter_range, CanonBlock, FastRefs, Geometry,
    LayoutError,
};
use crate::lanes::Level;
use shadowvol_mesh_topology::EdgeTable;
use std::sync::Arc;

/// One edge table laid out for the kernels.
#[derive(Debug)]
pub(crate) struct CopyLayout {
    /// Positions as 16-byte records `[x, y, z, 0]` (one aligned load per vertex).
    pub xyz: Vec<[f32; 4]>,
    /// Canonical triangles (ascending ids `t0 < t1 < t2`), sorted, a block of [`LANES`] at a
    /// time as the kernels read them (the last block padded with vertex 0).
    pub tris: Vec<CanonBlock>,
    /// Number of real triangles in `tris`.
    pub tri_count: usize,
    /// Number of edges.
    pub edge_count: usize,
    /// Per block of [`LANES`] edges: true when every edge of the block is manifold. The last
    /// block may be partial: the per-edge arrays below are padded to whole blocks, and the
    /// kernels keep only the lanes of real edges.
    pub block_fast: Vec<bool>,
    /// Per edge `a`, `b` and the two OVs (only meaningful in fast blocks; 0 elsewhere and in
    /// the padding, vertex 0 being valid wherever a fast block exists), padded with 0 to a
    /// multiple of [`LANES`].
    pub ea: Vec<u32>,
    /// See `ea`.
    pub eb: Vec<u32>,
    /// See `ea`.
    pub eo1: Vec<u32>,
    /// See `ea`.
    pub eo2: Vec<u32>,
    /// Per block of [`LANES`] edges, each fast edge's two references `4 s + r` (triangle slot
    /// `s`, `r` 1 for odd parity, else 0) as [`FastRefs`]; 0 elsewhere and in the padding.
    pub refs: Vec<FastRefs>,
    /// The CSR records of the blocks that are not fast, for the general path.
    pub general: GeneralBlocks,
    /// Every stored coordinate passes
    /// [`coord_in_filter_range`](super::coord_in_filter_range) (a multiple of 2^-40 of magnitude
    /// at most 2^39): then, with a light whose coordinates pass too, no difference the `f32`
    /// filter forms can fail its range check.
    pub coords_in_filter_range: bool,
}

/// The edges of the blocks whose `block_fast` is false, in CSR form, block by block: a mesh
/// with few boundary or non-manifold edges keeps few of them (a closed manifold one none).
#[derive(Debug, Default)]
pub(crate) struct GeneralBlocks {
    /// Per block of [`LANES`] edges: its index among the general blocks, or [`NOT_GENERAL`].
    pub index: Vec<u32>,
    /// Per general block, [`LANES`] edge endpoints (storage indices), padded with `[0, 0]`.
    pub edges: Vec<[u32; 2]>,
    /// Per general block, [`LANES`] + 1 offsets into `ovs` / `refs` (equal past the last
    /// edge).
    pub offsets: Vec<u32>,
    /// Opposite vertices (storage indices).
    pub ovs: Vec<u32>,
    /// The reference `4 s + r` of each entry of `ovs` (as [`CopyLayout::refs`]).
    pub refs: Vec<u32>,
}

/// [`GeneralBlocks::index`] of a fast block.
pub(crate) const NOT_GENERAL: u32 = u32::MAX;

impl GeneralBlocks {
    /// The records of the blocks of `table`'s edges that `block_fast` marks as not fast, with
    /// vertices at their storage index `st` and the references `refs` of [`slot_refs`].
    fn new(table: &EdgeTable, st: &[u32], refs: &[u32], block_fast: &[bool]) -> Self {
        let ne = table.edges.len();
        let mut g = Self {
            index: Vec::with_capacity(block_fast.len()),
            ..Self::default()
        };
        let mut count = 0u32;
        for (blk, &fast) in block_fast.iter().enumerate() {
            if fast {
                g.index.push(NOT_GENERAL);
                continue;
            }
            g.index.push(count);
            count += 1;
            for k in 0..LANES {
                let e = blk * LANES + k;
                g.offsets.push(g.ovs.len() as u32);
                if e >= ne {
                    g.edges.push([0, 0]);
                    continue;
                }
                let [a, b] = table.edges[e];
                g.edges.push([st[a as usize], st[b as usize]]);
                let r = table.ov_offsets[e] as usize..table.ov_offsets[e + 1] as usize;
                g.ovs.extend(
                    table.ov_refs[r.clone()]
                        .iter()
                        .map(|&c| st[table.ov_vertex(c) as usize]),
                );
                g.refs.extend_from_slice(&refs[r]);
            }
            g.offsets.push(g.ovs.len() as u32);
        }
        g
    }

    fn heap_bytes(&self) -> u64 {
        use shadowvol_silhouette::vec_bytes;
        vec_bytes(&self.index)
            + vec_bytes(&self.edges)
            + vec_bytes(&self.offsets)
            + vec_bytes(&self.ovs)
            + vec_bytes(&self.refs)
    }
}

impl CopyLayout {
    /// Heap bytes of every array of the layout (capacities).
    pub(crate) fn heap_bytes(&self) -> u64 {
        use shadowvol_silhouette::vec_bytes;
        vec_bytes(&self.xyz)
            + vec_bytes(&self.tris)
            + vec_bytes(&self.block_fast)
            + vec_bytes(&self.ea)
            + vec_bytes(&self.eb)
            + vec_bytes(&self.eo1)
            + vec_bytes(&self.eo2)
            + vec_bytes(&self.refs)
            + self.general.heap_bytes()
    }

    /// Edge `e` of a general block: its ends (storage indices) and the range of its OVs in
    /// [`GeneralBlocks::ovs`] and [`GeneralBlocks::refs`].
    ///
    /// # Panics
    /// If `e`'s block is fast, or `e` is out of range.
    #[inline(always)]
    fn general_edge(&self, e: usize) -> ([u32; 2], std::ops::Range<usize>) {
        let g = &self.general;
        let blk = g.index[e / LANES];
        assert!(blk != NOT_GENERAL, "edge {e} is in a fast block");
        let (k, o) = (blk as usize * LANES, blk as usize * (LANES + 1));
        let i = e % LANES;
        (
            g.edges[k + i],
            g.offsets[o + i] as usize..g.offsets[o + i + 1] as usize,
        )
    }
}

const fn zero_record() -> [f32; 4] {
    [0.0; 4]
}

impl CopyLayout {
    /// Lays out `table`. Checks every index against the vertex count, so the kernels may rely
    /// on it.
    pub(crate) fn build(table: &Arc<EdgeTable>) -> Result<Self, LayoutError> {
        check_table(table)?;
        let nv = table.positions.len();
        let st = storage_order(table);
        let mut stored = vec![zero_record(); nv];
        for (v, p) in table.positions.iter().enumerate() {
            stored[st[v] as usize] = [p.x, p.y, p.z, 0.0];
        }
        let coords_in_filter_range = positions_in_filter_range(table);
        let xyz = stored;
        let sv = |v: u32| st[v as usize];

        // Canonical triangles, sorted for locality; `slot[t]` = position of table triangle t.
        let mut canon: Vec<([u32; 3], u32)> = table
            .triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let mut c = *tri;
                c.sort_unstable();
                (c, t as u32)
            })
            .collect();
        canon.sort_unstable();
        let mut slot = vec![0u32; canon.len()];
        for (i, &(_, t)) in canon.iter().enumerate() {
            slot[t as usize] = i as u32;
        }
        let tri_count = canon.len();
        let tris: Vec<CanonBlock> = canon
            .chunks(LANES)
            .map(|block| {
                let mut ids = [[0u32; LANES]; 3];
                for (i, (c, _)) in block.iter().enumerate() {
                    for k in 0..3 {
                        ids[k][i] = sv(c[k]);
                    }
                }
                ids
            })
            .collect();
        // Freed as soon as they are done with (16 and 4 bytes a triangle), so that the per-edge
        // columns below are not built beside them.
        drop(canon);
        let refs = slot_refs(table, &slot);
        drop(slot);
        let ne = table.edges.len();
        let manifold = ManifoldEdges::new(table, &st, &refs);
        let general = GeneralBlocks::new(table, &st, &refs, &manifold.block_fast);
        drop(refs);
        Ok(Self {
            xyz,
            tris,
            tri_count,
            edge_count: ne,
            block_fast: manifold.block_fast,
            ea: manifold.ea,
            eb: manifold.eb,
            eo1: manifold.eo1,
            eo2: manifold.eo2,
            refs: manifold.refs,
            general,
            coords_in_filter_range,
        })
    }
}

/// The storage index of each vertex: order of first reference when walking the edges (and their
/// OVs) in table order, so the vertices one block of edges touches sit close together in memory
/// (a Cuthill-McKee-like renumbering). Only where positions are *stored* changes; canonical
/// order and parity still use the table's ids.
fn storage_order(table: &EdgeTable) -> Vec<u32> {
    let nv = table.positions.len();
    let mut st = vec![u32::MAX; nv];
    let mut next = 0u32;
    let mut place = |v: u32, st: &mut Vec<u32>| {
        if st[v as usize] == u32::MAX {
            st[v as usize] = next;
            next += 1;
        }
    };
    for (e, &[a, b]) in table.edges.iter().enumerate() {
        place(a, &mut st);
        place(b, &mut st);
        for o in table.ovs_of(e) {
            place(o, &mut st);
        }
    }
    for v in 0..nv as u32 {
        place(v, &mut st);
    }
    st
}

/// For each (edge, OV) entry of `table`, its reference with the triangle slot `slot[t]` in
/// place of the table's triangle `t`: `4 slot[t] + 1` for odd parity, `4 slot[t]` for even.
fn slot_refs(table: &EdgeTable, slot: &[u32]) -> Vec<u32> {
    table
        .ov_refs
        .iter()
        .map(|&r| 4 * slot[EdgeTable::ov_triangle(r) as usize] + u32::from(EdgeTable::ov_odd(r)))
        .collect()
}

/// The fast path's columns: for each two-OV (manifold) edge its ends, OVs (storage indices) and
/// references; zeros elsewhere and in the padding to whole blocks. A block is fast when all its
/// edges are manifold.
struct ManifoldEdges {
    block_fast: Vec<bool>,
    ea: Vec<u32>,
    eb: Vec<u32>,
    eo1: Vec<u32>,
    eo2: Vec<u32>,
    refs: Vec<FastRefs>,
}

impl ManifoldEdges {
    /// The columns of `table`, with vertices at their storage index `st` and the references
    /// `refs` of [`slot_refs`].
    fn new(table: &EdgeTable, st: &[u32], refs: &[u32]) -> Self {
        let sv = |v: u32| st[v as usize];
        let ne = table.edges.len();
        let block_fast = fast_blocks(table);
        // Padded to whole blocks, so a partial last block of manifold edges takes the fast path.
        let ne_padded = ne.div_ceil(LANES) * LANES;
        let (mut ea, mut eb) = (vec![0u32; ne_padded], vec![0u32; ne_padded]);
        let (mut eo1, mut eo2) = (vec![0u32; ne_padded], vec![0u32; ne_padded]);
        let mut pairs = vec![[[0u32; LANES]; 2]; ne_padded / LANES];
        for e in 0..ne {
            let (s, t) = (
                table.ov_offsets[e] as usize,
                table.ov_offsets[e + 1] as usize,
            );
            if t - s == 2 {
                let [a, b] = table.edges[e];
                (ea[e], eb[e]) = (sv(a), sv(b));
                let ov = |k: usize| sv(table.ov_vertex(table.ov_refs[k]));
                (eo1[e], eo2[e]) = (ov(s), ov(s + 1));
                let (blk, i) = (e / LANES, e % LANES);
                (pairs[blk][0][i], pairs[blk][1][i]) = (refs[s], refs[s + 1]);
            }
        }
        Self {
            block_fast,
            ea,
            eb,
            eo1,
            eo2,
            refs: pairs,
        }
    }
}

impl Geometry for CopyLayout {
    type Canon<'a> = &'a CanonBlock;
    type Refs<'a> = &'a FastRefs;

    #[inline(always)]
    fn tri_count(&self) -> usize {
        self.tri_count
    }

    #[inline(always)]
    fn edge_count(&self) -> usize {
        self.edge_count
    }

    #[inline(always)]
    fn block_fast(&self, blk: usize) -> bool {
        self.block_fast[blk]
    }

    #[inline(always)]
    fn coords_in_filter_range(&self) -> bool {
        self.coords_in_filter_range
    }

    #[inline(always)]
    fn canon_block<Lv: Level>(&self, t: usize) -> &CanonBlock {
        &self.tris[t / LANES]
    }

    #[inline(always)]
    unsafe fn gather<Lv: Level>(&self, idx: &[u32]) -> [Lv::F; 3] {
        // SAFETY: the ids are stored vertices (the caller).
        unsafe { Lv::gather_records(&self.xyz, idx) }
    }

    #[inline(always)]
    fn pos(&self, v: u32) -> [f32; 3] {
        let [x, y, z, _] = self.xyz[v as usize];
        [x, y, z]
    }

    #[inline(always)]
    fn fast_refs(&self, blk: usize) -> &FastRefs {
        &self.refs[blk]
    }

    #[inline(always)]
    fn fast_ends_and_ovs(&self, blk: usize) -> [[u32; LANES]; 4] {
        let e0 = blk * LANES;
        let col =
            |c: &[u32]| -> [u32; LANES] { c[e0..e0 + LANES].try_into().unwrap_or([0; LANES]) };
        [col(&self.ea), col(&self.eb), col(&self.eo1), col(&self.eo2)]
    }

    #[inline(always)]
    fn general_ends(&self, e: usize) -> [u32; 2] {
        self.general_edge(e).0
    }

    #[inline(always)]
    fn general_refs(&self, e: usize) -> &[u32] {
        &self.general.refs[self.general_edge(e).1]
    }

    #[inline(always)]
    fn general_ovs(&self, e: usize) -> impl Iterator<Item = u32> + '_ {
        self.general.ovs[self.general_edge(e).1].iter().copied()
    }
}
