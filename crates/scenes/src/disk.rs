//! Lights with a size: the disk a light's samples lie on, and the samples.
//!
//! A point or spot light of radius `r` is a disk of radius `r` (world units) centred on the
//! light: a point light's disk faces the scene's bounding-box centre ([`crate::Scene::light_aim`]),
//! a spot light's faces along its axis. A directional light of angular radius `θ` is the cone of
//! directions within `θ` of its direction; its "disk" lies in the plane tangent to the unit
//! sphere at the direction, with radius `tan θ`, so that a direction is a point of that disk
//! and the share of the cone a point sees is the share of that disk (the measure every sampler
//! and the reference use).

use glam::{DVec3, Vec3};
use shadowvol_robust_math::Light;

/// The golden angle in radians, `π (3 − √5)`: the turn between consecutive samples of
/// [`LightDisk::samples`].
pub const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// The disk of a light with a size ([`crate::SceneLight::disk`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightDisk {
    /// The disk's centre: a point light's position, or a directional light's unit direction
    /// (towards the light).
    pub centre: DVec3,
    /// A unit vector in the disk's plane.
    pub u: DVec3,
    /// The unit vector `normal × u`, in the disk's plane.
    pub v: DVec3,
    /// The unit normal of the disk: from the light towards the scene (point), along the spot
    /// axis (spot), or minus the direction (directional).
    pub normal: DVec3,
    /// The radius in the disk's plane: world units, or `tan θ` for a directional light.
    pub radius: f64,
    /// True for a directional light (`w = 0`): disk points are directions.
    pub directional: bool,
}

/// Checks a radius for `light`: finite, not negative, and under π/2 for a directional light.
pub(crate) fn check_radius(light: Light, radius: f32) -> Result<(), String> {
    if !radius.is_finite() || radius < 0.0 {
        return Err(format!(
            "radius {radius}: it must be a finite number of at least 0"
        ));
    }
    if light.to_array()[3] == 0.0 && f64::from(radius) >= std::f64::consts::FRAC_PI_2 {
        return Err(format!(
            "radius {radius}: a directional light's radius is an angle in radians, under π/2"
        ));
    }
    Ok(())
}

impl LightDisk {
    /// The disk of `light` aimed at `aim`; `None` for radius 0 (or a radius that is not a
    /// valid size: negative, not finite, a directional one of π/2 or more).
    #[must_use]
    pub fn of(light: &crate::SceneLight, aim: Vec3) -> Option<Self> {
        if light.radius == 0.0 || check_radius(light.light, light.radius).is_err() {
            return None;
        }
        let [x, y, z, w] = light.light.to_array().map(f64::from);
        let directional = w == 0.0;
        let (centre, normal) = if directional {
            let d = DVec3::new(x, y, z).normalize();
            (d, -d)
        } else {
            let c = DVec3::new(x, y, z) / w;
            let spot = light
                .emission
                .and_then(|e| e.spot)
                .map(|s| s.direction.as_dvec3());
            let n = spot
                .unwrap_or(aim.as_dvec3() - c)
                .normalize_or(DVec3::NEG_Y);
            (c, n)
        };
        let helper = if normal.y.abs() < 0.9 {
            DVec3::Y
        } else {
            DVec3::X
        };
        let u = normal.cross(helper).normalize();
        let v = normal.cross(u);
        let r = f64::from(light.radius);
        let radius = if directional { r.tan() } else { r };
        Some(Self {
            centre,
            u,
            v,
            normal,
            radius,
            directional,
        })
    }

    /// The point at `(a, b)` in the disk's own coordinates (`centre + a u + b v`).
    #[must_use]
    pub fn point(&self, a: f64, b: f64) -> DVec3 {
        self.centre + a * self.u + b * self.v
    }

    /// Sample `i` of `n` in the disk's coordinates: a Vogel (golden-angle) spiral, radius
    /// `R √((i + ½) / n)` at angle `i ×` [`GOLDEN_ANGLE`]: a low-discrepancy pattern with equal
    /// area per sample, fixed for the light.
    #[must_use]
    pub fn sample_offset(&self, i: u32, n: u32) -> (f64, f64) {
        let r = self.radius * ((f64::from(i) + 0.5) / f64::from(n.max(1))).sqrt();
        let a = f64::from(i) * GOLDEN_ANGLE;
        (r * a.cos(), r * a.sin())
    }

