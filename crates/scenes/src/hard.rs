//! The hard cases behind the `hard-<case>` presets: small scenes whose lights hit degeneracies.
//!
//! Each case is a small scene (one or more objects, at most a few thousand triangles) with
//! lights chosen to hit degeneracies: lights in the plane of faces (edge-on triangles), at a
//! vertex, on the line of an edge, directional lights exactly parallel to faces, coordinates
//! offset by 1e4, non-manifold books of 3-5 pages, double-sided sheets, zero-area and collinear
//! triangles, duplicate vertices that weld, triangle soups around the light, UV-sphere poles
//! on the light's axis, and objects with non-identity transforms.
//!
//! [`preset`](crate::preset)`("hard-<case>")` frames each case with a camera; the conformance
//! tests (the workspace's test-support crate) run every backend on every case. The meshes are
//! built from [`shapes`](mod@crate::shapes), with basic IEEE operations only, so every case is
//! bit-identical on every platform.
//!
//! ```
//! use shadowvol_scenes::hard;
//!
//! let cases = hard::cases();
//! for case in &cases {
//!     let triangles: usize = case.objects.iter().map(|(m, _)| m.triangles.len()).sum();
//!     assert!(triangles <= 5000, "{} is small", case.name);
//!     assert!(!case.lights.is_empty());
//! }
//! assert!(hard::case("book-4").is_some());
//! ```

