//! The conformance corpus: the hard cases every backend must pass, as test cases.
//!
//! The cases are [`shadowvol_scenes::hard::cases`] (the `hard-*` presets), each with what the
//! tests know about it: [`CorpusCase::original_cracks`], and the topology scene the backends
//! prepare ([`CorpusCase::scene`]).
//!
//! Conformance tests run every backend on every case and light and check that `exact` equals
//! the CPU reference (and an independent big-integer oracle) edge for edge, and that the
//! consistent modes (`robust`, `ordered`, `exact`) have no open vertices. Cases marked
//! [`CorpusCase::original_cracks`] show the problem the paper solves: `original` opens the
//! silhouette chain there.
//!
//! ```
//! use shadowvol_test_support::corpus;
//!
//! let cases = corpus::cases();
//! assert!(cases.iter().any(|c| c.original_cracks));
//! for case in &cases {
//!     let scene = case.scene().unwrap();
//!     assert!(scene.total_triangles() <= 5000, "{} is small", case.name);
//!     assert!(!case.lights.is_empty());
//! }
//! assert!(corpus::case("book-4").is_some());
//! ```

use glam::Affine3A;
use shadowvol_mesh_topology::{EdgeTable, Mesh, MeshError};
use shadowvol_robust_math::Light;
use shadowvol_silhouette::{SceneObject, TopologyScene};
use std::sync::Arc;

/// The cases where `original` is known to open the chain (`open_vertices > 0`) for at least one
/// light; the CPU backend's tests verify each. The others may still crack, they are just not
/// relied on to. The `offset-1e4-*` cases stay closed: `original` evaluates `N·(O − A)`, whose
/// differences are exact that close together (the expanded `N·O − N·A` would crack there).
pub const ORIGINAL_CRACKS: &[&str] = &[
    "edge-on-tilted-grid",
    "edge-on-tilted-fan",
    "light-at-vertex",
    "double-sided-sheet",
    "zero-area-collinear",
    "soup-near-light",
    "directional-parallel",
    "multi-object-transforms",
];

/// One hard case, as the tests use it.
#[derive(Debug, Clone)]
pub struct CorpusCase {
    /// Short name, used in test names and reports (the preset is `hard-<name>`).
    pub name: &'static str,
    /// What it exercises.
    pub description: &'static str,
    /// Objects: mesh (object space) and world-from-object transform.
    pub objects: Vec<(Mesh, Affine3A)>,
    /// Lights in world space.
    pub lights: Vec<Light>,
    /// True when `original` is known to open the chain for at least one light of this case
    /// (listed in [`ORIGINAL_CRACKS`]): the baseline's cracks.
    pub original_cracks: bool,
}

impl CorpusCase {
    /// Builds the topology scene of this case: one object per mesh, named `<case>#<index>`.
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

/// All cases of the corpus, in the fixed order of [`shadowvol_scenes::hard::cases`].
#[must_use]
pub fn cases() -> Vec<CorpusCase> {
    shadowvol_scenes::hard::cases()
        .into_iter()
        .map(|c| CorpusCase {
            original_cracks: ORIGINAL_CRACKS.contains(&c.name),
            name: c.name,
            description: c.description,
            objects: c.objects,
            lights: c.lights,
        })
        .collect()
}

/// The cases with `min_lights` or more lights, for tests that split the lights into batches.
///
/// # Panics
/// When fewer than three cases qualify: the batch tests need several.
#[must_use]
pub fn multi_light_cases(min_lights: usize) -> Vec<CorpusCase> {
    let out: Vec<_> = cases()
        .into_iter()
        .filter(|c| c.lights.len() >= min_lights)
        .collect();
    assert!(
        out.len() >= 3,
        "the corpus should have several cases with {min_lights} or more lights, has {}",
        out.len()
    );
    out
}

/// The case called `name`, if any.
#[must_use]
pub fn case(name: &str) -> Option<CorpusCase> {
    cases().into_iter().find(|c| c.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_said_to_crack_exists() {
        let names: Vec<_> = cases().iter().map(|c| c.name).collect();
        for name in ORIGINAL_CRACKS {
            assert!(names.contains(name), "{name} is not a corpus case");
        }
    }
}
