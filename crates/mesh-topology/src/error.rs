//! Errors from building or validating a mesh.

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
        /// What overflowed (for example "vertices" or "opposite-vertex references (4 x
        /// triangles)").
        what: &'static str,
        /// The count found.
        count: u64,
        /// The limit.
        limit: u64,
    },
    /// Building the edge table would need more memory than is available (checked by
    /// [`EdgeTable::check_size`](crate::EdgeTable::check_size) before anything big is allocated).
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
        /// Upper bound of the bytes the build allocates
        /// ([`EdgeTable::estimate_bytes`](crate::EdgeTable::estimate_bytes)).
        needed: u64,
        /// Bytes available.
        available: u64,
        /// Where `available` comes from (`/proc/meminfo MemAvailable`, the cgroup limit or
        /// [`MEMORY_LIMIT_ENV`](crate::MEMORY_LIMIT_ENV)).
        origin: String,
    },
}