use crate::shapes::{
    self, book, cuboid, cuboid_unwelded, f32v, merge, plane_fan, plane_grid, uv_sphere, Rng,
};
use glam::{Affine3A, DVec3, Quat, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_robust_math::Light;

/// One hard case.
#[derive(Debug, Clone)]
pub struct HardCase {
    /// Short name (the preset is `hard-<name>`), used in test names and reports.
    pub name: &'static str,
    /// What it exercises.
    pub description: &'static str,
    /// Objects: mesh (object space) and world-from-object transform.
    pub objects: Vec<(Mesh, Affine3A)>,
    /// Lights in world space.
    pub lights: Vec<Light>,
}

fn single(
    name: &'static str,
    description: &'static str,
    mesh: Mesh,
    lights: Vec<Light>,
) -> HardCase {
    multi(name, description, vec![(mesh, Affine3A::IDENTITY)], lights)
}

fn multi(
    name: &'static str,
    description: &'static str,
    objects: Vec<(Mesh, Affine3A)>,
    lights: Vec<Light>,
) -> HardCase {
    HardCase {
        name,
        description,
        objects,
        lights,
    }
}

fn point(x: f32, y: f32, z: f32) -> Light {
    Light::point(Vec3::new(x, y, z))
}

fn point_v(p: Vec3) -> Light {
    Light::point(p)
}

fn directional(x: f32, y: f32, z: f32) -> Light {
    Light::directional(Vec3::new(x, y, z))
}

/// The tilted plane used by the edge-on cases: through `TILT_ORIGIN`, spanned by the
/// orthonormal rational directions `TILT_U`, `TILT_V` (no coordinate axis in the plane).
const TILT_ORIGIN: DVec3 = DVec3::new(0.3, -0.7, 1.1);
const TILT_U: DVec3 = DVec3::new(2.0 / 3.0, 2.0 / 3.0, 1.0 / 3.0);
const TILT_V: DVec3 = DVec3::new(-2.0 / 3.0, 1.0 / 3.0, 2.0 / 3.0);

fn tilted(u: f64, v: f64) -> DVec3 {
    TILT_ORIGIN + u * TILT_U + v * TILT_V
}

fn edge_on_tilted_grid() -> HardCase {
    // 24 x 24 quads of size 0.25 on the tilted plane, rounded to f32 (so only nearly coplanar),
    // with a bump of a few 1e-7 on some vertices.
    let mesh = plane_grid(
        tilted(0.0, 0.0),
        TILT_U * 0.25,
        TILT_V * 0.25,
        24,
        24,
        |i, j| {
            if (i * 7 + j * 3) % 5 == 0 {
                3e-7 * f64::from((i + j) % 3) - 3e-7
            } else {
                0.0
            }
        },
    );
    let lights = vec![
        // In the plane, outside the grid, on the grid's diagonal and off it.
        point_v(f32v(tilted(-2.0, -1.5))),
        point_v(f32v(tilted(9.0, -3.0))),
        // In the plane, inside the grid (between vertices).
        point_v(f32v(tilted(2.9, 3.1))),
        // Directional, parallel to the plane (rounded to f32).
        Light::directional(f32v(TILT_U + 0.5 * TILT_V)),
        // Off the plane (sanity).
        point_v(f32v(tilted(3.0, 3.0) + DVec3::new(0.3, -0.2, 0.9))),
    ];
    single(
        "edge-on-tilted-grid",
        "a tilted (non-axis-aligned) 24x24 grid of nearly coplanar triangles, lights in its plane",
        mesh,
        lights,
    )
}

fn edge_on_tilted_fan() -> HardCase {
    let mesh = plane_fan(tilted(1.0, 1.0), TILT_U, TILT_V, 1.5, 64);
    let lights = vec![
        point_v(f32v(tilted(6.0, 2.5))),
        point_v(f32v(tilted(1.3, 0.8))),
        point_v(f32v(tilted(-40.0, 17.0))),
        Light::directional(f32v(TILT_V - 0.25 * TILT_U)),
    ];
    single(
        "edge-on-tilted-fan",
        "a tilted fan of 64 nearly coplanar triangles, lights in its plane (outside, inside, far)",
        mesh,
        lights,
    )
}

fn edge_on_axis_grid() -> HardCase {
    // Exactly coplanar (z = 0.5): every determinant is exactly 0 for lights in z = 0.5.
    let mesh = plane_grid(
        DVec3::new(-1.0, -1.0, 0.5),
        DVec3::X * 0.125,
        DVec3::Y * 0.125,
        16,
        16,
        |_, _| 0.0,
    );
    single(
        "edge-on-axis-grid",
        "an exactly planar axis-aligned grid (z = 0.5), point lights in its plane and a directional light parallel to it",
        mesh,
        vec![
            point(3.0, 0.25, 0.5),
            point(0.0625, 0.0625, 0.5),
            directional(1.0, 2.0, 0.0),
            point(0.2, 0.3, 2.0),
        ],
    )
}

fn light_at_vertex() -> HardCase {
    let sphere = uv_sphere(DVec3::new(0.1, -0.2, 0.3), 1.0, 12, 16);
    let v0 = sphere.positions[2 + 16 * 3 + 5];
    let v1 = sphere.positions[2 + 16 * 7 + 11];
    let tet = shapes::tetrahedron(1.0);
    let mesh = merge(sphere, &tet);
    single(
        "light-at-vertex",
        "a UV sphere and a tetrahedron with point lights exactly at mesh vertices",
        mesh,
        vec![
            point_v(v0),
            point_v(v1),
            point(0.0, 0.0, 0.0),
            point(1.0, 0.0, 0.0),
        ],
    )
}

fn light_on_edge_line() -> HardCase {
    // Integer boxes: lights exactly on the lines through box edges (beyond and between ends),
    // and on the line of a face diagonal.
    let mesh = merge(
        cuboid(Vec3::ZERO, Vec3::new(2.0, 3.0, 4.0)),
        &cuboid(Vec3::new(5.0, 1.0, 1.0), Vec3::new(6.0, 2.0, 3.0)),
    );
    single(
        "light-on-edge-line",
        "boxes with point lights exactly on the lines of edges and face diagonals",
        mesh,
        vec![
            point(7.0, 0.0, 0.0),  // line of edge (0,0,0)-(2,0,0), beyond
            point(-1.0, 3.0, 0.0), // line of edge (0,3,0)-(2,3,0), before
            point(1.0, 0.0, 4.0),  // on edge (0,0,4)-(2,0,4), between the ends
            point(4.0, 6.0, 0.0),  // line of the face diagonal (0,0,0)-(2,3,0)
            point(5.0, 1.0, -4.0), // line of the second box's edge along z
        ],
    )
}

fn offset_1e4_sphere() -> HardCase {
    let center = DVec3::new(1.0e4, -1.0e4, 1.0e4);
    let sphere = uv_sphere(center, 1.0, 20, 32);
    let near = |d: DVec3| point_v(f32v(center + d));
    let pole = sphere.positions[0];
    let v = sphere.positions[2 + 32 * 9 + 7];
    single(
        "offset-1e4-sphere",
        "a unit UV sphere 1e4 from the origin (f32 spacing 1e-3 there), lights close to it",
        sphere,
        vec![
            near(DVec3::new(1.5, 0.3, 0.2)),
            near(DVec3::new(0.0, 0.0, 2.0)),
            point_v(pole),
            point_v(v),
            near(DVec3::new(0.0, 0.0, 1.0) + DVec3::new(5.0, 3.0, 0.0)), // in the pole's tangent plane
            Light::directional(Vec3::new(1.0, 1.0, 0.0)),
        ],
    )
}

fn offset_1e4_grid() -> HardCase {
    let origin = DVec3::new(1.0e4, 1.0e4, -1.0e4);
    let mesh = plane_grid(origin, TILT_U * 0.1, TILT_V * 0.1, 20, 20, |_, _| 0.0);
    let lights = vec![
        point_v(f32v(origin + 3.0 * TILT_U - 1.0 * TILT_V)),
        point_v(f32v(origin + 1.0 * TILT_U + 0.7 * TILT_V)),
        point_v(f32v(
            origin + 0.5 * (TILT_U + TILT_V) + 0.5 * TILT_U.cross(TILT_V),
        )),
    ];
    single(
        "offset-1e4-tilted-grid",
        "a tilted grid 1e4 from the origin (rounded far off its plane), lights in and near its plane",
        mesh,
        lights,
    )
}

fn book_case(name: &'static str, description: &'static str, pages: usize) -> HardCase {
    // Integer spine (0,0,0)-(1,2,3); integer page vertices, so "in the plane" is exact.
    let all = [
        Vec3::new(2.0, 0.0, 1.0),
        Vec3::new(-1.0, 1.0, 0.0),
        Vec3::new(0.0, -2.0, 2.0),
        Vec3::new(1.0, 3.0, -1.0),
        Vec3::new(-2.0, -1.0, 3.0),
    ];
    let a = Vec3::ZERO;
    let b = Vec3::new(1.0, 2.0, 3.0);
    let mesh = book(a, b, &all[..pages]);
    let p0 = all[0];
    single(
        name,
        description,
        mesh,
        vec![
            point(3.0, -1.0, 2.0),
            point(2.0, 4.0, 6.0),                  // on the spine's line
            point_v(a + (p0 - a) * 3.0),           // in page 0's plane, on the line a-p0
            point_v(b + (p0 - b) * 2.0 + (b - a)), // in page 0's plane
            directional(1.0, 2.0, 3.0),            // parallel to the spine
            point(0.5, 1.0, 1.5),                  // on the spine, between its ends
        ],
    )
}

fn double_sided_sheet() -> HardCase {
    // A curved sheet whose every triangle also appears with reversed winding: once sharing the
    // vertices, once on a separate copy of the vertices that welding merges.
    let sheet = plane_grid(
        DVec3::new(-1.0, -1.0, 0.0),
        DVec3::X * 0.2,
        DVec3::Y * 0.2,
        10,
        10,
        |i, j| f64::from(i * j % 4) * 0.05,
    );
    let mut mesh = sheet.clone();
    let n = sheet.triangles.len();
    for k in 0..n {
        let [a, b, c] = sheet.triangles[k];
        if k % 2 == 0 {
            mesh.triangles.push([a, c, b]);
        }
    }
    let base = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&sheet.positions);
    for k in (1..n).step_by(2) {
        let [a, b, c] = sheet.triangles[k];
        mesh.triangles.push([base + a, base + c, base + b]);
    }
    single(
        "double-sided-sheet",
        "a bumpy sheet with every triangle doubled in reverse winding (shared and welded copies)",
        mesh,
        vec![
            point(0.1, 0.2, 2.0),
            point(3.0, 0.4, 0.0),
            directional(1.0, 0.5, 0.0),
            point(0.2, 0.2, 0.1),
        ],
    )
}

