//! The edge table: every undirected edge once, with the opposite vertices of all its triangles
//! (CSR), each triangle's edges and the counts; the triangles across each edge on demand.

use crate::{weld, Mesh, MeshError, Weld};
use glam::Vec3;

/// Marker for "no triangle" in [`EdgeTable::manifold_neighbors`].
pub const NO_NEIGHBOR: u32 = u32::MAX;

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

/// Per-triangle-edge connectivity: for every kept triangle and each of its three edges, the edge
/// index.
///
/// Edge `i` of triangle `[v0, v1, v2]` goes from `v_i` to `v_{(i+1) % 3}` (in the triangle's own
/// winding). The backends that decide signs per triangle read it; the seeds' baselines also
/// need the triangle across each edge, which [`EdgeTable::manifold_neighbors`] builds when
/// asked.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Connectivity {
    /// `tri_edges[t][i]` is the index into [`EdgeTable::edges`] of edge `i` of triangle `t`.
    pub tri_edges: Vec<[u32; 3]>,
}

/// The edge table: every undirected edge once, with the opposite vertices of all its triangles.
///
/// All vertex ids in this table are *compact* ids into [`EdgeTable::positions`]; use
/// [`EdgeTable::vertex_names`] to turn them back into input indices. Edges are sorted by `(a, b)`
/// with `a < b`; since compact ids are ordered like names, this is also the order by name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EdgeTable {
    /// Welded positions, indexed by compact id.
    pub positions: Vec<Vec3>,
    /// Compact id → smallest input index of the weld group.
    pub vertex_names: Vec<u32>,
    /// Kept (non-degenerate) triangles in compact ids, original winding.
    pub triangles: Vec<[u32; 3]>,
    /// For each kept triangle, its index in the input mesh.
    pub triangle_sources: Vec<u32>,
    /// Unique edges `[a, b]`, `a < b`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// CSR offsets into [`EdgeTable::ovs`]; `edges.len() + 1` entries.
    pub ov_offsets: Vec<u32>,
    /// Opposite vertices, grouped by edge, in ascending triangle order within an edge.
    pub ovs: Vec<u32>,
    /// Per-triangle-edge connectivity.
    pub connectivity: Connectivity,
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
        Ok(Self::from_compact(
            weld,
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
        Self::from_compact(weld, triangles, triangle_sources, input_triangles.len())
    }

    /// The rest of [`EdgeTable::from_weld`] once the kept triangles (compact ids) and their
    /// input indices are known; `input_triangles` counts the input's triangles.
    fn from_compact(
        weld: Weld,
        triangles: Vec<[u32; 3]>,
        triangle_sources: Vec<u32>,
        input_triangles: usize,
    ) -> Self {
        let vertex_count = weld.names.len();
        let mut stats = MeshStats {
            vertices: weld.compact_of_input.len(),
            welded_vertices: vertex_count,
            triangles: input_triangles,
            degenerate_triangles: input_triangles - triangles.len(),
            opposite_vertices: triangles.len() * 3,
            ..MeshStats::default()
        };
        // Only the names and positions of the weld are kept.
        let Weld {
            compact_of_input,
            names,
            positions,
        } = weld;
        drop(compact_of_input);
        let (start, mut entries) = bucket_entries(&triangles, vertex_count);
        let grouped = group_edges(&triangles, &start, &mut entries, &mut stats);
        drop(entries);
        Self {
            positions,
            vertex_names: names,
            triangles,
            triangle_sources,
            edges: grouped.edges,
            ov_offsets: grouped.ov_offsets,
            ovs: grouped.ovs,
            connectivity: Connectivity {
                tri_edges: grouped.tri_edges,
            },
            stats,
        }
    }

    /// For each triangle edge (`[t][i]`, as [`Connectivity::tri_edges`]), the other triangle
    /// across it when the edge is manifold (exactly two triangles), otherwise [`NO_NEIGHBOR`].
    /// Built on each call (12 bytes a triangle, and 8 an edge while it runs): only the seeds'
    /// connectivity-table baselines walk it.
    #[must_use]
    pub fn manifold_neighbors(&self) -> Vec<[u32; 3]> {
        manifold_neighbors(&self.connectivity.tri_edges, &self.ov_offsets)
    }

    /// Number of edges.
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Every kept triangle in order as `(t, triangle, edges)`: its index, its vertices (compact
    /// ids, original winding) and [`Connectivity::tri_edges`]`[t]`, the indices into
    /// [`EdgeTable::edges`] of its edges `(v0, v1)`, `(v1, v2)`, `(v2, v0)`.
    pub fn triangles_with_edges(&self) -> impl Iterator<Item = (usize, &[u32; 3], &[u32; 3])> {
        self.triangles
            .iter()
            .zip(&self.connectivity.tri_edges)
            .enumerate()
            .map(|(t, (tri, te))| (t, tri, te))
    }

    /// The opposite vertices (compact ids) of edge `e`.
    ///
    /// # Panics
    /// Panics if `e >= self.edge_count()`.
    #[must_use]
    pub fn ovs_of(&self, e: usize) -> &[u32] {
        &self.ovs[self.ov_offsets[e] as usize..self.ov_offsets[e + 1] as usize]
    }

    /// The input-index names `(name(a), name(b))` of edge `e`; `name(a) < name(b)`.
    ///
    /// # Panics
    /// Panics if `e >= self.edge_count()`.
    #[must_use]
    pub fn edge_names(&self, e: usize) -> (u32, u32) {
        let [a, b] = self.edges[e];
        (self.vertex_names[a as usize], self.vertex_names[b as usize])
    }

    /// Bytes that one pass over the table must read at least: edge records, OV lists, offsets and
    /// positions. Used for the measured memory floor.
    #[must_use]
    pub fn streamed_bytes(&self) -> usize {
        self.edges.len() * 8
            + self.ov_offsets.len() * 4
            + self.ovs.len() * 4
            + self.positions.len() * 12
    }
}

/// Step 1 of [`EdgeTable::from_weld`]: the triangles in compact ids without those that are
/// degenerate after welding (a repeated vertex), and each kept triangle's input index.
fn compact_triangles(weld: &Weld, input_triangles: &[[u32; 3]]) -> (Vec<[u32; 3]>, Vec<u32>) {
    let mut triangles = Vec::with_capacity(input_triangles.len());
    let mut triangle_sources = Vec::with_capacity(input_triangles.len());
    for (i, t) in input_triangles.iter().enumerate() {
        let c = [
            weld.compact_of_input[t[0] as usize],
            weld.compact_of_input[t[1] as usize],
            weld.compact_of_input[t[2] as usize],
        ];
        if c[0] != c[1] && c[1] != c[2] && c[0] != c[2] {
            triangles.push(c);
            triangle_sources.push(i as u32);
        }
    }
    (triangles, triangle_sources)
}

/// [`compact_triangles`] in place: `triangles` (input ids) becomes the kept triangles in compact
/// ids, in order; returns each kept triangle's input index.
fn compact_in_place(weld: &Weld, triangles: &mut Vec<[u32; 3]>) -> Vec<u32> {
    let mut sources = Vec::with_capacity(triangles.len());
    let mut kept = 0;
    for i in 0..triangles.len() {
        let t = triangles[i];
        let c = t.map(|v| weld.compact_of_input[v as usize]);
        if c[0] != c[1] && c[1] != c[2] && c[0] != c[2] {
            triangles[kept] = c;
            sources.push(i as u32);
            kept += 1;
        }
    }
    triangles.truncate(kept);
    sources
}

/// One edge entry of a triangle: (larger endpoint, `3 t + i` for corner `i` of triangle `t`,
/// where the edge starts); the OV is corner `(i + 2) % 3`. Eight bytes: `3 t + i` fits `u32`
/// because [`EdgeTable::check_size`] refuses `3 × triangles >= 2^32 - 1`.
type Entry = (u32, u32);

/// Step 2: a counting sort of the 3 entries per triangle by their smaller endpoint. Returns the
/// bucket starts (`vertex_count + 1` offsets) and the entries, bucket by bucket.
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
    let mut entries = vec![(0u32, 0u32); triangles.len() * 3];
    let mut fill = start.clone();
    for (ti, t) in triangles.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let slot = &mut fill[a.min(b) as usize];
            entries[*slot as usize] = (a.max(b), 3 * ti as u32 + i as u32);
            *slot += 1;
        }
    }
    (start, entries)
}

