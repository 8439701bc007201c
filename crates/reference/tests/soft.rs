//! The soft reference ([`shadowvol_reference::soft`]) against two oracles that share none of its
//! method: the closed form of a convex polygon clipped by a disk, for plates whose projection the
//! test computes itself (point after point, no clipping, no cancellation, no slabs); and dense
//! jittered sampling of the disk, each sample decided by the hard reference's exact occlusion
//! test ([`ShadowRay::crossing`]), within the sampling's own statistical bound.

mod common;

use common::Frame;
use glam::{DVec3, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_reference::occlusion::{light_side, Caster, Crossing, ShadowRay};
use shadowvol_reference::soft::{Integration, SoftCasters, Visibility};
use shadowvol_reference::{self as reference, polygon_disk_area};
use shadowvol_robust_math::Light;
use shadowvol_scenes::procedural::icosphere;
use shadowvol_scenes::shapes::{cuboid, Rng};
use shadowvol_scenes::{Camera, LightDisk, Receiver, Scene, SceneLight};
use std::f64::consts::PI;
use std::sync::Arc;

const EYE: DVec3 = DVec3::new(0.0, 0.0, 10.0);

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// The disk of a light of radius `radius` aimed at `aim`.
fn disk_of(light: Light, radius: f32, aim: Vec3) -> LightDisk {
    let mut l = SceneLight::unit(light);
    l.radius = radius;
    l.disk(aim).expect("a disk")
}

fn mesh_tris(m: &Mesh) -> Vec<[Vec3; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize]))
        .collect()
}

/// A horizontal square plate of two triangles at height `z`.
fn square(cx: f32, cy: f32, half: f32, z: f32) -> Vec<[Vec3; 3]> {
    let (a, b) = (v(cx - half, cy - half, z), v(cx + half, cy - half, z));
    let (c, d) = (v(cx + half, cy + half, z), v(cx - half, cy + half, z));
    vec![[a, b, c], [a, c, d]]
}

/// The closed form: the plate's corners projected from `p` onto the disk's plane (the test's
/// own projection), the convex polygon clipped by the disk. `None` unless the whole plate lies
/// strictly between `p` and the disk's plane (for a directional light, in front of `p`), where
/// the projection of the corners is the projection of the plate.
fn closed_form(corners: &[Vec3], disk: &LightDisk, p: DVec3) -> Option<f64> {
    let h = (disk.centre - p).dot(disk.normal);
    let mut ring = Vec::new();
    for &x in corners {
        let r = x.as_dvec3() - p;
        let y = if disk.directional {
            let w = r.dot(disk.centre);
            if w <= 0.0 {
                return None;
            }
            r / w
        } else {
            let w = r.dot(disk.normal) / h;
            if !(w > 0.0 && w < 1.0) {
                return None;
            }
            p + r / w - disk.centre
        };
        ring.push([y.dot(disk.u), y.dot(disk.v)]);
    }
    let area2: f64 = (0..ring.len())
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum();
    if area2 < 0.0 {
        ring.reverse();
    }
    Some(1.0 - polygon_disk_area(&ring, disk.radius) / (PI * disk.radius * disk.radius))
}

#[derive(Default, Debug)]
struct Seen {
    lit: usize,
    umbra: usize,
    penumbra: usize,
}

impl Seen {
    fn add(&mut self, v: &Visibility) {
        if v.is_lit() {
            self.lit += 1;
        } else if v.is_umbra() {
            self.umbra += 1;
        } else if v.is_penumbra() {
            self.penumbra += 1;
        }
    }
}

/// Every point of a `k × k` grid over `[-s, s]²` at height `z`.
fn grid(k: usize, s: f64, z: f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..k {
        for j in 0..k {
            let f = |n: usize| -s + 2.0 * s * (n as f64 + 0.37) / k as f64;
            out.push(DVec3::new(f(i), f(j), z));
        }
    }
    out
}

