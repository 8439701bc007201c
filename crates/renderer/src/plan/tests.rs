//! Tests of the plan's geometry and choice.

use super::geometry::*;
use super::scissor::uniform;
use super::*;
use glam::DVec4;

fn near_rect() -> [DVec3; 4] {
    // Camera at the origin looking down -z, near plane at z = -1, 2x2.
    [
        DVec3::new(-1.0, -1.0, -1.0),
        DVec3::new(1.0, -1.0, -1.0),
        DVec3::new(1.0, 1.0, -1.0),
        DVec3::new(-1.0, 1.0, -1.0),
    ]
}

#[test]
fn near_clip_volume_separates() {
    let light = [0.0, 0.0, -10.0, 1.0];
    let planes = near_clip_volume(near_rect(), light).unwrap();
    // A box between the near plane and the light: inside the volume.
    assert!(!box_outside(
        DVec3::new(-0.1, -0.1, -5.1),
        DVec3::new(0.1, 0.1, -4.9),
        &planes
    ));
    // A box far to the side: outside.
    assert!(box_outside(
        DVec3::new(5.0, 5.0, -5.1),
        DVec3::new(6.0, 6.0, -4.9),
        &planes
    ));
    // A box behind the light: outside (the volume ends at the light).
    assert!(box_outside(
        DVec3::new(-0.1, -0.1, -20.0),
        DVec3::new(0.1, 0.1, -15.0),
        &planes
    ));
    // Directional light from +y: the slab swept upwards.
    let planes = near_clip_volume(near_rect(), [0.0, 1.0, 0.0, 0.0]);
    // Direction parallel to the near plane: degenerate, never proven safe.
    assert!(planes.is_none());
    let planes = near_clip_volume(near_rect(), [0.0, 1.0, -1.0, 0.0]).unwrap();
    assert!(!box_outside(
        DVec3::new(-0.1, 3.0, -4.1),
        DVec3::new(0.1, 3.2, -3.9),
        &planes
    ));
    assert!(box_outside(
        DVec3::new(-0.1, -3.0, -4.1),
        DVec3::new(0.1, -2.8, -3.9),
        &planes
    ));
}

#[test]
fn near_rect_clear_of_shadows_decides_triangle_by_triangle() {
    let near = near_rect();
    let clear = |tri: [[f32; 3]; 3], light: [f32; 4]| {
        let world: Vec<Vec3> = tri.iter().map(|&p| Vec3::from_array(p)).collect();
        let planes = near_clip_volume(near, light).unwrap();
        near_rect_clear_of_shadows(&world, &[[0, 1, 2]], light, near, &planes)
    };
    let across = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 1.0, -5.0]];
    // Light beyond the triangle: its shadow comes towards the camera and covers the
    // near rectangle.
    assert!(!clear(across, [0.0, 0.0, -10.0, 1.0]));
    assert!(!clear(across, [0.0, 0.0, -1.0, 0.0]));
    // Light between the triangle and the camera: the shadow goes the other way.
    assert!(clear(across, [0.0, 0.0, -3.0, 1.0]));
    assert!(clear(across, [0.0, 0.0, 1.0, 0.0]));
    // The same with the light given as (w·P, w).
    assert!(!clear(across, [0.0, 0.0, -20.0, 2.0]));
    assert!(clear(across, [0.0, 0.0, -6.0, 2.0]));
    // A light one f32 step off the plane z = -5 of a triangle beside it, the camera on
    // the far side: the corners are not on the light's side and no face plane of the
    // near-clip volume separates the triangle (it straddles both axes around the apex),
    // but its shadow is a sliver in that plane, nowhere near the camera.
    let beside = [[1.0, -0.1, -5.0], [-0.1, 1.0, -5.0], [1.0, 1.0, -5.0]];
    let hair = -5.000_000_5_f32;
    assert!(hair < -5.0);
    assert!(clear(beside, [0.0, 0.0, hair, 1.0]));
    // The light exactly in the plane: a shadow of no volume.
    assert!(clear(beside, [0.0, 0.0, -5.0, 1.0]));
    // The same hair off, but with the triangle around the apex: the shadow is almost the
    // whole half-space beyond, camera included.
    let around = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 1.0, -5.0]];
    assert!(!clear(around, [0.0, 0.0, hair, 1.0]));
    // A light 10⁻¹⁰ above a triangle it lies over (or exactly on it), closer than any
    // margin, and the near rectangle above both: only the exact side of the light proves
    // the rectangle clear (the triangle and the near-clip volume touch at the apex, no
    // axis parts them); 10⁻¹⁰ below, the shadow takes in the rectangle.
    let above = [
        DVec3::new(-1.0, -1.0, 3.0),
        DVec3::new(1.0, -1.0, 3.0),
        DVec3::new(1.0, 1.0, 3.0),
        DVec3::new(-1.0, 1.0, 3.0),
    ];
    let flat = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]];
    let world: Vec<Vec3> = flat.iter().map(|&p| Vec3::from_array(p)).collect();
    // 0: the light exactly on the triangle, whose shadow then has no volume.
    for (lz, want) in [(1e-10f32, true), (-1e-10, false), (0.0, true)] {
        let light = [0.0, 0.25, lz, 1.0];
        let planes = near_clip_volume(above, light).unwrap();
        assert!(!triangle_misses_near_clip(
            [0, 1, 2].map(|i| world[i].as_dvec3()),
            &NearClipHull::new(light, above).unwrap()
        ));
        assert_eq!(
            near_rect_clear_of_shadows(&world, &[[0, 1, 2]], light, above, &planes),
            want,
            "light z {lz}"
        );
    }
}

