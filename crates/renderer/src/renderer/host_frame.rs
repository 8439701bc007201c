//! The host pipeline's steps of a frame: the plan (shared with the GPU pipeline), the
//! silhouettes from the backend (reused where nothing moved), and the volumes built from them.

use super::{bounds_f64, object_space_lights, LightCache, RenderOptions, Renderer};
use crate::gpu::LightDraws;
use crate::plan::{self, PlanEntry, SilhouetteSource, Technique};
use crate::volume::{build_caps, build_sides, remove_triangles, touching_triangles};
use crate::{RenderError, RenderScene};
use glam::DVec3;
use shadowvol_robust_math::Light;
use shadowvol_silhouette::Multiplicities;
use std::time::{Duration, Instant};

/// What the silhouette step reports.
pub(super) struct Extracted {
    /// Time spent in the backend's `extract`.
    pub time: Duration,
    /// Uncertain pairs the backend resolved on the host.
    pub uncertain: u64,
    /// Multiplicity bytes brought to the host.
    pub readback_bytes: u64,
}

/// One light's scissor rectangle, `None` for the whole image.
pub(super) type Scissor = Option<[u32; 4]>;

impl Renderer {
    /// The plan: per (light, object) the technique and why ([`plan::choose`]), in
    /// `light * object_count + object` order, and each light's scissor rectangle.
    pub(super) fn plan_frame(
        &self,
        scene: &RenderScene,
        aspect: f64,
    ) -> (Vec<PlanEntry>, Vec<Scissor>) {
        let RenderOptions {
            width,
            height,
            policy,
            scissor,
            ..
        } = self.options;
        let n_lights = scene.lights.len();
        let near = scene.camera.near_corners(aspect);
        let frustum = plan::frustum_planes(scene.camera.eye.as_dvec3(), near);
        let mut entries = Vec::with_capacity(n_lights * scene.objects.len());
        let bounds: Vec<(DVec3, DVec3)> = self.cache.iter().map(|c| bounds_f64(&c.world)).collect();
        let view_proj = scene.camera.view_proj_f64(aspect);
        let scene_bounds = bounds.iter().fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), &(a, b)| (lo.min(a), hi.max(b)),
        );
        let scissors: Vec<Option<[u32; 4]>> = scene
            .lights
            .iter()
            .enumerate()
            .map(|(li, light)| {
                scissor
                    .then(|| {
                        plan::light_scissor(
                            light.to_array(),
                            scene.emission.get(li),
                            scene_bounds,
                            view_proj,
                            f64::from(scene.camera.near),
                            width,
                            height,
                        )
                    })
                    .flatten()
            })
            .collect();
        for (li, light) in scene.lights.iter().enumerate() {
            let l = light.to_array();
            let ncv = plan::near_clip_volume(near, l);
            for (oi, obj) in scene.objects.iter().enumerate() {
                let c = &self.cache[oi];
                let (technique, reason) = plan::choose(
                    policy,
                    l,
                    scene.emission.get(li),
                    plan::PlanObject {
                        casts_shadows: obj.casts_shadows,
                        world: &c.world,
                        triangles: &c.table.triangles,
                        bounds: bounds[oi],
                    },
                    plan::PlanView {
                        frustum: &frustum,
                        near,
                        near_clip: ncv.as_deref(),
                    },
                );
                entries.push(PlanEntry {
                    light: li,
                    object: oi,
                    object_name: obj.name.clone(),
                    technique,
                    back_cap: technique == Technique::ZFail && !light.is_directional(),
                    silhouette: SilhouetteSource::Skipped,
                    silhouette_edges: 0,
                    side_quads: 0,
                    cap_triangles: 0,
                    reason,
                    scissor: scissors[li],
                });
            }
        }

        (entries, scissors)
    }

    /// The silhouettes of every (light, object) the plan draws, from the cache where neither
    /// the light nor the object moved (nor the mode changed), else from the backend: one call
    /// over the whole scene when several still objects need new ones, else per object. Marks
    /// each entry's [`SilhouetteSource`].
    ///
    /// # Errors
    /// [`RenderError::Backend`] when extraction fails, [`RenderError::InvalidInput`] for a light
    /// that is not finite in an object's space.
    pub(super) fn extract_silhouettes(
        &mut self,
        scene: &RenderScene,
        entries: &mut [PlanEntry],
    ) -> Result<Extracted, RenderError> {
        let mode = self.options.mode;
        let n_lights = scene.lights.len();
        let n_obj = scene.objects.len();
        let mut silhouette_time = Duration::ZERO;
        let mut m_buf = Multiplicities::default();
        let mut uncertain = 0u64;
        let mut readback_bytes = 0u64;
        let mut stale_by_obj: Vec<Vec<usize>> = Vec::with_capacity(n_obj);
        for oi in 0..n_obj {
            let needed: Vec<usize> = (0..n_lights)
                .filter(|&li| entries[li * n_obj + oi].technique != Technique::Culled)
                .collect();
            let stale: Vec<usize> = needed
            .iter()
            .copied()
            .filter(|&li| {
                !matches!(&self.cache[oi].lights[li], Some(c) if c.light == scene.lights[li] && c.mode == mode)
            })
            .collect();
            for &li in &needed {
                entries[li * n_obj + oi].silhouette = if stale.contains(&li) {
                    SilhouetteSource::Extracted
                } else {
                    SilhouetteSource::Reused
                };
            }
            stale_by_obj.push(stale);
        }
        // When no object moved and several objects need new silhouettes (a light moved), one
        // call over the whole prepared scene serves them all: no per-object round trips, which
        // is what costs GPU backends most (the paper's OpenCL path lost up to 4x on 100 objects
        // that way). Objects that moved go through their own prepared scene instead, so a moving
        // object never re-uploads the others.
        let batch: Vec<usize> = (0..n_obj)
            .filter(|&oi| !stale_by_obj[oi].is_empty())
            .collect();
        if batch.len() >= 2 && !self.changed.iter().any(|&c| c) {
            let mut union: Vec<usize> = batch
                .iter()
                .flat_map(|&oi| stale_by_obj[oi].iter().copied())
                .collect();
            union.sort_unstable();
            union.dedup();
            let whole = self.whole_scene(scene)?;
            let lights: Vec<Light> = union.iter().map(|&li| scene.lights[li]).collect();
            let t = Instant::now();
            uncertain += self
                .backend
                .extract(whole, &lights, mode, &mut m_buf)?
                .uncertain;
            silhouette_time += t.elapsed();
            readback_bytes += 4 * (m_buf.edge_count() * m_buf.light_count()) as u64;
            let offsets: Vec<usize> = std::iter::once(0)
                .chain(self.cache.iter().scan(0, |acc, c| {
                    *acc += c.table.edges.len();
                    Some(*acc)
                }))
                .collect();
            for &oi in &batch {
                for (k, &li) in union.iter().enumerate() {
                    self.cache[oi].lights[li] = Some(LightCache {
                        light: scene.lights[li],
                        mode,
                        m: m_buf.values(k)[offsets[oi]..offsets[oi + 1]].to_vec(),
                    });
                    if entries[li * n_obj + oi].technique != Technique::Culled {
                        entries[li * n_obj + oi].silhouette = SilhouetteSource::Extracted;
                    }
                }
                stale_by_obj[oi].clear();
            }
        }
        for (oi, obj) in scene.objects.iter().enumerate() {
            let stale = &stale_by_obj[oi];
            if stale.is_empty() {
                continue;
            }
            let c = &self.cache[oi];
            let stale_lights: Vec<Light> = stale.iter().map(|&li| scene.lights[li]).collect();
            let obj_lights = object_space_lights(&obj.name, &c.table, c.transform, &stale_lights)?;
            let t = Instant::now();
            uncertain += self
                .backend
                .extract(c.prepared, &obj_lights, mode, &mut m_buf)?
                .uncertain;
            silhouette_time += t.elapsed();
            readback_bytes += 4 * (m_buf.edge_count() * m_buf.light_count()) as u64;
            let c = &mut self.cache[oi];
            for (k, &li) in stale.iter().enumerate() {
                c.lights[li] = Some(LightCache {
                    light: scene.lights[li],
                    mode,
                    m: m_buf.values(k).to_vec(),
                });
            }
        }

        Ok(Extracted {
            time: silhouette_time,
            uncertain,
            readback_bytes,
        })
    }

    /// The volume geometry of every light, from the cached silhouettes (sides) and the
    /// triangle signs (caps, z-fail only), and each light's draw ranges: z-pass sides, then
    /// z-fail sides, back caps and counter-clockwise caps, then clockwise caps. Fills each
    /// entry's edge, side and cap counts.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a light that is not finite in an object's space.
    pub(super) fn build_volumes(
        &self,
        scene: &RenderScene,
        entries: &mut [PlanEntry],
        colors: &[[f32; 3]],
        scissors: &[Scissor],
    ) -> Result<(Vec<[f32; 4]>, Vec<LightDraws>), RenderError> {
        let mode = self.options.mode;
        let n_lights = scene.lights.len();
        let mut volumes: Vec<[f32; 4]> = Vec::new();
        let mut draws = Vec::with_capacity(n_lights);
        for (li, light) in scene.lights.iter().enumerate() {
            let l = light.to_array();
            let mut d = LightDraws {
                light: l,
                color: colors[li],
                scissor: scissors[li],
                emission: scene.emission.get(li).copied(),
                ..LightDraws::default()
            };
            let mut zfail_objects = Vec::new();
            // Z-pass sides first, then z-fail sides + back caps + ccw caps, then cw caps.
            let start = volumes.len() as u32;
            for (oi, obj) in scene.objects.iter().enumerate() {
                let e = &mut entries[li * scene.objects.len() + oi];
                if e.technique == Technique::Culled {
                    continue;
                }
                let c = &self.cache[oi];
                let m = &c.lights[li].as_ref().expect("extracted above").m;
                e.silhouette_edges = m.iter().filter(|&&v| v != 0).count();
                let ol =
                    object_space_lights(&obj.name, &c.table, c.transform, &[*light])?[0].to_array();
                let touching = touching_triangles(&c.table, ol);
                let mut m = m.clone();
                if !touching.is_empty() {
                    remove_triangles(&c.table, ol, mode, &touching, &mut m);
                    e.reason
                        .push_str("; triangles touching the light are drawn without a volume");
                }
                if e.technique == Technique::ZPass {
                    e.side_quads = build_sides(&c.table.edges, &m, &c.world, l, &mut volumes);
                } else {
                    zfail_objects.push((oi, ol, touching, m));
                }
            }
            d.zpass = start..volumes.len() as u32;
            let start = volumes.len() as u32;
            let mut cw_caps = Vec::new();
            for (oi, ol, touching, m) in &zfail_objects {
                let e = &mut entries[li * scene.objects.len() + *oi];
                let c = &self.cache[*oi];
                e.side_quads = build_sides(&c.table.edges, m, &c.world, l, &mut volumes);
                let caps = build_caps(&c.table, *ol, &c.world, l, mode, e.back_cap, touching);
                e.cap_triangles =
                    (caps.front_ccw.len() + caps.front_cw.len() + caps.back.len()) / 3;
                volumes.extend_from_slice(&caps.back);
                volumes.extend_from_slice(&caps.front_ccw);
                cw_caps.extend_from_slice(&caps.front_cw);
            }
            d.zfail_ccw = start..volumes.len() as u32;
            let start = volumes.len() as u32;
            volumes.extend_from_slice(&cw_caps);
            d.zfail_cw = start..volumes.len() as u32;
            draws.push(d);
        }
        Ok((volumes, draws))
    }
}