    /// `n` lights sampling the disk ([`LightDisk::sample_offset`]), rounded to `f32`: points
    /// (`w = 1`) or directions (`w = 0`, not normalised). Every sample's shadow is a hard
    /// shadow of that light, exactly as a point light there casts it.
    ///
    /// # Panics
    /// Never for a disk made by [`LightDisk::of`] of a finite light: the samples are finite.
    #[must_use]
    pub fn samples(&self, n: u32) -> Vec<Light> {
        let w = if self.directional { 0.0 } else { 1.0 };
        (0..n.max(1))
            .map(|i| {
                let (a, b) = self.sample_offset(i, n);
                let p = self.point(a, b).as_vec3();
                Light::new(p.x, p.y, p.z, w).expect("a finite sample")
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SceneLight;

    #[test]
    fn samples_lie_on_the_disk_and_spread() {
        let mut l = SceneLight::unit(Light::point(Vec3::new(0.0, 10.0, 0.0)));
        l.radius = 0.5;
        let d = l.disk(Vec3::ZERO).expect("a disk");
        assert!((d.normal - DVec3::NEG_Y).length() < 1e-12);
        let s = l.samples(64, Vec3::ZERO);
        assert_eq!(s.len(), 64);
        let mut mean = DVec3::ZERO;
        for x in &s {
            let [px, py, pz, _] = x.to_array().map(f64::from);
            let p = DVec3::new(px, py, pz);
            assert!((p.y - 10.0).abs() < 1e-6, "in the disk's plane: {p}");
            assert!(
                (p - d.centre).length() <= 0.5 + 1e-6,
                "inside the disk: {p}"
            );
            mean += p;
        }
        mean /= 64.0;
        // An equal-area spiral is centred on the disk to well under a sample's spacing.
        assert!((mean - d.centre).length() < 0.05, "mean {mean}");
        // Not all at the centre: the spread is near the disk's (r² / 2 for a uniform disk).
        let spread = s
            .iter()
            .map(|x| {
                let a = x.to_array();
                f64::from(a[0]).powi(2) + f64::from(a[2]).powi(2)
            })
            .sum::<f64>()
            / 64.0;
        assert!((spread - 0.125).abs() < 0.01, "spread {spread}");
    }

    #[test]
    fn one_sample_or_radius_zero_is_the_light() {
        let light = Light::point(Vec3::new(1.0, 2.0, 3.0));
        let mut l = SceneLight::unit(light);
        assert_eq!(l.samples(16, Vec3::ZERO), vec![light]);
        l.radius = 0.25;
        assert_eq!(l.samples(1, Vec3::ZERO), vec![light]);
        assert_eq!(l.samples(4, Vec3::ZERO).len(), 4);
    }

    #[test]
    fn directional_samples_are_within_the_angle() {
        let mut l = SceneLight::unit(Light::directional(Vec3::new(0.3, 1.0, 0.2)));
        l.radius = 0.1;
        let dir = Vec3::new(0.3, 1.0, 0.2).normalize();
        for s in l.samples(32, Vec3::ZERO) {
            let a = s.to_array();
            assert_eq!(a[3], 0.0);
            let v = Vec3::new(a[0], a[1], a[2]).normalize();
            assert!(v.dot(dir).acos() <= 0.1 + 1e-5);
        }
    }

    #[test]
    fn bad_radii_are_refused() {
        let p = Light::point(Vec3::ONE);
        let d = Light::directional(Vec3::Y);
        assert!(check_radius(p, -1.0).is_err());
        assert!(check_radius(p, f32::NAN).is_err());
        assert!(check_radius(d, 2.0).is_err());
        assert!(check_radius(p, 2.0).is_ok());
    }

    #[test]
    fn gltf_extras_radius_round_trips_and_bad_ones_are_named() {
        let mut scene = crate::preset("hard-edge-on-axis-grid").expect("a preset");
        scene.set_light_radius(0.125).expect("a valid radius");
        let glb = crate::to_glb(&scene).expect("exports");
        let back = crate::load_gltf_slice(&glb, "t.glb", None).expect("loads");
        assert!(!back.lights.is_empty());
        assert!(back.lights.iter().all(|l| l.radius == 0.125));
        // The same bytes with the radius made negative (same length, so the GLB stays valid).
        let (from, to) = (b"\"radius\":0.125", b"\"radius\":-0.50");
        let at = glb
            .windows(from.len())
            .position(|w| w == from)
            .expect("the radius is written");
        let mut bad = glb.clone();
        bad[at..at + to.len()].copy_from_slice(to);
        let err = crate::load_gltf_slice(&bad, "t.glb", None).expect_err("negative");
        assert!(err.to_string().contains("extras.radius"), "{err}");
        assert!(scene.set_light_radius(f32::INFINITY).is_err());
    }
}
