//! The flattened scene the GPU-resident pass uploads once: the scene's edge tables as the `wgpu`
//! silhouette backend uploads them ([`TableLayout`]: positions, edge ends, CSR offsets, each
//! opposite vertex as a reference to its triangle, canonical triangles, object bases), plus the
//! object of each vertex.

use crate::RenderError;
use shadowvol_silhouette::gpu::{TableLayout, FIRST_VERTEX};
use shadowvol_silhouette::TopologyScene;

/// Set on a side record (a global edge) for `m < 0`: the side is drawn with the edge reversed.
pub const NEGATIVE: u32 = 0x8000_0000;

/// The name the pass gives itself in layout errors.
pub(crate) const NAME: &str = "gpu pipeline";

/// [`RenderError::InvalidInput`] when `edges` edges cannot be named in a side record, whose top
/// bit is [`NEGATIVE`].
pub(crate) fn check_edge_count(edges: usize) -> Result<(), RenderError> {
    if edges >= NEGATIVE as usize {
        return Err(RenderError::InvalidInput(format!(
            "the scene has {edges} edges; the {NAME} names them with 31 bits"
        )));
    }
    Ok(())
}

/// Everything the pass uploads once for a scene. Vertex, edge and triangle ids are global (all
/// objects concatenated, in scene order).
#[derive(Debug, Clone, PartialEq)]
pub struct ResidentLayout {
    /// The scene's tables, exactly as the `wgpu` backend uploads them.
    pub tables: TableLayout,
    /// The object of each global vertex.
    pub vertex_objects: Vec<u32>,
}

impl ResidentLayout {
    /// Flattens `scene` (object-space positions; transforms are per-frame inputs).
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when the scene has more vertices, edges, opposite vertices,
    /// triangles or objects than `u32` ids can name (an opposite vertex names its triangle `t`
    /// as `4 t + r`, so fewer than 2^30 triangles); the edge ids of side records keep their top
    /// bit for [`NEGATIVE`].
    pub fn build(scene: &TopologyScene) -> Result<Self, RenderError> {
        let invalid =
            |e: shadowvol_silhouette::BackendError| RenderError::InvalidInput(e.to_string());
        let tables = TableLayout::build(scene, NAME).map_err(invalid)?;
        check_edge_count(tables.edge_count())?;
        let vertex_objects = tables
            .objects
            .windows(2)
            .enumerate()
            .flat_map(|(oi, w)| {
                std::iter::repeat_n(
                    oi as u32,
                    (w[1][FIRST_VERTEX] - w[0][FIRST_VERTEX]) as usize,
                )
            })
            .collect();
        Ok(Self {
            tables,
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
        self.tables.tri_count()
    }

    /// Number of objects.
    #[must_use]
    pub fn object_count(&self) -> usize {
        self.tables.object_count()
    }

    /// Side records a light can need at most: `Σ |m|` over edges is at most the number of
    /// opposite vertices (at least 1, so buffers are never empty).
    #[must_use]
    pub fn capacity(&self) -> usize {
        self.tables.ov_refs.len().max(1)
    }
}
