//! Triangle meshes and the edge topology that silhouette extraction runs on.
//!
//! The pipeline is `Mesh` → [`weld`] → [`EdgeTable`]:
//!
//! * [`Mesh`] holds `f32` positions and `u32` triangles exactly as they were loaded.
//! * [`weld`] merges vertices whose positions are bit-for-bit equal (with `-0.0 == +0.0`). A weld
//!   group is named by its smallest input index, and compact (welded) ids are assigned in
//!   ascending order of that name, so ordering by compact id is ordering by name.
//! * [`EdgeTable::build`] drops triangles that are degenerate after welding (a repeated vertex),
//!   and lists every undirected edge `(a, b)` with `a < b` once, together with the *opposite
//!   vertices* (OVs) of all triangles that share it, in compressed-sparse-row form. Any number of
//!   triangles per edge is allowed: boundary (1), manifold (2) and non-manifold (3 or more).
//!
//! Construction is linear in the number of triangles: a counting sort buckets the edge entries by
//! their smaller endpoint and each (small) bucket is sorted by the larger one.
//!
//! ```
//! use shadowvol_mesh_topology::{EdgeTable, Mesh};
//! use glam::Vec3;
//!
//! // A tetrahedron: closed and manifold.
//! let mesh = Mesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! )?;
//! let table = EdgeTable::build(&mesh)?;
//! assert_eq!(table.stats.edges, 6);
//! assert_eq!(table.stats.manifold_edges, 6);
//! assert_eq!(table.ovs_of(0).len(), 2);
//! # Ok::<(), shadowvol_mesh_topology::MeshError>(())
//! ```

use glam::Vec3;

/// Marker for "no triangle" in [`Connectivity::neighbors`].
pub const NO_NEIGHBOR: u32 = u32::MAX;

/// Errors from building or validating a mesh.
///
/// Every variant names the offending element (vertex, triangle, corner) so that a loader can
/// turn it into a message that points into the source file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// A position coordinate is NaN or infinite.
    #[error("vertex {vertex}: coordinate {axis} is {value}, but positions must be finite")]
    NonFinitePosition {
        /// Input vertex index.
        vertex: usize,
        /// `'x'`, `'y'` or `'z'`.
        axis: char,
        /// The offending value.
        value: f32,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle}, corner {corner}: vertex index {index} is out of range (the mesh has {vertices} vertices)")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// Corner 0, 1 or 2.
        corner: usize,
        /// The index found.
        index: u32,
        /// Number of vertices in the mesh.
        vertices: usize,
    },
    /// The mesh has more vertices or edge entries than `u32` indices can address.
    #[error(
        "the mesh is too large: {what} is {count}, but at most {limit} can be indexed with u32"
    )]
    TooLarge {
        /// What overflowed (for example "vertices" or "edge entries (3 x triangles)").
        what: &'static str,
        /// The count found.
        count: u64,
        /// The limit.
        limit: u64,
    },
    /// Building the edge table would need more memory than is available (checked by
    /// [`EdgeTable::check_size`] before anything big is allocated).
    #[error(
        "not enough memory for the edge table of {triangles} triangles and {vertices} vertices: \
         it needs up to {needed} bytes ({} MiB) but {available} bytes ({} MiB) are available \
         ({origin})",
        .needed >> 20,
        .available >> 20
    )]
    OutOfMemory {
        /// Input triangles.
        triangles: u64,
        /// Input vertices.
        vertices: u64,
        /// Upper bound of the bytes the build allocates ([`EdgeTable::estimate_bytes`]).
        needed: u64,
        /// Bytes available.
        available: u64,
        /// Where `available` comes from (`/proc/meminfo MemAvailable`, the cgroup limit or
        /// [`MEMORY_LIMIT_ENV`]).
        origin: String,
    },
}

