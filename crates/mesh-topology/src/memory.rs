//! What an edge table costs: the available memory, the estimate of a build's allocations, and the
//! check that refuses a mesh before allocating when it would not fit.

use crate::{EdgeTable, MeshError};
use std::collections::HashSet;
use std::sync::Arc;

/// Heap bytes of a vector's allocation (its capacity, not its length).
#[must_use]
pub fn vec_bytes<T>(v: &Vec<T>) -> u64 {
    (v.capacity() * std::mem::size_of::<T>()) as u64
}

/// The sum of `bytes` over `items`, each shared allocation counted once however many times it
/// appears (instances of one mesh share one table or one layout).
pub fn unique_arc_bytes<'a, T: 'a>(
    items: impl IntoIterator<Item = &'a Arc<T>>,
    bytes: impl Fn(&T) -> u64,
) -> u64 {
    let mut seen = HashSet::new();
    items
        .into_iter()
        .filter(|a| seen.insert(Arc::as_ptr(a)))
        .map(|a| bytes(a))
        .sum()
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

impl EdgeTable {
    /// Upper bound of the heap bytes [`EdgeTable::build`] allocates for a mesh of `triangles`
    /// triangles and `vertices` input vertices, not counting the input mesh itself.
    ///
    /// Per triangle (68 bytes): kept triangles (12) and their sources when some are dropped (up
    /// to 8 while that vector grows), the counting-sort entries that become the OV lists (12),
    /// edge records and CSR offsets at the worst case of 3 edges per triangle (36). Per vertex
    /// (52 bytes): the weld's index table (up to 12), each vertex's compact id (4), names,
    /// positions and (on one thread) keys reserved for as many groups as vertices (28), the
    /// buckets' and the edges' starts (8). A closed manifold mesh needs about 70 % of this.
    #[must_use]
    pub fn estimate_bytes(triangles: u64, vertices: u64) -> u64 {
        triangles
            .saturating_mul(68)
            .saturating_add(vertices.saturating_mul(52))
    }

    /// Heap bytes the table holds now: the capacity of each of its vectors times the size of
    /// its element (positions, names and triangle sources where stored, triangles, edges, CSR
    /// offsets and opposite-vertex corners). The struct itself is not counted.
    #[must_use]
    pub fn heap_bytes(&self) -> u64 {
        vec_bytes(&self.positions)
            + self.vertex_names.heap_bytes()
            + vec_bytes(&self.triangles)
            + self.triangle_sources.heap_bytes()
            + vec_bytes(&self.edges)
            + vec_bytes(&self.ov_offsets)
            + vec_bytes(&self.ov_refs)
    }

    /// Checks, without allocating, that a mesh of `triangles` triangles and `vertices` vertices
    /// fits `u32` indexing and that its edge table ([`EdgeTable::estimate_bytes`]) fits the
    /// available memory ([`available_memory`]). Returns the estimate in bytes.
    ///
    /// The memory check runs when the estimate is at least [`MEMORY_CHECK_THRESHOLD`] or when
    /// [`MEMORY_LIMIT_ENV`] is set; it is skipped when the available memory cannot be read.
    ///
    /// # Errors
    /// [`MeshError::TooLarge`] when `vertices >= 2^32 - 1` or `4 * triangles >= 2^32 - 1` (the
    /// opposite-vertex references `4 t + r`, [`EdgeTable::ov_refs`], are 32-bit);
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
        if triangles.saturating_mul(4) >= limit {
            return Err(MeshError::TooLarge {
                what: "opposite-vertex references (4 x triangles)",
                count: triangles.saturating_mul(4),
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
}
