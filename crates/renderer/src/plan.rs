//! The frame plan: for each (light, object), the cheapest technique that is still correct.
//!
//! * **Culled**: the object's shadow volume lies outside one of the view frustum's planes
//!   (left, right, bottom, top, near; the far plane is at infinity). The volume is contained in
//!   the union of the rays from the corners of the object's world box away from the light, so
//!   if every corner is outside a plane and every corner's extrusion direction does not point
//!   back inside, nothing of the volume is visible.
//! * **Z-pass**: the near-clip volume (Kwoon; Lengyel) — the convex hull of the light and the
//!   near-plane rectangle, or for a directional light the rectangle swept towards the light — does
//!   not meet the object's box. Then no point of the near plane sees the light through the
//!   object, the camera's near plane is outside the object's shadow volume, and z-pass counts
//!   are correct. The test is conservative: an intersection it cannot rule out gives z-fail.
//!   When the box test fails (typically: the light is on or inside the object), z-pass is
//!   still chosen if no point of the near rectangle lies in the shadow of any of the object's
//!   triangles, decided triangle by triangle with the exact side of the light
//!   ([`near_rect_clear_of_shadows`]; objects of at most [`ZPASS_TRIANGLE_TEST_MAX`]
//!   triangles). This matters when a light lies a hair off a caster's plane: that triangle's
//!   shadow is almost a half-space, its back cap at infinity is almost a great circle, and
//!   `f32` clipping can draw the cap's complement, while z-pass needs no caps at all.
//! * **Z-fail** with caps otherwise; the back cap is dropped for directional lights (all of its
//!   vertices are the same point at infinity).
//!
//! [`choose`] makes this choice for one (light, object) pair.

use crate::occlusion::light_side;
use glam::{DVec3, DVec4, Vec3};
use serde::Serialize;
use shadowvol_scenes::Emission;

/// How one (light, object) pair is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Technique {
    /// Not drawn: its shadow volume cannot reach the view.
    Culled,
    /// Depth-pass counting, sides only.
    ZPass,
    /// Depth-fail counting, sides plus front cap (and back cap for point lights).
    ZFail,
}

impl Technique {
    /// `culled`, `z-pass`, `z-fail`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Technique::Culled => "culled",
            Technique::ZPass => "z-pass",
            Technique::ZFail => "z-fail",
        }
    }
}

/// Where a (light, object)'s silhouette came from this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SilhouetteSource {
    /// Computed by the backend this frame.
    Extracted,
    /// Last frame's, because neither the light nor the object moved (nor mesh or mode changed).
    Reused,
    /// Not needed (culled).
    Skipped,
}

/// What the planner may choose (tests and comparisons force one technique).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlanPolicy {
    /// Cull, then z-pass where proven safe, else z-fail.
    #[default]
    Auto,
    /// Cull, then always z-fail.
    AlwaysZFail,
    /// Cull, then always z-pass (wrong when the camera is in a shadow volume; for comparisons).
    AlwaysZPass,
}

/// One line of the plan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanEntry {
    /// Light index.
    pub light: usize,
    /// Object index.
    pub object: usize,
    /// Object name.
    pub object_name: String,
    /// The technique chosen.
    pub technique: Technique,
    /// True when a back cap is drawn (z-fail with a point light).
    pub back_cap: bool,
    /// Where the silhouette came from.
    pub silhouette: SilhouetteSource,
    /// Silhouette edges (m != 0).
    pub silhouette_edges: usize,
    /// Side quads drawn (`Σ |m|`; directional lights: triangles).
    pub side_quads: usize,
    /// Cap triangles drawn (front plus back).
    pub cap_triangles: usize,
    /// Why this technique, in words.
    pub reason: String,
    /// The light's scissor rectangle `[x, y, width, height]` in pixels (top-left origin), which
    /// limits its stencil and lit passes; `None`: the whole image. The same for every object of
    /// a light.
    pub scissor: Option<[u32; 4]>,
}

