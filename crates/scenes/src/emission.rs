//! What a light emits, as glTF's `KHR_lights_punctual` defines it: colour, intensity, range and
//! spot cone. The light's position or direction stays a [`shadowvol_robust_math::Light`]; this is
//! the rest, which only lighting (not silhouettes or shadow volumes) depends on.
//!
//! Every function here is the one definition the renderer's lit pass (in WGSL, in `f32`) and
//! its ray-traced reference (in `f64`) both follow.

use glam::{Affine3A, DVec3, Vec3};

/// The cone of a spot light (glTF `spot`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpotCone {
    /// The direction the light shines in, world space, unit length (glTF: the node's `-Z`).
    pub direction: Vec3,
    /// Angle from the axis where the falloff begins, radians, in `[0, outer)`.
    pub inner_cone_angle: f32,
    /// Angle from the axis where the light reaches zero, radians, in `(inner, π/2]`.
    pub outer_cone_angle: f32,
}

impl SpotCone {
    /// glTF's angular attenuation at `cos_angle` (the cosine between the axis and the direction
    /// from the light to the point): `s = saturate(cos_angle · scale + offset)` with
    /// `scale = 1 / max(0.001, cos inner − cos outer)` and `offset = −cos outer · scale`, then
    /// `s²`. 1 inside the inner cone, 0 outside the outer one, a smooth falloff between.
    #[must_use]
    pub fn attenuation(&self, cos_angle: f64) -> f64 {
        let (scale, offset) = self.scale_offset();
        let s = (cos_angle * f64::from(scale) + f64::from(offset)).clamp(0.0, 1.0);
        s * s
    }

    /// The `(scale, offset)` pair of [`SpotCone::attenuation`] in `f32`, as the shader gets it.
    #[must_use]
    pub fn scale_offset(&self) -> (f32, f32) {
        let (ci, co) = (self.inner_cone_angle.cos(), self.outer_cone_angle.cos());
        let scale = 1.0 / (ci - co).max(0.001);
        (scale, -co * scale)
    }
}

/// What one light emits (glTF `KHR_lights_punctual`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Emission {
    /// Linear RGB colour, each channel in `[0, 1]` (glTF `color`, default white).
    pub color: [f32; 3],
    /// glTF `intensity` (default 1): luminous intensity in candela for point and spot lights,
    /// illuminance in lux for directional lights.
    pub intensity: f32,
    /// glTF `range` in world units: the falloff reaches zero there. `None`: unbounded. Ignored
    /// for directional lights.
    pub range: Option<f32>,
    /// The cone, for a spot light.
    pub spot: Option<SpotCone>,
}

impl Default for Emission {
    /// glTF's defaults: a white point light of intensity 1 with no range and no cone.
    fn default() -> Self {
        Self {
            color: [1.0; 3],
            intensity: 1.0,
            range: None,
            spot: None,
        }
    }
}

impl Emission {
    /// The illuminance factor at distance `d` from a point or spot light, before the cone:
    /// glTF's recommended `saturate(1 − (d / range)⁴) / d²` (`1 / d²` without a range). `d`
    /// in world units; the result times [`Emission::intensity`] is in lux.
    #[must_use]
    pub fn distance_falloff(&self, d: f64) -> f64 {
        let d2 = (d * d).max(1e-300);
        let window = self.range.map_or(1.0, |r| {
            let q = d / f64::from(r);
            (1.0 - q * q * q * q).clamp(0.0, 1.0)
        });
        window / d2
    }

    /// How much of [`Emission::intensity`] reaches world point `p` from light `light`
    /// (homogeneous `[x, y, z, w]`): [`Emission::distance_falloff`] times the cone's
    /// [`SpotCone::attenuation`] for a point or spot light (`w ≠ 0`; at `xyz / w`), and 1 for a
    /// directional light (`w = 0`).
    #[must_use]
    pub fn attenuation(&self, light: [f32; 4], p: DVec3) -> f64 {
        if light[3] == 0.0 {
            return 1.0;
        }
        let pos =
            DVec3::new(light[0].into(), light[1].into(), light[2].into()) / f64::from(light[3]);
        let to_p = p - pos;
        let d = to_p.length();
        let cone = self.spot.map_or(1.0, |s| {
            let cos = if d > 0.0 {
                to_p.dot(s.direction.as_dvec3()) / d
            } else {
                1.0
            };
            s.attenuation(cos)
        });
        self.distance_falloff(d) * cone
    }

    /// Why light `light` cannot light anything in the axis-aligned box `[lo, hi]`, nor the
    /// shadow that anything in it casts, or `None` when it may: the box lies wholly beyond the
    /// range, or wholly outside the outer cone. Both hold for the shadow as well: it lies on the
    /// same rays from the light, farther out. Conservative (box as its bounding sphere for the
    /// cone).
    #[must_use]
    pub fn unreachable(&self, light: [f32; 4], lo: DVec3, hi: DVec3) -> Option<&'static str> {
        if light[3] == 0.0 {
            return None;
        }
        let pos =
            DVec3::new(light[0].into(), light[1].into(), light[2].into()) / f64::from(light[3]);
        if let Some(r) = self.range {
            let nearest = pos.clamp(lo, hi);
            if (nearest - pos).length() >= f64::from(r) {
                return Some("beyond the light's range");
            }
        }
        if let Some(s) = self.spot {
            let centre = (lo + hi) * 0.5;
            let radius = (hi - lo).length() * 0.5;
            let to_c = centre - pos;
            let d = to_c.length();
            if d > radius {
                let axis = s.direction.as_dvec3().normalize_or_zero();
                let angle = (to_c.dot(axis) / d).clamp(-1.0, 1.0).acos();
                let half = (radius / d).asin();
                if angle - half > f64::from(s.outer_cone_angle) {
                    return Some("outside the spot light's cone");
                }
            }
        }
        None
    }
}

