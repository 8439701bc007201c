//! Light gains and exposure: how bright each light's lit pass is, in the renderer and in the
//! reference alike.
//!
//! A light without an [`Emission`](shadowvol_scenes::Emission) (presets, `--light`, the default key light) is a unit light:
//! white, no distance falloff, gain `min(1.2 / lights, 0.85)`, so that several lights together
//! do not burn out. A light with one (glTF `KHR_lights_punctual`) adds
//! `albedo × colour × intensity × attenuation × exposure × cos θ`, where the attenuation is
//! glTF's range window over `d²` and the cone's falloff ([`Emission::attenuation`](shadowvol_scenes::Emission::attenuation)).
//!
//! [`Exposure::Auto`] meters what the camera sees, like a camera's light meter
//! ([`ExposureMeter`]): a grid of [`METER_GRID`] rays from the camera finds the visible surface
//! points, and the illuminance the lights with an emission bring to each (colour × intensity ×
//! attenuation × cos θ, shadows left out) is measured. The [`METER_PERCENTILE`] of the lit
//! points gives [`AUTO_TARGET`] of the unit light's gain: most of what is lit in view is well
//! exposed, and only the brightest tenth (a hot spot under a light close to a surface) may
//! saturate. It keeps images neither black nor burnt out whatever units a file uses; the ratios
//! between lights, the distance falloff, range, cone and colour all show. When no metered point
//! is lit, the brightest light's nominal illuminance at the centre of the scene's bounds is used
//! instead ([`exposure_factor`]). [`Exposure::Fixed`] sets the factor per lux, so that a light's
//! intensity shows in absolute terms too.

use crate::nearest::NearestHit;
use crate::world::{World, WorldChanges};
use crate::Camera;
use glam::{DMat4, DVec3, DVec4};
use shadowvol_scenes::{Scene, SceneLight};

/// How lux map to the lit pass's output (linear, `1.0` = full 8-bit white on a white albedo).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Exposure {
    /// From the scene: see the [module docs](self).
    #[default]
    Auto,
    /// Output per lux (finite, `> 0`).
    Fixed(f32),
}

/// [`Exposure::Auto`]: the metered illuminance ([`METER_PERCENTILE`] of the lit points in view)
/// gives this fraction of a unit light's gain, leaving headroom for the brighter points.
pub const AUTO_TARGET: f64 = 0.6;

/// The metering grid: this many rays across the view's wider side (and as many as the aspect
/// gives across the other).
pub const METER_GRID: u32 = 64;

/// The percentile of the lit points' illuminance that [`Exposure::Auto`] exposes for.
pub const METER_PERCENTILE: f64 = 0.9;

/// The gain of a unit light (no [`Emission`](shadowvol_scenes::Emission)) among `n` lights.
#[must_use]
pub fn unit_gain(n: usize) -> f32 {
    (1.2 / n.max(1) as f32).min(0.85)
}

/// The exposure factor from the illuminance the lights with an emission bring to `samples`,
/// visible surface points with their normals turned towards the camera: [`AUTO_TARGET`] of the
/// unit gain over the [`METER_PERCENTILE`] of the lit ones; `None` when none is lit.
#[must_use]
pub fn metered_factor(lights: &[SceneLight], samples: &[(DVec3, DVec3)]) -> Option<f32> {
    let mut lit: Vec<f64> = samples
        .iter()
        .map(|&(p, n)| illuminance(lights, p, n))
        .filter(|&e| e > 0.0 && e.is_finite())
        .collect();
    if lit.is_empty() {
        return None;
    }
    lit.sort_by(f64::total_cmp);
    let e = lit[((lit.len() - 1) as f64 * METER_PERCENTILE).round() as usize];
    Some((AUTO_TARGET * f64::from(unit_gain(lights.len())) / e) as f32)
}

/// The illuminance (lux, brightest colour channel) the lights with an emission bring to point
/// `p` of unit-ish normal `n`, shadows left out.
fn illuminance(lights: &[SceneLight], p: DVec3, n: DVec3) -> f64 {
    let n = n.normalize_or_zero();
    lights
        .iter()
        .filter_map(|l| l.emission.map(|e| (l.light.to_array(), e)))
        .map(|(l, e)| {
            let xyz = DVec3::new(l[0].into(), l[1].into(), l[2].into());
            let to_light = if l[3] == 0.0 {
                xyz
            } else {
                xyz / f64::from(l[3]) - p
            };
            let cos = n.dot(to_light.normalize_or_zero()).max(0.0);
            let peak = f64::from(e.color.iter().copied().fold(0.0, f32::max));
            f64::from(e.intensity) * peak * e.attenuation(l, p) * cos
        })
        .sum()
}

/// [`Exposure::Auto`]'s light meter: the visible surface points of a grid of camera rays, cast
/// against a BVH of every surface that is built when the surfaces change, and the factor they
/// give, measured again when the camera, the lights or the surfaces change.
#[derive(Debug, Default)]
pub struct ExposureMeter {
    surfaces: Option<NearestHit>,
    last: Option<(Camera, f64, Vec<SceneLight>, Option<f32>)>,
}