impl std::fmt::Display for PlanEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "light {} x object {} ({}): {}{}; silhouette {}; {} edges, {} side quads, {} cap triangles; {}",
            self.light,
            self.object,
            self.object_name,
            self.technique.name(),
            if self.technique == Technique::ZFail {
                if self.back_cap {
                    " with front and back caps"
                } else {
                    " with front cap only (directional light)"
                }
            } else {
                ""
            },
            match self.silhouette {
                SilhouetteSource::Extracted => "extracted",
                SilhouetteSource::Reused => "reused from last frame",
                SilhouetteSource::Skipped => "skipped",
            },
            self.silhouette_edges,
            self.side_quads,
            self.cap_triangles,
            self.reason
        )
    }
}

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
    emission: Option<&shadowvol_scenes::Emission>,
    scene_bounds: (DVec3, DVec3),
    view_proj: glam::DMat4,
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
#[cfg(test)]
fn uniform(seed: u64) -> impl FnMut() -> f64 {
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

/// A plane `n · x + d >= 0` is inside, as `(n, d)`.
pub type Plane = DVec4;

fn plane_through(p: DVec3, normal: DVec3, inside: DVec3) -> Option<Plane> {
    let len = normal.length();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return None;
    }
    let n = normal / len;
    let mut pl = n.extend(-n.dot(p));
    if eval(pl, inside) < 0.0 {
        pl = -pl;
    }
    // The reference point must be strictly inside, or the plane is degenerate for it.
    (eval(pl, inside) > 0.0).then_some(pl)
}

#[inline]
fn eval(pl: Plane, p: DVec3) -> f64 {
    pl.truncate().dot(p) + pl.w
}

/// The five inward planes of the view frustum (left, right, bottom, top, near).
#[must_use]
pub fn frustum_planes(eye: DVec3, near: [DVec3; 4]) -> Vec<Plane> {
    let centre = (near[0] + near[1] + near[2] + near[3]) / 4.0;
    let forward = centre - eye;
    let inside = eye + forward * 2.0;
    let mut v = Vec::with_capacity(5);
    for i in 0..4 {
        let (a, b) = (near[i], near[(i + 1) % 4]);
        if let Some(p) = plane_through(eye, (a - eye).cross(b - eye), inside) {
            v.push(p);
        }
    }
    if let Some(p) = plane_through(centre, forward, inside) {
        v.push(p);
    }
    v
}

/// The 8 corners of a box.
#[must_use]
pub fn box_corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    let mut c = [DVec3::ZERO; 8];
    for (i, v) in c.iter_mut().enumerate() {
        *v = DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
    }
    c
}

/// True when the shadow volume of the box `(lo, hi)` under `light` provably lies outside the
/// frustum given by its inward `planes` (then the object's shadow cannot be seen).
#[must_use]
pub fn shadow_outside_frustum(lo: DVec3, hi: DVec3, light: [f32; 4], planes: &[Plane]) -> bool {
    let l = DVec4::new(
        f64::from(light[0]),
        f64::from(light[1]),
        f64::from(light[2]),
        f64::from(light[3]),
    );
    let corners = box_corners(lo, hi);
    let margin = relative_margin(lo, hi);
    planes.iter().any(|&pl| {
        corners.iter().all(|&c| {
            let dir = c * l.w - l.truncate();
            eval(pl, c) < -margin && pl.truncate().dot(dir) <= 0.0
        })
    })
}

