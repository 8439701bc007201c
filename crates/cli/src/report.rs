//! The silhouette report: what `shadowvol silhouette` computes and prints.
//!
//! The JSON form follows the CLI contract of DESIGN.md (scripts depend on it; fields are only
//! ever added):
//!
//! ```text
//! {"backend": "...", "mode": "...", "mesh": {"vertices": N, "welded_vertices": N,
//!  "triangles": N, "edges": N, "boundary_edges": N, "nonmanifold_edges": N, ...},
//!  "lights": [{"light": [x,y,z,w], "edges": [[a, b, m], ...], "open_vertices": N}], ...,
//!  "peak_rss_bytes": N or null, "table_bytes": N, "table_bytes_parts": {"topology", "host",
//!  "device"}}
//! ```
//!
//! `a < b` are input vertex indices (0-based; a weld group is named by its smallest input index),
//! only `m != 0` is listed, sorted by `(a, b)`.

use crate::memory::{peak_rss_bytes, table_bytes, TableBytes};
use crate::CliError;
use serde::Serialize;
use shadowvol_mesh_topology::{EdgeTable, MeshStats};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{invariant, SilhouetteBackend, TopologyScene};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Mesh statistics as reported. The first six fields are the contract; the rest are additions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct MeshSummary {
    /// Input vertices.
    pub vertices: usize,
    /// Vertices after exact-position welding.
    pub welded_vertices: usize,
    /// Input triangles (degenerate ones included).
    pub triangles: usize,
    /// Unique undirected edges.
    pub edges: usize,
    /// Edges with one triangle.
    pub boundary_edges: usize,
    /// Edges with three or more triangles.
    pub nonmanifold_edges: usize,
    /// Edges with exactly two triangles.
    pub manifold_edges: usize,
    /// Triangles dropped because two corners weld to the same vertex.
    pub degenerate_triangles: usize,
}

impl From<MeshStats> for MeshSummary {
    fn from(s: MeshStats) -> Self {
        Self {
            vertices: s.vertices,
            welded_vertices: s.welded_vertices,
            triangles: s.triangles,
            edges: s.edges,
            boundary_edges: s.boundary_edges,
            nonmanifold_edges: s.nonmanifold_edges,
            manifold_edges: s.manifold_edges,
            degenerate_triangles: s.degenerate_triangles,
        }
    }
}

/// The silhouette for one light.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LightReport {
    /// The light `[x, y, z, w]`.
    pub light: Light,
    /// Silhouette edges `(a, b, m)`: input vertex names `a < b`, multiplicity `m != 0`, sorted.
    pub edges: Vec<(u32, u32, i32)>,
    /// Vertices whose signed multiplicity sum is not 0 (0 for a closed chain).
    pub open_vertices: usize,
}

/// Times of the run, in milliseconds, and the exact-mode host work.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timings {
    /// `prepare` (upload and layout of the edge table).
    pub prepare_ms: f64,
    /// Per-frame upload (lights).
    pub upload_ms: f64,
    /// Computation.
    pub compute_ms: f64,
    /// Readback of results.
    pub readback_ms: f64,
    /// Host time deciding uncertain pairs exactly.
    pub host_resolve_ms: f64,
    /// (edge, opposite vertex, light) evaluations decided on the host (exact mode).
    pub uncertain: u64,
    /// Of `uncertain`, the pairs decided on the host: every backend resolves what its filter
    /// leaves on the host, so this equals `uncertain` (the GPU pipeline of `render` reports its
    /// own, 0).
    pub host_resolved: u64,
}

/// The whole report. Field order is the JSON order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SilhouetteReport {
    /// Registry name of the backend.
    pub backend: String,
    /// Accuracy mode.
    pub mode: Accuracy,
    /// Mesh statistics.
    pub mesh: MeshSummary,
    /// One entry per light, in the order given.
    pub lights: Vec<LightReport>,
    /// The backend's device, in words (addition to the contract).
    pub device: String,
    /// Timings (addition to the contract).
    pub timings: Timings,
    /// The process's peak resident set in bytes when the report was made
    /// ([`crate::memory::peak_rss_bytes`]; `None` off Linux).
    pub peak_rss_bytes: Option<u64>,
    /// Bytes the prepared scene held: its edge table plus the backend's host layout and device
    /// buffers ([`TableBytes::total`]).
    pub table_bytes: u64,
    /// `table_bytes` by part.
    pub table_bytes_parts: TableBytes,
}

/// Milliseconds, from whole nanoseconds (one rounding, so JSON shows e.g. `0.007955`).
fn ms(d: Duration) -> f64 {
    d.as_nanos() as f64 / 1e6
}

/// Runs `backend` once on `table` for all `lights` in `mode`, checks the shape of the result
/// and returns the report.
///
/// # Errors
/// [`CliError::Usage`] for an empty light list, [`CliError::Backend`] from the backend,
/// [`CliError::Other`] for a result of the wrong shape.
pub fn silhouette_report(
    backend: &mut dyn SilhouetteBackend,
    table: &Arc<EdgeTable>,
    lights: &[Light],
    mode: Accuracy,
) -> Result<SilhouetteReport, CliError> {
    if lights.is_empty() {
        return Err(CliError::Usage(
            "no light given: add --light X,Y,Z,W (w = 1 point, w = 0 directional)".to_owned(),
        ));
    }
    let stats = table.stats;
    let scene = TopologyScene::one("mesh", Arc::clone(table));
    let start = Instant::now();
    let id = backend.prepare(&scene)?;
    let prepare = start.elapsed();
    let mut m = shadowvol_silhouette::Multiplicities::default();
    let result = backend.extract(id, lights, mode, &mut m);
    let prepared = backend.prepared_bytes(id);
    backend.release(id);
    let extract = result?;
    let table_bytes = table_bytes(scene.table_bytes(), prepared?);
    let info = backend.info();
    if m.edge_count() != scene.total_edges() || m.light_count() != lights.len() {
        return Err(CliError::Other(format!(
            "{} backend returned {} edges x {} lights, expected {} x {}",
            info.name,
            m.edge_count(),
            m.light_count(),
            scene.total_edges(),
            lights.len()
        )));
    }
    let table = &scene.objects[0].table;
    let lights = lights
        .iter()
        .enumerate()
        .map(|(l, &light)| {
            let mut edges: Vec<(u32, u32, i32)> = m
                .values(l)
                .iter()
                .enumerate()
                .filter(|(_, &v)| v != 0)
                .map(|(e, &v)| {
                    let (a, b) = table.edge_names(e);
                    (a, b, v)
                })
                .collect();
            edges.sort_unstable();
            LightReport {
                light,
                edges,
                open_vertices: invariant::open_vertices_scene(&scene, &m, l),
            }
        })
        .collect();
    Ok(SilhouetteReport {
        backend: info.name.to_owned(),
        mode,
        mesh: stats.into(),
        lights,
        device: info.device,
        timings: Timings {
            prepare_ms: ms(prepare),
            upload_ms: ms(extract.upload),
            compute_ms: ms(extract.compute),
            readback_ms: ms(extract.readback),
            host_resolve_ms: ms(extract.host_resolve),
            uncertain: extract.uncertain,
            host_resolved: extract.uncertain,
        },
        peak_rss_bytes: peak_rss_bytes(),
        table_bytes: table_bytes.total(),
        table_bytes_parts: table_bytes,
    })
}
