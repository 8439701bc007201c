//! The edge table: every undirected edge once, with references to the opposite vertices of all
//! its triangles (CSR) and the counts; each triangle's edges and the triangles across each edge
//! on demand.

use crate::welding::split_by;
use crate::{weld, Mesh, MeshError, Renumbering, SoupWeld, Weld};
use glam::Vec3;
use rayon::prelude::*;

/// Marker for "no triangle" in [`EdgeTable::manifold_neighbors`].
pub const NO_NEIGHBOR: u32 = u32::MAX;

/// Marker for "no such edge" in [`EdgeTable::triangles_with_edges`].
pub const NO_EDGE: u32 = u32::MAX;

/// Topology statistics of an [`EdgeTable`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MeshStats {
    /// Input vertices.
    pub vertices: usize,
    /// Vertices after exact-position welding.
    pub welded_vertices: usize,
    /// Input triangles.
    pub triangles: usize,
    /// Triangles dropped because two of their corners weld to the same vertex.
    pub degenerate_triangles: usize,
    /// Unique undirected edges.
    pub edges: usize,
    /// Edges with exactly one triangle.
    pub boundary_edges: usize,
    /// Edges with exactly two triangles.
    pub manifold_edges: usize,
    /// Edges with three or more triangles.
    pub nonmanifold_edges: usize,
    /// Total number of (edge, opposite vertex) pairs, i.e. 3 × kept triangles.
    pub opposite_vertices: usize,
}

/// The edge table: every undirected edge once, with the opposite vertices of all its triangles.
///
/// All vertex ids in this table are *compact* ids into [`EdgeTable::positions`]; use
/// [`EdgeTable::vertex_names`] to turn them back into input indices. Edges are sorted by `(a, b)`
/// with `a < b`; since compact ids are ordered like names, this is also the order by name.
///
/// It holds what every backend reads and nothing else: for a closed mesh, 48 bytes a triangle
/// (positions 6, triangles 12, edges 12, CSR offsets 6, opposite-vertex references 12). An
/// opposite vertex is stored as a *reference* `4 t + r` ([`EdgeTable::ov_refs`]): its triangle
/// `t` and its rank `r` among that triangle's vertex ids. That names the vertex
/// ([`EdgeTable::ov_vertex`]), the triangle whose canonical orientation the (edge, OV) pair takes
/// ([`EdgeTable::ov_triangle`]) and the pair's permutation parity ([`EdgeTable::ov_odd`]), so
/// kernels that evaluate each triangle once find an edge's triangles in the table itself. Each
/// triangle's
/// edges ([`EdgeTable::tri_edges`]) and the triangles across each edge
/// ([`EdgeTable::manifold_neighbors`]) are built when asked for; the maps back to the input
/// ([`Renumbering`]) are stored only when they are not the identity.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EdgeTable {
    /// Welded positions, indexed by compact id.
    pub positions: Vec<Vec3>,
    /// Compact id → smallest input index of the weld group.
    pub vertex_names: Renumbering,
    /// Kept (non-degenerate) triangles in compact ids, original winding.
    pub triangles: Vec<[u32; 3]>,
    /// For each kept triangle, its index in the input mesh.
    pub triangle_sources: Renumbering,
    /// Unique edges `[a, b]`, `a < b`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// CSR offsets into [`EdgeTable::ov_refs`]; `edges.len() + 1` entries.
    pub ov_offsets: Vec<u32>,
    /// The opposite vertices of each edge as references `4 t + r`, grouped by edge, in
    /// ascending triangle order within an edge: triangle `t` has the edge, and its opposite
    /// vertex is the one of rank `r` among the triangle's three ids (0 the smallest, 1 the
    /// middle, 2 the largest). For edge `(a, b)`, `a < b`, and opposite vertex `o`: `r = 0` when
    /// `o < a`, `r = 1` when `a < o < b` (odd permutation parity), `r = 2` when `o > b`.
    pub ov_refs: Vec<u32>,
    /// Counts.
    pub stats: MeshStats,
}

