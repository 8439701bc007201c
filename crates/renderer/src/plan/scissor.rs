//! The scissor of a light: the screen rectangle outside which it adds nothing.

use super::geometry::box_corners;
use glam::{DMat4, DVec3};
use shadowvol_scenes::Emission;

/// The screen rectangle `[x, y, width, height]` (pixels, top-left origin) outside which light
/// `light` adds nothing, widened by a pixel on each side: the projection of the bounding box of
/// what it can light.
///
/// * A point light with a range: its range sphere.
/// * A spot light: its outer cone (widened by [`SPOT_SCISSOR_MARGIN`]), cut at its range, or
///   without a range at the farthest corner of `scene_bounds` (the world box `(lo, hi)` of every
///   receiver: nothing farther can be lit), and within the range sphere.
///
/// Either box is clipped to `scene_bounds`, since only receivers are lit.
///
/// `None` (the whole image) for a point light without a range, a directional light, or a box
/// that reaches behind the near plane. `view_proj` is the `f64` matrix of the frame
/// ([`crate::Camera::view_proj_f64`]).
#[must_use]
pub fn light_scissor(
    light: [f32; 4],
    emission: Option<&Emission>,
    scene_bounds: (DVec3, DVec3),
    view_proj: DMat4,
    near: f64,
    width: u32,
    height: u32,
) -> Option<[u32; 4]> {
    let emission = emission?;
    if light[3] == 0.0 {
        return None;
    }
    let c = DVec3::new(light[0].into(), light[1].into(), light[2].into()) / f64::from(light[3]);
    let reach = match (emission.range, &emission.spot) {
        (Some(r), _) => f64::from(r),
        (None, Some(_)) => box_corners(scene_bounds.0, scene_bounds.1)
            .iter()
            .map(|&p| p.distance(c))
            .fold(0.0, f64::max),
        (None, None) => return None,
    };
    if !reach.is_finite() {
        return None;
    }
    let (mut lo, mut hi) = (c - DVec3::splat(reach), c + DVec3::splat(reach));
    if let Some(spot) = &emission.spot {
        let axis = spot.direction.as_dvec3().normalize_or_zero();
        // No receiver lies farther along the axis than the scene box's farthest corner.
        let axial = box_corners(scene_bounds.0, scene_bounds.1)
            .iter()
            .map(|&p| (p - c).dot(axis))
            .fold(0.0, f64::max);
        let (clo, chi) = cone_box(
            c,
            axis,
            f64::from(spot.outer_cone_angle) + SPOT_SCISSOR_MARGIN,
            reach,
            axial,
        );
        lo = lo.max(clo);
        hi = hi.min(chi);
    }
    // Only receivers can be lit: clip to the scene's box (to a point when nothing can be lit).
    lo = lo.max(scene_bounds.0);
    hi = hi.min(scene_bounds.1).max(lo);
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for corner in box_corners(lo, hi) {
        let p = view_proj * corner.extend(1.0);
        // Clip w is the view depth: a corner at or behind the near plane projects unboundedly.
        if p.w.is_nan() || p.w <= near {
            return None;
        }
        let (sx, sy) = (
            (p.x / p.w * 0.5 + 0.5) * f64::from(width),
            (0.5 - p.y / p.w * 0.5) * f64::from(height),
        );
        x0 = x0.min(sx);
        y0 = y0.min(sy);
        x1 = x1.max(sx);
        y1 = y1.max(sy);
    }
    let clamp = |v: f64, hi: u32| v.clamp(0.0, f64::from(hi)) as u32;
    let (ax, ay) = (
        clamp(x0.floor() - 1.0, width),
        clamp(y0.floor() - 1.0, height),
    );
    let (bx, by) = (
        clamp(x1.ceil() + 1.0, width),
        clamp(y1.ceil() + 1.0, height),
    );
    Some([ax, ay, bx.saturating_sub(ax), by.saturating_sub(ay)])
}

