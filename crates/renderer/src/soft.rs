//! Lights with a size: how many samples each light gets, and the frame's lights expanded into
//! the passes the volume pipelines record.
//!
//! A light of radius `R > 0` ([`shadowvol_scenes::SceneLight::radius`]) sampled by `N > 1`
//! points becomes, for the pipelines, `N` point lights at its samples
//! ([`shadowvol_scenes::LightDisk::samples`]), each drawing its exact stencil shadow, which is
//! counted into the visibility target ([`LightPass::Sample`]), followed by the light itself,
//! which casts nothing and whose lit pass is scaled by the count `k / N`
//! ([`LightPass::Composite`]). A light with one sample is drawn as today ([`LightPass::Hard`]),
//! so radius 0, or a penumbra under a pixel, gives the same image as a point light.

use crate::plan::{FramePlan, Technique};
use crate::world::World;
use crate::Camera;
use glam::DVec3;
use shadowvol_scenes::{Scene, SceneLight};

pub use shadowvol_report::SamplesChoice;

/// The most samples the plan gives a light (`--light-samples` may ask for more).
pub const MAX_PLANNED_SAMPLES: u32 = 64;

/// The most samples a light may have: the visibility target counts exactly up to 2048.
pub const MAX_SAMPLES: u32 = 1024;

/// What one light of the pipelines' list draws after its stencil pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightPass {
    /// A point light (one sample): its lit pass where its stencil is 0.
    Hard,
    /// Sample `index` of `samples` of scene light `light`: its stencil counted into the
    /// visibility target (cleared by sample 0); no lit pass.
    Sample {
        /// The scene light it samples.
        light: usize,
        /// Which sample.
        index: u32,
        /// How many samples the light has.
        samples: u32,
    },
    /// Scene light `light` itself after its samples: it casts nothing; its lit pass draws
    /// unshadowed into the light target, which is added to the colour times `k / samples`.
    Composite {
        /// The scene light.
        light: usize,
        /// How many samples it has.
        samples: u32,
        /// Its place among the frame's lights with a size (the visibility readback's slot).
        slot: usize,
    },
}

/// The lights the pipelines draw for a frame whose scene has lights with a size: the scene with
/// its lights expanded, and what each of them draws.
#[derive(Debug, Clone)]
pub struct Expanded {
    /// The scene with each light of several samples replaced by its samples and then itself
    /// ([`LightPass`]); the samples carry no emission (no range or cone culls their shadows,
    /// which only count where the light itself shines).
    pub scene: Scene,
    /// Per light of [`Expanded::scene`]: what it draws.
    pub passes: Vec<LightPass>,
    /// Per light of [`Expanded::scene`]: the scene light it belongs to.
    pub of: Vec<usize>,
    /// Lights with several samples.
    pub soft_lights: usize,
}

/// `scene` with its lights expanded by `samples` (per scene light; 1: drawn as a point light),
/// aimed at `aim` ([`Scene::light_aim`]); `None` when every light has one sample.
#[must_use]
pub fn expand(scene: &Scene, samples: &[u32], aim: glam::Vec3) -> Option<Expanded> {
    if samples.iter().all(|&n| n <= 1) {
        return None;
    }
    let mut lights = Vec::new();
    let mut passes = Vec::new();
    let mut of = Vec::new();
    let mut slot = 0;
    for (li, (l, &n)) in scene.lights.iter().zip(samples).enumerate() {
        let centre = SceneLight { radius: 0.0, ..*l };
        if n <= 1 {
            lights.push(centre);
            passes.push(LightPass::Hard);
            of.push(li);
            continue;
        }
        for (index, s) in l.samples(n, aim).into_iter().enumerate() {
            lights.push(SceneLight::unit(s));
            passes.push(LightPass::Sample {
                light: li,
                index: index as u32,
                samples: n,
            });
            of.push(li);
        }
        lights.push(centre);
        passes.push(LightPass::Composite {
            light: li,
            samples: n,
            slot,
        });
        of.push(li);
        slot += 1;
    }
    let mut expanded = scene.clone();
    expanded.lights = lights;
    Some(Expanded {
        scene: expanded,
        passes,
        of,
        soft_lights: slot,
    })
}

