//! What the user steers: an orbit camera, the light, the accuracy mode, the technique policy
//! and how the volumes are shown. Pure state, no window: the keys and drags map to these
//! methods, and tests call them directly.

use glam::Vec3;
use shadowvol_renderer::{Accuracy, Camera, Light, PlanPolicy};

/// How the shadow volumes themselves are drawn over the image.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum VolumeView {
    /// Not at all.
    #[default]
    Hidden,
    /// Translucent sides and caps (overlaps darken, so cracks and gaps show).
    Translucent,
    /// Every volume triangle's edges.
    Wire,
}

impl VolumeView {
    /// The next one in the cycle hidden → translucent → wire → hidden.
    #[must_use]
    pub fn next(self) -> Self {
        match self {
            Self::Hidden => Self::Translucent,
            Self::Translucent => Self::Wire,
            Self::Wire => Self::Hidden,
        }
    }

    /// Its name on screen.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Hidden => "hidden",
            Self::Translucent => "translucent",
            Self::Wire => "wire",
        }
    }
}

/// The next technique policy in the cycle auto → z-pass → z-fail → auto.
#[must_use]
pub fn next_policy(p: PlanPolicy) -> PlanPolicy {
    match p {
        PlanPolicy::Auto => PlanPolicy::AlwaysZPass,
        PlanPolicy::AlwaysZPass => PlanPolicy::AlwaysZFail,
        PlanPolicy::AlwaysZFail => PlanPolicy::Auto,
    }
}

/// The policy's name on screen.
#[must_use]
pub fn policy_name(p: PlanPolicy) -> &'static str {
    match p {
        PlanPolicy::Auto => "auto",
        PlanPolicy::AlwaysZPass => "z-pass",
        PlanPolicy::AlwaysZFail => "z-fail",
    }
}

/// The mode of keys 1–4: original, ordered, robust, exact.
#[must_use]
pub fn mode_of_key(k: u8) -> Option<Accuracy> {
    match k {
        1 => Some(Accuracy::Original),
        2 => Some(Accuracy::Ordered),
        3 => Some(Accuracy::Robust),
        4 => Some(Accuracy::Exact),
        _ => None,
    }
}

/// An orbit camera around a target: yaw about `+y`, pitch above the horizon, distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// The point the camera looks at and orbits (world units).
    pub target: Vec3,
    /// Angle about `+y`, radians (0: the eye on `+z`).
    pub yaw: f32,
    /// Angle above the horizontal plane, radians, within `±89°`.
    pub pitch: f32,
    /// Eye–target distance (world units, `> 0`).
    pub distance: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Near plane as a fraction of the distance.
    pub near_fraction: f32,
}

const MAX_PITCH: f32 = 89f32 * std::f32::consts::PI / 180.0;

impl Orbit {
    /// The orbit that reproduces `camera` (its eye, target and field of view; up is `+y`).
    #[must_use]
    pub fn from_camera(camera: &Camera) -> Self {
        let d = camera.eye - camera.target;
        let distance = d.length().max(1e-6);
        let pitch = (d.y / distance)
            .clamp(-1.0, 1.0)
            .asin()
            .clamp(-MAX_PITCH, MAX_PITCH);
        let yaw = d.x.atan2(d.z);
        Self {
            target: camera.target,
            yaw,
            pitch,
            distance,
            fov_y: camera.fov_y,
            near_fraction: (camera.near / distance).clamp(1e-5, 0.5),
        }
    }

    /// The eye position.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(sy * cp, sp, cy * cp)
    }

    /// The renderer's camera for this orbit.
    #[must_use]
    pub fn camera(&self) -> Camera {
        Camera {
            eye: self.eye(),
            target: self.target,
            up: Vec3::Y,
            fov_y: self.fov_y,
            near: self.distance * self.near_fraction,
        }
    }

    /// Orbits by a drag of `(dx, dy)` pixels (a full window width turns by about 180°).
    pub fn rotate(&mut self, dx: f32, dy: f32, window_height: f32) {
        let k = std::f32::consts::PI / window_height.max(1.0);
        self.yaw -= dx * k;
        self.pitch = (self.pitch + dy * k).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Pans the target in the view plane by a drag of `(dx, dy)` pixels, so that the point under
    /// the cursor at the target's depth follows it.
    pub fn pan(&mut self, dx: f32, dy: f32, window_height: f32) {
        let cam = self.camera();
        let f = (cam.target - cam.eye).normalize();
        let r = f.cross(Vec3::Y).normalize_or(Vec3::X);
        let u = r.cross(f);
        let per_pixel = 2.0 * self.distance * (self.fov_y * 0.5).tan() / window_height.max(1.0);
        self.target += (-dx * r + dy * u) * per_pixel;
    }

    /// Zooms by `steps` wheel notches (positive: closer), 10 % per notch.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).max(1e-4);
    }
}

