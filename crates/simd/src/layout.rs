//! The prepared, streaming-friendly layout of one edge table.
//!
//! * Positions are stored as three arrays (`xs`, `ys`, `zs`: structure of arrays), indexed by
//!   compact vertex id.
//! * Triangles are stored in canonical vertex order (ascending ids) and sorted, so the
//!   per-triangle pass walks the vertex arrays roughly front to back, in the same order as the
//!   edges (which [`EdgeTable`] sorts by their smaller vertex).
//! * Edges keep the table's order (global edge index = output slot) and are processed in blocks
//!   of [`LANES`]. A block whose edges all have exactly two opposite vertices (the closed-manifold
//!   case) takes the fast path, which needs no CSR offsets: `abo[e] = [a, b, o1, o2]` for the
//!   per-edge `original` mode and `tri_a[e]`, `tri_b[e]` (canonical-triangle index with the
//!   permutation parity in bit 31) for the per-triangle modes. Every other block takes the general
//!   CSR path (`ov_offsets`, `ovs`, `ov_tri`).

use shadowvol_mesh_topology::EdgeTable;

/// Lanes per `f32` vector and edges / triangles per block.
pub(crate) const LANES: usize = 8;

/// Bit 31 of a triangle reference: the (edge, OV) pair has odd parity (`a < o < b`).
pub(crate) const ODD: u32 = 1 << 31;

/// One edge table laid out for the kernels.
#[derive(Debug)]
pub(crate) struct Layout {
    pub xs: Vec<f32>,
    pub ys: Vec<f32>,
    pub zs: Vec<f32>,
    /// Positions as 16-byte records `[x, y, z, 0]` (one aligned load per vertex).
    pub xyz: Vec<[f32; 4]>,
    /// Canonical triangles (ascending ids `t0 < t1 < t2`), sorted, as three arrays; padded with
    /// vertex 0 to a multiple of [`LANES`].
    pub t0: Vec<u32>,
    /// Second vertex of each canonical triangle.
    pub t1: Vec<u32>,
    /// Third vertex of each canonical triangle.
    pub t2: Vec<u32>,
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
    /// Per edge: the two canonical triangles with parity bits (only meaningful in fast blocks;
    /// padded with triangle slot 0 like `ea`).
    pub tri_a: Vec<u32>,
    /// Second triangle reference of each edge (see `tri_a`).
    pub tri_b: Vec<u32>,
    /// The CSR records of the blocks that are not fast, for the general path.
    pub general: GeneralBlocks,
    /// Every stored coordinate passes [`coord_in_filter_range`] (a multiple of 2^-40 of
    /// magnitude at most 2^39): then, with a light whose coordinates pass too, no difference the
    /// `f32` filter forms can fail its range check.
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
    /// Per general block, [`LANES`] + 1 offsets into `ovs` / `ov_tri` (equal past the last
    /// edge).
    pub offsets: Vec<u32>,
    /// Opposite vertices (storage indices).
    pub ovs: Vec<u32>,
    /// Canonical-triangle index of each entry of `ovs`, with [`ODD`] for odd parity.
    pub ov_tri: Vec<u32>,
}

/// [`GeneralBlocks::index`] of a fast block.
pub(crate) const NOT_GENERAL: u32 = u32::MAX;

impl GeneralBlocks {
    /// The records of the blocks of `table`'s edges that `block_fast` marks as not fast, with
    /// vertices at their storage index `st` and the OV triangles `ov_tri` of [`ov_triangles`].
    fn new(table: &EdgeTable, st: &[u32], ov_tri: &[u32], block_fast: &[bool]) -> Self {
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
                g.ovs
                    .extend(table.ovs[r.clone()].iter().map(|&o| st[o as usize]));
                g.ov_tri.extend_from_slice(&ov_tri[r]);
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
            + vec_bytes(&self.ov_tri)
    }
}

impl Layout {
    /// Heap bytes of every array of the layout (capacities).
    pub(crate) fn heap_bytes(&self) -> u64 {
        use shadowvol_silhouette::vec_bytes;
        vec_bytes(&self.xs)
            + vec_bytes(&self.ys)
            + vec_bytes(&self.zs)
            + vec_bytes(&self.xyz)
            + vec_bytes(&self.t0)
            + vec_bytes(&self.t1)
            + vec_bytes(&self.t2)
            + vec_bytes(&self.block_fast)
            + vec_bytes(&self.ea)
            + vec_bytes(&self.eb)
            + vec_bytes(&self.eo1)
            + vec_bytes(&self.eo2)
            + vec_bytes(&self.tri_a)
            + vec_bytes(&self.tri_b)
            + self.general.heap_bytes()
    }

