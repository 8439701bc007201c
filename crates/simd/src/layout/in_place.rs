//! The table itself, read in place: its positions (12-byte records, compact ids), its
//! triangles in their own order and winding (sorted into canonical order eight at a time as the
//! triangle pass loads them), its edges and its opposite-vertex references `4 t + r`, whose
//! triangle `t` is the sign slot and whose rank `r` the parity. It adds only, per block of
//! [`LANES`] edges, whether the block is fast.

use super::LANES;
use super::{
    check_table, fast_blocks, positions_in_filter_range, CanonBlock, FastRefs, Geometry,
    LayoutError,
};
use crate::lanes::{canon8_scalar, Level};
use shadowvol_mesh_topology::EdgeTable;
use std::sync::Arc;

/// One edge table, read in place.
#[derive(Debug)]
pub(crate) struct InPlaceLayout {
    /// The table.
    table: Arc<EdgeTable>,
    /// Per block of [`LANES`] edges: true when every edge of the block is manifold.
    block_fast: Vec<bool>,
    /// Every coordinate passes [`coord_in_filter_range`](super::coord_in_filter_range).
    coords_in_filter_range: bool,
}

impl InPlaceLayout {
    /// Checks `table` and notes its fast blocks.
    pub(crate) fn build(table: &Arc<EdgeTable>) -> Result<Self, LayoutError> {
        check_table(table)?;
        let coords_in_filter_range = positions_in_filter_range(table);
        Ok(Self {
            table: Arc::clone(table),
            block_fast: fast_blocks(table),
            coords_in_filter_range,
        })
    }

    /// Heap bytes the layout adds to its table.
    pub(crate) fn heap_bytes(&self) -> u64 {
        shadowvol_silhouette::vec_bytes(&self.block_fast)
    }

    /// The references of the fast block `blk`, which the table keeps two by two, as
    /// [`FastRefs`].
    #[inline(always)]
    fn refs_of_block(&self, blk: usize) -> FastRefs {
        let e0 = blk * LANES;
        let n = (self.edge_count() - e0).min(LANES);
        let k0 = self.table.ov_offsets[e0] as usize;
        let mut refs = [[0u32; LANES]; 2];
        for (i, pair) in self.table.ov_refs[k0..k0 + 2 * n]
            .chunks_exact(2)
            .enumerate()
        {
            (refs[0][i], refs[1][i]) = (pair[0], pair[1]);
        }
        refs
    }
}

/// What the layout makes as it reads the table: a block of triangles sorted into canonical
/// order, or a block's references in columns.
pub(crate) struct Made<T>(T);

impl<T> std::ops::Deref for Made<T> {
    type Target = T;
    #[inline(always)]
    fn deref(&self) -> &T {
        &self.0
    }
}

impl Geometry for InPlaceLayout {
    type Canon<'a> = Made<CanonBlock>;
    type Refs<'a> = Made<FastRefs>;

    #[inline(always)]
    fn tri_count(&self) -> usize {
        self.table.triangles.len()
    }

    #[inline(always)]
    fn edge_count(&self) -> usize {
        self.table.edges.len()
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
    fn canon_block<Lv: Level>(&self, t: usize) -> Made<CanonBlock> {
        let tris = &self.table.triangles[t..(t + LANES).min(self.tri_count())];
        Made(match tris.try_into() {
            Ok(whole) => Lv::canon8(whole),
            Err(_) => canon8_scalar(tris),
        })
    }

    #[inline(always)]
    unsafe fn gather<Lv: Level>(&self, idx: &[u32]) -> [Lv::F; 3] {
        // SAFETY: the ids are vertices (the caller); a table with a triangle has three.
        unsafe { Lv::gather_vec3(&self.table.positions, idx) }
    }

    #[inline(always)]
    fn pos(&self, v: u32) -> [f32; 3] {
        self.table.positions[v as usize].to_array()
    }

    #[inline(always)]
    fn fast_refs(&self, blk: usize) -> Made<FastRefs> {
        Made(self.refs_of_block(blk))
    }

    #[inline(always)]
    fn fast_ends_and_ovs(&self, blk: usize) -> [[u32; LANES]; 4] {
        let e0 = blk * LANES;
        let [first, second] = self.refs_of_block(blk);
        let edges = &self.table.edges[e0..(e0 + LANES).min(self.edge_count())];
        let tris = &self.table.triangles;
        let mut v = [[0u32; LANES]; 4];
        for (i, &[a, b]) in edges.iter().enumerate() {
            // The triangle holds a, b and the opposite vertex: the xor of its ids and the
            // edge's ends is that vertex.
            let ov = |r: u32| {
                let [x, y, z] = tris[EdgeTable::ov_triangle(r) as usize];
                x ^ y ^ z ^ a ^ b
            };
            v[0][i] = a;
            v[1][i] = b;
            v[2][i] = ov(first[i]);
            v[3][i] = ov(second[i]);
        }
        v
    }

    #[inline(always)]
    fn general_ends(&self, e: usize) -> [u32; 2] {
        self.table.edges[e]
    }

    #[inline(always)]
    fn general_refs(&self, e: usize) -> &[u32] {
        self.table.ov_refs_of(e)
    }

    #[inline(always)]
    fn general_ovs(&self, e: usize) -> impl Iterator<Item = u32> + '_ {
        self.table.ovs_of(e)
    }
}