fn zero_area_collinear() -> HardCase {
    let mut positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::new(0.5, 1.0, 0.0),
        Vec3::new(1.5, 1.0, 0.25),
        Vec3::new(2.5, 1.0, 0.0),
        // Collinear along a tilted line (exact: integer steps of (1, 2, 3)).
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(2.0, 4.0, 6.0),
        Vec3::new(3.0, 6.0, 9.0),
        // Nearly collinear: one ulp off the line.
        Vec3::new(1.5, 3.0, 4.5f32.next_up()),
        // Duplicate of vertex 1 (welds) and a -0.0 copy of vertex 0.
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(-0.0, 0.0, -0.0),
    ];
    positions.push(Vec3::new(0.1, 0.1, 0.1f32.next_up()));
    let triangles = vec![
        [0, 1, 4],
        [1, 5, 4],
        [1, 2, 5],
        [2, 6, 5],
        [2, 3, 6],
        [0, 1, 2],  // zero area: collinear on the x axis
        [1, 3, 2],  // zero area
        [0, 2, 3],  // zero area
        [7, 8, 9],  // zero area, tilted line
        [7, 10, 9], // nearly collinear
        [0, 7, 8],  // collinear with the origin
        [1, 11, 4], // degenerate after welding (11 = 1): dropped
        [12, 1, 4], // shares edge (0,1) and (0,4) through the -0.0 weld
        [0, 13, 1], // tiny triangle
    ];
    single(
        "zero-area-collinear",
        "a strip mixed with zero-area (collinear) and nearly collinear triangles, degenerate-after-weld ones",
        Mesh {
            positions,
            triangles,
        },
        vec![
            point(4.0, 0.0, 0.0),  // on the collinear line
            point(4.0, 8.0, 12.0), // on the tilted collinear line
            point(1.0, 0.5, 2.0),
            directional(1.0, 2.0, 3.0), // parallel to the tilted line
            point(0.0, 0.0, 0.0),       // at a vertex
        ],
    )
}

