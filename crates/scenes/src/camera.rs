//! The camera of the workspace: a pinhole in world space with an infinite far plane.

use glam::{DMat4, DVec3, Mat4, Vec3};

/// A pinhole camera in world space (right-handed, `y` up by default) with an infinite far
/// plane (shadow volumes need it): the one camera of the workspace, which files and presets fill
/// in and the renderer, the reference and the viewer use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position (world units).
    pub eye: Vec3,
    /// A point the camera looks at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction, must not be parallel to it).
    pub up: Vec3,
    /// Vertical field of view, radians, in `(0, π)`.
    pub fov_y: f32,
    /// Near-plane distance (world units, `> 0`). There is no far plane.
    pub near: f32,
}

/// Why a camera cannot be used (what [`Camera::validate`] found), in words.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidCamera(pub String);

impl Camera {
    /// A camera at `eye` looking at `target`, `y` up, 45° vertical field of view, near plane at
    /// 1/1000 of the eye-target distance.
    #[must_use]
    pub fn look_at(eye: Vec3, target: Vec3) -> Self {
        let d = (target - eye).length().max(1e-6);
        let up = if (target - eye).normalize_or_zero().abs().y > 0.999 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        Self {
            eye,
            target,
            up,
            fov_y: 45f32.to_radians(),
            near: d * 1e-3,
        }
    }

    /// Checks that the camera is usable: finite, eye apart from target, `up` not along the
    /// view direction, `fov_y` in `(0, π)`, `near > 0`.
    ///
    /// # Errors
    /// [`InvalidCamera`] naming the bad field.
    pub fn validate(&self) -> Result<(), InvalidCamera> {
        let finite = self.eye.is_finite()
            && self.target.is_finite()
            && self.up.is_finite()
            && self.fov_y.is_finite()
            && self.near.is_finite();
        if !finite {
            return Err(InvalidCamera(format!(
                "camera has a non-finite component: {self:?}"
            )));
        }
        if self.eye == self.target {
            return Err(InvalidCamera("camera eye equals its target".into()));
        }
        if (self.target - self.eye).cross(self.up).length_squared() == 0.0 {
            return Err(InvalidCamera(
                "camera up is parallel to the view direction".into(),
            ));
        }
        if !(self.fov_y > 0.0 && self.fov_y < std::f32::consts::PI) {
            return Err(InvalidCamera(format!(
                "camera fov_y is {} rad; it must be in (0, π)",
                self.fov_y
            )));
        }
        if self.near <= 0.0 {
            return Err(InvalidCamera(format!(
                "camera near is {}; it must be > 0",
                self.near
            )));
        }
        Ok(())
    }

    /// View matrix (world → camera), `f32`.
    #[must_use]
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up)
    }

    /// Projection with an infinite far plane and depth range `[0, 1]` (points with `w = 0` map
    /// to depth exactly 1), `f32`.
    #[must_use]
    pub fn projection(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective_infinite(self.fov_y, aspect, self.near)
    }

    /// `projection * view`, the matrix every pass uses.
    #[must_use]
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// The same matrices in `f64` (for the reference and the plan).
    #[must_use]
    pub fn view_proj_f64(&self, aspect: f64) -> DMat4 {
        let v = glam::dcamera::rh::view::look_at_mat4(
            self.eye.as_dvec3(),
            self.target.as_dvec3(),
            self.up.as_dvec3(),
        );
        glam::dcamera::rh::proj::directx::perspective_infinite(
            f64::from(self.fov_y),
            aspect,
            f64::from(self.near),
        ) * v
    }

    /// The four corners of the near-plane rectangle in world space (`f64`), counter-clockwise
    /// as seen from the eye: bottom-left, bottom-right, top-right, top-left.
    #[must_use]
    pub fn near_corners(&self, aspect: f64) -> [DVec3; 4] {
        let eye = self.eye.as_dvec3();
        let f = (self.target.as_dvec3() - eye).normalize();
        let r = f.cross(self.up.as_dvec3()).normalize();
        let u = r.cross(f);
        let n = f64::from(self.near);
        let h = n * (f64::from(self.fov_y) * 0.5).tan();
        let w = h * aspect;
        let c = eye + f * n;
        [
            c - r * w - u * h,
            c + r * w - u * h,
            c + r * w + u * h,
            c - r * w + u * h,
        ]
    }

    /// A camera that sees the axis-aligned box `[min, max]` whole, from the direction `from`
    /// (pointing from the box centre towards the eye), with a 45° vertical field of view.
    #[must_use]
    pub fn framing(min: Vec3, max: Vec3, from: Vec3) -> Self {
        let (centre, radius) = box_centre_radius(min, max);
        let radius = radius.max(1e-3);
        let fov_y = 45f32.to_radians();
        let distance = radius / (fov_y * 0.5).sin() * 1.05;
        let dir = from
            .try_normalize()
            .unwrap_or(Vec3::new(0.3, 0.5, 1.0).normalize());
        let up = if dir.cross(Vec3::Y).length_squared() < 1e-6 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        Self {
            eye: centre + dir * distance,
            target: centre,
            up,
            fov_y,
            near: (distance - radius).max(distance * 1e-3) * 0.5,
        }
    }
}

/// The centre and half the diagonal of the box `[lo, hi]`, computed so that neither overflows
/// while the result fits in `f32`: the centre as `lo / 2 + hi / 2` and the half diagonal in
/// `f64` (an `f32` [`Vec3::length`] overflows for extents beyond about 1.8e19). The half
/// diagonal is infinite only when it exceeds `f32::MAX`.
///
/// ```
/// use glam::Vec3;
/// // The extent, 6e38, is beyond f32::MAX: `hi - lo` would be infinite.
/// let (c, r) = shadowvol_scenes::box_centre_radius(Vec3::new(-3e38, 0.0, 0.0), Vec3::new(3e38, 0.0, 0.0));
/// assert_eq!(c, Vec3::ZERO);
/// assert_eq!(r, 3e38);
/// ```
#[must_use]
pub fn box_centre_radius(lo: Vec3, hi: Vec3) -> (Vec3, f32) {
    let centre = lo * 0.5 + hi * 0.5;
    let radius = (hi.as_dvec3() - lo.as_dvec3()).length() * 0.5;
    (centre, radius as f32)
}