fn check_plate(tris: &[[Vec3; 3]], corners: &[Vec3], disk: &LightDisk, points: &[DVec3]) -> Seen {
    let casters = SoftCasters::from_triangles(tris, EYE);
    let mut seen = Seen::default();
    let mut worst: f64 = 0.0;
    let mut least = f64::INFINITY;
    for &p in points {
        let Some(want) = closed_form(corners, disk, p) else {
            continue;
        };
        for integration in [Integration::Slabs, Integration::Auto] {
            let got = casters.visibility(disk, p, u32::MAX, integration);
            let err = (got.value - want).abs();
            worst = worst.max(err);
            assert!(
                err <= got.bound + 1e-14,
                "{integration:?} at {p}: {} against the closed form {want} (bound {})",
                got.value,
                got.bound
            );
            assert!(got.bound < 1e-9, "bound {} at {p}", got.bound);
            if got.is_penumbra() {
                least = least.min(got.bound);
            }
            if want > 1e-9 && want < 1.0 - 1e-9 {
                assert!(got.is_penumbra(), "{p}: {got:?}, closed form {want}");
            }
            if integration == Integration::Auto {
                seen.add(&got);
            }
        }
    }
    println!("{seen:?}, largest error {worst:e}, smallest penumbra bound {least:e}");
    seen
}

#[test]
fn polygon_disk_area_closed_forms() {
    let r = 2.0;
    // A square inside the disk, a disk inside a square, a half-disk, a clockwise ring.
    let small = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    assert!((polygon_disk_area(&small, r) - 4.0).abs() < 1e-14);
    let big = [[-3.0, -3.0], [3.0, -3.0], [3.0, 3.0], [-3.0, 3.0]];
    assert!((polygon_disk_area(&big, r) - PI * 4.0).abs() < 1e-13);
    let half = [[-5.0, 0.0], [5.0, 0.0], [5.0, 5.0], [-5.0, 5.0]];
    assert!((polygon_disk_area(&half, r) - PI * 2.0).abs() < 1e-13);
    let mut cw = small;
    cw.reverse();
    assert!((polygon_disk_area(&cw, r) + 4.0).abs() < 1e-14);
    // A strip |x| < 1: 2 (r² asin(1/r) + √(r² − 1)).
    let strip = [[-1.0, -9.0], [1.0, -9.0], [1.0, 9.0], [-1.0, 9.0]];
    let want = 2.0 * (r * r * (1.0f64 / r).asin() + (r * r - 1.0).sqrt());
    assert!((polygon_disk_area(&strip, r) - want).abs() < 1e-13);
    // A triangle with one corner inside, two outside: against a fine midpoint rule.
    let tri = [[0.5, 0.25], [3.0, -1.0], [2.0, 2.5]];
    let n = 2000;
    let mut hits = 0u64;
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (
                -2.0 + 4.0 * (f64::from(i) + 0.5) / f64::from(n),
                -2.0 + 4.0 * (f64::from(j) + 0.5) / f64::from(n),
            );
            let inside_tri = (0..3).all(|k| {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]) >= 0.0
            });
            hits += u64::from(inside_tri && x * x + y * y <= r * r);
        }
    }
    let grid_area = hits as f64 * 16.0 / f64::from(n * n);
    assert!((polygon_disk_area(&tri, r) - grid_area).abs() < 5e-3);
}

#[test]
fn plates_match_the_closed_form_under_a_point_light() {
    let light = Light::point(v(0.2, 0.1, 3.0));
    let disk = disk_of(light, 0.5, Vec3::ZERO);
    let points = grid(15, 2.0, 0.0);
    let sq = square(0.0, 0.0, 0.5, 1.0);
    let corners = [sq[0][0], sq[0][1], sq[0][2], sq[1][2]];
    let seen = check_plate(&sq, &corners, &disk, &points);
    assert!(
        seen.lit > 10 && seen.umbra > 3 && seen.penumbra > 30,
        "{seen:?}"
    );
    let tri = [[v(-0.6, -0.4, 1.5), v(0.7, -0.2, 1.2), v(0.1, 0.8, 1.0)]];
    let seen = check_plate(&tri, &tri[0], &disk, &points);
    assert!(
        seen.lit > 10 && seen.umbra > 0 && seen.penumbra > 30,
        "{seen:?}"
    );
    // Reversed winding: the same shadow.
    let rev = [[tri[0][0], tri[0][2], tri[0][1]]];
    check_plate(&rev, &tri[0], &disk, &points);
}

