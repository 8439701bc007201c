//! What the kernels read for one edge table: a [`Layout`], either a copy laid out for speed
//! ([`copy`]) or the table itself, read in place ([`in_place`]).
//!
//! Both present the same [`Geometry`]: blocks of [`LANES`] triangles in canonical order (ids
//! ascending), and blocks of [`LANES`] edges, each either *fast* (every edge manifold: two
//! opposite-vertex references per edge, `4 s + r`, naming the triangle slot `s` of the sign
//! arrays and, by `r == 1`, the odd parity) or *general* (any number, read per edge). The
//! kernels are generic over it, so each layout runs the same operations in the same order and
//! gives the same bits.
//!
//! The copy holds about 56 bytes a triangle beside the table and runs at the speed the kernels
//! were tuned at; in place adds under one byte a triangle and runs 1.5–3x slower (the
//! canonical triangles are sorted as they are loaded and the opposite vertices found through
//! their triangles; docs/MEMORY.md). [`LayoutChoice::Auto`] copies scenes of up to
//! [`COPY_MAX_TRIANGLES`] triangles and reads larger ones in place.

pub(crate) mod copy;
pub(crate) mod in_place;

use crate::lanes::Level;
use shadowvol_mesh_topology::EdgeTable;
use std::sync::Arc;

/// Lanes per `f32` vector and edges / triangles per block.
pub(crate) const LANES: usize = 8;

/// The vertex ids of one block of [`LANES`] canonical triangles: `[t0, t1, t2]`, each `[u32;
/// 8]`, with `t0 < t1 < t2` per lane in the table's order (vertex 0 in the lanes past the last
/// triangle).
pub(crate) type CanonBlock = [[u32; LANES]; 3];

/// The OV references `4 s + r` of one fast block of [`LANES`] edges: `[0][i]` is edge `i`'s
/// first, `[1][i]` its second (0 past the last edge).
pub(crate) type FastRefs = [[u32; LANES]; 2];

/// Why a table cannot be laid out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LayoutError(pub String);

/// How the `simd` backend lays out the tables of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum LayoutChoice {
    /// A copy when the scene's distinct tables have at most [`COPY_MAX_TRIANGLES`] triangles
    /// in all, else in place.
    #[default]
    Auto,
    /// Always a copy laid out for speed (about 56 bytes a triangle beside the table).
    Copy,
    /// Always the table, read in place (under one byte a triangle beside it).
    InPlace,
}

impl LayoutChoice {
    /// The name recorded with results: `auto`, `copy` or `in-place`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Copy => "copy",
            Self::InPlace => "in-place",
        }
    }
}

impl std::str::FromStr for LayoutChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "copy" => Ok(Self::Copy),
            "in-place" => Ok(Self::InPlace),
            other => Err(format!(
                "unknown simd layout {other:?}; expected \"auto\", \"copy\" or \"in-place\""
            )),
        }
    }
}

/// The largest scene (triangles of its distinct tables) that [`LayoutChoice::Auto`] copies:
/// 2^22, about 4.2 million triangles (a copy of 235 MB).
pub const COPY_MAX_TRIANGLES: usize = 1 << 22;

/// One table as the kernels read it. (Held in an `Arc` per table, so the copy's size beside
/// the in-place view costs nothing per object.)
#[derive(Debug)]
#[allow(clippy::large_enum_variant)]
pub(crate) enum Layout {
    /// A copy laid out for speed.
    Copy(copy::CopyLayout),
    /// The table, read in place.
    InPlace(in_place::InPlaceLayout),
}

/// Runs `$body` with `$g` bound to the [`Geometry`] inside the layout `$layout`.
macro_rules! with_geometry {
    ($layout:expr, $g:ident => $body:expr) => {
        match $layout {
            $crate::layout::Layout::Copy($g) => $body,
            $crate::layout::Layout::InPlace($g) => $body,
        }
    };
}
pub(crate) use with_geometry;

impl Layout {
    /// Lays out `table`, copied or in place. Checks every index, so the kernels may rely on
    /// them.
    pub(crate) fn build(table: &Arc<EdgeTable>, copy: bool) -> Result<Self, LayoutError> {
        Ok(if copy {
            Self::Copy(copy::CopyLayout::build(table)?)
        } else {
            Self::InPlace(in_place::InPlaceLayout::build(table)?)
        })
    }

    /// Heap bytes the layout adds to its table.
    pub(crate) fn heap_bytes(&self) -> u64 {
        match self {
            Self::Copy(l) => l.heap_bytes(),
            Self::InPlace(l) => l.heap_bytes(),
        }
    }

    /// Its name in results: `copy` or `in-place`.
    pub(crate) fn name(&self) -> &'static str {
        match self {
            Self::Copy(_) => LayoutChoice::Copy.name(),
            Self::InPlace(_) => LayoutChoice::InPlace.name(),
        }
    }

    /// Number of triangles.
    pub(crate) fn tri_count(&self) -> usize {
        with_geometry!(self, g => g.tri_count())
    }

    /// Number of edges.
    pub(crate) fn edge_count(&self) -> usize {
        with_geometry!(self, g => g.edge_count())
    }
}

