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
//!
//! In `exact` mode, several lights of one `w` in one call (a light's samples) are extracted
//! together ([`extract_table_shared`]): each triangle is classified once against the box of the
//! lights ([`LightBox::sign`]), and an edge whose triangles all have one sign for the whole box
//! is computed once for every light. The results are those of one call per light, bit for bit.

use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::{ov_sign, Accuracy, Light, LightBox};
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

/// Computes the multiplicities of one object's edges for every light of `lights` in exact mode,
/// as [`extract_table`] does for each light, sharing the work between lights of one `w`.
///
/// Each triangle, in canonical order, gets the sign it shares with every light in the box of
/// `lights` ([`LightBox::sign`]: a certified filter, then the exact predicate at the box's
/// corners), or none when its plane cuts the box. An edge whose triangles all have a shared sign
/// gets `Σ sign · parity` once, for every light; every other edge is computed per light with
/// [`ov_sign`]. `out[l][e]` receives the multiplicity of `table.edges[e]` for `lights[l]`.
/// Returns the number of triangles whose plane cuts the box, or `None` (writing nothing) when
/// the lights span no box (none, or different `w`).
///
/// # Panics
/// Panics unless `out` holds one slice of `table.edges.len()` values per light.
pub fn extract_table_shared(
    table: &EdgeTable,
    lights: &[[f32; 4]],
    out: &mut [&mut [i32]],
) -> Option<usize> {
    assert!(
        out.len() == lights.len() && out.iter().all(|o| o.len() == table.edges.len()),
        "extract_table_shared: one output slice per light, one slot per edge"
    );
    let bx = LightBox::of(lights)?;
    let p = |i: u32| table.positions[i as usize].to_array();
    let shared: Vec<Option<i8>> = table
        .triangles
        .iter()
        .map(|&[a, b, c]| {
            let mut t = [a, b, c];
            t.sort_unstable();
            bx.sign(p(t[0]), p(t[1]), p(t[2]))
        })
        .collect();
    let cut = shared.iter().filter(|s| s.is_none()).count();
    for (e, &[a, b]) in table.edges.iter().enumerate() {
        let refs = table.ov_refs_of(e);
        let once: Option<i32> = refs
            .iter()
            .map(|&r| {
                let s = shared[EdgeTable::ov_triangle(r) as usize]?;
                let parity = if r & 3 == 1 { -1 } else { 1 };
                Some(i32::from(s) * parity)
            })
            .sum();
        for (row, &light) in out.iter_mut().zip(lights) {
            row[e] = once.unwrap_or_else(|| {
                table
                    .ovs_of(e)
                    .map(|o| i32::from(ov_sign(Accuracy::Exact, &table.positions, a, b, o, light)))
                    .sum()
            });
        }
    }
    Some(cut)
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
        let (edges, nl) = (scene.total_edges(), lights.len());
        for (i, (o, per_light)) in scene.objects.iter().zip(&obj_lights).enumerate() {
            if mode == Accuracy::Exact && nl > 1 && edges > 0 {
                let range = offsets[i]..offsets[i + 1];
                let mut rows: Vec<&mut [i32]> = out
                    .all_values_mut()
                    .chunks_mut(edges)
                    .map(|row| &mut row[range.clone()])
                    .collect();
                if extract_table_shared(&o.table, per_light, &mut rows).is_some() {
                    continue;
                }
            }
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
