//! The plan of a whole frame: every (light, surface) pair's technique, and each light's scissor.

use super::{
    choose, light_scissor, PlanEntry, PlanObject, PlanPolicy, PlanView, SilhouetteSource, Technique,
};
use crate::world::World;
use crate::Camera;
use glam::DVec3;
use shadowvol_scenes::Scene;

/// One light's scissor rectangle `[x, y, width, height]`, `None` for the whole image.
pub type Scissor = Option<[u32; 4]>;

/// The plan of one frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FramePlan {
    /// Per (light, surface), light-major (`light * surfaces + surface`): the technique and why;
    /// the pipeline fills in the silhouette source and the counts of what it drew.
    pub entries: Vec<PlanEntry>,
    /// Per light: its scissor.
    pub scissors: Vec<Scissor>,
}

impl FramePlan {
    /// Pixels the scissors keep out of the stencil and lit passes, summed over lights.
    #[must_use]
    pub fn scissor_pixels_saved(&self, width: u32, height: u32) -> usize {
        self.scissors
            .iter()
            .flatten()
            .map(|r| (width * height - r[2] * r[3]) as usize)
            .sum()
    }
}

/// Plans a `width` x `height` frame of `scene` from `camera`: per (light, surface) the technique
/// ([`choose`] under `policy`), from the surfaces' world positions in `world`; with `scissor`,
/// each light's scissor ([`light_scissor`]) within the bounds of every surface.
#[must_use]
pub fn plan_frame(
    scene: &Scene,
    world: &World,
    camera: &Camera,
    (width, height): (u32, u32),
    policy: PlanPolicy,
    scissor: bool,
) -> FramePlan {
    let aspect = f64::from(width) / f64::from(height);
    let near = camera.near_corners(aspect);
    let frustum = super::frustum_planes(camera.eye.as_dvec3(), near);
    let view_proj = camera.view_proj_f64(aspect);
    let scene_bounds = world
        .surfaces()
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s.bounds.0), hi.max(s.bounds.1))
        });
    let scissors: Vec<Scissor> = scene
        .lights
        .iter()
        .map(|l| {
            scissor
                .then(|| {
                    light_scissor(
                        l.light.to_array(),
                        l.emission.as_ref(),
                        scene_bounds,
                        view_proj,
                        f64::from(camera.near),
                        width,
                        height,
                    )
                })
                .flatten()
        })
        .collect();
    let mut entries = Vec::with_capacity(scene.lights.len() * world.surfaces().len());
    for (li, light) in scene.lights.iter().enumerate() {
        let l = light.light.to_array();
        let ncv = super::near_clip_volume(near, l);
        for (oi, (surface, w)) in scene.surfaces().zip(world.surfaces()).enumerate() {
            let (technique, reason) = choose(
                policy,
                l,
                light.emission.as_ref(),
                PlanObject {
                    casts_shadows: surface.casts_shadows,
                    world: &w.positions,
                    triangles: &surface.table.triangles,
                    bounds: w.bounds,
                },
                PlanView {
                    frustum: &frustum,
                    near,
                    near_clip: ncv.as_deref(),
                },
            );
            entries.push(PlanEntry {
                light: li,
                object: oi,
                object_name: surface.name.to_owned(),
                technique,
                back_cap: technique == Technique::ZFail && !light.light.is_directional(),
                silhouette: SilhouetteSource::Skipped,
                silhouette_edges: 0,
                side_quads: 0,
                cap_triangles: 0,
                reason,
                scissor: scissors[li],
            });
        }
    }
    FramePlan { entries, scissors }
}