/// The planes of the near-clip volume (convex hull of the light and the near rectangle; for a
/// directional light the rectangle swept towards the light), inward. `None` when the volume is
/// degenerate (light in the near plane, direction parallel to it): then z-pass is never proven
/// safe.
#[must_use]
pub fn near_clip_volume(near: [DVec3; 4], light: [f32; 4]) -> Option<Vec<Plane>> {
    let l = DVec3::new(
        f64::from(light[0]),
        f64::from(light[1]),
        f64::from(light[2]),
    );
    let w = f64::from(light[3]);
    let centre = (near[0] + near[1] + near[2] + near[3]) / 4.0;
    let rect_n = (near[1] - near[0]).cross(near[3] - near[0]);
    let mut planes = Vec::with_capacity(5);
    if w == 0.0 {
        let d = l;
        let inside = centre + d.normalize() * (near[1] - near[0]).length();
        planes.push(plane_through(centre, rect_n, inside)?);
        for i in 0..4 {
            let (a, b) = (near[i], near[(i + 1) % 4]);
            planes.push(plane_through(a, (b - a).cross(d), inside)?);
        }
    } else {
        let lp = l / w;
        if !lp.is_finite() {
            return None;
        }
        let inside = (centre * 4.0 + lp) / 5.0;
        planes.push(plane_through(centre, rect_n, inside)?);
        for i in 0..4 {
            let (a, b) = (near[i], near[(i + 1) % 4]);
            planes.push(plane_through(a, (b - a).cross(lp - a), inside)?);
        }
    }
    Some(planes)
}

/// Objects with more triangles than this keep z-fail when their box meets the near-clip volume:
/// [`near_rect_clear_of_shadows`] costs one exact side test per triangle per light, on the host,
/// every frame.
pub const ZPASS_TRIANGLE_TEST_MAX: usize = 1 << 18;

/// True when no point of the near-plane rectangle `near` (world space, `f64`) lies in the
/// shadow of any triangle `triangles` (ids into `world`, the `f32` world positions the volumes
/// are drawn from) under `light` (world space, homogeneous `f32`): then z-pass counts are
/// correct for this object whatever its silhouette.
///
/// A triangle's shadow lies on the far side of its plane from the light, so the rectangle is
/// clear of it when each of its corners is strictly on the light's side ([`light_side`], exact),
/// or, for a light in the plane (a shadow of no volume), strictly off the plane; or when the
/// triangle lies strictly outside one of the near-clip volume's inward `planes` (see
/// [`near_clip_volume`]; then no ray from the light to the rectangle passes through it). The
/// corners' sides are evaluated in `f64` with a relative margin of `10⁻⁹`, so the test is
/// conservative: a corner near a triangle's plane makes it false.
///
/// # Panics
/// Panics if a triangle's id is out of range of `world`.
#[must_use]
pub fn near_rect_clear_of_shadows(
    world: &[Vec3],
    triangles: &[[u32; 3]],
    light: [f32; 4],
    near: [DVec3; 4],
    planes: &[Plane],
) -> bool {
    let hull = NearClipHull::new(light, near);
    triangles.iter().all(|t| {
        let v = [
            world[t[0] as usize],
            world[t[1] as usize],
            world[t[2] as usize],
        ];
        let a = v[0].as_dvec3();
        let n = (v[1].as_dvec3() - a).cross(v[2].as_dvec3() - a);
        let nlen = n.length();
        if !nlen.is_finite() {
            return false;
        }
        // sgn H(a, b, c, X) = −sgn(n · (X − a)) for a point X: the convention of light_side.
        let side = light_side(v, light);
        let corners_clear = nlen > 0.0
            && near.iter().all(|&x| {
                let h = -n.dot(x - a);
                let margin = 1e-9 * nlen * (x - a).length();
                if side == 0 {
                    h.abs() > margin
                } else {
                    h * f64::from(side) > margin
                }
            });
        corners_clear || {
            let t = [a, v[1].as_dvec3(), v[2].as_dvec3()];
            points_outside(&t, planes)
                || hull
                    .as_ref()
                    .is_some_and(|h| triangle_misses_near_clip(t, h))
        }
    })
}

/// The near-clip volume of one light as the separating-axis test needs it: its apex (a point,
/// or for a directional light the direction the rectangle is swept along), its edges and face
/// normals, and the largest coordinate. Built once per light and object, not per triangle.
struct NearClipHull {
    apex: DVec3,
    directional: bool,
    near: [DVec3; 4],
    edges: Vec<DVec3>,
    face_axes: Vec<DVec3>,
    scale: f64,
}