#[test]
fn plates_match_the_closed_form_under_a_directional_light() {
    let light = Light::directional(v(0.3, -0.2, 1.0));
    let disk = disk_of(light, 0.15, Vec3::ZERO);
    let points = grid(15, 2.0, 0.0);
    let sq = square(0.1, 0.0, 0.4, 1.0);
    let corners = [sq[0][0], sq[0][1], sq[0][2], sq[1][2]];
    let seen = check_plate(&sq, &corners, &disk, &points);
    assert!(
        seen.lit > 10 && seen.umbra > 0 && seen.penumbra > 10,
        "{seen:?}"
    );
    let tri = [[v(-0.6, -0.4, 1.5), v(0.7, -0.2, 1.2), v(0.1, 0.8, 1.0)]];
    let seen = check_plate(&tri, &tri[0], &disk, &points);
    assert!(
        seen.lit > 10 && seen.umbra > 0 && seen.penumbra > 10,
        "{seen:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// Dense sampling with the hard reference's exact test.

/// The share of `n × n` jittered disk samples (those inside the disk) that `p` sees: each
/// sample is a light (rounded to `f32`, as the renderer's samples are) decided by the hard
/// reference's exact occlusion against every caster but `skip`. Returns the share and the
/// number of samples.
fn sampled(
    tris: &[[Vec3; 3]],
    skip: Option<usize>,
    disk: &LightDisk,
    p: DVec3,
    n: u32,
    rng: &mut Rng,
) -> (f64, usize) {
    let casters: Vec<Caster> = tris.iter().map(|t| Caster::new(*t)).collect();
    let (mut seen, mut total) = (0usize, 0usize);
    let r = disk.radius;
    for i in 0..n {
        for j in 0..n {
            let a =
                -r + 2.0 * r * (f64::from(i) + 0.5 + 0.49 * f64::from(rng.unit())) / f64::from(n);
            let b =
                -r + 2.0 * r * (f64::from(j) + 0.5 + 0.49 * f64::from(rng.unit())) / f64::from(n);
            if a * a + b * b > r * r {
                continue;
            }
            let q = disk.point(a, b).as_vec3();
            let l = [q.x, q.y, q.z, if disk.directional { 0.0 } else { 1.0 }];
            let ray = ShadowRay::new(p, l, EYE);
            total += 1;
            let blocked = tris.iter().enumerate().any(|(k, t)| {
                Some(k) != skip && ray.crossing(&casters[k], light_side(*t, l)) == Crossing::Blocks
            });
            seen += usize::from(!blocked);
        }
    }
    (seen as f64 / total as f64, total)
}

/// Checks the reference against sampling at every point; returns what it saw.
fn check_sampled(
    tris: &[[Vec3; 3]],
    disk: &LightDisk,
    points: &[(DVec3, Option<usize>)],
    n: u32,
    max_bound: f64,
) -> Seen {
    let casters = SoftCasters::from_triangles(tris, EYE);
    let mut rng = Rng::new(5);
    let mut seen = Seen::default();
    let mut worst: f64 = 0.0;
    for &(p, skip) in points {
        let skip_id = skip.map_or(u32::MAX, |s| s as u32);
        let got = casters.visibility(disk, p, skip_id, Integration::Auto);
        let slabs = casters.visibility(disk, p, skip_id, Integration::Slabs);
        assert!(
            (got.value - slabs.value).abs() <= got.bound + slabs.bound + 1e-12,
            "{p}: closed form {got:?}, slabs {slabs:?}"
        );
        let (est, count) = sampled(tris, skip, disk, p, n, &mut rng);
        let sigma = (got.value * (1.0 - got.value) / count as f64).sqrt();
        let tol = 5.0 * sigma + 2.0 / count as f64 + got.bound;
        worst = worst.max((est - got.value).abs() / tol);
        assert!(
            (est - got.value).abs() <= tol,
            "{p}: reference {got:?}, sampled {est} of {count} (tolerance {tol})"
        );
        assert!(got.bound < max_bound, "{p}: bound {}", got.bound);
        seen.add(&got);
    }
    println!("{seen:?}, worst error / tolerance {worst:.3}");
    seen
}

/// A cube, an icosphere, two overlapping plates and a ceiling above the light (beyond its
/// disk, so it must not occlude), over a floor of points.
fn crowd() -> Vec<[Vec3; 3]> {
    let mut tris = mesh_tris(&cuboid(v(-1.2, -0.3, 0.6), v(-0.6, 0.3, 1.1)));
    let mut ball = icosphere(80, 0.35);
    for p in &mut ball.positions {
        *p += v(0.8, 0.5, 1.2);
    }
    tris.extend(mesh_tris(&ball));
    tris.extend(square(0.2, -0.9, 0.3, 1.4));
    tris.extend(square(0.45, -0.7, 0.25, 0.9));
    tris.extend(square(0.0, 0.0, 3.0, 3.6));
    tris
}

#[test]
fn closed_meshes_and_overlapping_plates_match_dense_sampling() {
    let disk = disk_of(Light::point(v(0.1, -0.1, 3.0)), 0.6, Vec3::ZERO);
    let tris = crowd();
    let points: Vec<(DVec3, Option<usize>)> =
        grid(7, 2.2, 0.0).into_iter().map(|p| (p, None)).collect();
    let seen = check_sampled(&tris, &disk, &points, 48, 1e-6);
    assert!(seen.penumbra >= 10 && seen.lit >= 3, "{seen:?}");
}

#[test]
fn a_directional_light_matches_dense_sampling() {
    let disk = disk_of(Light::directional(v(0.25, 0.1, 1.0)), 0.2, Vec3::ZERO);
    let mut tris = crowd();
    tris.truncate(tris.len() - 2); // no ceiling: a directional light is beyond every caster
    let points: Vec<(DVec3, Option<usize>)> =
        grid(7, 2.2, 0.0).into_iter().map(|p| (p, None)).collect();
    let seen = check_sampled(&tris, &disk, &points, 48, 1e-6);
    assert!(seen.penumbra >= 8 && seen.lit >= 3, "{seen:?}");
}

/// Points in the disk's plane (the disk seen edge-on) and a hair off it, with casters crossing
/// the plane between them and the disk.
#[test]
fn an_edge_on_disk_matches_dense_sampling() {
    // A horizontal disk at z = 3 (the light straight above its aim).
    let disk = disk_of(Light::point(v(0.0, 0.0, 3.0)), 0.5, v(0.0, 0.0, 0.0));
    assert!((disk.normal - DVec3::NEG_Z).length() < 1e-12);
    let mut tris = vec![
        // A wall crossing the plane at x = 1.
        [v(1.0, -0.2, 2.5), v(1.0, 0.3, 2.5), v(1.0, 0.3, 3.5)],
        [v(1.0, -0.2, 2.5), v(1.0, 0.3, 3.5), v(1.0, -0.2, 3.5)],
    ];
    // A cube crossing the plane on the other side.
    tris.extend(mesh_tris(&cuboid(v(-1.3, 0.1, 2.8), v(-1.0, 0.5, 3.3))));
    let mut points = Vec::new();
    for (x, y) in [
        (2.0, 0.05),
        (1.6, -0.1),
        (3.0, 0.4),
        (-2.0, 0.5),
        (-1.8, 0.0),
        (0.2, 1.2),
    ] {
        for dz in [0.0, 1e-12, -1e-9, 1e-6, -1e-3] {
            points.push((DVec3::new(x, y, 3.0 + dz), None));
        }
    }
    let seen = check_sampled(&tris, &disk, &points, 48, 1e-4);
    assert!(seen.penumbra >= 10, "{seen:?}");
}

/// A point on a sphere near its terminator: part of the disk lies below the surface's own
/// plane, hidden by the sphere's far side and the point's neighbours.
#[test]
fn a_point_near_a_spheres_terminator_matches_dense_sampling() {
    let ball = icosphere(320, 1.0);
    let tris = mesh_tris(&ball);
    let disk = disk_of(Light::point(v(0.0, 0.0, 4.0)), 0.8, Vec3::ZERO);
    // The triangles whose planes pass closest to the disk's centre, from either side.
    let mut by_angle: Vec<(f64, usize, DVec3)> = tris
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let t = t.map(Vec3::as_dvec3);
            let c = (t[0] + t[1] + t[2]) / 3.0;
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let to = (disk.centre - c).normalize();
            (n.dot(to), k, c)
        })
        .filter(|(cos, _, _)| cos.abs() < 0.15)
        .collect();
    by_angle.sort_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
    let points: Vec<(DVec3, Option<usize>)> = by_angle
        .iter()
        .take(8)
        .map(|&(_, k, c)| (c, Some(k)))
        .collect();
    assert_eq!(points.len(), 8);
    let seen = check_sampled(&tris, &disk, &points, 48, 1e-6);
    assert!(seen.penumbra >= 6, "{seen:?}");
}

