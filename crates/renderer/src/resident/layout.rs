//! The flattened scene the GPU-resident pass uploads once: the `wgpu` silhouette backend's
//! [`SceneLayout`] (positions, edges, opposite vertices), plus the triangles and, per
//! opposite-vertex slot, its triangle and permutation parity.

use crate::RenderError;
use shadowvol_silhouette::gpu::SceneLayout;
use shadowvol_silhouette::TopologyScene;

/// Set on an [`ResidentLayout::ov_tris`] entry when `(a, b, o)` is an odd permutation of the
/// triangle's canonical order (`a < o < b`).
pub const NEGATIVE: u32 = 0x8000_0000;

/// The name the pass gives itself in layout errors.
const NAME: &str = "gpu pipeline";

/// Everything the pass uploads once for a scene. Vertex, edge and triangle ids are global (all
/// objects concatenated, in scene order).
#[derive(Debug, Clone, PartialEq)]
pub struct ResidentLayout {
    /// Positions, edges and opposite vertices, exactly as the `wgpu` backend lays them out.
    pub scene: SceneLayout,
    /// Per global triangle: its vertex ids in canonical (ascending) order and its object.
    pub tris: Vec<[u32; 4]>,
    /// Per opposite-vertex slot of [`SceneLayout::ovs`]: the global triangle `(a, b, o)` belongs
    /// to, with [`NEGATIVE`] set for an odd permutation.
    pub ov_tris: Vec<u32>,
    /// First global triangle of each object; `object_count + 1` entries.
    pub tri_offsets: Vec<u32>,
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
        let layout = SceneLayout::build(scene, NAME)
            .map_err(|e| RenderError::InvalidInput(e.to_string()))?;
        let total: usize = scene.objects.iter().map(|o| o.table.triangles.len()).sum();
        if total >= NEGATIVE as usize {
            return Err(RenderError::InvalidInput(format!(
                "the scene has {total} triangles; the GPU pipeline names them with 31 bits (at most {})",
                NEGATIVE - 1
            )));
        }
        let mut tris = Vec::with_capacity(total);
        let mut ov_tris = vec![0u32; layout.ovs.len()];
        let mut tri_offsets = Vec::with_capacity(scene.objects.len() + 1);
        tri_offsets.push(0u32);
        for (oi, o) in scene.objects.iter().enumerate() {
            let t = &o.table;
            let vbase = layout.vertex_offsets[oi];
            let ebase = layout.edge_offsets[oi];
            let mut cursor = vec![0u32; t.edges.len()];
            for (ti, tri) in t.triangles.iter().enumerate() {
                let global = tris.len() as u32;
                let mut c = *tri;
                c.sort_unstable();
                tris.push([c[0] + vbase, c[1] + vbase, c[2] + vbase, oi as u32]);
                for &e in &t.connectivity.tri_edges[ti] {
                    let [a, b] = t.edges[e as usize];
                    let o = tri
                        .iter()
                        .copied()
                        .find(|&v| v != a && v != b)
                        .expect("a kept triangle has three distinct vertices");
                    let slot = (layout.edges[ebase + e as usize][2] + cursor[e as usize]) as usize;
                    cursor[e as usize] += 1;
                    // The edge table lists an edge's opposite vertices in ascending triangle
                    // order, which is the order this loop visits them.
                    debug_assert_eq!(layout.ovs[slot], o + vbase);
                    let odd = a < o && o < b;
                    ov_tris[slot] = global | if odd { NEGATIVE } else { 0 };
                }
            }
            tri_offsets.push(tris.len() as u32);
        }
        let vertex_objects = layout
            .vertex_offsets
            .windows(2)
            .enumerate()
            .flat_map(|(oi, w)| std::iter::repeat_n(oi as u32, (w[1] - w[0]) as usize))
            .collect();
        Ok(Self {
            scene: layout,
            tris,
            ov_tris,
            tri_offsets,
            vertex_objects,
        })
    }

    /// Number of triangles (all objects).
    #[must_use]
    pub fn tri_count(&self) -> usize {
        self.tris.len()
    }

    /// Number of objects.
    #[must_use]
    pub fn object_count(&self) -> usize {
        self.tri_offsets.len().saturating_sub(1)
    }

    /// Side records a light can need at most: `Σ |m|` over edges is at most the number of
    /// opposite vertices (at least 1, so buffers are never empty).
    #[must_use]
    pub fn capacity(&self) -> usize {
        self.scene.ovs.len().max(1)
    }
}