impl Expanded {
    /// Adjusts the plan of the expanded scene: a light's own entry ([`LightPass::Composite`])
    /// casts nothing, and the passes of a light with a size cover the whole image (no scissor).
    pub fn adjust_plan(&self, plan: &mut FramePlan) {
        let n = plan.entries.len() / self.passes.len().max(1);
        for (li, pass) in self.passes.iter().enumerate() {
            if *pass == LightPass::Hard {
                continue;
            }
            plan.scissors[li] = None;
            for e in &mut plan.entries[li * n..(li + 1) * n] {
                e.scissor = None;
                if matches!(pass, LightPass::Composite { .. }) && e.technique != Technique::Culled {
                    e.technique = Technique::Culled;
                    e.back_cap = false;
                    e.reason = "the light itself, lit after its samples: no volume".to_owned();
                }
            }
        }
    }

    /// The plan entries of the scene's own lights, from those of the expanded scene (after the
    /// frame): a light with a size gets, per surface, z-fail when any sample drew z-fail,
    /// else z-pass when any drew z-pass, else culled, with the counts summed over its samples.
    #[must_use]
    pub fn merge_plan(
        &self,
        entries: Vec<crate::plan::PlanEntry>,
        scene_lights: usize,
    ) -> Vec<crate::plan::PlanEntry> {
        let n = entries.len() / self.passes.len().max(1);
        let mut out: Vec<Option<crate::plan::PlanEntry>> = vec![None; scene_lights * n];
        for (k, mut e) in entries.into_iter().enumerate() {
            let li = k / n;
            let (light, samples) = match self.passes[li] {
                LightPass::Hard => (self.of[li], 1),
                LightPass::Sample { light, samples, .. } => (light, samples),
                LightPass::Composite { .. } => continue,
            };
            e.light = light;
            let slot = &mut out[light * n + k % n];
            match slot {
                None => {
                    if samples > 1 {
                        e.reason = format!("{} ({samples} samples)", e.reason);
                    }
                    *slot = Some(e);
                }
                Some(m) => {
                    let rank = |t: Technique| match t {
                        Technique::ZFail => 2,
                        Technique::ZPass => 1,
                        Technique::Culled => 0,
                    };
                    if rank(e.technique) > rank(m.technique) {
                        m.technique = e.technique;
                        m.back_cap = e.back_cap;
                        m.reason = format!("{} ({samples} samples)", e.reason);
                    }
                    m.silhouette_edges += e.silhouette_edges;
                    m.side_quads += e.side_quads;
                    m.cap_triangles += e.cap_triangles;
                    if e.silhouette == crate::plan::SilhouetteSource::Extracted {
                        m.silhouette = e.silhouette;
                    }
                }
            }
        }
        out.into_iter().flatten().collect()
    }
}

/// The samples of each light of `scene` for a `width` x `height` frame from `camera`: `forced`
/// when given (`--light-samples`; 1 for a light of radius 0), else the plan's choice
/// ([`plan_samples`]).
#[must_use]
pub fn choose_samples(
    scene: &Scene,
    world: &World,
    camera: &Camera,
    size: (u32, u32),
    forced: Option<u32>,
) -> Vec<SamplesChoice> {
    scene
        .lights
        .iter()
        .map(|l| {
            if l.radius == 0.0 {
                return SamplesChoice {
                    samples: 1,
                    penumbra_px: 0.0,
                    reason: "a point light (radius 0): hard shadows".to_owned(),
                };
            }
            let mut c = plan_samples(scene, world, camera, size, l);
            if let Some(n) = forced {
                c.samples = n.clamp(1, MAX_SAMPLES);
                c.reason = format!("{} samples (--light-samples)", c.samples);
            }
            c
        })
        .collect()
}