/// Environment variable that caps the bytes [`EdgeTable::build`] may allocate (a decimal
/// number of bytes). It takes precedence over `/proc/meminfo`; use it to test the
/// out-of-memory path or to keep a build inside a budget.
pub const MEMORY_LIMIT_ENV: &str = "SHADOWVOL_MEMORY_LIMIT";

/// Builds whose estimate is below this many bytes skip the memory check (it reads
/// `/proc/meminfo`), unless [`MEMORY_LIMIT_ENV`] is set.
pub const MEMORY_CHECK_THRESHOLD: u64 = 64 << 20;

/// Bytes available for new allocations and where that number comes from: [`MEMORY_LIMIT_ENV`]
/// if set, otherwise the smaller of `MemAvailable` in `/proc/meminfo` and the cgroup v2 limit
/// (`memory.max - memory.current`). `None` when none of these can be read (non-Linux hosts).
#[must_use]
pub fn available_memory() -> Option<(u64, String)> {
    if let Ok(v) = std::env::var(MEMORY_LIMIT_ENV) {
        if let Ok(n) = v.trim().parse::<u64>() {
            return Some((n, format!("{MEMORY_LIMIT_ENV}={n}")));
        }
    }
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map(|kb| (kb * 1024, "/proc/meminfo MemAvailable".to_owned()))
    });
    let read = |f: &str| {
        std::fs::read_to_string(format!("/sys/fs/cgroup/{f}"))
            .ok()
            .and_then(|t| t.trim().parse::<u64>().ok())
    };
    let cgroup = match (read("memory.max"), read("memory.current")) {
        (Some(max), Some(cur)) => Some((
            max.saturating_sub(cur),
            "cgroup memory.max - memory.current".to_owned(),
        )),
        _ => None,
    };
    match (meminfo, cgroup) {
        (Some(m), Some(c)) => Some(if c.0 < m.0 { c } else { m }),
        (m, c) => m.or(c),
    }
}

/// A triangle mesh as loaded: `f32` positions and `u32` vertex-index triples.
///
/// Positions are in the object's own coordinate frame. The winding of triangles is kept but is
/// irrelevant to silhouette extraction, which works on unoriented, possibly non-manifold meshes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Creates a mesh and validates it with [`Mesh::validate`].
    ///
    /// # Errors
    /// Returns the first [`MeshError`] found: a non-finite coordinate, an index out of range, or a
    /// mesh too large for `u32` indexing.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        let mesh = Self {
            positions,
            triangles,
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Checks that every coordinate is finite, every index is in range, and the mesh fits `u32`
    /// indexing (vertices < 2^32 and 3 × triangles < 2^32).
    ///
    /// # Errors
    /// The first problem found, in vertex order then triangle order.
    pub fn validate(&self) -> Result<(), MeshError> {
        let limit = u64::from(u32::MAX);
        if self.positions.len() as u64 >= limit {
            return Err(MeshError::TooLarge {
                what: "vertices",
                count: self.positions.len() as u64,
                limit: limit - 1,
            });
        }
        if self.triangles.len() as u64 * 3 >= limit {
            return Err(MeshError::TooLarge {
                what: "edge entries (3 x triangles)",
                count: self.triangles.len() as u64 * 3,
                limit: limit - 1,
            });
        }
        for (vertex, p) in self.positions.iter().enumerate() {
            for (axis, value) in ['x', 'y', 'z'].into_iter().zip(p.to_array()) {
                if !value.is_finite() {
                    return Err(MeshError::NonFinitePosition {
                        vertex,
                        axis,
                        value,
                    });
                }
            }
        }
        let n = self.positions.len();
        for (triangle, t) in self.triangles.iter().enumerate() {
            for (corner, &index) in t.iter().enumerate() {
                if index as usize >= n {
                    return Err(MeshError::IndexOutOfRange {
                        triangle,
                        corner,
                        index,
                        vertices: n,
                    });
                }
            }
        }
        Ok(())
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Appends `other` to this mesh, offsetting its indices. Used to bake several objects into one.
    ///
    /// # Errors
    /// [`MeshError::TooLarge`] when the result would not fit `u32` indexing.
    pub fn append(&mut self, other: &Mesh) -> Result<(), MeshError> {
        let base = self.positions.len() as u64;
        if base + other.positions.len() as u64 >= u64::from(u32::MAX) {
            return Err(MeshError::TooLarge {
                what: "vertices",
                count: base + other.positions.len() as u64,
                limit: u64::from(u32::MAX) - 1,
            });
        }
        let base = base as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
        Ok(())
    }
}

