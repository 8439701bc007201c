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
        Self::one("mesh", Arc::new(table))
    }

    /// The objects' world-from-object transforms, in order (the input of [`object_lights`]).
    pub fn transforms(&self) -> impl Iterator<Item = Affine3A> + '_ {
        self.objects.iter().map(|o| o.world_from_object)
    }

    /// A scene of one object, `table` named `name` at the identity: how a renderer prepares one
    /// object on its own and brings the light into its space per frame.
    #[must_use]
    pub fn one(name: &str, table: Arc<EdgeTable>) -> Self {
        Self {
            objects: vec![SceneObject {
                name: name.to_owned(),
                table,
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
        self.objects.iter().map(|o| o.table.ov_refs.len()).sum()
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

    /// Heap bytes of the objects' edge tables ([`EdgeTable::heap_bytes`]), each table counted
    /// once however many objects share it.
    #[must_use]
    pub fn table_bytes(&self) -> u64 {
        crate::unique_arc_bytes(self.objects.iter().map(|o| &o.table), EdgeTable::heap_bytes)
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

/// One light in the space of an object placed by `world_from_object`, as `[x, y, z, w]` in `f32`.
///
/// The light is transformed by the inverse of the transform in `f64` and rounded to `f32` once.
/// Every backend and both render pipelines use this function, so all of them evaluate the
/// predicate on the same `f32` inputs and exact mode agrees bit for bit. For the identity
/// transform the light is returned unchanged. `w` is preserved exactly (affine transforms).
/// The transform must be invertible; a singular one gives non-finite coordinates.
#[must_use]
pub fn object_light(world_from_object: Affine3A, light: Light) -> [f32; 4] {
    if world_from_object == Affine3A::IDENTITY {
        return light.to_array();
    }
    through(&to_f64(world_from_object).inverse(), light)
}

/// Object-space lights: `result[object][light]` is [`object_light`] of each transform (in the
/// order given, for example [`TopologyScene::transforms`]) and each light.
#[must_use]
pub fn object_lights(
    transforms: impl IntoIterator<Item = Affine3A>,
    lights: &[Light],
) -> Vec<Vec<[f32; 4]>> {
    transforms
        .into_iter()
        .map(|t| {
            if t == Affine3A::IDENTITY {
                return lights.iter().map(|l| l.to_array()).collect();
            }
            // One inverse per object, shared by its lights.
            let inv = to_f64(t).inverse();
            lights.iter().map(|&l| through(&inv, l)).collect()
        })
        .collect()
}

/// Homogeneous `light` through the object-from-world transform `inv`, rounded to `f32` once.
fn through(inv: &DAffine3, light: Light) -> [f32; 4] {
    let [x, y, z, w] = light.to_array();
    let v = DVec3::new(f64::from(x), f64::from(y), f64::from(z));
    let xyz = inv.matrix3 * v + inv.translation * f64::from(w);
    [xyz.x as f32, xyz.y as f32, xyz.z as f32, w]
}

/// `t` in `f64` (exact: every `f32` is an `f64`).
fn to_f64(t: Affine3A) -> DAffine3 {
    DAffine3::from_cols(
        t.matrix3.x_axis.as_dvec3(),
        t.matrix3.y_axis.as_dvec3(),
        t.matrix3.z_axis.as_dvec3(),
        t.translation.as_dvec3(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3, Vec3A};

    /// Brings light `l` into the object space of `t`, independently of `object_lights`: the inverse
    /// of the 3x3 part from its adjugate (rows `c1 x c2`, `c2 x c0`, `c0 x c1` over the
    /// determinant), applied to `l.xyz - w t`, in `f64`.
    fn independent(t: Affine3A, l: [f32; 4]) -> ([f64; 3], f64) {
        let c = [t.matrix3.x_axis, t.matrix3.y_axis, t.matrix3.z_axis].map(|v| v.as_dvec3());
        let rows = [c[1].cross(c[2]), c[2].cross(c[0]), c[0].cross(c[1])];
        let det = c[0].dot(rows[0]);
        let w = f64::from(l[3]);
        let rhs = DVec3::new(f64::from(l[0]), f64::from(l[1]), f64::from(l[2]))
            - w * t.translation.as_dvec3();
        let y = rows.map(|r| r.dot(rhs) / det);
        // A bound on the absolute size of the terms, for the tolerance near 0.
        let scale = rows.iter().map(|r| r.length()).sum::<f64>() / det.abs()
            * (rhs.length() + w.abs() * t.translation.as_dvec3().length() + 1e-300);
        (y, scale)
    }

    fn scene_of(transforms: &[Affine3A]) -> TopologyScene {
        let table = Arc::new(
            EdgeTable::build(
                &shadowvol_mesh_topology::Mesh::new(
                    vec![Vec3::ZERO, Vec3::X, Vec3::Y],
                    vec![[0, 1, 2]],
                )
                .unwrap(),
            )
            .unwrap(),
        );
        TopologyScene {
            objects: transforms
                .iter()
                .enumerate()
                .map(|(i, &t)| SceneObject {
                    name: format!("o{i}"),
                    table: Arc::clone(&table),
                    world_from_object: t,
                })
                .collect(),
        }
    }

    #[test]
    fn object_lights_match_an_independent_inverse() {
        let rot = Quat::from_xyzw(1.0, 2.0, 3.0, 4.0).normalize();
        let transforms = [
            Affine3A::IDENTITY,
            Affine3A::from_translation(Vec3::new(5.0, -3.0, 1e4)),
            Affine3A::from_scale_rotation_translation(
                Vec3::new(2.0, 0.5, 1.5),
                rot,
                Vec3::new(3.0, -1.0, 0.5),
            ),
            // A shear with a large translation.
            Affine3A::from_cols(
                Vec3A::new(1.0, 0.25, 0.0),
                Vec3A::new(-0.5, 2.0, 0.125),
                Vec3A::new(0.3, 0.0, 0.7),
                Vec3A::new(-250.0, 1e3, 42.0),
            ),
        ];
        let lights = [
            Light::new(1.0, 2.0, 3.0, 1.0).unwrap(),
            Light::new(0.3, -0.4, 1.0, 0.0).unwrap(),
            Light::new(-7.5, 0.25, 2.0, 0.75).unwrap(),
            Light::new(3.0, -1.0, 0.5, 1.0).unwrap(), // at the origin of one object
            Light::new(1e-3, 2e-3, 4e-3, 1e-3).unwrap(),
        ];
        let scene = scene_of(&transforms);
        let got = object_lights(scene.transforms(), &lights);
        for (o, t) in transforms.iter().enumerate() {
            for (i, l) in lights.iter().enumerate() {
                assert_eq!(
                    got[o][i].map(f32::to_bits),
                    object_light(*t, *l).map(f32::to_bits)
                );
            }
        }
        for (o, t) in transforms.iter().enumerate() {
            for (i, l) in lights.iter().enumerate() {
                let l = l.to_array();
                let r = got[o][i];
                assert_eq!(
                    r[3].to_bits(),
                    l[3].to_bits(),
                    "w is kept: object {o}, light {i}"
                );
                let (want, scale) = independent(*t, l);
                for c in 0..3 {
                    // Rounded once from f64: within one f32 ulp of the exact value, up to the
                    // f64 error of either computation.
                    let ulp = f64::from((want[c] as f32).abs().next_up() - (want[c] as f32).abs());
                    let err = (f64::from(r[c]) - want[c]).abs();
                    assert!(
                        err <= ulp + 1e-12 * scale,
                        "object {o}, light {i}, component {c}: {} vs independent {} (err {err:e})",
                        r[c],
                        want[c]
                    );
                }
            }
        }
    }

    #[test]
    fn identity_transform_returns_the_light_unchanged() {
        let lights = [Light::new(0.1, f32::MIN_POSITIVE, -3.0, 0.0).unwrap()];
        let got = object_lights(scene_of(&[Affine3A::IDENTITY]).transforms(), &lights);
        assert_eq!(
            got[0][0].map(f32::to_bits),
            lights[0].to_array().map(f32::to_bits)
        );
    }
}