#[test]
fn near_clip_planes_pass_through_the_light_and_the_rectangle() {
    // An off-axis, non-square rectangle, so that no symmetry hides a wrong plane.
    let near = [
        DVec3::new(0.3, -0.2, -1.0),
        DVec3::new(2.1, -0.1, -1.2),
        DVec3::new(2.0, 0.9, -1.25),
        DVec3::new(0.2, 0.8, -1.05),
    ];
    let on = |pl: Plane, p: DVec3| eval(pl, p).abs() < 1e-9;
    // A point light: the rectangle's plane holds the 4 corners, side plane i the light and
    // corners i, i + 1; the centroid of the 5 vertices is strictly inside every plane.
    let lp = DVec3::new(-3.0, 4.0, -9.0);
    let planes = near_clip_volume(near, [-3.0, 4.0, -9.0, 1.0]).unwrap();
    assert_eq!(planes.len(), 5);
    assert!(near.iter().all(|&c| on(planes[0], c)));
    for i in 0..4 {
        let pl = planes[i + 1];
        assert!(
            on(pl, lp) && on(pl, near[i]) && on(pl, near[(i + 1) % 4]),
            "plane {i}"
        );
    }
    let centroid = (near.iter().copied().sum::<DVec3>() + lp) / 5.0;
    assert!(planes.iter().all(|&pl| eval(pl, centroid) > 0.0));
    // The same light as (w·P, w).
    let planes_w = near_clip_volume(near, [-6.0, 8.0, -18.0, 2.0]).unwrap();
    for (a, b) in planes.iter().zip(&planes_w) {
        assert!((*a - *b).abs().max_element() < 1e-12);
    }
    // A directional light: the side planes hold corners i, i + 1 and are parallel to the
    // direction; a point a step from the rectangle's centre towards the light is inside.
    let d = Vec3::new(0.2, -0.3, -1.0).as_dvec3(); // the f32 light the function sees
    let planes = near_clip_volume(near, [0.2, -0.3, -1.0, 0.0]).unwrap();
    assert!(near.iter().all(|&c| on(planes[0], c)));
    for i in 0..4 {
        let pl = planes[i + 1];
        assert!(on(pl, near[i]) && on(pl, near[(i + 1) % 4]), "plane {i}");
        assert!(
            pl.truncate().dot(d).abs() < 1e-9,
            "plane {i} along the light"
        );
    }
    let centre = near.iter().copied().sum::<DVec3>() / 4.0;
    assert!(planes.iter().all(|&pl| eval(pl, centre + d * 0.1) > 0.0));
}