/// Moves a light about the vertical axis through `centre` by `yaw` radians and raises it by
/// `pitch` radians (kept within ±89° of the horizon): a point light keeps its distance from
/// `centre`, a directional light its direction's length. The `w` stays as it is.
#[must_use]
pub fn orbit_light(light: Light, centre: Vec3, yaw: f32, pitch: f32) -> Light {
    let [x, y, z, w] = light.to_array();
    let v = if w == 0.0 {
        Vec3::new(x, y, z)
    } else {
        Vec3::new(x, y, z) / w - centre
    };
    let len = v.length();
    if len == 0.0 || !len.is_finite() {
        return light;
    }
    let el = (v.y / len).clamp(-1.0, 1.0).asin();
    let az = v.x.atan2(v.z) + yaw;
    let el = (el + pitch).clamp(-MAX_PITCH, MAX_PITCH);
    let dir = Vec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos()) * len;
    let p = if w == 0.0 { dir } else { (centre + dir) * w };
    Light::new(p.x, p.y, p.z, w).unwrap_or(light)
}

/// The next radius of a light of radius `radius` after the key `]` (`grow`) or `[`: doubled
/// or halved, starting from `start` (a size for the scene: world units for a point light,
/// radians for a directional one) at 0 and back to 0 below a sixteenth of it; a directional
/// light's stays under 0.5 rad.
#[must_use]
pub fn step_radius(radius: f32, start: f32, grow: bool, directional: bool) -> f32 {
    let r = match (grow, radius == 0.0) {
        (true, true) => start,
        (true, false) => radius * 2.0,
        (false, _) if radius <= start / 16.0 => 0.0,
        (false, _) => radius * 0.5,
    };
    if directional {
        r.min(0.5)
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_steps_double_halve_and_reach_zero() {
        assert_eq!(step_radius(0.0, 0.1, true, false), 0.1);
        assert_eq!(step_radius(0.1, 0.1, true, false), 0.2);
        assert_eq!(step_radius(0.2, 0.1, false, false), 0.1);
        assert_eq!(step_radius(0.1 / 16.0, 0.1, false, false), 0.0);
        assert_eq!(step_radius(0.0, 0.1, false, false), 0.0);
        assert_eq!(step_radius(0.4, 0.1, true, true), 0.5);
    }

    #[test]
    fn an_orbit_reproduces_its_camera() {
        let cam = Camera::look_at(Vec3::new(3.0, 4.0, 5.0), Vec3::new(0.5, 0.0, -1.0));
        let o = Orbit::from_camera(&cam);
        assert!(
            (o.eye() - cam.eye).length() < 1e-4,
            "{} vs {}",
            o.eye(),
            cam.eye
        );
        assert!((o.camera().near - cam.near).abs() < 1e-6);
    }

    #[test]
    fn rotate_pan_zoom_move_the_eye_as_expected() {
        let mut o = Orbit::from_camera(&Camera::look_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO));
        o.zoom(1.0);
        assert!((o.distance - 9.0).abs() < 1e-5);
        o.rotate(0.0, 1e6, 100.0);
        assert!(o.pitch <= MAX_PITCH && o.eye().y > 8.9);
        let before = o.target;
        o.pan(10.0, 0.0, 100.0);
        assert!((o.target - before).length() > 0.0 && (o.target.y - before.y).abs() < 1e-3);
    }

    #[test]
    fn orbiting_a_light_keeps_its_distance_and_w() {
        let l = Light::point(Vec3::new(0.0, 5.0, 5.0));
        let m = orbit_light(l, Vec3::ZERO, 0.5, 0.1).to_array();
        assert_eq!(m[3], 1.0);
        let len = Vec3::new(m[0], m[1], m[2]).length();
        assert!((len - 50f32.sqrt()).abs() < 1e-4);
        let d = orbit_light(
            Light::directional(Vec3::new(1.0, 1.0, 0.0)),
            Vec3::ONE,
            1.0,
            0.0,
        );
        assert_eq!(d.to_array()[3], 0.0);
        assert!((d.to_array()[1] - 1.0).abs() < 1e-5);
    }

    #[test]
    fn keys_and_cycles() {
        assert_eq!(mode_of_key(4), Some(Accuracy::Exact));
        assert_eq!(mode_of_key(5), None);
        let mut p = PlanPolicy::Auto;
        for _ in 0..3 {
            p = next_policy(p);
        }
        assert_eq!(p, PlanPolicy::Auto);
        assert_eq!(VolumeView::Wire.next(), VolumeView::Hidden);
    }
}