/// Radians added to a spot light's outer cone angle for its scissor: margin for the shader's `f32`
/// evaluation of the cone's falloff, which need not reach zero exactly at the outer angle.
pub const SPOT_SCISSOR_MARGIN: f64 = 1e-3;

/// A bounding box of the points of the cone with apex `apex`, unit axis `axis` and half-angle
/// `angle` (radians) that lie within `length` of the apex and at most `axial` along the axis.
/// Below 89.9 degrees it is the box of the cone cut by the plane at `min(length, axial)` along
/// the axis, within the ball's box; from 89.9 degrees up the box of the half ball on the axis'
/// side, widened by `length · sin(excess over 90 degrees)`; above π/2 + 2
/// [`SPOT_SCISSOR_MARGIN`], the ball's box.
fn cone_box(apex: DVec3, axis: DVec3, angle: f64, length: f64, axial: f64) -> (DVec3, DVec3) {
    let ball = (apex - DVec3::splat(length), apex + DVec3::splat(length));
    let axis = axis.normalize_or_zero();
    if axis == DVec3::ZERO
        || angle.is_nan()
        || angle > std::f64::consts::FRAC_PI_2 + 2.0 * SPOT_SCISSOR_MARGIN
    {
        return ball;
    }
    // sqrt(1 - axis_i²): how far a unit vector perpendicular to the axis reaches along i.
    let across = (DVec3::ONE - axis * axis).max(DVec3::ZERO).map(f64::sqrt);
    if angle >= 89.9_f64.to_radians() {
        // The half ball: along i it reaches `length` on the side the axis points to, and the
        // rim's `length · across_i` on the other.
        let slack = length * (angle - std::f64::consts::FRAC_PI_2).max(0.0).sin();
        let up = DVec3::select(axis.cmpge(DVec3::ZERO), DVec3::ONE, across);
        let down = DVec3::select(axis.cmple(DVec3::ZERO), DVec3::ONE, across);
        return (
            apex - down * length - DVec3::splat(slack),
            apex + up * length + DVec3::splat(slack),
        );
    }
    let depth = length.min(axial).max(0.0);
    let centre = apex + axis * depth;
    // The cap disc of radius r about `centre`, normal `axis`, reaches r · across_i along i.
    let extent = across * (depth * angle.tan());
    (
        apex.min(centre - extent).max(ball.0),
        apex.max(centre + extent).min(ball.1),
    )
}

/// A small xorshift generator of uniform numbers in `[0, 1)`, for the tests' random cases.
/// A deterministic uniform `[0, 1)` generator for the tests.
#[cfg(test)]
pub(super) fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod cone_tests {
    use super::*;

    /// Every point of the cone within the sphere and the axial limit lies in the box, for random
    /// axes, angles, limits and points, hemispheres included.
    #[test]
    fn the_cone_box_contains_the_cone() {
        let mut rnd = uniform(0x9e37_79b9_7f4a_7c15);
        for _ in 0..2000 {
            let apex = DVec3::new(rnd() * 4.0 - 2.0, rnd() * 4.0 - 2.0, rnd() * 4.0 - 2.0);
            let axis =
                DVec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0).normalize();
            let angle = match (rnd() * 4.0) as u32 {
                0 => std::f64::consts::FRAC_PI_2 + SPOT_SCISSOR_MARGIN,
                1 => std::f64::consts::FRAC_PI_2,
                _ => rnd() * 1.56 + 0.01,
            };
            let length = rnd() * 10.0 + 0.1;
            let axial = rnd() * 12.0 - 1.0;
            let (lo, hi) = cone_box(apex, axis, angle, length, axial);
            for _ in 0..50 {
                let dir =
                    DVec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0).normalize();
                if dir.dot(axis) < angle.cos() {
                    continue;
                }
                let p = apex + dir * length * rnd().sqrt();
                if (p - apex).dot(axis) > axial {
                    continue;
                }
                let eps = 1e-9 * (1.0 + length);
                assert!(
                    p.cmpge(lo - eps).all() && p.cmple(hi + eps).all(),
                    "{p} outside {lo}..{hi} (apex {apex}, axis {axis}, angle {angle})"
                );
            }
        }
    }
}