#[test]
fn points_outside_keeps_a_relative_margin() {
    let planes = [DVec4::new(0.0, 0.0, 1.0, 0.0)]; // inside: z >= 0
    let at = |z: f64, spread: f64| {
        [
            DVec3::new(-spread, -spread, z),
            DVec3::new(spread, -spread, z),
            DVec3::new(0.0, spread, z),
        ]
    };
    assert!(points_outside(&at(-1.0, 1.0), &planes));
    // 10⁻⁷ below the plane at scale 1: within the 10⁻⁶ margin, so not proven outside.
    assert!(!points_outside(&at(-1e-7, 1.0), &planes));
    // The margin scales with the points' extent (here |hi − lo| ≈ 283): 2·10⁻⁴ below is
    // inside it, 10⁻³ below is not.
    assert!(!points_outside(&at(-2e-4, 100.0), &planes));
    assert!(points_outside(&at(-1e-3, 100.0), &planes));
}

#[test]
fn separating_axis_keeps_a_relative_margin() {
    // A large triangle parallel to the near plane, just on the camera's side of it: only
    // the near plane's normal can part it from the pyramid of the light at z = −10 over
    // the rectangle at z = −1. The margin is 10⁻⁹ of |axis| · the largest coordinate (20
    // here), so a gap of 5·10⁻¹⁰ of the scale is not trusted and 10⁻⁶ is; the same holds
    // with everything scaled by 2^±20, since the margin is relative.
    for s in [1.0, 2f64.powi(20), 2f64.powi(-20)] {
        let near = near_rect().map(|p| p * s);
        let hull = NearClipHull::new([0.0, 0.0, (-10.0 * s) as f32, 1.0], near).unwrap();
        let tri = |gap: f64| {
            let z = s * (-1.0 + 20.0 * gap);
            [
                DVec3::new(-20.0 * s, -20.0 * s, z),
                DVec3::new(20.0 * s, -20.0 * s, z),
                DVec3::new(0.0, 20.0 * s, z),
            ]
        };
        assert!(!triangle_misses_near_clip(tri(5e-10), &hull), "scale {s}");
        assert!(triangle_misses_near_clip(tri(1e-6), &hull), "scale {s}");
        assert!(!triangle_misses_near_clip(tri(0.0), &hull), "scale {s}");
    }
}

#[test]
fn frustum_culls_shadow_behind_the_camera() {
    let eye = DVec3::ZERO;
    let planes = frustum_planes(eye, near_rect());
    assert_eq!(planes.len(), 5);
    // A box behind the camera with the light in front: the shadow goes further behind.
    let light = [0.0, 0.0, -5.0, 1.0];
    assert!(shadow_outside_frustum(
        DVec3::new(-0.5, -0.5, 3.0),
        DVec3::new(0.5, 0.5, 4.0),
        light,
        &planes
    ));
    // The same box with the light behind it: the shadow comes forward into view.
    let light = [0.0, 0.0, 10.0, 1.0];
    assert!(!shadow_outside_frustum(
        DVec3::new(-0.5, -0.5, 3.0),
        DVec3::new(0.5, 0.5, 4.0),
        light,
        &planes
    ));
    // A box between the eye and the near plane, a light beside it a little farther: the
    // shadow reaches into view, whether the light is written with w = 1 or w = 2.
    let (lo, hi) = (DVec3::new(-0.1, -0.1, -0.9), DVec3::new(0.1, 0.1, -0.5));
    for light in [[3.0, 0.0, -0.6, 1.0], [6.0, 0.0, -1.2, 2.0]] {
        assert!(!shadow_outside_frustum(lo, hi, light, &planes), "{light:?}");
    }
    // A box in view is never culled.
    assert!(!shadow_outside_frustum(
        DVec3::new(-0.5, -0.5, -4.0),
        DVec3::new(0.5, 0.5, -3.0),
        light,
        &planes
    ));
}

