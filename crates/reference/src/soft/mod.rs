//! The judge of soft shadows: the true share of a light's disk that a surface point sees.
//!
//! A light with a size ([`LightDisk`]) is a disk: for a point or spot light a disk in world
//! units, for a directional light its cone of directions, represented by the tangent-plane disk
//! of radius `tan θ` at unit distance along the direction (a direction is a point of that disk).
//! The **visibility** of a surface point `P` is the share of the disk's area (area measure in
//! the disk's plane) whose points `Y` it sees: the open segment from `P` to `Y` (for a
//! directional light, the open ray from `P` along `Y`) crosses no caster triangle. The casters
//! are the same `f32` world triangles the hard reference casts against ([`Shot::triangles`] of
//! the surfaces that [`Shot::casts_shadows`]), with the same conventions: the pixel's own
//! triangle never occludes, and a caster whose plane passes within the contact distance of `P`
//! ([`crate::occlusion::CONTACT`]) touches it and does not occlude. Facing is not part of it: a
//! disk partly behind the surface's own plane is hidden there only by casters (for a closed
//! caster, by its far side), as the hard reference separates occlusion from `cos θ`.
//!
//! # Method
//!
//! 1. **Gather.** The BVH ([`crate::Bvh`]) lists the casters whose boxes may meet the pyramid
//!    with apex `P` over the square `[−R′, R′]²` around the disk (`R′ = R (1 + 2⁻²⁰)`; for a
//!    directional light an infinite pyramid of directions). None: the visibility is exactly 1.
//! 2. **Project.** Every disk point `Y` the caster hides is the central projection from `P`
//!    onto the disk's plane of a caster point between `P` and that plane. Each vertex `X` is
//!    mapped linearly to homogeneous coordinates `(A, B, W)` with `r = X − P`: for a point light
//!    `W = r·t` (`t` the unit normal from `P` towards the plane, at distance `h`),
//!    `A = h r·u + p_u W`, `B = h r·v + p_v W` (`p_u`, `p_v` the disk coordinates of `P`'s foot),
//!    so that `a = A / W`, `b = B / W` are the disk coordinates of the projection; for a
//!    directional light `(A, B, W) = (r·u, r·v, r·d)` with `d` the unit direction. The triangle
//!    is clipped in these coordinates to the pyramid, `|A| ≤ R′ W`, `|B| ≤ R′ W` (which keeps
//!    `W > 0`: nothing behind `P`), and for a point light to `W ≤ h` (points beyond the light's
//!    plane do not occlude); no near plane is needed, since the pyramid closes at `P` and every
//!    projected point stays in the square. Each clipped triangle is oriented counter-clockwise
//!    in the disk's coordinates from the exact sign of its plane at `P` (`robust::orient3d`).
//! 3. **Cancel.** The covered region is `{w > 0}`, where `w(x)` counts the projected triangles
//!    covering `x`; `w` is the sum of its polygons' signed edges, so an edge that two triangles
//!    traverse in opposite directions (a shared edge of a mesh that is not a silhouette from
//!    `P`) contributes nothing. Every projected point is a function of one vertex, or of one
//!    (clipped) edge and one clip plane, evaluated with the edge's ends in a fixed order, so the
//!    two copies of a shared edge are bit-identical and cancel exactly; silhouette edges (both
//!    neighbours on the same side) add to multiplicity 2. What remains is the silhouette from
//!    `P` of what the pyramid holds, plus the square's sides.
//! 4. **Integrate.** When no remaining edge that separates `w = 0` from `w > 0` comes within its
//!    error of the disk, the disk is all covered or all seen: the visibility is exactly 0 or 1.
//!    Otherwise, when the edges form one convex
//!    counter-clockwise cycle (one convex occluder, clipped or not), the area is the closed form
//!    [`polygon_disk_area`] (a convex polygon clipped by a disk). Otherwise the disk's `x` range
//!    is cut into slabs at every edge end, every crossing of two edges inside the disk and every
//!    crossing of an edge with the circle; within a slab no two edges cross inside the disk, so
//!    sorting the edges at the slab's middle and counting `w` from below gives the intervals
//!    where `w > 0`, each bounded above and below by an edge (a trapezoid) or by the circle (the
//!    arc's integral `∫√(R² − x²) dx`, in closed form). An order decided wrongly only between
//!    two edges closer than their rounding changes the area by at most their distance, so the
//!    integration is stable where a boundary walk that classifies pieces would not be.
//!
//! The disk's plane may pass through `P` (the disk seen edge-on, `h ≤ 2⁻²⁶ |C − P|`, [`EDGE_ON`]): the
//! projection then degenerates, and the method works in the plane instead: a caster crossing
//! it meets it in a segment, which hides the part of the disk behind it as seen from `P`'s foot
//! (a wedge beyond the segment, clipped to the square); the same cancellation and integration
//! follow. A caster lying in the plane never blocks (the hard reference's convention for a light
//! in a caster's plane); one within `h` of the plane on `P`'s side that does not cross it is not
//! seen by this model, and the bound does not cover it (it would have to be parallel to the
//! disk's plane to `2⁻²⁶`).
//!
//! # Error bound
//!
//! [`Visibility::bound`] bounds `|value − true visibility|`. It is a first-order forward error
//! bound (terms in `u²`, `u = 2⁻⁵³`, left out), made of:
//! * the projection: each edge left after cancellation lies on a known line: a caster edge's
//!   projection (the homogeneous cross product of its ends' `(A, B, W)`, whose error follows
//!   from each coordinate's: the rounding of `r = X − P` and of the dot products), a side of the
//!   square, or the caster's plane met with the light's. Both ends' distance from the exact
//!   line is bounded a posteriori (the computed point put into the line, with the line's and
//!   the evaluation's errors), plus the frame's own rounding (`u, v, t, h, p_u, p_v`). Sliding
//!   along its line (a clip point's ill-conditioned part) moves no edge; an edge moved by `δ`
//!   changes the covered area by at most `δ` times its length inside the disk enlarged by `δ`,
//!   summed over the edges left (cancelled copies move together and change nothing);
//! * the integration: `16 u` times the sum of the magnitudes of the terms summed
//!   (compensated summation), plus `4 u π R²` per evaluation of the arc integral;
//! * edge-on, the in-plane model's own error: `h` times `1 / sin` of the angle between the
//!   plane and the caster edge or face that makes each wedge boundary, times the boundary's
//!   length over its distance from `P` (first order in `h`).
//!
//! Measured (`tests/soft.rs`): against the closed form on plates the error is at most
//! `2·10⁻¹⁵`, the bound `3·10⁻¹⁵` to `10⁻¹³`; the bound grows like `u |C − P| / h` as `P` nears the
//! disk's plane (about `10⁻⁶` at [`EDGE_ON`] on the tests' scene); on a 256² bunny on a floor
//! the largest is `4·10⁻⁹`. Exactly 0 or 1 (bound 0) is reported only as step 4 says.
//! [`Visibility::is_penumbra`] is strictly between, beyond the bound.