#[cfg(test)]
mod scissor_tests {
    use super::*;
    use glam::DMat4;
    use glam::Vec3;
    use shadowvol_scenes::SpotCone;

    const W: u32 = 160;
    const H: u32 = 120;
    const NEAR: f64 = 0.1;

    /// A camera at `eye` looking at `target`.
    fn view_proj(eye: DVec3, target: DVec3) -> DMat4 {
        glam::dcamera::rh::proj::directx::perspective(
            60f64.to_radians(),
            f64::from(W) / f64::from(H),
            NEAR,
            100.0,
        ) * glam::dcamera::rh::view::look_at_mat4(eye, target, DVec3::Y)
    }

    /// Where world point `p` lands in the image (column, row, in pixels; row 0 at the top), or
    /// `None` behind the near plane.
    fn pixel(vp: DMat4, p: DVec3) -> Option<(f64, f64)> {
        let c = vp * p.extend(1.0);
        (c.w > NEAR).then(|| {
            (
                (c.x / c.w * 0.5 + 0.5) * f64::from(W),
                (0.5 - c.y / c.w * 0.5) * f64::from(H),
            )
        })
    }

    fn emission(range: Option<f32>, spot: Option<(Vec3, f32)>) -> Emission {
        Emission {
            range,
            spot: spot.map(|(direction, outer)| SpotCone {
                direction,
                inner_cone_angle: outer * 0.8,
                outer_cone_angle: outer,
            }),
            ..Emission::default()
        }
    }

    /// Every point of `bounds` that the light reaches by glTF's definition
    /// (`Emission::attenuation > 0`, written independently of the scissor) lands inside the
    /// scissor rectangle; returns the scissor and the box of those points' pixels.
    fn check_contains(
        light: [f32; 4],
        e: &Emission,
        bounds: (DVec3, DVec3),
        (eye, target): (DVec3, DVec3),
    ) -> ([u32; 4], [f64; 4]) {
        let vp = view_proj(eye, target);
        let r = light_scissor(light, Some(e), bounds, vp, NEAR, W, H).expect("a scissor");
        let mut rnd = uniform(0x2545_f491_4f6c_dd1d);
        let (lo, hi) = bounds;
        let mut lit = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        let samples = (0..40_000)
            .map(|_| lo + (hi - lo) * DVec3::new(rnd(), rnd(), rnd()))
            .chain(box_corners(lo, hi));
        for p in samples {
            if e.attenuation(light, p) <= 0.0 {
                continue;
            }
            let (x, y) = pixel(vp, p).expect("in front of the camera");
            if !(0.0..f64::from(W)).contains(&x) || !(0.0..f64::from(H)).contains(&y) {
                continue; // off screen: the scissor is clamped to the image
            }
            let (col, row) = (x.floor() as u32, y.floor() as u32);
            assert!(
                (r[0]..r[0] + r[2]).contains(&col) && (r[1]..r[1] + r[3]).contains(&row),
                "lit point {p} at pixel ({col}, {row}) outside the scissor {r:?}"
            );
            lit = [lit[0].min(x), lit[1].min(y), lit[2].max(x), lit[3].max(y)];
        }
        assert!(
            lit[0] < lit[2],
            "no lit point on screen: the case tests nothing"
        );
        (r, lit)
    }

    fn area(r: [u32; 4]) -> u32 {
        r[2] * r[3]
    }

    #[test]
    fn a_range_light_covering_the_box_is_scissored_to_the_box() {
        // The range reaches past the whole box, so what is lit is the box itself: the scissor
        // is its projection, widened by one pixel, to the pixel.
        let bounds = (DVec3::new(-1.0, 0.0, -1.0), DVec3::new(1.0, 1.0, 1.0));
        let light = [0.3, 2.0, 0.2, 1.0];
        let (r, lit) = check_contains(
            light,
            &emission(Some(50.0), None),
            bounds,
            (DVec3::new(1.0, 3.0, 6.0), DVec3::ZERO),
        );
        assert_eq!(
            r,
            [
                (lit[0].floor() - 1.0) as u32,
                (lit[1].floor() - 1.0) as u32,
                (lit[2].ceil() + 1.0) as u32 - (lit[0].floor() - 1.0) as u32,
                (lit[3].ceil() + 1.0) as u32 - (lit[1].floor() - 1.0) as u32,
            ],
            "scissor {r:?} against the box's pixels {lit:?}"
        );
    }