/// The edge records that [`group_edges`] makes.
struct Grouped {
    edges: Vec<[u32; 2]>,
    ov_offsets: Vec<u32>,
    ovs: Vec<u32>,
    tri_edges: Vec<[u32; 3]>,
}

/// Step 3: sorts each bucket (its size is the vertex's degree) and walks its groups of equal
/// larger endpoint: one edge per group, with the group's opposite vertices. Counts the edges by
/// kind into `stats`.
fn group_edges(
    triangles: &[[u32; 3]],
    start: &[u32],
    entries: &mut [Entry],
    stats: &mut MeshStats,
) -> Grouped {
    let total = entries.len();
    let mut edges = Vec::with_capacity(total / 2 + 1);
    let mut ov_offsets = Vec::with_capacity(total / 2 + 2);
    let mut ovs = Vec::with_capacity(total);
    let mut tri_edges = vec![[0u32; 3]; triangles.len()];
    ov_offsets.push(0);
    for a in 0..start.len() - 1 {
        let bucket = &mut entries[start[a] as usize..start[a + 1] as usize];
        bucket.sort_unstable();
        let mut k = 0;
        while k < bucket.len() {
            let b = bucket[k].0;
            let edge_index = edges.len() as u32;
            let mut n = 0usize;
            while k < bucket.len() && bucket[k].0 == b {
                let (t, i) = ((bucket[k].1 / 3) as usize, (bucket[k].1 % 3) as usize);
                ovs.push(triangles[t][(i + 2) % 3]);
                tri_edges[t][i] = edge_index;
                n += 1;
                k += 1;
            }
            edges.push([a as u32, b]);
            ov_offsets.push(ovs.len() as u32);
            match n {
                1 => stats.boundary_edges += 1,
                2 => stats.manifold_edges += 1,
                _ => stats.nonmanifold_edges += 1,
            }
        }
    }
    stats.edges = edges.len();
    Grouped {
        edges,
        ov_offsets,
        ovs,
        tri_edges,
    }
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