use crate::bvh::Bvh;
use crate::occlusion::CONTACT;
use crate::Shot;
use glam::{DVec3, Vec3};
use shadowvol_scenes::LightDisk;

/// `f64` unit roundoff `2⁻⁵³`.
const U: f64 = 1.0 / 9_007_199_254_740_992.0;

/// The square around the disk: `R′ = R · SQUARE` (`1 + 2⁻²⁰`).
const SQUARE: f64 = 1.0 + 1.0 / 1_048_576.0;

/// Relative distance of `P` from the disk's plane below which the disk is taken edge-on (`2⁻²⁶`
/// of `|C − P|`): the projection's bound grows like `u |C − P| / h`, the in-plane model's like
/// `h`; on the tests' scene they meet near `2⁻²⁶`, at about `10⁻⁶`.
pub const EDGE_ON: f64 = 1.0 / 67_108_864.0;

/// At most this many edges left after cancellation are tried as one convex cycle.
const FAST_PATH_EDGES: usize = 64;

/// How the covered area is integrated once the edges are known.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Integration {
    /// The closed form when the edges form one convex cycle, slabs otherwise (the default).
    #[default]
    Auto,
    /// Always the slabs (to test them against the closed form).
    Slabs,
}

/// The visibility of a light's disk from one surface point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Visibility {
    /// The share of the disk's area the point sees past the casters, in `[0, 1]`.
    pub value: f64,
    /// `|value − true visibility| ≤ bound` (see the module's error bound). 0 when the value is
    /// exactly 0 or 1 (no edge separating seen from hidden comes near the disk).
    pub bound: f64,
    /// Casters whose BVH boxes met the pyramid from the point to the disk's square.
    pub casters: u32,
    /// Projected edges left after cancellation (silhouettes and the square's sides), all of
    /// them, inside the disk or not.
    pub edges: u32,
}

impl Visibility {
    /// Exactly 1: the point sees the whole disk.
    #[must_use]
    pub fn is_lit(&self) -> bool {
        self.value == 1.0 && self.bound == 0.0
    }

    /// Exactly 0: the point sees none of the disk.
    #[must_use]
    pub fn is_umbra(&self) -> bool {
        self.value == 0.0 && self.bound == 0.0
    }