/// Whether `p` is in the view frustum of a camera at `eye` with near rectangle `near`
/// (a parallelogram, corners in order), by the definition: the ray from the eye through `p`
/// crosses the rectangle at or before `p`. Solved directly: the ray's parameter `t` at the
/// rectangle's plane must be in `(0, 1]`, and the crossing's coordinates along the
/// rectangle's two edges in `[0, 1]`.
fn in_frustum(eye: DVec3, near: [DVec3; 4], p: DVec3) -> bool {
    let (u, v) = (near[1] - near[0], near[3] - near[0]);
    let n = u.cross(v);
    let t = (near[0] - eye).dot(n) / (p - eye).dot(n);
    if !(t > 0.0 && t <= 1.0) {
        return false; // behind the eye, or between the eye and the near plane
    }
    let q = eye + (p - eye) * t - near[0];
    let (a, b) = (q.dot(u) / u.length_squared(), q.dot(v) / v.length_squared());
    (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)
}

/// An off-axis camera's five planes: each is unit length, the side planes hold the eye and
/// their edge of the near rectangle, the near plane holds all four corners, and a point is
/// inside all five exactly when it is in the frustum by definition.
#[test]
fn frustum_planes_bound_exactly_the_frustum() {
    let eye = DVec3::new(0.3, 1.2, 4.0);
    let (f, r) = (
        DVec3::new(-0.1, -0.3, -1.0).normalize(),
        DVec3::new(1.0, 0.0, -0.1),
    );
    let r = (r - f * r.dot(f)).normalize();
    let up = r.cross(f);
    let c = eye + f * 0.5;
    let near = [
        c - r * 0.4 - up * 0.25,
        c + r * 0.4 - up * 0.25,
        c + r * 0.4 + up * 0.25,
        c - r * 0.4 + up * 0.25,
    ];
    let planes = frustum_planes(eye, near);
    assert_eq!(planes.len(), 5);
    for (i, &pl) in planes.iter().enumerate() {
        assert!(
            (pl.truncate().length() - 1.0).abs() < 1e-12,
            "plane {i} not unit"
        );
        let on: Vec<DVec3> = if i < 4 {
            vec![eye, near[i], near[(i + 1) % 4]]
        } else {
            near.to_vec()
        };
        for p in on {
            assert!(eval(pl, p).abs() < 1e-12, "plane {i} misses {p}");
        }
    }
    let mut rnd = uniform(0x9e37_79b9_7f4a_7c15);
    let (mut inside, mut outside) = (0, 0);
    for _ in 0..20_000 {
        let p = eye + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 12.0;
        let want = in_frustum(eye, near, p);
        let got = planes.iter().all(|&pl| eval(pl, p) >= 0.0);
        assert_eq!(got, want, "{p}");
        if want {
            inside += 1;
        } else {
            outside += 1;
        }
    }
    assert!(
        inside > 100 && outside > 100,
        "{inside} inside, {outside} outside"
    );
}

/// Whenever `shadow_outside_frustum` culls a box's shadow, no point of the shadow (the box
/// and every point behind it as seen from the light, sampled to 50 light-distances) is in
/// the frustum by definition; and it culls some of the random cases, at every scale. The
/// lights are directional, point lights, and point lights written with `w = 2`.
#[test]
fn a_culled_shadow_never_reaches_the_frustum() {
    let eye = DVec3::ZERO;
    let mut rnd = uniform(0x2545_f491_4f6c_dd1d);
    for scale in [1.0, 2f64.powi(20), 2f64.powi(-20)] {
        let near = near_rect().map(|p| p * scale);
        let planes = frustum_planes(eye, near);
        let mut culled = 0;
        for case in 0..3000 {
            let centre = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 16.0 * scale;
            let half = DVec3::new(rnd(), rnd(), rnd()) * scale;
            let (lo, hi) = (centre - half, centre + half);
            let at = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 16.0 * scale;
            let light = match case % 4 {
                0 => [at.x as f32, at.y as f32, at.z as f32, 0.0], // directional, towards `at`
                1 => [2.0 * at.x as f32, 2.0 * at.y as f32, 2.0 * at.z as f32, 2.0], // at `at`
                _ => [at.x as f32, at.y as f32, at.z as f32, 1.0],
            };
            if !shadow_outside_frustum(lo, hi, light, &planes) {
                continue;
            }
            culled += 1;
            let l = DVec4::from(light.map(f64::from));
            for _ in 0..200 {
                let p = lo + (hi - lo) * DVec3::new(rnd(), rnd(), rnd());
                // Away from the light: from a point light through p, or against a
                // directional light's direction.
                let away = if l.w == 0.0 {
                    -l.truncate()
                } else {
                    p - l.truncate() / l.w
                };
                let q = p + away * (rnd() * 50.0);
                assert!(
                    !in_frustum(eye, near, p) && !in_frustum(eye, near, q),
                    "culled, but {q} of the shadow of {lo}..{hi} under {light:?} is in view"
                );
            }
        }
        assert!(culled > 100, "scale {scale}: only {culled} culled");
    }
}