/// The result of exact-position welding.
#[derive(Debug, Clone, PartialEq)]
pub struct Weld {
    /// For each input vertex, its compact (welded) id.
    pub compact_of_input: Vec<u32>,
    /// For each compact id, the smallest input index of its weld group (its *name*).
    /// Strictly increasing.
    pub names: Vec<u32>,
    /// For each compact id, the position (identical for the whole group, up to the sign of zero).
    pub positions: Vec<Vec3>,
}

/// The bit pattern used as the weld key: `-0.0` is mapped to `+0.0`, everything else is kept.
#[inline]
fn weld_key(p: Vec3) -> [u32; 3] {
    // Adding +0.0 turns -0.0 into +0.0 and leaves every other finite value unchanged.
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

/// Hash of a weld key: the top `bits` bits of a multiplicative mix of the three words.
#[inline]
fn weld_hash(k: [u32; 3], bits: u32) -> usize {
    let lo = u64::from(k[0]) | (u64::from(k[1]) << 32);
    let mut h = lo.wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ u64::from(k[2]).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    h ^= h >> 29;
    h = h.wrapping_mul(0x1656_67b1_9e37_79f9);
    (h >> (64 - bits)) as usize
}

/// Welds vertices whose positions are exactly equal (`-0.0 == +0.0`).
///
/// Each group is named by its smallest input index, and compact ids are numbered in ascending
/// order of names. The position of a group is the position of its named (first) vertex. Runs in
/// expected linear time (hashing with open addressing). Positions are expected to be finite (see [`Mesh::validate`]);
/// NaN positions weld only with NaNs of the identical bit pattern (their bits are kept).
#[must_use]
pub fn weld(positions: &[Vec3]) -> Weld {
    // Open addressing with linear probing in a table of at least twice the vertex count; a
    // slot holds a compact id (4 bytes), the key is compared against that group's key. This is
    // about half the memory traffic of a general hash map on 10^6-triangle meshes.
    let bits = (positions.len().max(8) * 2)
        .next_power_of_two()
        .trailing_zeros();
    let mask = (1usize << bits) - 1;
    let mut slots = vec![u32::MAX; 1 << bits];
    let mut keys: Vec<[u32; 3]> = Vec::new();
    let mut compact_of_input = Vec::with_capacity(positions.len());
    let mut names = Vec::new();
    let mut out_positions = Vec::new();
    for (i, &p) in positions.iter().enumerate() {
        let key = weld_key(p);
        let mut h = weld_hash(key, bits);
        let id = loop {
            let s = slots[h];
            if s == u32::MAX {
                let id = names.len() as u32;
                slots[h] = id;
                keys.push(key);
                names.push(i as u32);
                out_positions.push(p);
                break id;
            }
            if keys[s as usize] == key {
                break s;
            }
            h = (h + 1) & mask;
        };
        compact_of_input.push(id);
    }
    Weld {
        compact_of_input,
        names,
        positions: out_positions,
    }
}

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
/// index and the triangle across that edge.
///
/// Edge `i` of triangle `[v0, v1, v2]` goes from `v_i` to `v_{(i+1) % 3}` (in the triangle's own
/// winding). The seeds' baseline algorithms (Toy Wars' connectivity table, the thesis' two-step
/// method) walk this table.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Connectivity {
    /// `tri_edges[t][i]` is the index into [`EdgeTable::edges`] of edge `i` of triangle `t`.
    pub tri_edges: Vec<[u32; 3]>,
    /// `neighbors[t][i]` is the other triangle on edge `i` of triangle `t` when that edge is
    /// manifold (exactly two triangles), otherwise [`NO_NEIGHBOR`].
    pub neighbors: Vec<[u32; 3]>,
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

    /// Builds the table from an existing weld and the input triangles (already validated).
    ///
    /// # Panics
    /// Panics if a triangle index is out of range of `weld.compact_of_input`; call
    /// [`Mesh::validate`] first (as [`EdgeTable::build`] does).
    #[must_use]
    pub fn from_weld(weld: Weld, input_triangles: &[[u32; 3]]) -> Self {
        let vertex_count = weld.names.len();
        // 1. Map to compact ids and drop degenerate triangles.
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
        let degenerate = input_triangles.len() - triangles.len();

        // 2. Counting sort of the 3 entries per triangle by their smaller endpoint.
        let mut start = vec![0u32; vertex_count + 1];
        for t in &triangles {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                start[a.min(b) as usize + 1] += 1;
            }
        }
        for v in 0..vertex_count {
            start[v + 1] += start[v];
        }
        // Entry: (larger endpoint, triangle, corner i of the edge) — the OV is t[(i + 2) % 3].
        let total = triangles.len() * 3;
        let mut entries = vec![(0u32, 0u32, 0u8); total];
        let mut fill = start.clone();
        for (ti, t) in triangles.iter().enumerate() {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let slot = &mut fill[a.min(b) as usize];
                entries[*slot as usize] = (a.max(b), ti as u32, i as u8);
                *slot += 1;
            }
        }

        // 3. Sort each bucket (its size is the vertex's degree) and walk the groups.
        let mut edges = Vec::with_capacity(total / 2 + 1);
        let mut ov_offsets = Vec::with_capacity(total / 2 + 2);
        let mut ovs = Vec::with_capacity(total);
        let mut tri_edges = vec![[0u32; 3]; triangles.len()];
        let mut stats = MeshStats {
            vertices: weld.compact_of_input.len(),
            welded_vertices: vertex_count,
            triangles: input_triangles.len(),
            degenerate_triangles: degenerate,
            opposite_vertices: total,
            ..MeshStats::default()
        };
        ov_offsets.push(0);
        for a in 0..vertex_count {
            let bucket = &mut entries[start[a] as usize..start[a + 1] as usize];
            bucket.sort_unstable_by_key(|&(b, t, i)| (b, t, i));
            let mut k = 0;
            while k < bucket.len() {
                let b = bucket[k].0;
                let edge_index = edges.len() as u32;
                let mut n = 0usize;
                while k < bucket.len() && bucket[k].0 == b {
                    let (_, t, i) = bucket[k];
                    let tri = triangles[t as usize];
                    ovs.push(tri[(usize::from(i) + 2) % 3]);
                    tri_edges[t as usize][usize::from(i)] = edge_index;
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

        // 4. Neighbours across manifold edges.
        let mut first_tri = vec![NO_NEIGHBOR; edges.len()];
        let mut second_tri = vec![NO_NEIGHBOR; edges.len()];
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
        let neighbors = tri_edges
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
            .collect();

        Self {
            positions: weld.positions,
            vertex_names: weld.names,
            triangles,
            triangle_sources,
            edges,
            ov_offsets,
            ovs,
            connectivity: Connectivity {
                tri_edges,
                neighbors,
            },
            stats,
        }
    }

    /// Upper bound of the heap bytes [`EdgeTable::build`] allocates for a mesh of `triangles`
    /// triangles and `vertices` input vertices, not counting the input mesh itself.
    ///
    /// Per triangle (166 bytes): kept triangles and their sources (16), the counting-sort entries
    /// (36), OV lists (12), per-triangle edge ids and neighbours (24), edge records, CSR offsets
    /// and the neighbour scratch at the worst case of 3 edges per triangle, including one vector
    /// regrowth (78). Per vertex (76 bytes): the weld's hash slots (up to 16), keys, names and
    /// positions at double capacity (56) and the input-to-compact map (4). A closed manifold mesh
    /// needs about 70 % of this.
    #[must_use]
    pub fn estimate_bytes(triangles: u64, vertices: u64) -> u64 {
        triangles
            .saturating_mul(166)
            .saturating_add(vertices.saturating_mul(76))
    }

    /// Checks, without allocating, that a mesh of `triangles` triangles and `vertices` vertices
    /// fits `u32` indexing and that its edge table ([`EdgeTable::estimate_bytes`]) fits the
    /// available memory ([`available_memory`]). Returns the estimate in bytes.
    ///
    /// The memory check runs when the estimate is at least [`MEMORY_CHECK_THRESHOLD`] or when
    /// [`MEMORY_LIMIT_ENV`] is set; it is skipped when the available memory cannot be read.
    ///
    /// # Errors
    /// [`MeshError::TooLarge`] when `vertices >= 2^32 - 1` or `3 * triangles >= 2^32 - 1`;
    /// [`MeshError::OutOfMemory`] naming both numbers when the estimate exceeds what is available.
    pub fn check_size(triangles: u64, vertices: u64) -> Result<u64, MeshError> {
        let limit = u64::from(u32::MAX);
        if vertices >= limit {
            return Err(MeshError::TooLarge {
                what: "vertices",
                count: vertices,
                limit: limit - 1,
            });
        }
        if triangles.saturating_mul(3) >= limit {
            return Err(MeshError::TooLarge {
                what: "edge entries (3 x triangles)",
                count: triangles.saturating_mul(3),
                limit: limit - 1,
            });
        }
        let needed = Self::estimate_bytes(triangles, vertices);
        if needed >= MEMORY_CHECK_THRESHOLD || std::env::var_os(MEMORY_LIMIT_ENV).is_some() {
            if let Some((available, source)) = available_memory() {
                if needed > available {
                    return Err(MeshError::OutOfMemory {
                        triangles,
                        vertices,
                        needed,
                        available,
                        origin: source,
                    });
                }
            }
        }
        Ok(needed)
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

/// Peak-allocation tracking for the estimate tests: a global allocator that counts each
/// thread's live bytes (only in this crate's unit-test binary).
#[cfg(test)]
mod counting {
    // The counts are per thread: the test harness runs tests on parallel threads, and a
    // process-wide count let one test's allocations show up in another's peak (seen in CI: a
    // 9834-byte "peak" in a test that allocates nothing). Nothing measured here spawns threads.
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    pub struct Counting;

    thread_local! {
        // Const-initialised, no destructor: reading them never allocates.
        static LIVE: Cell<isize> = const { Cell::new(0) };
        static PEAK: Cell<isize> = const { Cell::new(0) };
    }

    // SAFETY: forwards to the system allocator; only counts.
    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            let size = layout.size() as isize;
            // `try_with`: during thread teardown the counters may be gone; then nothing counts.
            let _ = LIVE.try_with(|live| {
                live.set(live.get() + size);
                let _ = PEAK.try_with(|peak| peak.set(peak.get().max(live.get())));
            });
            // SAFETY: same contract as the caller's.
            unsafe { System.alloc(layout) }
        }
        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            let size = layout.size() as isize;
            let _ = LIVE.try_with(|live| live.set(live.get() - size));
            // SAFETY: same contract as the caller's.
            unsafe { System.dealloc(ptr, layout) }
        }
    }

    #[global_allocator]
    static GLOBAL: Counting = Counting;

    /// Peak live bytes allocated by this thread above its level at the start, while `f` runs.
    pub fn peak_during<R>(f: impl FnOnce() -> R) -> (R, usize) {
        let base = LIVE.with(Cell::get);
        PEAK.with(|p| p.set(base));
        let r = f();
        let peak = PEAK.with(Cell::get);
        (r, usize::try_from(peak - base).unwrap_or(0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An `n x n` grid of quads (2 n^2 triangles, manifold inside, boundary around).
    fn grid(n: u32) -> Mesh {
        let mut positions = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                positions.push(Vec3::new(x as f32, y as f32, ((x * 7 + y * 3) % 5) as f32));
            }
        }
        let mut triangles = Vec::new();
        let id = |x: u32, y: u32| y * (n + 1) + x;
        for y in 0..n {
            for x in 0..n {
                triangles.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                triangles.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
            }
        }
        Mesh::new(positions, triangles).unwrap()
    }

    /// A soup: every triangle has its own three vertices (3 boundary edges per triangle, the
    /// most edges a mesh can have).
    fn soup(t: u32) -> Mesh {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..t {
            let f = i as f32;
            positions.extend([
                Vec3::new(f, 0.0, 0.0),
                Vec3::new(f, 1.0, 0.0),
                Vec3::new(f, 0.0, 1.0),
            ]);
            triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        Mesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn estimate_bounds_the_measured_peak_allocation() {
        for (name, mesh) in [("grid", grid(300)), ("soup", soup(150_000))] {
            let t = mesh.triangles.len() as u64;
            let v = mesh.positions.len() as u64;
            let estimate = EdgeTable::estimate_bytes(t, v);
            let (table, peak) = counting::peak_during(|| EdgeTable::build(&mesh).unwrap());
            assert_eq!(table.stats.triangles, mesh.triangles.len());
            let peak = peak as u64;
            eprintln!("{name}: {t} triangles, {v} vertices: peak {peak} B, estimate {estimate} B");
            assert!(
                peak <= estimate,
                "{name}: peak {peak} > estimate {estimate}"
            );
            // Not uselessly loose either.
            assert!(
                2 * peak >= estimate,
                "{name}: peak {peak} is under half of {estimate}"
            );
        }
    }

    #[test]
    fn beyond_u32_is_refused_without_allocating() {
        let ((), peak) = counting::peak_during(|| {
            let e = EdgeTable::check_size(1 << 31, 10).unwrap_err();
            assert!(matches!(
                e,
                MeshError::TooLarge {
                    what: "edge entries (3 x triangles)",
                    ..
                }
            ));
            assert!(e.to_string().contains("6442450944"), "{e}");
            let e = EdgeTable::check_size(10, u64::from(u32::MAX)).unwrap_err();
            assert!(
                matches!(
                    e,
                    MeshError::TooLarge {
                        what: "vertices",
                        ..
                    }
                ),
                "{e}"
            );
        });
        assert!(peak < 4096, "{peak} bytes allocated");
        // Just inside the limit passes the index check (the memory check may still refuse).
        let inside = EdgeTable::check_size((u64::from(u32::MAX) - 1) / 3, 3);
        assert!(
            !matches!(inside, Err(MeshError::TooLarge { .. })),
            "{inside:?}"
        );
    }

    #[test]
    fn memory_check_names_the_numbers() {
        // 10^12 triangles fits no machine this runs on (1.66e14 bytes); vertices stay in range
        // but triangles don't: use a count inside u32 and a huge vertex count instead.
        let Some((available, _)) = available_memory() else {
            return; // not Linux: nothing to compare against
        };
        let t = (u64::from(u32::MAX) - 1) / 3;
        let v = u64::from(u32::MAX) - 2;
        let needed = EdgeTable::estimate_bytes(t, v);
        if needed <= available {
            return; // a machine with over 500 GB free
        }
        let e = EdgeTable::check_size(t, v).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, MeshError::OutOfMemory { .. }), "{msg}");
        assert!(
            msg.contains(&needed.to_string()) && msg.contains("MiB"),
            "{msg}"
        );
        assert!(
            msg.contains(&t.to_string()) && msg.contains(&v.to_string()),
            "{msg}"
        );
    }

    #[test]
    fn weld_negative_zero_and_names() {
        let p = vec![
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, -0.0, 0.0),
            Vec3::new(0.0, 1.0, -0.0),
            Vec3::new(2.0, 0.0, 0.0),
        ];
        let w = weld(&p);
        assert_eq!(w.names, vec![0, 1, 4]);
        assert_eq!(w.compact_of_input, vec![0, 1, 0, 1, 2]);
    }

    /// Linear probing wraps from the table's last slot to slot 0 (a table of 16 slots for up
    /// to 8 vertices): keys that hash to slot 15 and to slot 0 collide across the wrap.
    #[test]
    fn weld_probing_wraps_around_the_table() {
        let find = |slot: usize, n: usize| -> Vec<Vec3> {
            (0..)
                .map(|i| Vec3::new(i as f32, 0.5, -2.0))
                .filter(|&p| weld_hash(weld_key(p), 4) == slot)
                .take(n)
                .collect()
        };
        let (last, first) = (find(15, 3), find(0, 2));
        let p = vec![
            last[0], last[1], first[0], last[2], last[0], first[1], last[1], first[0],
        ];
        assert_eq!(p.len(), 8, "8 vertices: 16 slots");
        let w = weld(&p);
        // The reference: a group is named by its first index, compact ids in order of names.
        let names: Vec<u32> = (0..p.len())
            .map(|i| (0..=i).find(|&j| p[j] == p[i]).unwrap() as u32)
            .collect();
        let mut distinct = names.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(w.names, distinct);
        assert_eq!(w.names, vec![0, 1, 2, 3, 5]);
        for (i, &c) in w.compact_of_input.iter().enumerate() {
            assert_eq!(w.names[c as usize], names[i], "vertex {i}");
            assert_eq!(w.positions[c as usize], p[i]);
        }
    }

    #[test]
    fn nonmanifold_book() {
        // Spine (0,1) shared by 4 pages.
        let mut positions = vec![Vec3::ZERO, Vec3::Z];
        let mut triangles = Vec::new();
        for k in 0..4 {
            let ang = k as f32;
            positions.push(Vec3::new(ang.cos(), ang.sin(), 0.5));
            triangles.push([0, 1, 2 + k]);
        }
        let t = EdgeTable::build(&Mesh::new(positions, triangles).unwrap()).unwrap();
        assert_eq!(t.stats.nonmanifold_edges, 1);
        assert_eq!(t.stats.boundary_edges, 8);
        assert_eq!(t.ovs_of(0), &[2, 3, 4, 5]);
        assert_eq!(t.connectivity.neighbors[0][0], NO_NEIGHBOR);
    }

    #[test]
    fn degenerate_after_weld_dropped() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::X, Vec3::Y];
        let t = EdgeTable::build(&Mesh::new(p, vec![[0, 1, 2], [0, 1, 3]]).unwrap()).unwrap();
        assert_eq!(t.stats.degenerate_triangles, 1);
        assert_eq!(t.triangles.len(), 1);
        assert_eq!(t.triangle_sources, vec![1]);
    }

    #[test]
    fn errors_name_the_place() {
        let e = Mesh::new(vec![Vec3::ZERO], vec![[0, 0, 7]]).unwrap_err();
        assert_eq!(
            e,
            MeshError::IndexOutOfRange {
                triangle: 0,
                corner: 2,
                index: 7,
                vertices: 1
            }
        );
        let e = Mesh::new(vec![Vec3::new(0.0, f32::NAN, 0.0)], vec![]).unwrap_err();
        assert!(e.to_string().contains("vertex 0: coordinate y"));
    }
}

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