    /// Edge `e` of a general block: its ends (storage indices) and the range of its OVs in
    /// [`GeneralBlocks::ovs`] and [`GeneralBlocks::ov_tri`].
    ///
    /// # Panics
    /// If `e`'s block is fast, or `e` is out of range.
    #[inline(always)]
    pub(crate) fn general_edge(&self, e: usize) -> ([u32; 2], std::ops::Range<usize>) {
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

/// Largest coordinate magnitude (2^39) for which the `f32` filter's range check is known to
/// pass without evaluating it.
pub(crate) const COORD_MAX: f32 = 549_755_813_888.0;

/// The grid step (2^-40 = `F32_FILTER_MIN`) every coordinate must be a multiple of.
const COORD_STEP_INV: f32 = 1_099_511_627_776.0; // 2^40

/// Whether `x` is an integer multiple of 2^-40 with `|x| <= 2^39` (false for NaN and
/// infinities). Every `f32` of magnitude at least 2^-17 is such a multiple (its ulp is 2^-40 or
/// coarser), and so are 0 and, for example, `1 - 0.99999994 = 2^-24`.
///
/// If every coordinate of `A`, `B`, `O` and `L.xyz` passes and `L.w` is 0 or 1, each of the nine
/// differences of `orient_filter_f32` (`A - B`, `L.xyz - w A`, `O - A`) passes its range check
/// (`0` or a magnitude in `[2^-40, 2^40]`): `w A` is `A` or a zero exactly, so each exact
/// difference is a multiple of 2^-40 of magnitude at most 2^39 + 2^39 = 2^40; round-to-nearest
/// is monotone and both bounds are representable, so a non-zero exact difference rounds into
/// `[2^-40, 2^40]`, and a zero one gives 0.
#[inline]
pub(crate) fn coord_in_filter_range(x: f32) -> bool {
    // `x * 2^40` is exact: a power-of-two scaling that cannot overflow for |x| <= 2^39.
    x.abs() <= COORD_MAX && (x * COORD_STEP_INV).fract() == 0.0
}

const fn zero_record() -> [f32; 4] {
    [0.0; 4]
}

/// Why a table cannot be laid out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LayoutError(pub String);

impl Layout {
    /// Lays out `table`. Checks every index against the vertex count, so the kernels may rely
    /// on it.
    pub(crate) fn build(table: &EdgeTable) -> Result<Self, LayoutError> {
        check_table(table)?;
        let nv = table.positions.len();
        let st = storage_order(table);
        let mut stored = vec![zero_record(); nv];
        for (v, p) in table.positions.iter().enumerate() {
            stored[st[v] as usize] = [p.x, p.y, p.z, 0.0];
        }
        let xs = stored.iter().map(|p| p[0]).collect();
        let ys = stored.iter().map(|p| p[1]).collect();
        let zs = stored.iter().map(|p| p[2]).collect();
        let coords_in_filter_range = stored
            .iter()
            .all(|p| p[..3].iter().all(|&c| coord_in_filter_range(c)));
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
        let padded = tri_count.div_ceil(LANES) * LANES;
        let column = |k: usize| -> Vec<u32> {
            let mut v: Vec<u32> = canon.iter().map(|(c, _)| sv(c[k])).collect();
            v.resize(padded, 0);
            v
        };
        let (t0, t1, t2) = (column(0), column(1), column(2));
        // Freed as soon as they are done with (16 and 4 bytes a triangle), so that the per-edge
        // columns below are not built beside them.
        drop(canon);
        let ov_tri = ov_triangles(table, &slot)?;
        drop(slot);
        let ne = table.edges.len();
        let manifold = ManifoldEdges::new(table, &st, &ov_tri);
        let general = GeneralBlocks::new(table, &st, &ov_tri, &manifold.block_fast);
        drop(ov_tri);
        Ok(Self {
            xs,
            ys,
            zs,
            xyz,
            t0,
            t1,
            t2,
            tri_count,
            edge_count: ne,
            block_fast: manifold.block_fast,
            ea: manifold.ea,
            eb: manifold.eb,
            eo1: manifold.eo1,
            eo2: manifold.eo2,
            tri_a: manifold.tri_a,
            tri_b: manifold.tri_b,
            general,
            coords_in_filter_range,
        })
    }

    /// Position of the vertex stored at index `v` (all index arrays of the layout hold storage
    /// indices) as an array.
    #[inline(always)]
    pub(crate) fn pos(&self, v: u32) -> [f32; 3] {
        let v = v as usize;
        [self.xs[v], self.ys[v], self.zs[v]]
    }
}

/// Checks that `table` fits the layout's index range and is consistent (offsets and OVs agree,
/// every vertex id is in range), so the kernels may rely on it.
fn check_table(table: &EdgeTable) -> Result<(), LayoutError> {
    let nv = table.positions.len();
    if nv >= i32::MAX as usize || table.triangles.len() >= (ODD as usize) - LANES {
        return Err(LayoutError(format!(
            "{nv} vertices / {} triangles exceed the 2^31 limit of the layout",
            table.triangles.len()
        )));
    }
    if table.ov_offsets.len() != table.edges.len() + 1
        || table.ov_offsets.last().copied().unwrap_or(0) as usize != table.ovs.len()
    {
        return Err(LayoutError(
            "edge table is inconsistent (offsets and OVs disagree)".to_owned(),
        ));
    }
    let in_range = |v: u32| (v as usize) < nv;
    if !table.triangles.iter().flatten().all(|&v| in_range(v))
        || !table.edges.iter().flatten().all(|&v| in_range(v))
        || !table.ovs.iter().all(|&v| in_range(v))
    {
        return Err(LayoutError(format!(
            "edge table refers to a vertex id >= its {nv} positions"
        )));
    }
    Ok(())
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
        for &o in table.ovs_of(e) {
            place(o, &mut st);
        }
    }
    for v in 0..nv as u32 {
        place(v, &mut st);
    }
    st
}

/// For each (edge, OV) entry, its triangle's slot (`slot[t]` for table triangle `t`), with
/// [`ODD`] set when the OV lies between the edge's ends. OVs of an edge are listed in ascending
/// triangle order, so filling per edge while walking triangles in order reproduces it; a table
/// where it does not is an error.
fn ov_triangles(table: &EdgeTable, slot: &[u32]) -> Result<Vec<u32>, LayoutError> {
    let ne = table.edges.len();
    let mut fill: Vec<u32> = table.ov_offsets[..ne].to_vec();
    let mut ov_tri = vec![0u32; table.ovs.len()];
    for (t, tri, te) in table.triangles_with_edges() {
        for i in 0..3 {
            let e = te[i] as usize;
            let o = tri[(i + 2) % 3];
            let [a, b] = *table.edges.get(e).ok_or_else(|| {
                LayoutError(format!("triangle {t} refers to edge {e} out of range"))
            })?;
            let k = fill[e] as usize;
            if k >= table.ov_offsets[e + 1] as usize || table.ovs[k] != o {
                return Err(LayoutError(format!(
                    "edge {e}: opposite vertex list does not match triangle {t}"
                )));
            }
            fill[e] += 1;
            let odd = if a < o && o < b { ODD } else { 0 };
            ov_tri[k] = slot[t] | odd;
        }
    }
    Ok(ov_tri)
}

/// The fast path's columns: for each two-OV (manifold) edge its ends, OVs (storage indices) and
/// OV triangles; zeros elsewhere and in the padding to whole blocks. A block is fast when all its
/// edges are manifold.
struct ManifoldEdges {
    block_fast: Vec<bool>,
    ea: Vec<u32>,
    eb: Vec<u32>,
    eo1: Vec<u32>,
    eo2: Vec<u32>,
    tri_a: Vec<u32>,
    tri_b: Vec<u32>,
}

impl ManifoldEdges {
    /// The columns of `table`, with vertices at their storage index `st` and the OV triangles
    /// `ov_tri` of [`ov_triangles`].
    fn new(table: &EdgeTable, st: &[u32], ov_tri: &[u32]) -> Self {
        let sv = |v: u32| st[v as usize];
        let ne = table.edges.len();
        let mut block_fast = Vec::with_capacity(ne.div_ceil(LANES));
        // Padded to whole blocks, so a partial last block of manifold edges takes the fast path.
        let ne_padded = ne.div_ceil(LANES) * LANES;
        let (mut ea, mut eb) = (vec![0u32; ne_padded], vec![0u32; ne_padded]);
        let (mut eo1, mut eo2) = (vec![0u32; ne_padded], vec![0u32; ne_padded]);
        let (mut tri_a, mut tri_b) = (vec![0u32; ne_padded], vec![0u32; ne_padded]);
        for e in 0..ne {
            let (s, t) = (
                table.ov_offsets[e] as usize,
                table.ov_offsets[e + 1] as usize,
            );
            if t - s == 2 {
                let [a, b] = table.edges[e];
                (ea[e], eb[e]) = (sv(a), sv(b));
                (eo1[e], eo2[e]) = (sv(table.ovs[s]), sv(table.ovs[s + 1]));
                (tri_a[e], tri_b[e]) = (ov_tri[s], ov_tri[s + 1]);
            }
        }
        for blk in 0..ne.div_ceil(LANES) {
            let r = blk * LANES..((blk + 1) * LANES).min(ne);
            block_fast.push(
                r.into_iter()
                    .all(|e| table.ov_offsets[e + 1] - table.ov_offsets[e] == 2),
            );
        }
        Self {
            block_fast,
            ea,
            eb,
            eo1,
            eo2,
            tri_a,
            tri_b,
        }
    }
}