impl EdgeTable {
    /// Validates `mesh`, welds it and builds the edge table in linear time.
    ///
    /// Before allocating anything, [`EdgeTable::check_size`] refuses meshes beyond `u32`
    /// indexing and meshes whose table would not fit the available memory.
    ///
    /// # Errors
    /// [`MeshError::TooLarge`] or [`MeshError::OutOfMemory`] from [`EdgeTable::check_size`], or
    /// any [`MeshError`] from [`Mesh::validate`].
    pub fn build(mesh: &Mesh) -> Result<Self, MeshError> {
        Self::check_size(mesh.triangles.len() as u64, mesh.positions.len() as u64)?;
        mesh.validate()?;
        let weld = weld(&mesh.positions);
        Ok(Self::from_weld(weld, &mesh.triangles))
    }

    /// [`EdgeTable::build`], consuming `mesh` so that its parts are freed as soon as the build
    /// is done with them: the input positions after welding, the input triangles turned into
    /// the kept ones in place. The same table as [`EdgeTable::build`], at a lower peak (by the
    /// input mesh, 18 bytes per triangle of a closed mesh).
    ///
    /// # Errors
    /// As [`EdgeTable::build`].
    pub fn build_owned(mesh: Mesh) -> Result<Self, MeshError> {
        Self::check_size(mesh.triangles.len() as u64, mesh.positions.len() as u64)?;
        mesh.validate()?;
        let Mesh {
            positions,
            mut triangles,
        } = mesh;
        let weld = weld(&positions);
        drop(positions);
        let input_triangles = triangles.len();
        let triangle_sources = compact_in_place(&weld, &mut triangles);
        let inputs = weld.compact_of_input.len();
        Ok(Self::from_compact(
            (weld, inputs),
            triangles,
            triangle_sources,
            input_triangles,
        ))
    }