    /// Strictly between 0 and 1, beyond the bound.
    #[must_use]
    pub fn is_penumbra(&self) -> bool {
        self.value - self.bound > 0.0 && self.value + self.bound < 1.0
    }

    const LIT: Self = Self {
        value: 1.0,
        bound: 0.0,
        casters: 0,
        edges: 0,
    };
}

/// The casters of a scene as the soft reference reads them: a BVH over the `f32` world
/// triangles of the surfaces that cast shadows, each with its global triangle index (surfaces
/// concatenated, what [`crate::SurfacePoint::triangle`] names). Build once per shot, query per
/// point and light.
#[derive(Debug, Clone)]
pub struct SoftCasters {
    bvh: Bvh,
    ids: Vec<u32>,
    /// `|eye|∞`: with the point's own magnitude, it sets the contact distance.
    eye: f64,
}

impl SoftCasters {
    /// The casters of `shot` (the same triangles and bits as the hard reference's).
    #[must_use]
    pub fn new(shot: &Shot<'_>) -> Self {
        let casts: Vec<bool> = shot.scene.surfaces().map(|s| s.casts_shadows).collect();
        let mut tris = Vec::new();
        let mut ids = Vec::new();
        let mut next = 0u32;
        for (oi, obj) in shot.triangles().iter().enumerate() {
            for t in obj {
                if casts[oi] {
                    tris.push(t.map(Vec3::as_dvec3));
                    ids.push(next);
                }
                next += 1;
            }
        }
        Self::build(tris, ids, shot.camera.eye.as_dvec3())
    }

    /// Casters from bare triangles; triangle `i`'s id is `i`. `eye` plays the camera's part in
    /// the contact distance (`CONTACT × (|P|∞ + |eye|∞)`, as in the hard reference).
    #[must_use]
    pub fn from_triangles(tris: &[[Vec3; 3]], eye: DVec3) -> Self {
        let ids = (0..tris.len() as u32).collect();
        Self::build(
            tris.iter().map(|t| t.map(Vec3::as_dvec3)).collect(),
            ids,
            eye,
        )
    }

    fn build(tris: Vec<[DVec3; 3]>, ids: Vec<u32>, eye: DVec3) -> Self {
        Self {
            bvh: Bvh::build_with_ids(tris, ids.clone()),
            ids,
            eye: eye.abs().max_element(),
        }
    }

    /// Number of caster triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when there is no caster.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// The visibility of `disk` from `point`, ignoring the caster with id `skip` (the point's
    /// own triangle; `u32::MAX` for none). See the module documentation. A disk or point that is
    /// not finite gives value 0 with bound 1 (nothing known).
    #[must_use]
    pub fn visibility(
        &self,
        disk: &LightDisk,
        point: DVec3,
        skip: u32,
        integration: Integration,
    ) -> Visibility {
        let contact = CONTACT * (point.abs().max_element() + self.eye);
        let Some(frame) = Frame::new(disk, point) else {
            return Visibility {
                value: 0.0,
                bound: 1.0,
                casters: 0,
                edges: 0,
            };
        };
        let mut edges = Vec::new();
        let mut casters = 0u32;
        let mut bad = false;
        self.bvh.visit_boxes(
            |lo, hi| frame.box_may_meet(lo, hi),
            |i| {
                if self.ids[i] == skip {
                    return false;
                }
                casters += 1;
                let tri = self.bvh.triangle(i);
                bad |= !frame.project(tri, contact, &mut edges);
                false
            },
        );
        if casters == 0 {
            return Visibility::LIT;
        }
        let merged = cancel(edges);
        let mut v = integrate(&merged, frame.r, integration);
        v.casters = casters;
        if bad {
            v.bound = v.bound.max(1.0);
        }
        v
    }
}

/// The visibility of `disk` from `point` among bare casters: [`SoftCasters::visibility`] of
/// [`SoftCasters::from_triangles`] with nothing skipped and the default integration. Builds
/// the BVH on every call; for many points build [`SoftCasters`] once.
#[must_use]
pub fn disk_visibility(
    tris: &[[Vec3; 3]],
    disk: &LightDisk,
    point: DVec3,
    eye: DVec3,
) -> Visibility {
    SoftCasters::from_triangles(tris, eye).visibility(disk, point, u32::MAX, Integration::Auto)
}

mod frame;
mod image;
mod integrate;

use frame::Frame;
pub use image::{
    compare_visibility, compare_with_reference, visibility_reference, visibility_reference_with,
    SoftComparison, SoftReference,
};
pub use integrate::polygon_disk_area;
use integrate::{cancel, integrate};
