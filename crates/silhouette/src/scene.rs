use glam::{Affine3A, DAffine3, DVec3};
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::Light;
use std::sync::Arc;

/// One object of a [`TopologyScene`]: its edge table (object space) and where it is in the world.
#[derive(Debug, Clone)]
pub struct SceneObject {
    /// A name for messages and reports.
    pub name: String,
    /// Edge table in object space. Shared between instances of the same mesh.
    pub table: Arc<EdgeTable>,
    /// World-from-object transform (object-space points to world space). Must be invertible:
    /// [`object_lights`] brings the lights into object space with its inverse, and a singular
    /// transform gives non-finite object-space lights, so meaningless multiplicities.
    pub world_from_object: Affine3A,
}

/// Everything a backend prepares at once: many objects, each with its own transform.
#[derive(Debug, Clone, Default)]
pub struct TopologyScene {
    /// The objects, in order; global edge indices follow this order.
    pub objects: Vec<SceneObject>,
}

impl TopologyScene {
    /// A scene of one object with the identity transform.
    #[must_use]
    pub fn single(table: EdgeTable) -> Self {
        Self {
            objects: vec![SceneObject {
                name: "mesh".to_owned(),
                table: Arc::new(table),
                world_from_object: Affine3A::IDENTITY,
            }],
        }
    }

    /// Total number of edges over all objects.
    #[must_use]
    pub fn total_edges(&self) -> usize {
        self.objects.iter().map(|o| o.table.edges.len()).sum()
    }

    /// Total number of (edge, OV) pairs over all objects.
    #[must_use]
    pub fn total_ovs(&self) -> usize {
        self.objects.iter().map(|o| o.table.ovs.len()).sum()
    }

    /// Total number of welded vertices over all objects.
    #[must_use]
    pub fn total_vertices(&self) -> usize {
        self.objects.iter().map(|o| o.table.positions.len()).sum()
    }

    /// Total number of kept triangles over all objects.
    #[must_use]
    pub fn total_triangles(&self) -> usize {
        self.objects.iter().map(|o| o.table.triangles.len()).sum()
    }

    /// Prefix sums of edge counts: object `i` owns global edges
    /// `offsets[i]..offsets[i + 1]`; `objects.len() + 1` entries.
    #[must_use]
    pub fn edge_offsets(&self) -> Vec<usize> {
        let mut v = Vec::with_capacity(self.objects.len() + 1);
        let mut acc = 0;
        v.push(0);
        for o in &self.objects {
            acc += o.table.edges.len();
            v.push(acc);
        }
        v
    }

    /// Bytes one extraction pass must stream at least (tables and positions of every object,
    /// shared tables counted once per object as a backend reads them), without the output.
    #[must_use]
    pub fn streamed_bytes(&self) -> usize {
        self.objects.iter().map(|o| o.table.streamed_bytes()).sum()
    }
}

/// Object-space lights: `result[object][light]` as `[x, y, z, w]` in `f32`.
///
/// The light is transformed by the inverse of the object's transform in `f64` and rounded to
/// `f32` once. Every backend uses this function, so all of them evaluate the predicate on the
/// same `f32` inputs and exact mode agrees bit for bit. For the identity transform the light is
/// returned unchanged. `w` is preserved exactly (affine transforms).
#[must_use]
pub fn object_lights(scene: &TopologyScene, lights: &[Light]) -> Vec<Vec<[f32; 4]>> {
    scene
        .objects
        .iter()
        .map(|o| {
            if o.world_from_object == Affine3A::IDENTITY {
                return lights.iter().map(|l| l.to_array()).collect();
            }
            let m = DAffine3::from_cols(
                o.world_from_object.matrix3.x_axis.as_dvec3(),
                o.world_from_object.matrix3.y_axis.as_dvec3(),
                o.world_from_object.matrix3.z_axis.as_dvec3(),
                o.world_from_object.translation.as_dvec3(),
            );
            let inv = m.inverse();
            lights
                .iter()
                .map(|l| {
                    let [x, y, z, w] = l.to_array();
                    let v = DVec3::new(f64::from(x), f64::from(y), f64::from(z));
                    let xyz = inv.matrix3 * v + inv.translation * f64::from(w);
                    [xyz.x as f32, xyz.y as f32, xyz.z as f32, w]
                })
                .collect()
        })
        .collect()
}
