//! The scalar reference backend: one thread, one (edge, OV) at a time, exactly the definitions of
//! [`shadowvol_robust_math::ov_sign`]. Every other backend is checked against it.
//!
//! ```
//! use shadowvol_cpu::CpuBackend;
//! use shadowvol_silhouette::{extract_once, Accuracy, invariant};
//! use shadowvol_test_support::corpus;
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut cpu = CpuBackend::new();
//! let (m, _stats) = extract_once(&mut cpu, &scene, &case.lights, Accuracy::Exact).unwrap();
//! assert_eq!(invariant::open_vertices_scene(&scene, &m, 0), 0);
//! ```
//!
//! See the README (its example runs as a doctest) for the edge-on case.

use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::{ov_sign, Accuracy, Light};
use shadowvol_silhouette::{
    check_lights, object_lights, vec_bytes, BackendError, BackendInfo, ExtractStats,
    Multiplicities, PreparedBytes, PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::time::Instant;

pub mod baselines;

/// The backend's registry name.
pub const NAME: &str = "cpu";

/// Scenes of at most this many triangles keep each OV slot's vertex id beside their tables
/// (12 bytes a triangle), so that an edge reads its OVs in order rather than through their
/// triangles at random.
pub const OV_VERTICES_UP_TO: usize = 1 << 22;

/// The scalar reference backend. Always available.
#[derive(Debug)]
pub struct CpuBackend {
    scenes: PreparedScenes<Prepared>,
}

/// A prepared scene: the scene, and for a scene within [`OV_VERTICES_UP_TO`] each object's
/// [`ov_vertices`].
#[derive(Debug)]
struct Prepared {
    scene: TopologyScene,
    ov_vertices: Vec<Option<Vec<u32>>>,
}

impl Default for CpuBackend {
    fn default() -> Self {
        Self::new()
    }
}

impl CpuBackend {
    /// Creates the backend (no set-up needed).
    #[must_use]
    pub fn new() -> Self {
        Self {
            scenes: PreparedScenes::new(NAME),
        }
    }
}

/// Creates the CPU backend, boxed like every backend crate's `create_backend`.
///
/// # Errors
/// Never: the CPU backend is always available. The `Result` keeps the signature of the other
/// backend crates.
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Ok(Box::new(CpuBackend::new()))
}

/// Computes the multiplicities of one object's edges for one object-space light, in `mode`.
///
/// This is the reference definition: `m(a, b) = Σ_o ov_sign(mode, a, b, o)`. `light` is
/// `[x, y, z, w]` in the table's own (object) space, as [`object_lights`] produces it; `out[e]`
/// receives the multiplicity of `table.edges[e]`.
///
/// # Panics
/// Panics if `out.len() != table.edges.len()`.
pub fn extract_table(table: &EdgeTable, light: [f32; 4], mode: Accuracy, out: &mut [i32]) {
    assert_eq!(
        out.len(),
        table.edges.len(),
        "extract_table: one output slot per edge"
    );
    extract_with(table, light, mode, out);
}

/// [`extract_table`] without the length check.
///
/// Each loop is a function of its own, kept out of line: with one loop in the function, the
/// compiler takes the mode's dispatch and the edge's own terms out of the OV loop.
#[inline(never)]
fn extract_with(table: &EdgeTable, light: [f32; 4], mode: Accuracy, out: &mut [i32]) {
    for (e, (&[a, b], m)) in table.edges.iter().zip(out.iter_mut()).enumerate() {
        *m = table
            .ovs_of(e)
            .map(|o| i32::from(ov_sign(mode, &table.positions, a, b, o, light)))
            .sum();
    }
}

/// [`extract_table`], reading each OV's vertex id from `ov_vertices` ([`ov_vertices`] of the
/// table) rather than through its triangle.
#[inline(never)]
fn extract_listed(
    table: &EdgeTable,
    ov_vertices: &[u32],
    light: [f32; 4],
    mode: Accuracy,
    out: &mut [i32],
) {
    for (e, (&[a, b], m)) in table.edges.iter().zip(out.iter_mut()).enumerate() {
        let slots = table.ov_offsets[e] as usize..table.ov_offsets[e + 1] as usize;
        *m = ov_vertices[slots]
            .iter()
            .map(|&o| i32::from(ov_sign(mode, &table.positions, a, b, o, light)))
            .sum();
    }
}

/// Each OV slot's vertex id (`EdgeTable::ov_vertex` of each reference), in slot order: 12 bytes
/// a triangle of a closed mesh.
#[must_use]
pub fn ov_vertices(table: &EdgeTable) -> Vec<u32> {
    table.ov_refs.iter().map(|&r| table.ov_vertex(r)).collect()
}

impl SilhouetteBackend for CpuBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: NAME,
            device: "host CPU, scalar, 1 thread".to_owned(),
            modes: Accuracy::ALL.to_vec(),
            max_lights: None,
            details: vec![],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        let small = scene.total_triangles() <= OV_VERTICES_UP_TO;
        let ov_vertices = scene
            .objects
            .iter()
            .map(|o| small.then(|| ov_vertices(&o.table)))
            .collect();
        Ok(self.scenes.insert(Prepared {
            scene: scene.clone(),
            ov_vertices,
        }))
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        let Prepared { scene, ov_vertices } = self.scenes.get(id)?;
        check_lights(lights)?;
        let start = Instant::now();
        let obj_lights = object_lights(scene.transforms(), lights);
        let offsets = scene.edge_offsets();
        out.reset(scene.total_edges(), lights.len());
        for (i, (o, per_light)) in scene.objects.iter().zip(&obj_lights).enumerate() {
            for (l, &light) in per_light.iter().enumerate() {
                let values = &mut out.values_mut(l)[offsets[i]..offsets[i + 1]];
                match ov_vertices[i].as_deref() {
                    Some(ovs) => extract_listed(&o.table, ovs, light, mode, values),
                    None => extract_with(&o.table, light, mode, values),
                }
            }
        }
        out.rebuild_silhouettes();
        Ok(ExtractStats {
            compute: start.elapsed(),
            ..ExtractStats::default()
        })
    }

    fn prepared_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        // The scalar kernel reads the scene's own tables: only the object list is copied, and
        // the OV vertex ids of a small scene are added.
        let p = self.scenes.get(id)?;
        let ovs: u64 = p.ov_vertices.iter().flatten().map(vec_bytes).sum();
        Ok(PreparedBytes {
            host: vec_bytes(&p.scene.objects) + ovs,
            device: 0,
        })
    }

    fn release(&mut self, id: PreparedId) {
        self.scenes.remove(id);
    }
}

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