/// What the kernels read of one table, however it is laid out. Vertex ids are the layout's own
/// (the copy renumbers them for locality); triangle slots index the per-light sign arrays.
pub(crate) trait Geometry: Sync {
    /// Number of triangles.
    fn tri_count(&self) -> usize;
    /// Number of edges.
    fn edge_count(&self) -> usize;
    /// Whether every edge of block `blk` (edges `8 blk ..`) is manifold.
    fn block_fast(&self, blk: usize) -> bool;
    /// Every coordinate passes [`coord_in_filter_range`]: then, with a light whose coordinates
    /// pass too, no difference the `f32` filter forms can fail its range check.
    fn coords_in_filter_range(&self) -> bool;
    /// A block of canonical triangles as [`Geometry::canon_block`] gives it: a reference where
    /// the layout stores blocks, else the block made on the spot. (A copy of a stored block
    /// measured about 8 % slower: the kernels then read each id back from the copy.)
    type Canon<'a>: std::ops::Deref<Target = CanonBlock>
    where
        Self: 'a;
    /// A fast block's references as [`Geometry::fast_refs`] gives them, likewise.
    type Refs<'a>: std::ops::Deref<Target = FastRefs>
    where
        Self: 'a;
    /// The canonical triangles of slots `t .. t + 8` (`t` a multiple of 8, below
    /// [`Geometry::tri_count`]).
    fn canon_block<Lv: Level>(&self, t: usize) -> Self::Canon<'_>;
    /// The x, y and z lanes of the 8 vertices `idx[..8]`.
    ///
    /// # Safety
    /// `idx.len() >= 8` and every id is one the layout handed out (a vertex of the layout).
    unsafe fn gather<Lv: Level>(&self, idx: &[u32]) -> [Lv::F; 3];
    /// Position of vertex `v`.
    fn pos(&self, v: u32) -> [f32; 3];
    /// The references of the fast block `blk` ([`FastRefs`]).
    fn fast_refs(&self, blk: usize) -> Self::Refs<'_>;
    /// `[a, b, o1, o2]` of each edge of the fast block `blk` (vertex 0 past the last edge).
    fn fast_ends_and_ovs(&self, blk: usize) -> [[u32; LANES]; 4];
    /// The ends of edge `e` in a general block.
    fn general_ends(&self, e: usize) -> [u32; 2];
    /// The references of edge `e` in a general block.
    fn general_refs(&self, e: usize) -> &[u32];
    /// The opposite vertices of edge `e` in a general block, in the order of its references.
    fn general_ovs(&self, e: usize) -> impl Iterator<Item = u32> + '_;
    /// Triangle slots: the triangles, padded to whole blocks.
    #[inline(always)]
    fn tri_slots(&self) -> usize {
        self.tri_count().div_ceil(LANES) * LANES
    }
}

/// The triangle slot of reference `r = 4 s + rank`.
#[inline(always)]
pub(crate) fn ref_slot(r: u32) -> usize {
    EdgeTable::ov_triangle(r) as usize
}

/// Whether the (edge, OV) pair of reference `r` has odd parity (rank 1).
#[inline(always)]
pub(crate) fn ref_odd(r: u32) -> bool {
    EdgeTable::ov_odd(r)
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

/// For each block of [`LANES`] edges of `table`, whether all its edges are manifold (two
/// references each: the block's references are then consecutive, two per edge).
pub(crate) fn fast_blocks(table: &EdgeTable) -> Vec<bool> {
    let ne = table.edges.len();
    (0..ne.div_ceil(LANES))
        .map(|blk| {
            (blk * LANES..((blk + 1) * LANES).min(ne))
                .all(|e| table.ov_offsets[e + 1] - table.ov_offsets[e] == 2)
        })
        .collect()
}

/// Checks that `table` fits the layout's index range and is consistent (offsets and OV
/// references agree, every vertex id and reference is in range), so the kernels may rely on it.
pub(crate) fn check_table(table: &EdgeTable) -> Result<(), LayoutError> {
    let (nv, nt) = (table.positions.len(), table.triangles.len());
    if nv >= i32::MAX as usize || nt > (u32::MAX as usize) / 4 {
        return Err(LayoutError(format!(
            "{nv} vertices / {nt} triangles exceed the layout's limits (2^31 vertices, 2^30 \
             triangles)"
        )));
    }
    let offsets = &table.ov_offsets;
    if offsets.len() != table.edges.len() + 1
        || offsets.first().copied().unwrap_or(0) != 0
        || offsets.windows(2).any(|w| w[0] > w[1])
        || offsets.last().copied().unwrap_or(0) as usize != table.ov_refs.len()
    {
        return Err(LayoutError(
            "edge table is inconsistent (offsets and OV references disagree)".to_owned(),
        ));
    }
    let in_range = |v: u32| (v as usize) < nv;
    if !table.triangles.iter().flatten().all(|&v| in_range(v))
        || !table.edges.iter().flatten().all(|&v| in_range(v))
    {
        return Err(LayoutError(format!(
            "edge table refers to a vertex id >= its {nv} positions"
        )));
    }
    // Each reference names a triangle that has the edge, and the rank of the vertex opposite
    // it: the kernels find that vertex as the xor of the triangle's ids and the edge's ends.
    for (e, &[a, b]) in table.edges.iter().enumerate() {
        for &r in table.ov_refs_of(e) {
            let t = EdgeTable::ov_triangle(r) as usize;
            let ok = table.triangles.get(t).is_some_and(|&[x, y, z]| {
                let o = x ^ y ^ z ^ a ^ b;
                let has = |v: u32| x == v || y == v || z == v;
                has(a) && has(b) && has(o) && r & 3 == u32::from(o > a) + u32::from(o > b)
            });
            if !ok {
                return Err(LayoutError(format!(
                    "edge {e} ({a}, {b}): its opposite-vertex reference {r} does not name a \
                     triangle of its {nt} with that edge and rank"
                )));
            }
        }
    }
    Ok(())
}

/// Whether every coordinate of `table`'s positions passes [`coord_in_filter_range`] (what
/// [`Geometry::coords_in_filter_range`] reports, whatever order a layout stores them in).
pub(crate) fn positions_in_filter_range(table: &EdgeTable) -> bool {
    table
        .positions
        .iter()
        .all(|p| p.to_array().iter().all(|&c| coord_in_filter_range(c)))
}