fn welded_duplicates() -> HardCase {
    let mesh = merge(
        cuboid_unwelded(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.5)),
        &cuboid_unwelded(Vec3::new(-1.0, -1.0, -1.0), Vec3::new(-0.5, 0.0, 0.0)),
    );
    single(
        "welded-duplicates",
        "flat-shaded boxes (each face with its own corners, some zeros as -0.0) that weld to closed boxes",
        mesh,
        vec![
            point(2.0, 3.0, 4.0),
            point(0.5, 1.0, 0.5),  // in the top face's plane
            point(3.0, 2.0, -3.0), // in the plane y = 2
            directional(0.0, 0.0, 1.0),
            point(0.0, 0.0, 0.0), // at a welded vertex
        ],
    )
}

fn soup_near_light() -> HardCase {
    let light = Vec3::new(0.125, 0.25, -0.375);
    let mut rng = Rng::new(0x5eed);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..400u32 {
        let base = positions.len() as u32;
        // Coordinates on a 1/64 grid, so midpoints and the light's coordinates are exact.
        let mut q = || {
            light
                + Vec3::new(
                    (rng.below(129) as f32 - 64.0) / 64.0,
                    (rng.below(129) as f32 - 64.0) / 64.0,
                    (rng.below(129) as f32 - 64.0) / 64.0,
                )
        };
        let (a, b, mut c) = (q(), q(), q());
        match k % 5 {
            0 => c = light,                        // light at a vertex
            1 => c = light * 2.0 - a,              // light at the midpoint of (a, c)
            2 => c = Vec3::new(c.x, c.y, light.z), // near the light's plane z
            _ => {}
        }
        let (a, b) = if k % 5 == 2 {
            (Vec3::new(a.x, a.y, light.z), Vec3::new(b.x, b.y, light.z)) // light in the plane
        } else {
            (a, b)
        };
        positions.extend([a, b, c]);
        triangles.push([base, base + 1, base + 2]);
        // Half of the triangles share an edge with the previous one (soups have some adjacency).
        if k % 2 == 1 {
            triangles.push([base, base - 2, base + 1]);
        }
    }
    // Random perturbations of some coordinates by one ulp.
    for (i, p) in positions.iter_mut().enumerate() {
        if i % 7 == 3 {
            p.x = p.x.next_up();
        }
    }
    single(
        "soup-near-light",
        "a soup of 600 triangles within 1 of the light: light at vertices, on edges, in planes",
        Mesh {
            positions,
            triangles,
        },
        vec![
            point_v(light),
            point_v(light + Vec3::new(0.0, 0.0, 1.0 / 64.0)),
            directional(0.0, 1.0, 0.0),
        ],
    )
}

