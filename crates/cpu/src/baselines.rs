//! The seeds' CPU silhouette algorithms, as baselines.
//!
//! All four are defined for **closed, consistently oriented, manifold** meshes (every edge has
//! exactly two triangles that traverse it in opposite directions) and return the silhouette as
//! a sorted list of edge indices into [`EdgeTable::edges`]. They all start from the same per
//! triangle test, in `f32`:
//!
//! ```text
//! N = (v1 - v0) x (v2 - v0)            (the triangle's winding)
//! lit(t) = N . (L.xyz - L.w * v0) > 0  (the light is on the front side)
//! ```
//!
//! * [`ClosedMesh::two_step`] (Shi 2006, "traditional CPU silhouette algorithm"): step 1 computes
//!   `lit` for every triangle, step 2 marks every edge whose two triangles differ.
//! * [`ClosedMesh::classic`] (Toy Wars notes, "classical approach"): a list of candidate edges;
//!   every edge of a lit triangle is removed from the list if it is already there and appended
//!   otherwise. Quadratic in the worst case, as the notes say.
//! * [`ClosedMesh::fast_hash`] (Toy Wars, "fast implementation"): the candidate list replaced by
//!   a table with one row per vertex and `N` columns; a directed edge `(v1, v2)` of a lit triangle
//!   removes `v1` from row `v2` if present, otherwise it is stored in row `v1`. Fails when a row
//!   fills up ([`BaselineError::HashRowFull`]), the method's known limit.
//! * [`ClosedMesh::connectivity`] (Toy Wars, "connectivity table"): for every triangle edge, a
//!   lit triangle whose neighbour across the edge is not lit emits the edge (each triangle's
//!   edges from [`EdgeTable::tri_edges`], the neighbours from its edges' two triangles).
//!
//! On such meshes, with lights in general position, each returns exactly the edges with
//! `m != 0` of [`shadowvol_robust_math::Accuracy::Exact`] (tested in `tests/baselines.rs`).
//!
//! ```
//! use shadowvol_cpu::baselines::{Baseline, ClosedMesh};
//! use shadowvol_mesh_topology::{EdgeTable, Mesh};
//! use glam::Vec3;
//!
//! let mesh = Mesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! ).unwrap();
//! let table = EdgeTable::build(&mesh).unwrap();
//! let closed = ClosedMesh::new(&table).unwrap();
//! let light = [2.0, 3.0, 5.0, 1.0];
//! let a = closed.run(Baseline::TwoStep, light).unwrap();
//! assert_eq!(a, closed.run(Baseline::FastHash { columns: 8 }, light).unwrap());
//! assert!(a.len() == 3 || a.len() == 4); // a triangle or quadrilateral outline
//! ```

use shadowvol_mesh_topology::{EdgeTable, NO_NEIGHBOR};

/// Why a baseline cannot run on a mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BaselineError {
    /// An edge does not have exactly two triangles.
    NotClosedManifold {
        /// Edge index in [`EdgeTable::edges`].
        edge: usize,
        /// Its endpoints (input-vertex names).
        names: (u32, u32),
        /// Number of triangles on it.
        triangles: usize,
    },
    /// The two triangles of an edge traverse it in the same direction (inconsistent winding).
    NotOriented {
        /// Edge index in [`EdgeTable::edges`].
        edge: usize,
        /// Its endpoints (input-vertex names).
        names: (u32, u32),
    },
    /// The fast hash table's row for a vertex is full.
    HashRowFull {
        /// The vertex (input-vertex name) whose row overflowed.
        vertex: u32,
        /// Number of columns of the table.
        columns: usize,
    },
    /// `columns` was 0.
    NoColumns,
}

impl std::fmt::Display for BaselineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotClosedManifold {
                edge,
                names,
                triangles,
            } => write!(
                f,
                "edge {edge} (vertices {}-{}) has {triangles} triangle(s); the seed algorithms \
                 need a closed manifold mesh (exactly 2 per edge)",
                names.0, names.1
            ),
            Self::NotOriented { edge, names } => write!(
                f,
                "edge {edge} (vertices {}-{}): both triangles traverse it in the same direction; \
                 the seed algorithms need consistent winding",
                names.0, names.1
            ),
            Self::HashRowFull { vertex, columns } => write!(
                f,
                "fast hash table: the row of vertex {vertex} is full ({columns} columns); use \
                 more columns"
            ),
            Self::NoColumns => write!(f, "fast hash table: at least one column is needed"),
        }
    }
}

impl std::error::Error for BaselineError {}