    /// Builds the table of a soup welded as it was read: `weld` holds every corner pushed
    /// (`weld.pushed()` input vertices) and `triangles` each input triangle in compact ids, in
    /// input order. The same table as [`EdgeTable::build`] of the soup (every position pushed,
    /// in order, and the triangles over those input indices), without the soup: triangles with
    /// two equal corners are dropped, vertex names are the weld's.
    ///
    /// # Errors
    /// [`MeshError::TooLarge`] or [`MeshError::OutOfMemory`] from [`EdgeTable::check_size`]
    /// (for the triangles and the input vertices); [`MeshError::IndexOutOfRange`] for a
    /// triangle naming a compact id the weld does not have.
    pub fn from_soup_weld(weld: SoupWeld, mut triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        Self::check_size(triangles.len() as u64, weld.pushed())?;
        let vertices = weld.names().len();
        for (triangle, tri) in triangles.iter().enumerate() {
            if let Some(corner) = tri.iter().position(|&v| v as usize >= vertices) {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    corner,
                    index: tri[corner],
                    vertices,
                });
            }
        }
        let input_vertices = weld.pushed() as usize;
        let (names, positions) = weld.into_parts();
        let weld = Weld {
            compact_of_input: Vec::new(),
            names,
            positions,
        };
        let input_triangles = triangles.len();
        let triangle_sources = compact_in_place_by(&mut triangles, |v| v);
        Ok(Self::from_compact(
            (weld, input_vertices),
            triangles,
            triangle_sources,
            input_triangles,
        ))
    }

    /// Builds the table from an existing weld and the input triangles (already validated).
    ///
    /// # Panics
    /// Panics if a triangle index is out of range of `weld.compact_of_input`; call
    /// [`Mesh::validate`] first (as [`EdgeTable::build`] does).
    #[must_use]
    pub fn from_weld(weld: Weld, input_triangles: &[[u32; 3]]) -> Self {
        let (triangles, triangle_sources) = compact_triangles(&weld, input_triangles);
        let inputs = weld.compact_of_input.len();
        Self::from_compact(
            (weld, inputs),
            triangles,
            triangle_sources,
            input_triangles.len(),
        )
    }

    /// The rest of [`EdgeTable::from_weld`] once the kept triangles (compact ids) and their
    /// input indices are known; `input_vertices` and `input_triangles` count the input's.
    fn from_compact(
        (weld, input_vertices): (Weld, usize),
        triangles: Vec<[u32; 3]>,
        triangle_sources: Renumbering,
        input_triangles: usize,
    ) -> Self {
        let vertex_count = weld.names.len();
        let mut stats = MeshStats {
            vertices: input_vertices,
            welded_vertices: vertex_count,
            triangles: input_triangles,
            degenerate_triangles: input_triangles - triangles.len(),
            opposite_vertices: triangles.len() * 3,
            ..MeshStats::default()
        };
        // Only the names and positions of the weld are kept.
        let Weld {
            compact_of_input,
            mut names,
            mut positions,
        } = weld;
        drop(compact_of_input);
        // The weld grows these by doubling; the table keeps only what it holds (a shrinking
        // reallocation of a large block gives its tail back in place).
        positions.shrink_to_fit();
        names.shrink_to_fit();
        let vertex_names = Renumbering::from_vec(names);
        let (start, entries) = bucket_entries(&triangles, vertex_count);
        let grouped = group_edges(&triangles, &start, entries, &mut stats);
        Self {
            positions,
            vertex_names,
            triangles,
            triangle_sources,
            edges: grouped.edges,
            ov_offsets: grouped.ov_offsets,
            ov_refs: grouped.ov_refs,
            stats,
        }
    }

    /// For every kept triangle, the indices into [`EdgeTable::edges`] of its three edges: edge
    /// `i` of triangle `[v0, v1, v2]` goes from `v_i` to `v_{(i+1) % 3}` (the triangle's own
    /// winding). Built on each call in linear time (12 bytes a triangle); to walk them once
    /// without storing them, use [`EdgeTable::triangles_with_edges`].
    ///
    /// # Panics
    /// If the table is inconsistent (a triangle edge that is not in [`EdgeTable::edges`]); a
    /// table built by [`EdgeTable::build`] never is.
    #[must_use]
    pub fn tri_edges(&self) -> Vec<[u32; 3]> {
        self.triangles_with_edges()
            .map(|(t, _, te)| {
                assert!(
                    !te.contains(&NO_EDGE),
                    "triangle {t} has an edge the table lacks"
                );
                te
            })
            .collect()
    }

    /// Every kept triangle in order as `(t, triangle, edges)`: its index, its vertices (compact
    /// ids, original winding) and the indices into [`EdgeTable::edges`] of its edges
    /// `(v0, v1)`, `(v1, v2)`, `(v2, v0)`, looked up as it goes (each vertex's first edge is
    /// held meanwhile: 4 bytes a vertex). An edge the table lacks, or a vertex id out of range
    /// (only in a table not made by [`EdgeTable::build`]), gives [`NO_EDGE`].
    pub fn triangles_with_edges(&self) -> impl Iterator<Item = (usize, [u32; 3], [u32; 3])> + '_ {
        let first = self.first_edges();
        self.triangles.iter().enumerate().map(move |(t, &tri)| {
            let te = [0, 1, 2].map(|i| {
                let (u, v) = (tri[i], tri[(i + 1) % 3]);
                edge_in(&self.edges, &first, u.min(v), u.max(v)).unwrap_or(NO_EDGE)
            });
            (t, tri, te)
        })
    }

    /// The index of edge `(a, b)` (either order) in [`EdgeTable::edges`], if the table has it.
    /// A binary search: O(log edges), no allocation.
    #[must_use]
    pub fn edge_index(&self, a: u32, b: u32) -> Option<u32> {
        let key = [a.min(b), a.max(b)];
        self.edges.binary_search(&key).ok().map(|e| e as u32)
    }

    /// For each compact vertex `v`, the index of the first edge `[v, _]`; `positions.len() + 1`
    /// entries (edges are sorted by their smaller end).
    fn first_edges(&self) -> Vec<u32> {
        let mut first = vec![0u32; self.positions.len() + 1];
        for &[a, _] in &self.edges {
            if let Some(f) = first.get_mut(a as usize + 1) {
                *f += 1;
            }
        }
        for v in 0..self.positions.len() {
            first[v + 1] += first[v];
        }
        first
    }

    /// For each triangle edge (`[t][i]`, as [`EdgeTable::tri_edges`]), the other triangle
    /// across it when the edge is manifold (exactly two triangles), otherwise [`NO_NEIGHBOR`].
    /// Built on each call (24 bytes a triangle, and 8 an edge while it runs): only the seeds'
    /// connectivity-table baselines walk it.
    #[must_use]
    pub fn manifold_neighbors(&self) -> Vec<[u32; 3]> {
        manifold_neighbors(&self.tri_edges(), &self.ov_offsets)
    }

    /// Number of edges.
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The opposite vertices (compact ids) of edge `e`, in ascending triangle order.
    ///
    /// # Panics
    /// Panics if `e >= self.edge_count()`, or (while iterating) if a corner is out of range of
    /// [`EdgeTable::triangles`] (never in a table made by [`EdgeTable::build`]).
    pub fn ovs_of(
        &self,
        e: usize,
    ) -> impl ExactSizeIterator<Item = u32> + DoubleEndedIterator + Clone + '_ {
        self.ov_refs_of(e).iter().map(|&c| self.ov_vertex(c))
    }

    /// The opposite-vertex references `4 t + r` of edge `e` (see [`EdgeTable::ov_refs`]).
    ///
    /// # Panics
    /// Panics if `e >= self.edge_count()`.
    #[must_use]
    pub fn ov_refs_of(&self, e: usize) -> &[u32] {
        &self.ov_refs[self.ov_offsets[e] as usize..self.ov_offsets[e + 1] as usize]
    }

    /// The opposite vertex (compact id) that reference `r = 4 t + rank` names: the vertex of
    /// that rank among triangle `t`'s ids.
    ///
    /// # Panics
    /// Panics if `t >= self.triangles.len()`.
    #[must_use]
    #[inline]
    pub fn ov_vertex(&self, r: u32) -> u32 {
        let [a, b, c] = self.triangles[Self::ov_triangle(r) as usize];
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        match r & 3 {
            0 => lo,
            1 => a ^ b ^ c ^ lo ^ hi,
            _ => hi,
        }
    }

    /// The triangle `t` of reference `r = 4 t + rank`.
    #[must_use]
    #[inline]
    pub const fn ov_triangle(r: u32) -> u32 {
        r >> 2
    }

    /// Whether the (edge, OV) pair of reference `r` has odd permutation parity: the opposite
    /// vertex lies between the edge's ends (`a < o < b`), rank 1. The pair's sign is then the
    /// opposite of its canonical triangle's.
    #[must_use]
    #[inline]
    pub const fn ov_odd(r: u32) -> bool {
        r & 3 == 1
    }

    /// The input-index names `(name(a), name(b))` of edge `e`; `name(a) < name(b)`.
    ///
    /// # Panics
    /// Panics if `e >= self.edge_count()`.
    #[must_use]
    pub fn edge_names(&self, e: usize) -> (u32, u32) {
        let [a, b] = self.edges[e];
        (
            self.vertex_names.get(a as usize),
            self.vertex_names.get(b as usize),
        )
    }

    /// Bytes that one pass over the table must read at least: edge records, OV lists, offsets and
    /// positions. Used for the measured memory floor.
    #[must_use]
    pub fn streamed_bytes(&self) -> usize {
        self.edges.len() * 8
            + self.ov_offsets.len() * 4
            + self.ov_refs.len() * 4
            + self.positions.len() * 12
    }
}