impl ExposureMeter {
    /// The exposure factor of a frame of `scene` from `camera` (`aspect` = width / height):
    /// `None` when no light has an emission; the fixed one for [`Exposure::Fixed`]; otherwise
    /// metered ([`metered_factor`]), or [`exposure_factor`] when nothing lit is in view.
    pub fn exposure(
        &mut self,
        scene: &Scene,
        world: &World,
        changes: &WorldChanges,
        camera: &Camera,
        aspect: f64,
        exposure: Exposure,
    ) -> Option<f32> {
        if let Some(x) = unmetered(scene, exposure) {
            return x;
        }
        if changes.any() {
            self.surfaces = None;
            self.last = None;
        }
        if let Some((c, a, l, x)) = &self.last {
            if c == camera && *a == aspect && *l == scene.lights {
                return *x;
            }
        }
        let surfaces = self
            .surfaces
            .get_or_insert_with(|| surface_triangles(world));
        let samples = view_samples(surfaces, camera, aspect);
        let x = metered_factor(&scene.lights, &samples)
            .or_else(|| exposure_factor(scene, world.bounds(), exposure));
        self.last = Some((*camera, aspect, scene.lights.clone(), x));
        x
    }
}

/// Every surface's world triangles, arranged for nearest-hit casts.
fn surface_triangles(world: &World) -> NearestHit {
    let mut tris = Vec::new();
    for w in world.surfaces() {
        let p = &w.positions;
        tris.extend(
            w.triangles()
                .iter()
                .map(|t| t.map(|k| p[k as usize].as_dvec3())),
        );
    }
    NearestHit::new(tris)
}

/// The surface point and camera-facing normal of each ray of the metering grid that hits.
fn view_samples(surfaces: &NearestHit, camera: &Camera, aspect: f64) -> Vec<(DVec3, DVec3)> {
    let (gw, gh) = if aspect >= 1.0 {
        (
            METER_GRID,
            (f64::from(METER_GRID) / aspect).ceil().max(1.0) as u32,
        )
    } else {
        (
            (f64::from(METER_GRID) * aspect).ceil().max(1.0) as u32,
            METER_GRID,
        )
    };
    let inv: DMat4 = camera.view_proj_f64(aspect).inverse();
    let eye = camera.eye.as_dvec3();
    let mut out = Vec::with_capacity((gw * gh) as usize);
    for j in 0..gh {
        for i in 0..gw {
            let x = (f64::from(i) + 0.5) / f64::from(gw) * 2.0 - 1.0;
            let y = 1.0 - (f64::from(j) + 0.5) / f64::from(gh) * 2.0;
            let p = inv * DVec4::new(x, y, 0.5, 1.0);
            let dir = p.truncate() / p.w - eye;
            if let Some((k, t)) = surfaces.cast(eye, dir) {
                let tri = surfaces.triangle(k);
                let mut n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                if n.dot(dir) > 0.0 {
                    n = -n;
                }
                out.push((eye + dir * t, n));
            }
        }
    }
    out
}

/// The factor when nothing needs measuring: `Some(None)` when no light has an emission,
/// `Some(Some(x))` for [`Exposure::Fixed`]; `None` otherwise.
fn unmetered(scene: &Scene, exposure: Exposure) -> Option<Option<f32>> {
    if scene.lights.iter().all(|l| l.emission.is_none()) {
        return Some(None);
    }
    match exposure {
        Exposure::Fixed(x) => Some(Some(x)),
        Exposure::Auto => None,
    }
}

/// The exposure factor (output per lux) when nothing lit is in view: the brightest light's
/// nominal illuminance at the centre of `bounds`, the surfaces' world box (for example
/// [`Scene::surface_bounds`]; intensity over distance², lux for directional lights; range and
/// cone left out) gives [`AUTO_TARGET`] of the unit gain; or the fixed factor; `None` when no
/// light has an [`Emission`](shadowvol_scenes::Emission).
#[must_use]
pub fn exposure_factor(
    scene: &Scene,
    bounds: Option<(glam::Vec3, glam::Vec3)>,
    exposure: Exposure,
) -> Option<f32> {
    if let Some(x) = unmetered(scene, exposure) {
        return x;
    }
    let centre = bounds.map_or(glam::DVec3::ZERO, |(lo, hi)| ((lo + hi) * 0.5).as_dvec3());
    let nominal = scene
        .lights
        .iter()
        .filter_map(|l| l.emission.map(|e| (l.light, e)))
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
pub fn light_colors(scene: &Scene, exposure: Option<f32>) -> Vec<[f32; 3]> {
    let n = scene.lights.len();
    (0..n)
        .map(|li| match (scene.lights[li].emission, exposure) {
            (Some(e), Some(x)) => e.color.map(|c| c * e.intensity * x),
            _ => [unit_gain(n); 3],
        })
        .collect()
}

/// Checks the exposure and each light's emission (finite, non-negative, a valid cone).
///
/// # Errors
/// A message naming the light.
pub fn validate(scene: &Scene, exposure: Exposure) -> Result<(), String> {
    if let Exposure::Fixed(x) = exposure {
        if !(x.is_finite() && x > 0.0) {
            return Err(format!("exposure {x}: it must be finite and > 0"));
        }
    }
    for (i, e) in scene
        .lights
        .iter()
        .enumerate()
        .filter_map(|(i, l)| l.emission.map(|e| (i, e)))
    {
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