/// Which baseline to run (for benches and reports).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Baseline {
    /// [`ClosedMesh::two_step`].
    TwoStep,
    /// [`ClosedMesh::classic`].
    Classic,
    /// [`ClosedMesh::fast_hash`] with this many columns.
    FastHash {
        /// Columns per row (the notes use 64 and 8).
        columns: usize,
    },
    /// [`ClosedMesh::connectivity`].
    Connectivity,
}

impl Baseline {
    /// Short name: `two-step`, `classic`, `fast-hash-N`, `connectivity`.
    #[must_use]
    pub fn name(self) -> String {
        match self {
            Self::TwoStep => "two-step".to_owned(),
            Self::Classic => "classic".to_owned(),
            Self::FastHash { columns } => format!("fast-hash-{columns}"),
            Self::Connectivity => "connectivity".to_owned(),
        }
    }
}

/// A validated closed manifold mesh, with the per-edge triangle pairs the two-step method needs
/// (precomputed once, like the seeds' edge lists).
#[derive(Debug, Clone)]
pub struct ClosedMesh<'a> {
    table: &'a EdgeTable,
    edge_tris: Vec<[u32; 2]>,
    /// The connectivity table: the triangle across each edge of each triangle.
    neighbors: Vec<[u32; 3]>,
    /// Each triangle's edges ([`EdgeTable::tri_edges`]), for the connectivity table's output.
    tri_edges: Vec<[u32; 3]>,
}

/// The triangle across each edge of each triangle of a closed manifold mesh, from each
/// triangle's edges and each edge's two triangles.
fn manifold_neighbors(tri_edges: &[[u32; 3]], edge_tris: &[[u32; 2]]) -> Vec<[u32; 3]> {
    tri_edges
        .iter()
        .enumerate()
        .map(|(t, te)| {
            te.map(|e| {
                let [t0, t1] = edge_tris[e as usize];
                if t0 == t as u32 {
                    t1
                } else {
                    t0
                }
            })
        })
        .collect()
}

#[inline]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

impl<'a> ClosedMesh<'a> {
    /// Checks that `table` is closed, manifold and consistently oriented.
    ///
    /// # Errors
    /// [`BaselineError::NotClosedManifold`] or [`BaselineError::NotOriented`] naming the first
    /// offending edge.
    pub fn new(table: &'a EdgeTable) -> Result<Self, BaselineError> {
        let names = |e: usize| table.edge_names(e);
        for e in 0..table.edges.len() {
            let n = table.ovs_of(e).len();
            if n != 2 {
                return Err(BaselineError::NotClosedManifold {
                    edge: e,
                    names: names(e),
                    triangles: n,
                });
            }
        }
        let mut edge_tris = vec![[NO_NEIGHBOR; 2]; table.edges.len()];
        // Direction of each triangle's traversal of its edges: +1 for a -> b.
        let mut dir = vec![0i8; table.edges.len()];
        let tri_edges = table.tri_edges();
        for (t, (tri, te)) in table.triangles.iter().zip(&tri_edges).enumerate() {
            for i in 0..3 {
                let e = te[i] as usize;
                let forward = tri[i] == table.edges[e][0];
                let d = if forward { 1 } else { -1 };
                if edge_tris[e][0] == NO_NEIGHBOR {
                    edge_tris[e][0] = t as u32;
                    dir[e] = d;
                } else {
                    if dir[e] == d {
                        return Err(BaselineError::NotOriented {
                            edge: e,
                            names: names(e),
                        });
                    }
                    edge_tris[e][1] = t as u32;
                }
            }
        }
        Ok(Self {
            table,
            neighbors: manifold_neighbors(&tri_edges, &edge_tris),
            edge_tris,
            tri_edges,
        })
    }

