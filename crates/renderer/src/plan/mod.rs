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

mod frame;
mod geometry;
mod scissor;
#[cfg(test)]
mod tests;

pub use frame::{plan_frame, FramePlan, Scissor};
pub use geometry::{
    box_corners, box_outside, frustum_planes, near_clip_volume, near_rect_clear_of_shadows,
    shadow_outside_frustum, Plane, ZPASS_TRIANGLE_TEST_MAX,
};
pub use scissor::{light_scissor, SPOT_SCISSOR_MARGIN};
pub use shadowvol_report::{PlanEntry, SilhouetteSource, Technique};

use glam::{DVec3, Vec3};
use serde::Serialize;
use shadowvol_scenes::Emission;

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