/// Step 1 of [`EdgeTable::from_weld`]: the triangles in compact ids without those that are
/// degenerate after welding (a repeated vertex), and each kept triangle's input index.
fn compact_triangles(weld: &Weld, input_triangles: &[[u32; 3]]) -> (Vec<[u32; 3]>, Renumbering) {
    let mut triangles = input_triangles.to_vec();
    let sources = compact_in_place(weld, &mut triangles);
    (triangles, sources)
}

/// [`compact_triangles`] in place: `triangles` (input ids) becomes the kept triangles in compact
/// ids, in order; returns each kept triangle's input index, stored only once a triangle is
/// dropped.
fn compact_in_place(weld: &Weld, triangles: &mut Vec<[u32; 3]>) -> Renumbering {
    compact_in_place_by(triangles, |v| weld.compact_of_input[v as usize])
}

/// [`compact_in_place`] with each input id's compact id from `compact`.
fn compact_in_place_by(triangles: &mut Vec<[u32; 3]>, compact: impl Fn(u32) -> u32) -> Renumbering {
    let mut sources: Option<Vec<u32>> = None;
    let mut kept = 0;
    for i in 0..triangles.len() {
        let t = triangles[i];
        let c = t.map(&compact);
        if c[0] != c[1] && c[1] != c[2] && c[0] != c[2] {
            triangles[kept] = c;
            if let Some(s) = &mut sources {
                s.push(i as u32);
            }
            kept += 1;
        } else if sources.is_none() {
            // The first dropped triangle: every one before it was kept at its own index.
            sources = Some((0..kept as u32).collect());
        }
    }
    triangles.truncate(kept);
    triangles.shrink_to_fit();
    sources.map_or(Renumbering::Identity(kept), Renumbering::Stored)
}