/// A light in the near plane, or a directional light parallel to it, leaves no volume
/// between the light and the rectangle: `near_clip_volume` refuses it rather than return a
/// plane through its own inside point.
#[test]
fn a_flat_near_clip_volume_is_refused() {
    assert_eq!(near_clip_volume(near_rect(), [3.0, 0.5, -1.0, 1.0]), None);
    assert_eq!(near_clip_volume(near_rect(), [6.0, 1.0, -2.0, 2.0]), None);
    assert_eq!(near_clip_volume(near_rect(), [1.0, 2.0, 0.0, 0.0]), None);
    assert!(near_clip_volume(near_rect(), [3.0, 0.5, 1.0, 1.0]).is_some());
    assert!(near_clip_volume(near_rect(), [1.0, 2.0, 1.0, 0.0]).is_some());
}

/// A box whose nearest corner is `10⁻⁹` of the scale inside the near plane is in view, so
/// its shadow is not culled; `10⁻⁵` behind the plane it is (the margin is `10⁻⁶` of the
/// scale), at scales 1 and 2^±20.
#[test]
fn culling_keeps_a_relative_margin() {
    for scale in [1.0, 2f64.powi(20), 2f64.powi(-20)] {
        let planes = frustum_planes(DVec3::ZERO, near_rect().map(|p| p * scale));
        let light = [0.0, 0.0, (-10.0 * scale) as f32, 1.0];
        let box_at = |gap: f64| {
            let lo = DVec3::new(-0.1, -0.1, -1.0 - gap) * scale;
            (lo, DVec3::new(0.1, 0.1, 0.5) * scale)
        };
        let (lo, hi) = box_at(1e-9);
        assert!(
            !shadow_outside_frustum(lo, hi, light, &planes),
            "scale {scale}"
        );
        let (lo, hi) = box_at(-1e-5);
        assert!(
            shadow_outside_frustum(lo, hi, light, &planes),
            "scale {scale}"
        );
    }
}

/// The text names of the techniques are the JSON's (serde's kebab-case), and a plan line
/// says the technique, the caps, the silhouette's source and the counts.
#[test]
fn plan_lines_name_what_is_drawn() {
    for t in [Technique::Culled, Technique::ZPass, Technique::ZFail] {
        assert_eq!(serde_json::to_value(t).unwrap(), t.name());
    }
    let entry = PlanEntry {
        light: 1,
        object: 2,
        object_name: "box".into(),
        technique: Technique::ZFail,
        back_cap: true,
        silhouette: SilhouetteSource::Reused,
        silhouette_edges: 7,
        side_quads: 9,
        cap_triangles: 24,
        reason: "the camera may be in its shadow".into(),
        scissor: None,
    };
    assert_eq!(
        entry.to_string(),
        "light 1 x object 2 (box): z-fail with front and back caps; silhouette reused from \
         last frame; 7 edges, 9 side quads, 24 cap triangles; the camera may be in its shadow"
    );
    let directional = PlanEntry {
        back_cap: false,
        ..entry.clone()
    };
    assert!(directional
        .to_string()
        .contains("z-fail with front cap only (directional light)"));
    let culled = PlanEntry {
        technique: Technique::Culled,
        silhouette: SilhouetteSource::Skipped,
        ..entry
    };
    assert!(culled
        .to_string()
        .contains("(box): culled; silhouette skipped;"));
}