    /// The table this mesh was built from.
    #[must_use]
    pub fn table(&self) -> &'a EdgeTable {
        self.table
    }

    /// `f32` facing test of triangle `t` (see the module documentation).
    #[inline]
    #[must_use]
    pub fn lit(&self, t: usize, light: [f32; 4]) -> bool {
        let p = |v: u32| self.table.positions[v as usize].to_array();
        let [a, b, c] = self.table.triangles[t];
        let (v0, v1, v2) = (p(a), p(b), p(c));
        let (e1, e2) = (sub(v1, v0), sub(v2, v0));
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let l = [
            light[0] - light[3] * v0[0],
            light[1] - light[3] * v0[1],
            light[2] - light[3] * v0[2],
        ];
        n[0] * l[0] + n[1] * l[1] + n[2] * l[2] > 0.0
    }

    /// Runs one baseline.
    ///
    /// # Errors
    /// Only [`ClosedMesh::fast_hash`] fails (a full row, or 0 columns).
    pub fn run(&self, which: Baseline, light: [f32; 4]) -> Result<Vec<u32>, BaselineError> {
        match which {
            Baseline::TwoStep => Ok(self.two_step(light)),
            Baseline::Classic => Ok(self.classic(light)),
            Baseline::FastHash { columns } => self.fast_hash(light, columns),
            Baseline::Connectivity => Ok(self.connectivity(light)),
        }
    }

    /// Shi's two-step method: facing of every triangle, then every edge whose two triangles
    /// differ. Returns sorted edge indices.
    #[must_use]
    pub fn two_step(&self, light: [f32; 4]) -> Vec<u32> {
        let lit: Vec<bool> = (0..self.table.triangles.len())
            .map(|t| self.lit(t, light))
            .collect();
        self.edge_tris
            .iter()
            .enumerate()
            .filter(|(_, [t1, t2])| lit[*t1 as usize] != lit[*t2 as usize])
            .map(|(e, _)| e as u32)
            .collect()
    }

    /// The edge index of the undirected edge `{u, v}`.
    fn edge_index(&self, u: u32, v: u32) -> u32 {
        let key = [u.min(v), u.max(v)];
        // Every directed edge of a triangle is an edge of the table.
        self.table.edges.binary_search(&key).unwrap_or(0) as u32
    }

    /// The classic candidate-edge list: every directed edge of a lit triangle is removed from
    /// the list when its reverse is there and appended otherwise. Returns sorted edge indices.
    #[must_use]
    pub fn classic(&self, light: [f32; 4]) -> Vec<u32> {
        let mut list: Vec<(u32, u32)> = Vec::new();
        for (t, tri) in self.table.triangles.iter().enumerate() {
            if !self.lit(t, light) {
                continue;
            }
            for i in 0..3 {
                let (v1, v2) = (tri[i], tri[(i + 1) % 3]);
                match list.iter().position(|&(a, b)| a == v2 && b == v1) {
                    Some(k) => {
                        list.swap_remove(k);
                    }
                    None => list.push((v1, v2)),
                }
            }
        }
        let mut out: Vec<u32> = list.iter().map(|&(a, b)| self.edge_index(a, b)).collect();
        out.sort_unstable();
        out
    }

    /// The fast hash table with `columns` columns per vertex row (empty cells are `u32::MAX`).
    /// Returns sorted edge indices.
    ///
    /// # Errors
    /// [`BaselineError::HashRowFull`] when a vertex needs more than `columns` cells,
    /// [`BaselineError::NoColumns`] for `columns == 0`.
    pub fn fast_hash(&self, light: [f32; 4], columns: usize) -> Result<Vec<u32>, BaselineError> {
        const EMPTY: u32 = u32::MAX;
        if columns == 0 {
            return Err(BaselineError::NoColumns);
        }
        let mut table = vec![EMPTY; self.table.positions.len() * columns];
        for (t, tri) in self.table.triangles.iter().enumerate() {
            if !self.lit(t, light) {
                continue;
            }
            for i in 0..3 {
                let (v1, v2) = (tri[i], tri[(i + 1) % 3]);
                let row2 = &mut table[v2 as usize * columns..(v2 as usize + 1) * columns];
                if let Some(cell) = row2.iter_mut().find(|c| **c == v1) {
                    *cell = EMPTY;
                    continue;
                }
                let row1 = &mut table[v1 as usize * columns..(v1 as usize + 1) * columns];
                match row1.iter_mut().find(|c| **c == EMPTY) {
                    Some(cell) => *cell = v2,
                    None => {
                        return Err(BaselineError::HashRowFull {
                            vertex: self.table.vertex_names.get(v1 as usize),
                            columns,
                        })
                    }
                }
            }
        }
        let mut out = Vec::new();
        for (cell, &v2) in table.iter().enumerate() {
            if v2 != EMPTY {
                out.push(self.edge_index((cell / columns) as u32, v2));
            }
        }
        out.sort_unstable();
        Ok(out)
    }

    /// The connectivity table: for every edge of every triangle, emit it when the triangle is lit
    /// and its neighbour across the edge is not. Returns sorted edge indices.
    #[must_use]
    pub fn connectivity(&self, light: [f32; 4]) -> Vec<u32> {
        let mut out = Vec::new();
        for t in 0..self.table.triangles.len() {
            if !self.lit(t, light) {
                continue;
            }
            for i in 0..3 {
                // Closed manifold: every neighbour exists (checked in `new`).
                let n = self.neighbors[t][i] as usize;
                if !self.lit(n, light) {
                    out.push(self.tri_edges[t][i]);
                }
            }
        }
        out.sort_unstable();
        out
    }
}
