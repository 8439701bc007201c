//! Cases shared by the opencl tests: the conformance corpus plus extra hard scenes that exercise
//! the uncertain path, many objects with transforms, many lights and non-manifold edges.

#![allow(dead_code)]

use glam::{Affine3A, Quat, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_opencl::{OpenClBackend, OpenClOptions};
use shadowvol_silhouette::{Light, SceneObject, TopologyScene};
use shadowvol_test_support::Skip;
use shadowvol_test_support::{corpus, shapes};
use std::sync::Arc;

/// Starts the backend with `options`, or a visible skip ([`shadowvol_test_support::skip`]:
/// `ignored (opencl backend unavailable: ...)`; a failure under CI) when OpenCL is unavailable here.
pub fn start(options: OpenClOptions) -> Result<OpenClBackend, Skip> {
    shadowvol_test_support::started("OpenCL", OpenClBackend::with_options(options))
}

/// A named scene with its lights.
pub struct Case {
    pub name: String,
    pub scene: TopologyScene,
    pub lights: Vec<Light>,
}

fn scene_of(objects: Vec<(Mesh, Affine3A)>) -> TopologyScene {
    TopologyScene {
        objects: objects
            .into_iter()
            .enumerate()
            .map(|(i, (mesh, t))| SceneObject {
                name: format!("object{i}"),
                table: Arc::new(EdgeTable::build(&mesh).expect("test meshes are valid")),
                world_from_object: t,
            })
            .collect(),
    }
}

/// Deterministic pseudo-random numbers in [0, 1) (64-bit LCG).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

pub fn tetrahedron() -> Mesh {
    shapes::tetrahedron(1.0)
}

/// An `n` × `n` height field (open, with boundary) of amplitude `amp` around z = 0.
pub fn height_field(n: u32, amp: f32, rng: &mut Lcg) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let z = if amp == 0.0 {
                0.0
            } else {
                (rng.next_f32() - 0.5) * amp
            };
            positions.push(Vec3::new(i as f32 / n as f32, j as f32 / n as f32, z));
        }
    }
    let mut triangles = Vec::new();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// An `n` × `n` grid on the plane z = x (coplanar exactly: z takes x's f32 value).
pub fn tilted_grid(n: u32) -> Mesh {
    let mut m = height_field(n, 0.0, &mut Lcg(0));
    for p in &mut m.positions {
        p.z = p.x;
    }
    m
}

/// Four triangles sharing the edge (0, 1): a non-manifold "book", plus a triangle soup
/// duplicate of one page.
pub fn book() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::new(0.5, 0.0, 1.0),
            Vec3::new(0.5, -1.0, 0.0),
            Vec3::new(0.5, 0.7, -0.7),
            Vec3::new(0.5, 1.0, 0.0), // duplicate of 2 (welded)
        ],
        triangles: vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 0, 5], [0, 1, 6]],
    }
}

/// The conformance corpus plus the extra cases.
pub fn all_cases() -> Vec<Case> {
    let mut out: Vec<Case> = corpus::cases()
        .into_iter()
        .map(|c| Case {
            name: format!("corpus/{}", c.name),
            scene: c.scene().expect("corpus cases are valid"),
            lights: c.lights.clone(),
        })
        .collect();
    let mut rng = Lcg(7);

    // Light exactly in the plane of a face (det = 0, permanent != 0: uncertain in both filters),
    // light at a vertex, directional light along an axis.
    out.push(Case {
        name: "tetra-degenerate-lights".into(),
        scene: scene_of(vec![(tetrahedron(), Affine3A::IDENTITY)]),
        lights: vec![
            Light::point(Vec3::new(0.3, 0.4, 0.0)),
            Light::point(Vec3::new(0.0, 0.0, 1.0)),
            Light::directional(Vec3::Z),
            Light::directional(Vec3::new(1.0, -1.0, 0.0)),
            Light::point(Vec3::new(2.0, 3.0, 5.0)),
        ],
    });

    // A nearly flat height field, grazing lights: the f32 modes disagree, exact needs the host.
    out.push(Case {
        name: "flat-1e-6-grazing".into(),
        scene: scene_of(vec![(height_field(12, 1e-6, &mut rng), Affine3A::IDENTITY)]),
        lights: vec![
            Light::point(Vec3::new(3.0, 0.37, 1e-6)),
            Light::directional(Vec3::new(1.0, 0.3, 1e-7)),
            Light::point(Vec3::new(0.5, 0.5, 0.0)),
        ],
    });

    // An exactly flat grid with the light in its plane: every (edge, OV, light) is uncertain
    // (more than the initial uncertain buffer, so the device path must grow it and rerun).
    out.push(Case {
        name: "flat-in-plane".into(),
        scene: scene_of(vec![(tilted_grid(40), Affine3A::IDENTITY)]),
        lights: vec![Light::point(Vec3::new(-1.0, 0.25, -1.0))],
    });

    // Many objects, each with its own transform (rotation, scale, translation), many lights.
    let mut objects = Vec::new();
    for i in 0..12 {
        let mesh = if i % 3 == 0 {
            shapes::uv_sphere_y(5, 7, 0.4)
        } else if i % 3 == 1 {
            tetrahedron()
        } else {
            book()
        };
        let t = Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.5 + 0.25 * (i % 4) as f32),
            Quat::from_rotation_y(0.3 * i as f32) * Quat::from_rotation_x(0.1 * i as f32),
            Vec3::new((i % 4) as f32 * 1.7, (i / 4) as f32 * 1.3, 0.1 * i as f32),
        );
        objects.push((mesh, t));
    }
    out.push(Case {
        name: "twelve-objects-transformed".into(),
        scene: scene_of(objects),
        lights: vec![
            Light::point(Vec3::new(2.0, 2.0, 6.0)),
            Light::point(Vec3::new(-3.0, 1.0, 0.5)),
            Light::directional(Vec3::new(0.2, 1.0, 0.4)),
            Light::point(Vec3::new(1.7, 0.0, 0.0)),
            Light::directional(Vec3::X),
            Light::point(Vec3::new(2.55, 1.3, 0.4)),
            Light::point(Vec3::new(0.0, 0.0, 0.0)),
        ],
    });

    // Non-manifold book, identity transform, lights on page planes.
    out.push(Case {
        name: "book-nonmanifold".into(),
        scene: scene_of(vec![(book(), Affine3A::IDENTITY)]),
        lights: vec![
            Light::point(Vec3::new(0.2, 0.1, 2.0)),
            Light::point(Vec3::new(3.0, 2.0, 0.0)),
            Light::directional(Vec3::new(0.0, 1.0, 1.0)),
        ],
    });

    // A sphere of far-from-origin vertices (large offset, tiny features relative to it).
    out.push(Case {
        name: "sphere-offset-1e4".into(),
        scene: scene_of(vec![(
            {
                let mut m = shapes::uv_sphere_y(9, 13, 0.01);
                for p in &mut m.positions {
                    *p += Vec3::new(1.0e4, -1.0e4, 5.0e3);
                }
                m
            },
            Affine3A::IDENTITY,
        )]),
        lights: vec![
            Light::point(Vec3::new(1.0e4 + 1.0, -1.0e4, 5.0e3)),
            Light::directional(Vec3::new(0.0, 0.0, 1.0)),
        ],
    });
    out
}
