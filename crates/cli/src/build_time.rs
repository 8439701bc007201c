//! The edge-table build timed against reading its input from memory: `shadowvol bench
//! --build-runs N`.
//!
//! [`time_build`] rebuilds a table from its own positions and triangles (the mesh a loader
//! hands to [`EdgeTable::build`]) `runs` times, and times [`MemoryFloor::read_only`] passes over
//! the same bytes on the same threads. Their ratio says how far the build (welding, the counting
//! sort, the grouping) is from the cost of merely reading its input.

use crate::cmd_bench::percentiles;
use serde::Serialize;
use shadowvol::{CliError, MemoryFloor};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use std::time::{Duration, Instant};

/// One table's build time and its memory floor.
#[derive(Debug, Clone, Serialize)]
pub struct BuildTiming {
    /// Triangles of the mesh built.
    pub triangles: usize,
    /// Vertices of the mesh built.
    pub vertices: usize,
    /// Bytes of the mesh (12 per vertex, 12 per triangle): what the build must read.
    pub input_bytes: usize,
    /// Builds timed.
    pub runs: u32,
    /// Median build time, ms.
    pub median_ms: f64,
    /// Fastest build, ms.
    pub min_ms: f64,
    /// Median time to read `input_bytes` on all of rayon's threads, ms.
    pub read_ms: f64,
    /// `median_ms / read_ms`.
    pub ratio: f64,
    /// Threads in rayon's pool (the build's and the read's).
    pub threads: usize,
}

/// Builds `table`'s mesh `runs` times (at least once) and reads as many bytes `runs` times (at
/// least 5), each timed.
///
/// # Errors
/// [`CliError::Other`] if the table's own positions and triangles do not form a valid mesh
/// (never for a table made by [`EdgeTable::build`]) or do not build.
pub fn time_build(table: &EdgeTable, runs: u32) -> Result<BuildTiming, CliError> {
    let mesh = Mesh::new(table.positions.clone(), table.triangles.clone())
        .map_err(|e| CliError::Other(format!("the table's own mesh: {e}")))?;
    let input_bytes = 12 * (mesh.positions.len() + mesh.triangles.len());
    let mut builds = Vec::new();
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        let built = EdgeTable::build(&mesh)
            .map_err(|e| CliError::Other(format!("rebuilding the table: {e}")))?;
        builds.push(start.elapsed());
        drop(built);
    }
    drop(mesh);
    let mut floor = MemoryFloor::read_only(input_bytes);
    floor.run_once(); // brings the buffer in, untimed
    let mut reads: Vec<Duration> = (0..runs.max(5)).map(|_| floor.run_once()).collect();
    let (median_ms, _, _) = percentiles(&mut builds);
    let min_ms = builds.iter().min().map_or(0.0, |d| d.as_secs_f64() * 1e3);
    let (read_ms, _, _) = percentiles(&mut reads);
    Ok(BuildTiming {
        triangles: table.triangles.len(),
        vertices: table.positions.len(),
        input_bytes,
        runs: runs.max(1),
        median_ms,
        min_ms,
        read_ms,
        ratio: median_ms / read_ms.max(1e-9),
        threads: rayon::current_num_threads(),
    })
}