impl NearClipHull {
    /// `None` when the light's point is not finite (then nothing is proven separate).
    fn new(light: [f32; 4], near: [DVec3; 4]) -> Option<Self> {
        let w = f64::from(light[3]);
        let lxyz = DVec3::new(light[0].into(), light[1].into(), light[2].into());
        let (apex, directional) = if w == 0.0 {
            (lxyz, true)
        } else {
            (lxyz / w, false)
        };
        if !apex.is_finite() {
            return None;
        }
        let scale = near
            .iter()
            .fold(0.0f64, |m, p| m.max(p.abs().max_element()))
            .max(if directional {
                0.0
            } else {
                apex.abs().max_element()
            });
        let mut edges = Vec::with_capacity(8);
        let mut face_axes = Vec::with_capacity(5);
        for i in 0..4 {
            let (x, y) = (near[i], near[(i + 1) % 4]);
            let to_apex = if directional { apex } else { apex - x };
            edges.push(y - x);
            if !directional {
                edges.push(to_apex);
            }
            face_axes.push((y - x).cross(to_apex));
        }
        if directional {
            edges.push(apex);
        }
        face_axes.push((near[1] - near[0]).cross(near[3] - near[0]));
        Some(Self {
            apex,
            directional,
            near,
            edges,
            face_axes,
            scale,
        })
    }
}

/// Separating-axis test between the triangle `t` and the near-clip volume `hull` (the pyramid
/// from the light over the near rectangle, or for a directional light the rectangle swept
/// towards it): true when some axis among the volume's face normals, the triangle's normal and
/// the cross products of their edges has the two strictly apart, with a margin of `10⁻⁹`
/// relative to the coordinates. Complete for convex polyhedra, so it also separates a triangle
/// that passes a hair beside the light, which no single face plane does.
fn triangle_misses_near_clip(t: [DVec3; 3], hull: &NearClipHull) -> bool {
    let scale = t
        .iter()
        .fold(hull.scale, |m, p| m.max(p.abs().max_element()))
        .max(1e-30);
    let tri_edges = [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let separates = |u: DVec3| {
        let ulen = u.length();
        if !(ulen > 0.0 && ulen.is_finite()) {
            return false;
        }
        let margin = 1e-9 * ulen * scale;
        let (tlo, thi) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let d = u.dot(*p);
                (lo.min(d), hi.max(d))
            });
        let (mut vlo, mut vhi) =
            hull.near
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    let d = u.dot(*p);
                    (lo.min(d), hi.max(d))
                });
        let d = u.dot(hull.apex);
        if hull.directional {
            if d > 0.0 {
                vhi = f64::INFINITY;
            } else if d < 0.0 {
                vlo = f64::NEG_INFINITY;
            }
        } else {
            vlo = vlo.min(d);
            vhi = vhi.max(d);
        }
        thi < vlo - margin || vhi < tlo - margin
    };
    hull.face_axes.iter().any(|&u| separates(u))
        || separates(tri_edges[0].cross(tri_edges[1]))
        || tri_edges
            .iter()
            .any(|&e| hull.edges.iter().any(|&f| separates(e.cross(f))))
}

/// One object as the plan sees it, for [`choose`].
#[derive(Debug, Clone, Copy)]
pub struct PlanObject<'a> {
    /// False for a receiver that casts no shadow.
    pub casts_shadows: bool,
    /// World positions (`f32`), as drawn.
    pub world: &'a [Vec3],
    /// Triangles, ids into `world`.
    pub triangles: &'a [[u32; 3]],
    /// The world box `(lo, hi)` of `world`.
    pub bounds: (DVec3, DVec3),
}

/// The view as the plan sees it, for [`choose`]: built once per frame and light.
#[derive(Debug, Clone, Copy)]
pub struct PlanView<'a> {
    /// The view frustum's inward planes ([`frustum_planes`]).
    pub frustum: &'a [Plane],
    /// The near-plane rectangle's corners (world space).
    pub near: [DVec3; 4],
    /// The near-clip volume of this light ([`near_clip_volume`]); `None` when degenerate.
    pub near_clip: Option<&'a [Plane]>,
}

