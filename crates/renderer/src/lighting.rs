//! Light gains and exposure: how bright each light's lit pass is, in the renderer and in the
//! reference alike.
//!
//! A light without an [`Emission`](shadowvol_scenes::Emission) (presets, `--light`, the default key light) is a unit light:
//! white, no distance falloff, gain `min(1.2 / lights, 0.85)`, so that several lights together
//! do not burn out. A light with one (glTF `KHR_lights_punctual`) adds
//! `albedo × colour × intensity × attenuation × exposure × cos θ`, where the attenuation is
//! glTF's range window over `d²` and the cone's falloff ([`Emission::attenuation`](shadowvol_scenes::Emission::attenuation)).
//!
//! [`Exposure::Auto`] scales so that the brightest light's nominal illuminance at the centre of
//! the scene's bounds (intensity over distance², lux for directional lights; range and cone left
//! out, so that they change the image and not the exposure) gives [`AUTO_TARGET`] of the unit
//! light's gain. It
//! keeps images neither black nor burnt out whatever units a file uses; the ratios between
//! lights, the distance falloff, range, cone and colour all show. [`Exposure::Fixed`] sets the
//! factor per lux, so that a light's intensity shows in absolute terms too.

use crate::RenderScene;

/// How lux map to the lit pass's output (linear, `1.0` = full 8-bit white on a white albedo).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Exposure {
    /// From the scene: see the [module docs](self).
    #[default]
    Auto,
    /// Output per lux (finite, `> 0`).
    Fixed(f32),
}

/// [`Exposure::Auto`]: the brightest light's nominal illuminance at the scene's centre gives
/// this fraction of a unit light's gain, leaving headroom for surfaces nearer the light.
pub const AUTO_TARGET: f64 = 0.6;

/// The gain of a unit light (no [`Emission`](shadowvol_scenes::Emission)) among `n` lights.
#[must_use]
pub fn unit_gain(n: usize) -> f32 {
    (1.2 / n.max(1) as f32).min(0.85)
}

/// The exposure factor (output per lux) [`Exposure::Auto`] picks for `scene`, or the fixed one;
/// `None` when no light has an [`Emission`](shadowvol_scenes::Emission).
#[must_use]
pub fn exposure_factor(scene: &RenderScene, exposure: Exposure) -> Option<f32> {
    if scene.emission.is_empty() {
        return None;
    }
    if let Exposure::Fixed(x) = exposure {
        return Some(x);
    }
    let centre = scene
        .bounds()
        .map_or(glam::DVec3::ZERO, |(lo, hi)| ((lo + hi) * 0.5).as_dvec3());
    let nominal = scene
        .lights
        .iter()
        .zip(&scene.emission)
        .map(|(l, e)| {
            let l = l.to_array();
            let i = f64::from(e.intensity) * f64::from(e.color.iter().copied().fold(0.0, f32::max));
            if l[3] == 0.0 {
                i
            } else {
                let p = glam::DVec3::new(l[0].into(), l[1].into(), l[2].into()) / f64::from(l[3]);
                i / p.distance_squared(centre).max(1e-300)
            }
        })
        .fold(0.0, f64::max);
    let x = if nominal > 0.0 {
        AUTO_TARGET * f64::from(unit_gain(scene.lights.len())) / nominal
    } else {
        1.0
    };
    Some(x as f32)
}

/// Per light: its colour times its gain, the `rgb` its lit pass multiplies by `albedo × cos θ`
/// (and, for an [`Emission`](shadowvol_scenes::Emission), by the attenuation at the surface point).
#[must_use]
pub fn light_colors(scene: &RenderScene, exposure: Option<f32>) -> Vec<[f32; 3]> {
    let n = scene.lights.len();
    (0..n)
        .map(|li| match (scene.emission.get(li), exposure) {
            (Some(e), Some(x)) => e.color.map(|c| c * e.intensity * x),
            _ => [unit_gain(n); 3],
        })
        .collect()
}

/// Checks `scene.emission`: empty or one per light, each finite.
///
/// # Errors
/// A message naming the light.
pub fn validate(scene: &RenderScene, exposure: Exposure) -> Result<(), String> {
    if let Exposure::Fixed(x) = exposure {
        if !(x.is_finite() && x > 0.0) {
            return Err(format!("exposure {x}: it must be finite and > 0"));
        }
    }
    if !scene.emission.is_empty() && scene.emission.len() != scene.lights.len() {
        return Err(format!(
            "{} emissions for {} lights: give none or one per light",
            scene.emission.len(),
            scene.lights.len()
        ));
    }
    for (i, e) in scene.emission.iter().enumerate() {
        let ok = e.color.iter().all(|c| c.is_finite() && *c >= 0.0)
            && e.intensity.is_finite()
            && e.intensity >= 0.0
            && e.range.is_none_or(|r| r.is_finite() && r > 0.0)
            && e.spot.is_none_or(|s| {
                s.direction.is_finite()
                    && s.direction.length_squared() > 0.0
                    && s.inner_cone_angle >= 0.0
                    && s.inner_cone_angle < s.outer_cone_angle
                    && s.outer_cone_angle <= std::f32::consts::FRAC_PI_2
            });
        if !ok {
            return Err(format!("light {i}: invalid emission {e:?}"));
        }
    }
    Ok(())
}