    /// Range balls and cones, at the origin and moved far from it (so that a scissor which
    /// mixed up the light's position with a direction would show).
    #[test]
    fn range_and_cone_scissors_hold_every_lit_point_and_save_pixels() {
        let down = Vec3::new(0.1, -1.0, 0.2).normalize();
        for offset in [DVec3::ZERO, DVec3::new(40.0, 3.0, -25.0)] {
            let bounds = (
                DVec3::new(-3.0, -0.1, -3.0) + offset,
                DVec3::new(3.0, 1.0, 3.0) + offset,
            );
            let camera = (DVec3::new(0.5, 4.0, 7.0) + offset, offset);
            let at = DVec3::new(0.4, 1.5, -0.3) + offset;
            let light = [at.x as f32, at.y as f32, at.z as f32, 1.0];
            let whole = check_contains(light, &emission(Some(1e3), None), bounds, camera).0;
            for (what, e, at_most) in [
                ("range ball", emission(Some(1.2), None), 0.5),
                ("cone, no range", emission(None, Some((down, 0.35))), 0.5),
                (
                    "cone within a range",
                    emission(Some(1.4), Some((down, 0.5))),
                    0.5,
                ),
                (
                    "half-space cone",
                    emission(None, Some((down, std::f32::consts::FRAC_PI_2))),
                    1.0,
                ),
                ("sideways cone", emission(None, Some((Vec3::X, 0.3))), 0.6),
            ] {
                let (r, _) = check_contains(light, &e, bounds, camera);
                assert!(
                    f64::from(area(r)) <= at_most * f64::from(area(whole)),
                    "{what} at {offset}: scissor {r:?} saves too little against the box's \
                     {whole:?}"
                );
            }
        }
    }

    #[test]
    fn no_scissor_where_nothing_bounds_the_light() {
        let bounds = (DVec3::splat(-1.0), DVec3::splat(1.0));
        let vp = view_proj(DVec3::new(0.0, 2.0, 5.0), DVec3::ZERO);
        let scissor =
            |light: [f32; 4], e: Option<&Emission>| light_scissor(light, e, bounds, vp, NEAR, W, H);
        let ranged = emission(Some(2.0), None);
        assert_eq!(scissor([0.0, 1.0, 0.0, 1.0], None), None, "no emission");
        assert_eq!(
            scissor([0.0, 1.0, 0.0, 0.0], Some(&ranged)),
            None,
            "directional"
        );
        assert_eq!(
            scissor([0.0, 1.0, 0.0, 1.0], Some(&emission(None, None))),
            None,
            "a point light without a range"
        );
        assert_eq!(
            scissor(
                [0.0, 1.0, 0.0, 1.0],
                Some(&emission(Some(f32::INFINITY), None))
            ),
            None,
            "an infinite range"
        );
        // The camera inside the lit box: its corners straddle the near plane.
        let inside = view_proj(DVec3::new(0.0, 0.5, 0.5), DVec3::ZERO);
        assert_eq!(
            light_scissor(
                [0.0, 0.5, 0.0, 1.0],
                Some(&ranged),
                bounds,
                inside,
                NEAR,
                W,
                H
            ),
            None,
            "the box reaches behind the near plane"
        );
        // A homogeneous point light (w = 2) is at xyz / w: its scissor is the one at (0, 1, 0).
        assert_eq!(
            scissor([0.0, 2.0, 0.0, 2.0], Some(&ranged)),
            scissor([0.0, 1.0, 0.0, 1.0], Some(&ranged))
        );
        assert!(scissor([0.0, 1.0, 0.0, 1.0], Some(&ranged)).is_some());
    }
}