fn uv_sphere_poles() -> HardCase {
    let mesh = uv_sphere(DVec3::ZERO, 1.0, 16, 24);
    single(
        "uv-sphere-poles",
        "a UV sphere (poles on z) with lights on the polar axis: above, at and below the poles",
        mesh,
        vec![
            point(0.0, 0.0, 3.0),
            point(0.0, 0.0, 1.0), // at the north pole
            point(0.0, 0.0, -1.0),
            point(0.0, 0.0, 0.0), // centre
            directional(0.0, 0.0, 1.0),
            directional(0.0, 0.0, -1.0),
        ],
    )
}

fn directional_parallel() -> HardCase {
    let mesh = merge(
        merge(
            cuboid(Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, 0.5, 2.0)),
            &cuboid(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 4.0, 1.0)),
        ),
        &plane_grid(
            tilted(0.0, 0.0),
            TILT_U * 0.5,
            TILT_V * 0.5,
            6,
            6,
            |_, _| 0.0,
        ),
    );
    single(
        "directional-parallel",
        "boxes and a tilted grid under directional lights exactly parallel to faces (along axes, in face planes, along the tilted plane)",
        mesh,
        vec![
            directional(1.0, 0.0, 0.0),
            directional(0.0, 1.0, 0.0),
            directional(1.0, 1.0, 0.0),
            directional(0.0, 0.0, 1.0),
            Light::directional(f32v(TILT_U)),
            Light::directional(f32v(TILT_U - TILT_V)),
        ],
    )
}

fn multi_object_transforms() -> HardCase {
    // Rotation from a rational quaternion (normalised with sqrt only: deterministic).
    let rot_a = Quat::from_xyzw(1.0, 2.0, 3.0, 4.0).normalize();
    let rot_b = Quat::from_xyzw(-2.0, 1.0, 0.5, 3.0).normalize();
    let objects = vec![
        (
            uv_sphere(DVec3::ZERO, 1.0, 10, 16),
            Affine3A::from_scale_rotation_translation(
                Vec3::new(2.0, 0.5, 1.5),
                rot_a,
                Vec3::new(3.0, -1.0, 0.5),
            ),
        ),
        (
            cuboid(Vec3::new(-1.0, -1.0, -1.0), Vec3::ONE),
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.75),
                rot_b,
                Vec3::new(-2.0, 2.0, 1.0),
            ),
        ),
        (
            plane_grid(
                tilted(0.0, 0.0),
                TILT_U * 0.25,
                TILT_V * 0.25,
                12,
                12,
                |_, _| 0.0,
            ),
            Affine3A::from_scale_rotation_translation(
                Vec3::new(1.0, 3.0, 0.5),
                rot_a * rot_b,
                Vec3::new(0.0, 0.0, -2.0),
            ),
        ),
        (
            book(
                Vec3::ZERO,
                Vec3::new(1.0, 2.0, 3.0),
                &[Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X],
            ),
            Affine3A::IDENTITY,
        ),
    ];
    // A light in the plane of the transformed grid (in world space, rounded to f32).
    let grid_t = objects[2].1;
    let in_grid_plane = grid_t.transform_point3(f32v(tilted(4.0, -2.0)));
    multi(
        "multi-object-transforms",
        "a sphere, a box, a tilted grid and a book with rotation+translation+scale transforms",
        objects,
        vec![
            point(0.5, 0.5, 4.0),
            point(-2.0, 2.0, 1.0), // at the box's centre
            point_v(in_grid_plane),
            directional(0.3, -0.4, 1.0),
        ],
    )
}

fn homogeneous_w() -> HardCase {
    // Point lights with w != 1 (the point xyz / w): at a vertex and in the plane of faces, each
    // written as (fl(w * P), w). Then `L.xyz - w * A` cancels to (almost) 0 in f32 for the vertex
    // A = P, although w * A is not exact: the case that an f32 filter must not certify.
    let mesh = merge(
        plane_grid(
            tilted(0.0, 0.0),
            TILT_U * 0.25,
            TILT_V * 0.25,
            8,
            8,
            |_, _| 0.0,
        ),
        &uv_sphere(DVec3::new(3.0, -2.0, 1.0), 1.0, 8, 12),
    );
    let scaled = |p: Vec3, w: f32| Light::new(w * p.x, w * p.y, w * p.z, w).expect("finite, w > 0");
    let lights = vec![
        scaled(mesh.positions[10], 1.1),
        scaled(mesh.positions[40], 0.75),
        scaled(f32v(tilted(3.3, -1.7)), 3.0),
        scaled(mesh.positions[81 + 2 + 12 * 3 + 4], 1.3),
        scaled(Vec3::new(0.5, 0.25, 4.0), 1e-3),
    ];
    single(
        "homogeneous-w",
        "a tilted grid and a sphere with point lights given with w != 1 (xyz = w * P): at vertices and in the plane",
        mesh,
        lights,
    )
}