/// The plan's samples for `light` (of radius > 0): its widest penumbra's width on screen `w`
/// (in pixels, an upper bound: the light's full diameter projected from the nearest caster to
/// the farthest surface, seen at the nearest surface's distance from the eye); 1 sample under a
/// pixel (the hard path), else enough that each step of `k / N` is at most about a pixel wide:
/// the power of two at least `w`, from 2 to [`MAX_PLANNED_SAMPLES`].
#[must_use]
pub fn plan_samples(
    scene: &Scene,
    world: &World,
    camera: &Camera,
    (_, height): (u32, u32),
    light: &SceneLight,
) -> SamplesChoice {
    let surfaces: Vec<((DVec3, DVec3), bool)> = scene
        .surfaces()
        .zip(world.surfaces())
        .map(|(s, w)| (w.bounds, s.casts_shadows))
        .collect();
    let width = penumbra_world_width(light, &surfaces);
    let eye = camera.eye.as_dvec3();
    let nearest = surfaces
        .iter()
        .map(|(b, _)| box_distance(eye, *b))
        .fold(f64::INFINITY, f64::min)
        .max(f64::from(camera.near));
    let px_per_unit = f64::from(height) / (2.0 * nearest * (f64::from(camera.fov_y) * 0.5).tan());
    let w = width * px_per_unit;
    // NaN (no surface in view) counts as under a pixel.
    if w.is_nan() || w < 1.0 {
        return SamplesChoice {
            samples: 1,
            penumbra_px: if w.is_finite() { w } else { 0.0 },
            reason: format!("penumbra at most {w:.2} px wide, under a pixel: 1 sample (hard)"),
        };
    }
    let n = (w.ceil().min(f64::from(MAX_PLANNED_SAMPLES)) as u32)
        .next_power_of_two()
        .clamp(2, MAX_PLANNED_SAMPLES);
    SamplesChoice {
        samples: n,
        penumbra_px: w,
        reason: if w > f64::from(MAX_PLANNED_SAMPLES) {
            format!("penumbra up to {w:.0} px wide: {n} samples (the cap)")
        } else {
            format!("penumbra up to {w:.1} px wide: {n} samples")
        },
    }
}

/// An upper bound of the width in world units of `light`'s widest penumbra on the surfaces
/// (`(box, casts)`): the disk's diameter times `(far − near) / near`, with `near` the nearest
/// caster's distance from the light and `far` the farthest surface's; for a directional light,
/// `2 tan θ` times the depth from the highest caster to the lowest surface along the light.
fn penumbra_world_width(light: &SceneLight, surfaces: &[((DVec3, DVec3), bool)]) -> f64 {
    let [x, y, z, w] = light.light.to_array().map(f64::from);
    let casters = || surfaces.iter().filter(|(_, c)| *c).map(|(b, _)| *b);
    if casters().next().is_none() {
        return 0.0;
    }
    let r = f64::from(light.radius);
    if w == 0.0 {
        let d = DVec3::new(x, y, z).normalize();
        let along = |b: (DVec3, DVec3)| {
            corners(b)
                .iter()
                .map(|p| p.dot(d))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
                    (lo.min(t), hi.max(t))
                })
        };
        let top = casters()
            .map(|b| along(b).1)
            .fold(f64::NEG_INFINITY, f64::max);
        let bottom = surfaces
            .iter()
            .map(|(b, _)| along(*b).0)
            .fold(f64::INFINITY, f64::min);
        return 2.0 * r.tan() * (top - bottom).max(0.0);
    }
    let c = DVec3::new(x, y, z) / w;
    let near = casters()
        .map(|b| box_distance(c, b))
        .fold(f64::INFINITY, f64::min);
    let far = surfaces
        .iter()
        .flat_map(|(b, _)| corners(*b))
        .map(|p| p.distance(c))
        .fold(0.0, f64::max);
    if near <= r {
        // The light's disk reaches a caster's box: as wide as the scene.
        return far * 2.0;
    }
    2.0 * r * (far - near).max(0.0) / near
}

/// The distance from `p` to the box `b` (0 inside).
fn box_distance(p: DVec3, (lo, hi): (DVec3, DVec3)) -> f64 {
    (lo - p).max(p - hi).max(DVec3::ZERO).length()
}

/// The eight corners of the box `(lo, hi)`.
fn corners((lo, hi): (DVec3, DVec3)) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}