/// One edge entry of a triangle: the corner `3 t + i` where edge `i` of triangle `t` starts
/// (its ends are corners `i` and `(i + 1) % 3`, its OV corner `(i + 2) % 3`). Four bytes: `3 t
/// + i` fits `u32` because [`EdgeTable::check_size`] refuses `4 × triangles >= 2^32 - 1`.
type Entry = u32;

/// The two ends of the edge that starts at `corner`, smaller first.
#[inline]
fn corner_edge(triangles: &[[u32; 3]], corner: Entry) -> (u32, u32) {
    let (t, i) = ((corner / 3) as usize, (corner % 3) as usize);
    let (a, b) = (triangles[t][i], triangles[t][(i + 1) % 3]);
    (a.min(b), a.max(b))
}

/// Step 2: a counting sort of the 3 entries per triangle by their smaller endpoint. Returns the
/// bucket starts (`vertex_count + 1` offsets) and the entries, bucket by bucket, each bucket in
/// ascending triangle order.
fn bucket_entries(triangles: &[[u32; 3]], vertex_count: usize) -> (Vec<u32>, Vec<Entry>) {
    let mut start = vec![0u32; vertex_count + 1];
    for t in triangles {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            start[a.min(b) as usize + 1] += 1;
        }
    }
    for v in 0..vertex_count {
        start[v + 1] += start[v];
    }
    let mut entries = vec![0; triangles.len() * 3];
    let mut fill = start.clone();
    for (ti, t) in triangles.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let slot = &mut fill[a.min(b) as usize];
            entries[*slot as usize] = 3 * ti as u32 + i as u32;
            *slot += 1;
        }
    }
    (start, entries)
}

/// The edge records that [`group_edges`] makes.
struct Grouped {
    edges: Vec<[u32; 2]>,
    ov_offsets: Vec<u32>,
    ov_refs: Vec<u32>,
}

