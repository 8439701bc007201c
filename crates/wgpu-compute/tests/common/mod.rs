//! Shared test inputs: the conformance corpus plus this crate's own hard cases, aimed at the
//! device filters (exact zeros with a non-zero permanent, tiny/huge/subnormal coordinates,
//! transformed and shared objects, non-manifold edges).

#![allow(dead_code)]

use glam::{Affine3A, DVec3, Quat, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_silhouette::SilhouetteBackend;
use shadowvol_silhouette::{Light, SceneObject, TopologyScene};
use shadowvol_test_support::Skip;
use shadowvol_test_support::{corpus, shapes};
use shadowvol_wgpu_compute::{WgpuBackend, WgpuOptions};
use std::sync::Arc;

/// Starts the backend with `options` (naming its device for `test` on stderr), or a visible skip
/// (`ignored (wgpu backend unavailable: ...)`; a failure under CI, see
/// [`shadowvol_test_support::skip`]) when it cannot start here.
pub fn backend(test: &str, options: WgpuOptions) -> Result<WgpuBackend, Skip> {
    match WgpuBackend::new(options) {
        Ok(b) => {
            eprintln!("{test}: running on {}", b.info().device);
            Ok(b)
        }
        Err(e) => Err(shadowvol_test_support::skip(e)),
    }
}

/// A named scene with its lights.
pub struct Case {
    pub name: String,
    pub scene: TopologyScene,
    pub lights: Vec<Light>,
}

/// A flat n x n grid in the slanted plane z = x + 2y (an open surface, exact integer
/// coordinates), triangulated both ways.
pub fn grid(n: u32) -> Mesh {
    shapes::plane_grid(
        DVec3::ZERO,
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(0.0, 1.0, 2.0),
        n,
        n,
        |_, _| 0.0,
    )
}

/// Three triangles on one edge (a non-manifold "book") plus a boundary fan.
pub fn book() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::ZERO,
            Vec3::Z,
            Vec3::X,
            Vec3::new(-1.0, 0.2, 0.0),
            Vec3::new(0.1, 1.0, 0.0),
            Vec3::new(0.5, -1.0, 0.5),
        ],
        triangles: vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [2, 1, 5]],
    }
}

fn scene_of(objects: Vec<(Arc<EdgeTable>, Affine3A)>) -> TopologyScene {
    TopologyScene {
        objects: objects
            .into_iter()
            .enumerate()
            .map(|(i, (table, t))| SceneObject {
                name: format!("object{i}"),
                table,
                world_from_object: t,
            })
            .collect(),
    }
}

fn single(mesh: &Mesh) -> TopologyScene {
    scene_of(vec![(
        Arc::new(EdgeTable::build(mesh).unwrap()),
        Affine3A::IDENTITY,
    )])
}

fn p(x: f32, y: f32, z: f32) -> Light {
    Light::new(x, y, z, 1.0).unwrap()
}

fn d(x: f32, y: f32, z: f32) -> Light {
    Light::new(x, y, z, 0.0).unwrap()
}

/// This crate's own hard cases.
pub fn extra_cases() -> Vec<Case> {
    let sphere_table = Arc::new(EdgeTable::build(&shapes::uv_sphere_y(12, 16, 1.0)).unwrap());
    let tet_table = Arc::new(EdgeTable::build(&shapes::tetrahedron(1.0)).unwrap());
    vec![
        Case {
            name: "light-in-face-plane".into(),
            scene: single(&shapes::tetrahedron(1.0)),
            // On the plane x + y + z = 1 of the slanted face (exact zeros with a non-zero
            // permanent), on the axis plane z = 0 (exact zeros, zero permanent), then generic.
            lights: vec![
                p(0.25, 0.25, 0.5),
                p(1.0, 1.0, -1.0),
                d(1.0, -1.0, 0.0),
                p(0.3, 0.3, 0.0),
                p(2.0, 0.0, 3.0),
                p(0.2, 0.2, 0.2),
            ],
        },
        Case {
            name: "flat-grid-grazing".into(),
            scene: single(&grid(6)),
            // In the grid's plane (every determinant is exactly 0), then just off it.
            lights: vec![
                p(3.5, 2.25, 8.0),
                d(1.0, 0.5, 2.0),
                p(3.5, 2.25, 8.000001),
                d(1.0, 0.5, 2.0000002),
            ],
        },
        Case {
            name: "sphere-light-at-vertex".into(),
            scene: single(&shapes::uv_sphere_y(12, 16, 1.0)),
            lights: vec![
                p(0.0, 0.0, 1.0),
                p(0.0, 0.0, 3.0),
                d(0.3, -1.0, 0.2),
                p(1.0, 1.0, 1.0),
            ],
        },
        Case {
            name: "tiny-coordinates".into(),
            scene: single(&shapes::tetrahedron(1e-20)),
            lights: vec![p(2e-20, 3e-20, 5e-20), d(1.0, 2.0, 3.0)],
        },
        Case {
            name: "subnormal-coordinates".into(),
            scene: single(&shapes::tetrahedron(1e-40)),
            lights: vec![p(2e-40, 3e-40, 5e-40), d(1.0, 2.0, 3.0), p(1.0, 1.0, 1.0)],
        },
        Case {
            name: "huge-coordinates".into(),
            scene: single(&shapes::tetrahedron(1e30)),
            lights: vec![p(2e30, 3e30, 5e30), d(1.0, 2.0, 3.0), p(1e30, 0.0, 0.0)],
        },
        Case {
            name: "nonmanifold-book".into(),
            scene: single(&book()),
            lights: vec![p(0.3, 0.4, 2.0), p(0.0, 0.0, 0.5), d(-1.0, 0.1, 0.0)],
        },
        Case {
            name: "many-objects-transformed".into(),
            scene: scene_of(
                (0..7)
                    .map(|i| {
                        let t = Affine3A::from_scale_rotation_translation(
                            Vec3::splat(0.5 + i as f32 * 0.25),
                            Quat::from_rotation_y(0.3 * i as f32),
                            Vec3::new(3.0 * i as f32, (i % 3) as f32, -2.0),
                        );
                        let table = if i % 2 == 0 {
                            &sphere_table
                        } else {
                            &tet_table
                        };
                        (
                            Arc::clone(table),
                            if i == 0 { Affine3A::IDENTITY } else { t },
                        )
                    })
                    .collect(),
            ),
            lights: vec![
                p(5.0, 6.0, 7.0),
                d(0.2, 1.0, 0.1),
                p(9.0, 0.5, -2.0),
                p(0.0, 0.0, 1.0),
            ],
        },
    ]
}

/// The case of [`all_cases`] called `name`.
///
/// # Panics
/// When there is none.
pub fn case(name: &str) -> Case {
    all_cases()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no test case {name}"))
}

/// The conformance corpus followed by [`extra_cases`].
pub fn all_cases() -> Vec<Case> {
    let mut cases: Vec<Case> = corpus::cases()
        .into_iter()
        .map(|c| Case {
            name: format!("corpus/{}", c.name),
            scene: c.scene().expect("corpus scenes are valid"),
            lights: c.lights.clone(),
        })
        .collect();
    cases.extend(extra_cases());
    cases
}