/// Cancellation leaves exactly the silhouette from the point: for a cube whose shadow lies
/// inside the disk, the edges left are the cube's edges between a face that faces the point and
/// one that does not.
#[test]
fn cancellation_leaves_the_silhouette() {
    let cube = cuboid(v(-0.15, -0.1, 2.0), v(0.1, 0.12, 2.3));
    let tris = mesh_tris(&cube);
    let disk = disk_of(Light::point(v(0.0, 0.0, 3.0)), 1.0, Vec3::ZERO);
    let casters = SoftCasters::from_triangles(&tris, EYE);
    for p in [
        DVec3::new(0.3, 0.2, 0.0),
        DVec3::new(-0.4, 0.1, 0.5),
        DVec3::new(0.05, -0.5, 1.0),
    ] {
        let faces = |k: usize| {
            let t = tris[k].map(Vec3::as_dvec3);
            (t[1] - t[0]).cross(t[2] - t[0]).dot(p - t[0]) > 0.0
        };
        let mut silhouette = 0;
        for a in 0..12 {
            for b in a + 1..12 {
                let shared = cube.triangles[a]
                    .iter()
                    .filter(|x| cube.triangles[b].contains(x))
                    .count();
                if shared == 2 && faces(a) != faces(b) {
                    silhouette += 1;
                }
            }
        }
        let got = casters.visibility(&disk, p, u32::MAX, Integration::Slabs);
        assert!(got.is_penumbra(), "{p}: {got:?}");
        assert_eq!(got.edges as usize, silhouette, "{p}: {got:?}");
        assert_eq!(got.casters, 12);
    }
}

