//! The conformance corpus: hard cases every backend must pass.
//!
//! Each case is a small scene (one or more objects) with lights chosen to hit degeneracies.
//! Conformance tests run every backend on every case and check that `exact` equals the CPU
//! reference bit for bit and that the consistent modes close their chains.

use crate::{SceneObject, TopologyScene};
use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh, MeshError};
use shadowvol_robust_math::Light;
use std::sync::Arc;

/// One hard case.
#[derive(Debug, Clone)]
pub struct CorpusCase {
    /// Short name, used in test names and reports.
    pub name: &'static str,
    /// What it exercises.
    pub description: &'static str,
    /// Objects: mesh (object space) and world-from-object transform.
    pub objects: Vec<(Mesh, Affine3A)>,
    /// Lights in world space.
    pub lights: Vec<Light>,
    /// True when `original` is known to open the chain on this case (the baseline's cracks).
    pub original_cracks: bool,
}

impl CorpusCase {
    /// Builds the topology scene of this case.
    ///
    /// # Errors
    /// A [`MeshError`] if a mesh is invalid (never for the built-in cases).
    pub fn scene(&self) -> Result<TopologyScene, MeshError> {
        let objects = self
            .objects
            .iter()
            .enumerate()
            .map(|(i, (mesh, t))| {
                Ok(SceneObject {
                    name: format!("{}#{i}", self.name),
                    table: Arc::new(EdgeTable::build(mesh)?),
                    world_from_object: *t,
                })
            })
            .collect::<Result<Vec<_>, MeshError>>()?;
        Ok(TopologyScene { objects })
    }
}

fn single(
    name: &'static str,
    description: &'static str,
    mesh: Mesh,
    lights: Vec<Light>,
    original_cracks: bool,
) -> CorpusCase {
    CorpusCase {
        name,
        description,
        objects: vec![(mesh, Affine3A::IDENTITY)],
        lights,
        original_cracks,
    }
}

/// A closed tetrahedron.
fn tetrahedron() -> Mesh {
    Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    }
}

/// All cases of the corpus.
#[must_use]
pub fn cases() -> Vec<CorpusCase> {
    vec![single(
        "tetrahedron",
        "a closed manifold tetrahedron, light outside (sanity)",
        tetrahedron(),
        vec![
            Light::point(Vec3::new(2.0, 3.0, 5.0)),
            Light::directional(Vec3::new(1.0, 2.0, 3.0)),
        ],
        false,
    )]
}