/// A flat sheet of three triangles on the tilted plane `x + 2y + 3z = 6` (integer vertices, all
/// with `y >= 1`), scaled by `2^k`, with a point light exactly in the plane beside the sheet, at
/// `(12, 0, -2)`, then moved off it along y by `+2^e` and `-2^e` (times `2^k`) for each `e` in
/// `offsets`. The light's y is 0 in the plane, so `2^e` is the smallest step there is at that
/// exponent: one ulp of a coordinate near `2^(e+23)`.
///
/// Every vertex and the in-plane light are exact, so the in-plane light gives exactly 0. Off the
/// plane the determinant is about `2^e` times its permanent, far below the `f64` filter's bound
/// (`1e-15`, about `2^-50`), so the exact fallback decides each pair, and its answers are `+1`
/// and `-1`. In `f32` the step vanishes in `L.y - A.y`, so the `f32` modes see an in-plane light.
fn off_plane(name: &'static str, k: i32, offsets: &[i32]) -> HardCase {
    let s = 2f32.powi(k);
    let p = |x: f32, y: f32, z: f32| Vec3::new(x * s, y * s, z * s);
    let mesh = Mesh {
        positions: vec![
            p(1.0, 1.0, 1.0),
            p(4.0, 1.0, 0.0),
            p(0.0, 3.0, 0.0),
            p(3.0, 3.0, -1.0),
            p(-2.0, 1.0, 2.0),
        ],
        triangles: vec![[0, 1, 2], [1, 0, 3], [2, 1, 4]],
    };
    let mut lights = vec![point_v(p(12.0, 0.0, -2.0))];
    for &e in offsets {
        for side in [1.0, -1.0] {
            lights.push(point_v(p(12.0, side * 2f32.powi(e), -2.0)));
        }
    }
    single(
        name,
        "a flat sheet with point lights beside it in its plane and a tiny step off it: the f64 filter leaves them undecided, the exact answers are +1 and -1",
        mesh,
        lights,
    )
}

/// All hard cases, in a fixed order (the order of the `hard-*` presets).
#[must_use]
pub fn cases() -> Vec<HardCase> {
    vec![
        single(
            "tetrahedron",
            "a closed manifold tetrahedron, light outside (sanity)",
            shapes::tetrahedron(1.0),
            vec![
                Light::point(Vec3::new(2.0, 3.0, 5.0)),
                Light::directional(Vec3::new(1.0, 2.0, 3.0)),
            ],
        ),
        edge_on_tilted_grid(),
        edge_on_tilted_fan(),
        edge_on_axis_grid(),
        light_at_vertex(),
        light_on_edge_line(),
        offset_1e4_sphere(),
        offset_1e4_grid(),
        book_case("book-3", "a non-manifold book of 3 pages on one spine; lights on the spine line and in a page plane", 3),
        book_case("book-4", "a non-manifold book of 4 pages on one spine; lights on the spine line and in a page plane", 4),
        book_case("book-5", "a non-manifold book of 5 pages on one spine; lights on the spine line and in a page plane", 5),
        double_sided_sheet(),
        zero_area_collinear(),
        welded_duplicates(),
        soup_near_light(),
        uv_sphere_poles(),
        directional_parallel(),
        multi_object_transforms(),
        homogeneous_w(),
        off_plane("off-plane-steps", 0, &[-60, -80, -100]),
        off_plane("off-plane-steps-scaled-2e20", 20, &[-60, -80, -100]),
        off_plane("off-plane-steps-scaled-2e-20", -20, &[-60, -80, -100]),
    ]
}

/// The case called `name`, if any.
#[must_use]
pub fn case(name: &str) -> Option<HardCase> {
    cases().into_iter().find(|c| c.name == name)
}