// ---------------------------------------------------------------------------------------------
// Per image.

/// A cube and a sphere over one big ground triangle that fills the view (every pixel's id is
/// the ground's), a light of radius 0.5.
fn frame(size: u32) -> Frame {
    let mut mesh = cuboid(v(-0.8, -0.5, 0.5), v(-0.2, 0.1, 1.0));
    let mut ball = icosphere(80, 0.3);
    let base = mesh.positions.len() as u32;
    mesh.positions
        .extend(ball.positions.iter().map(|p| *p + v(0.6, 0.4, 1.1)));
    mesh.triangles
        .extend(ball.triangles.drain(..).map(|t| t.map(|i| i + base)));
    let mut scene = Scene::single("casters", &mesh).unwrap();
    let ground = Mesh {
        positions: vec![v(-40.0, -40.0, 0.0), v(40.0, -40.0, 0.0), v(0.0, 60.0, 0.0)],
        triangles: vec![[0, 1, 2]],
    };
    scene.receivers.push(Receiver {
        name: "ground".into(),
        table: Arc::new(shadowvol_mesh_topology::EdgeTable::build(&ground).unwrap()),
        albedo: [1.0; 3],
    });
    let mut light = SceneLight::unit(Light::point(v(0.3, -0.2, 3.0)));
    light.radius = 0.5;
    scene.lights.push(light);
    let camera = Camera {
        eye: Vec3::new(0.0, -0.5, 6.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y: 50f32.to_radians(),
        near: 0.01,
    };
    let n = (size * size) as usize;
    Frame {
        scene,
        camera,
        size,
        rgba: vec![0; 4 * n],
        ids: vec![[2, 0]; n],
        stencil: vec![vec![0; n]],
        colors: vec![[1.0; 3]],
    }
}

#[test]
fn the_image_reference_is_the_per_point_one_and_compare_counts() {
    let f = frame(64);
    let shot = f.shot();
    let disk = f.scene.lights[0].disk(f.scene.light_aim()).expect("a disk");
    let t = std::time::Instant::now();
    let image = reference::visibility_reference(&shot, 0, &disk);
    println!("64² reference: {:?}", t.elapsed());
    let points = reference::surface_points(&shot);
    let casters = SoftCasters::new(&shot);
    let mut seen = Seen::default();
    for (i, p) in points.iter().enumerate() {
        let sp = p.expect("the ground fills the view");
        let want = casters.visibility(&disk, sp.position, sp.triangle, Integration::Auto);
        assert_eq!(image.pixels[i], Some(want), "pixel {i}");
        seen.add(&want);
    }
    assert!(
        seen.lit > 100 && seen.umbra > 20 && seen.penumbra > 100,
        "{seen:?}"
    );

    // The reference itself as the render: no mismatch, errors within f32 rounding.
    let mut render: Vec<f32> = image
        .pixels
        .iter()
        .map(|p| p.unwrap().value as f32)
        .collect();
    let cmp = reference::compare_with_reference(&image, &render);
    assert_eq!(cmp.covered_pixels, 64 * 64);
    assert_eq!(cmp.penumbra_pixels, seen.penumbra);
    assert_eq!((cmp.lit_pixels, cmp.umbra_pixels), (seen.lit, seen.umbra));
    assert_eq!(
        (
            cmp.lit_mismatched,
            cmp.umbra_mismatched,
            cmp.border_mismatched
        ),
        (0, 0, 0)
    );
    assert!(cmp.penumbra_max_error < 1e-7, "{cmp:?}");
    assert!(cmp.reference_bound < 1e-9, "{cmp:?}");
    assert_eq!(cmp, reference::compare_visibility(&shot, 0, &disk, &render));

    // One lit and one umbra pixel away from every border, one lit pixel on a border, and a
    // penumbra error of 0.25.
    let class = |i: usize| {
        let v = image.pixels[i].unwrap();
        (v.is_lit(), v.is_umbra(), v.is_penumbra())
    };
    let uniform = |i: usize| {
        let (x, y) = (i % 64, i / 64);
        (x > 0 && y > 0 && x < 63 && y < 63)
            && (y - 1..=y + 1).all(|ny| (x - 1..=x + 1).all(|nx| class(ny * 64 + nx) == class(i)))
    };
    let lit = (0..64 * 64).find(|&i| class(i).0 && uniform(i)).unwrap();
    let umbra = (0..64 * 64).find(|&i| class(i).1 && uniform(i)).unwrap();
    let border = (64..64 * 63)
        .find(|&i| {
            let (x, y) = (i % 64, i / 64);
            class(i).0
                && x > 0
                && x < 63
                && (y - 1..=y + 1)
                    .any(|ny| (x - 1..=x + 1).any(|nx| class(ny * 64 + nx) != class(i)))
        })
        .unwrap();
    let pen = (0..64 * 64).find(|&i| class(i).2).unwrap();
    render[lit] = 0.96875;
    render[umbra] = 0.03125;
    render[border] = 0.5;
    render[pen] = (image.pixels[pen].unwrap().value + 0.25) as f32;
    let cmp = reference::compare_with_reference(&image, &render);
    assert_eq!(
        (
            cmp.lit_mismatched,
            cmp.umbra_mismatched,
            cmp.border_mismatched
        ),
        (1, 1, 1),
        "{cmp:?}"
    );
    assert!((cmp.penumbra_max_error - 0.25).abs() < 1e-6, "{cmp:?}");
    println!("{cmp:?}");
}

/// Across `soft::EDGE_ON` the in-plane model and the projection give the same value within
/// their bounds (and the change of the true value with the height, far below them here).
#[test]
fn edge_on_and_projection_agree_across_the_threshold() {
    let disk = disk_of(Light::point(v(0.0, 0.0, 3.0)), 0.5, v(0.0, 0.0, 0.0));
    let mut tris = vec![
        [v(1.0, -0.2, 2.5), v(1.0, 0.3, 2.5), v(1.0, 0.3, 3.5)],
        [v(1.0, -0.2, 2.5), v(1.0, 0.3, 3.5), v(1.0, -0.2, 3.5)],
    ];
    tris.extend(mesh_tris(&cuboid(v(-1.3, 0.1, 2.8), v(-1.0, 0.45, 3.3))));
    let casters = SoftCasters::from_triangles(&tris, EYE);
    for (x, y) in [(2.0, 0.05), (-2.0, 0.5), (1.5, -0.3)] {
        let base = casters.visibility(&disk, DVec3::new(x, y, 3.0), u32::MAX, Integration::Slabs);
        assert!(base.is_penumbra(), "{base:?}");
        for dz in [1e-12, 1e-9, 1e-7, 5e-7, 2e-6, 1e-5, 1e-4] {
            for sign in [1.0, -1.0] {
                let p = DVec3::new(x, y, 3.0 + sign * dz);
                let got = casters.visibility(&disk, p, u32::MAX, Integration::Slabs);
                let tol = base.bound + got.bound + 10.0 * dz;
                assert!(
                    (got.value - base.value).abs() <= tol,
                    "{p}: {got:?} against {base:?} in the plane"
                );
                assert!(got.bound < 1e-4, "{p}: {got:?}");
            }
        }
    }
}