/// A glTF light's [`Emission`] (`world`: its node's world transform), checked: finite colour in `[0, 1]`, finite intensity `>= 0`,
/// range `> 0`, cone angles with `0 <= inner < outer <= π/2`.
pub(crate) fn from_gltf(
    light: &gltf::khr_lights_punctual::Light<'_>,
    world: &Affine3A,
) -> Result<Emission, String> {
    let color = light.color();
    if !color
        .iter()
        .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
    {
        return Err(format!("color {color:?}: each channel must be in [0, 1]"));
    }
    let intensity = light.intensity();
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(format!("intensity {intensity}: must be finite and >= 0"));
    }
    let range = light.range();
    if let Some(r) = range {
        if !(r.is_finite() && r > 0.0) {
            return Err(format!("range {r}: must be > 0"));
        }
    }
    let spot = match light.kind() {
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let ok = inner_cone_angle >= 0.0
                && inner_cone_angle < outer_cone_angle
                && outer_cone_angle <= std::f32::consts::FRAC_PI_2;
            if !ok {
                return Err(format!(
                    "spot cone angles inner {inner_cone_angle}, outer {outer_cone_angle}: \
                     need 0 <= inner < outer <= pi/2"
                ));
            }
            let direction = (-Vec3::from(world.matrix3.z_axis)).normalize_or_zero();
            if direction == Vec3::ZERO {
                return Err("the spot light's node has no -Z direction".into());
            }
            Some(SpotCone {
                direction,
                inner_cone_angle,
                outer_cone_angle,
            })
        }
        _ => None,
    };
    Ok(Emission {
        color,
        intensity,
        range,
        spot,
    })
}

#[cfg(test)]
mod tests {
    use super::{Emission, SpotCone};
    use glam::{DVec3, Vec3};

    fn spot() -> Emission {
        Emission {
            spot: Some(SpotCone {
                direction: Vec3::NEG_Y,
                inner_cone_angle: 0.2,
                outer_cone_angle: 0.4,
            }),
            ..Emission::default()
        }
    }

    #[test]
    fn falloff_is_inverse_square_and_reaches_zero_at_the_range() {
        let e = Emission::default();
        assert!((e.distance_falloff(2.0) - 0.25).abs() < 1e-15);
        let r = Emission {
            range: Some(4.0),
            ..e
        };
        assert_eq!(r.distance_falloff(4.0), 0.0);
        assert_eq!(r.distance_falloff(5.0), 0.0);
        let half = r.distance_falloff(2.0);
        assert!((half - (1.0 - 1.0 / 16.0) / 4.0).abs() < 1e-15, "{half}");
    }

    #[test]
    fn the_cone_is_one_inside_zero_outside_and_smooth_between() {
        let e = spot();
        let l = [0.0, 10.0, 0.0, 1.0];
        let below = |x: f64| {
            let p = DVec3::new(x, 0.0, 0.0);
            e.attenuation(l, p) / e.distance_falloff(p.distance(DVec3::new(0.0, 10.0, 0.0)))
        };
        assert!((below(0.0) - 1.0).abs() < 1e-12);
        assert!((below(10.0 * 0.19f64.tan()) - 1.0).abs() < 1e-12);
        assert_eq!(below(10.0 * 0.41f64.tan()), 0.0);
        let mid = below(10.0 * 0.3f64.tan());
        assert!(mid > 0.05 && mid < 0.95, "{mid}");
        // Behind the light.
        assert_eq!(e.attenuation(l, DVec3::new(0.0, 20.0, 0.0)), 0.0);
    }

    #[test]
    fn unreachable_boxes_are_named() {
        let l = [0.0, 10.0, 0.0, 1.0];
        let lo = DVec3::new(8.0, 0.0, -1.0);
        let hi = DVec3::new(9.0, 1.0, 1.0);
        assert_eq!(
            spot().unreachable(l, lo, hi),
            Some("outside the spot light's cone")
        );
        assert_eq!(spot().unreachable(l, -hi, hi), None);
        let ranged = Emission {
            range: Some(5.0),
            ..Emission::default()
        };
        assert_eq!(
            ranged.unreachable(l, lo, hi),
            Some("beyond the light's range")
        );
        assert_eq!(
            ranged.unreachable(l, DVec3::splat(-1.0), DVec3::new(1.0, 6.0, 1.0)),
            None
        );
        assert_eq!(ranged.unreachable([0.0, 1.0, 0.0, 0.0], lo, hi), None);
    }
}