/// Step 3: sorts each bucket (its size is the vertex's degree) by larger endpoint, then
/// triangle, and walks its groups of equal larger endpoint: one edge per group, with the
/// group's opposite-vertex references. Counts the edges by kind into `stats`.
///
/// Buckets are independent: chunks of vertices run on rayon's threads, first sorting and
/// counting each bucket's edges, then (once the counts give each chunk its first edge) writing
/// edges, offsets and OV references. The references take the entries' place: entry `k` of the
/// sorted order (the edge's starting corner `3 t + i`) becomes reference `k` (`4 t + r`, `r`
/// the rank of the triangle's vertex `(i + 2) % 3`), read before it is written. So the build
/// holds 12 bytes a triangle for both, not 24 for the entries beside 12 for the references; the
/// result is the same on any number of threads.
fn group_edges(
    triangles: &[[u32; 3]],
    start: &[u32],
    mut entries: Vec<Entry>,
    stats: &mut MeshStats,
) -> Grouped {
    let nv = start.len() - 1;
    let chunk = nv.div_ceil(rayon::current_num_threads() * 8).max(1 << 12);
    let chunks: Vec<std::ops::Range<usize>> = (0..nv.div_ceil(chunk))
        .map(|c| c * chunk..((c + 1) * chunk).min(nv))
        .collect();
    let entry_lens = || {
        chunks
            .iter()
            .map(|r| (start[r.end] - start[r.start]) as usize)
    };
    // 1. Sort each bucket; count its edges into edge_start[v + 1].
    let mut edge_start = vec![0u32; nv + 1];
    split_by(&mut entries, entry_lens())
        .into_par_iter()
        .zip(split_by(
            &mut edge_start[1..],
            chunks.iter().map(ExactSizeIterator::len),
        ))
        .zip(&chunks)
        .for_each(|((ents, counts), r)| {
            let base = start[r.start] as usize;
            let mut keyed: Vec<[u32; 2]> = Vec::new();
            for (v, a) in r.clone().enumerate() {
                let bucket = &mut ents[start[a] as usize - base..start[a + 1] as usize - base];
                keyed.clear();
                keyed.extend(bucket.iter().map(|&c| [corner_edge(triangles, c).1, c]));
                // Ascending corners within a larger end are ascending triangles.
                keyed.sort_unstable();
                for (slot, &[_, c]) in bucket.iter_mut().zip(&keyed) {
                    *slot = c;
                }
                counts[v] = if keyed.is_empty() {
                    0
                } else {
                    1 + keyed.windows(2).filter(|w| w[0][0] != w[1][0]).count() as u32
                };
            }
        });
    for v in 0..nv {
        edge_start[v + 1] += edge_start[v];
    }
    let ne = edge_start[nv] as usize;
    let mut edges = vec![[0u32; 2]; ne];
    let mut ov_offsets = vec![0u32; ne + 1];
    // 2. Each chunk's edges, offsets and OVs.
    let edge_lens = || {
        chunks
            .iter()
            .map(|r| (edge_start[r.end] - edge_start[r.start]) as usize)
    };
    let kinds = split_by(&mut entries, entry_lens())
        .into_par_iter()
        .zip(split_by(&mut edges, edge_lens()))
        .zip(split_by(&mut ov_offsets[1..], edge_lens()))
        .zip(&chunks)
        .map(|(((ents, eds), offs), r)| {
            let base = start[r.start] as usize;
            let (mut e, mut kinds) = (0usize, [0usize; 3]);
            for a in r.clone() {
                let (lo, hi) = (start[a] as usize - base, start[a + 1] as usize - base);
                let mut j = lo;
                while j < hi {
                    let b = corner_edge(triangles, ents[j]).1;
                    let first = j;
                    while j < hi && corner_edge(triangles, ents[j]).1 == b {
                        let c = ents[j];
                        let o = triangles[(c / 3) as usize][((c % 3 + 2) % 3) as usize];
                        // The rank of `o` among the edge's ends `a < b` and itself.
                        let rank = u32::from(o > a as u32) + u32::from(o > b);
                        ents[j] = 4 * (c / 3) + rank;
                        j += 1;
                    }
                    eds[e] = [a as u32, b];
                    offs[e] = (base + j) as u32;
                    kinds[(j - first).min(3) - 1] += 1;
                    e += 1;
                }
            }
            kinds
        })
        .reduce(|| [0; 3], |x, y| [x[0] + y[0], x[1] + y[1], x[2] + y[2]]);
    stats.boundary_edges = kinds[0];
    stats.manifold_edges = kinds[1];
    stats.nonmanifold_edges = kinds[2];
    stats.edges = ne;
    Grouped {
        edges,
        ov_offsets,
        ov_refs: entries,
    }
}

/// The index of edge `[a, b]` (`a < b`) among the edges of `a`, which start at `first[a]`;
/// `None` when it is not there or `a` is out of range.
fn edge_in(edges: &[[u32; 2]], first: &[u32], a: u32, b: u32) -> Option<u32> {
    let lo = *first.get(a as usize)? as usize;
    let of_a = edges.get(lo..*first.get(a as usize + 1)? as usize)?;
    of_a.binary_search_by_key(&b, |e| e[1])
        .ok()
        .map(|i| (lo + i) as u32)
}

/// [`EdgeTable::manifold_neighbors`]: for each triangle edge, the other triangle across it when
/// the edge is manifold (exactly two triangles), otherwise [`NO_NEIGHBOR`].
fn manifold_neighbors(tri_edges: &[[u32; 3]], ov_offsets: &[u32]) -> Vec<[u32; 3]> {
    let edge_count = ov_offsets.len() - 1;
    let mut first_tri = vec![NO_NEIGHBOR; edge_count];
    let mut second_tri = vec![NO_NEIGHBOR; edge_count];
    for (t, te) in tri_edges.iter().enumerate() {
        for &e in te {
            let e = e as usize;
            if first_tri[e] == NO_NEIGHBOR {
                first_tri[e] = t as u32;
            } else if second_tri[e] == NO_NEIGHBOR {
                second_tri[e] = t as u32;
            }
        }
    }
    tri_edges
        .iter()
        .enumerate()
        .map(|(t, te)| {
            te.map(|e| {
                let e = e as usize;
                if ov_offsets[e + 1] - ov_offsets[e] != 2 {
                    NO_NEIGHBOR
                } else if first_tri[e] == t as u32 {
                    second_tri[e]
                } else {
                    first_tri[e]
                }
            })
        })
        .collect()
}