/// The technique for one (light, object) pair under `policy`, and why, in words: culled when
/// the object casts nothing, has no triangles, is out of the reach of the light's `emission`
/// (range, cone) or has its shadow outside the frustum; otherwise z-pass where proven safe
/// (the near-clip volume misses the object's box, or [`near_rect_clear_of_shadows`]), else
/// z-fail. `light` is the world light (homogeneous `f32`).
#[must_use]
pub fn choose(
    policy: PlanPolicy,
    light: [f32; 4],
    emission: Option<&Emission>,
    object: PlanObject<'_>,
    view: PlanView<'_>,
) -> (Technique, String) {
    let (lo, hi) = object.bounds;
    if !object.casts_shadows {
        return (
            Technique::Culled,
            "receiver only: casts no shadow".to_owned(),
        );
    }
    if object.world.is_empty() || object.triangles.is_empty() {
        return (Technique::Culled, "no triangles".to_owned());
    }
    if let Some(why) = emission.and_then(|e| e.unreachable(light, lo, hi)) {
        return (
            Technique::Culled,
            format!("{why}: it lights neither the object nor its shadow"),
        );
    }
    if shadow_outside_frustum(lo, hi, light, view.frustum) {
        return (
            Technique::Culled,
            "its shadow volume lies outside the view frustum".to_owned(),
        );
    }
    match policy {
        PlanPolicy::AlwaysZFail => (Technique::ZFail, "policy: always z-fail".to_owned()),
        PlanPolicy::AlwaysZPass => (Technique::ZPass, "policy: always z-pass".to_owned()),
        PlanPolicy::Auto => match view.near_clip {
            Some(planes) if box_outside(lo, hi, planes) => (
                Technique::ZPass,
                "object outside the near-clip volume: camera outside its shadow volume".to_owned(),
            ),
            Some(planes)
                if object.triangles.len() <= ZPASS_TRIANGLE_TEST_MAX
                    && near_rect_clear_of_shadows(
                        object.world,
                        object.triangles,
                        light,
                        view.near,
                        planes,
                    ) =>
            {
                (
                    Technique::ZPass,
                    "object meets the near-clip volume, but no triangle's shadow reaches the near plane: camera outside its shadow volume".to_owned(),
                )
            }
            Some(_) => (
                Technique::ZFail,
                "object meets the near-clip volume: camera may be inside its shadow volume"
                    .to_owned(),
            ),
            None => (
                Technique::ZFail,
                "near-clip volume degenerate (light in or parallel to the near plane)".to_owned(),
            ),
        },
    }
}

/// The margin a point must clear a plane by to count as outside: `10⁻⁶` of the larger of the
/// box `lo..hi`'s diagonal and its coordinates' magnitude (at least `10⁻³⁶`), so it scales with
/// both the extent and the rounding error of coordinates far from the origin.
fn relative_margin(lo: DVec3, hi: DVec3) -> f64 {
    (hi - lo)
        .length()
        .max(lo.abs().max_element())
        .max(hi.abs().max_element())
        .max(1e-30)
        * 1e-6
}

/// True when some inward plane has every point strictly outside it, with a margin of `10⁻⁶`
/// relative to the points' extent and magnitude.
fn points_outside(points: &[DVec3], planes: &[Plane]) -> bool {
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let margin = relative_margin(lo, hi);
    planes
        .iter()
        .any(|&pl| points.iter().all(|&c| eval(pl, c) < -margin))
}

/// True when the box `(lo, hi)` provably does not meet the convex volume given by its inward
/// `planes` (some plane has all 8 corners strictly outside, with a relative margin).
#[must_use]
pub fn box_outside(lo: DVec3, hi: DVec3, planes: &[Plane]) -> bool {
    points_outside(&box_corners(lo, hi), planes)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}

#[cfg(test)]
mod scissor_tests {
    use super::*;
    use glam::DMat4;
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
