//! The flattened scene the GPU-resident pass uploads once: the `wgpu` silhouette backend's
//! [`SceneLayout`] (positions, edges, opposite vertices) and [`TriangleLayout`] (the triangles
//! and, per opposite-vertex slot, its triangle and permutation parity), plus the object of each
//! vertex.

use crate::RenderError;
use shadowvol_silhouette::gpu::{SceneLayout, TriangleLayout};
use shadowvol_silhouette::TopologyScene;

pub use shadowvol_silhouette::gpu::NEGATIVE;

/// The name the pass gives itself in layout errors.
const NAME: &str = "gpu pipeline";

/// Everything the pass uploads once for a scene. Vertex, edge and triangle ids are global (all
/// objects concatenated, in scene order).
#[derive(Debug, Clone, PartialEq)]
pub struct ResidentLayout {
    /// Positions, edges and opposite vertices, exactly as the `wgpu` backend lays them out.
    pub scene: SceneLayout,
    /// Triangles and the triangle of each opposite-vertex slot, as the `wgpu` backend lays them
    /// out.
    pub triangles: TriangleLayout,
    /// The object of each global vertex.
    pub vertex_objects: Vec<u32>,
}

impl ResidentLayout {
    /// Flattens `scene` (object-space positions; transforms are per-frame inputs).
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when the scene has more vertices, edges, opposite vertices,
    /// triangles or objects than `u32` ids can name (the sign bit of a triangle id is the parity,
    /// so at most 2^31 - 1 triangles).
    pub fn build(scene: &TopologyScene) -> Result<Self, RenderError> {
        let invalid =
            |e: shadowvol_silhouette::BackendError| RenderError::InvalidInput(e.to_string());
        let layout = SceneLayout::build(scene, NAME).map_err(invalid)?;
        let triangles = TriangleLayout::build(scene, &layout, NAME).map_err(invalid)?;
        let vertex_objects = layout
            .vertex_offsets
            .windows(2)
            .enumerate()
            .flat_map(|(oi, w)| std::iter::repeat_n(oi as u32, (w[1] - w[0]) as usize))
            .collect();
        Ok(Self {
            scene: layout,
            triangles,
            vertex_objects,
        })
    }

    /// Flattens every surface of `scene` ([`shadowvol_scenes::Scene::surface_geometry`]:
    /// casters, then receivers).
    ///
    /// # Errors
    /// As [`ResidentLayout::build`].
    pub fn of_scene(scene: &shadowvol_scenes::Scene) -> Result<Self, RenderError> {
        Self::build(&scene.surface_geometry())
    }

    /// Number of triangles (all objects).
    #[must_use]
    pub fn tri_count(&self) -> usize {
        self.triangles.tri_count()
    }

    /// Number of objects.
    #[must_use]
    pub fn object_count(&self) -> usize {
        self.triangles.tri_offsets.len().saturating_sub(1)
    }

    /// Side records a light can need at most: `Σ |m|` over edges is at most the number of
    /// opposite vertices (at least 1, so buffers are never empty).
    #[must_use]
    pub fn capacity(&self) -> usize {
        self.scene.ovs.len().max(1)
    }
}
