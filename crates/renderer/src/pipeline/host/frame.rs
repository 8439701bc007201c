//! The host pipeline's steps of a frame: the silhouettes from the backend (reused where nothing
//! moved), and the volumes built from them.

use super::raster::LightDraws;
use super::volume::{build_caps, build_sides, remove_triangles, touching_triangles};
use super::{HostPipeline, LightCache};
use crate::pipeline::FrameInputs;
use crate::plan::{PlanEntry, SilhouetteSource, Technique};
use crate::RenderError;
use glam::Affine3A;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::{Accuracy, Light};
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

/// `light` in the space of object `name` placed by `transform`, through
/// [`shadowvol_silhouette::object_light`] (the one shared conversion).
fn object_space_light(name: &str, transform: Affine3A, light: Light) -> Result<Light, RenderError> {
    let l = shadowvol_silhouette::object_light(transform, light);
    Light::try_from(l).map_err(|e| {
        RenderError::InvalidInput(format!("object {name:?}: light in object space {l:?}: {e}"))
    })
}

impl LightCache {
    /// The cache of `light`'s multiplicities `m` in `mode` for the object `name` (`table`,
    /// placed by `transform`): the triangles touching the light found and taken out of `m` once,
    /// here, instead of every frame. A light that is not finite in the object's space is left
    /// for [`HostPipeline::build_volumes`] to refuse, as it draws.
    fn new(
        name: &str,
        transform: Affine3A,
        table: &EdgeTable,
        light: Light,
        mode: Accuracy,
        mut m: Vec<i32>,
    ) -> Self {
        let silhouette_edges = m.iter().filter(|&&v| v != 0).count();
        let mut touching = Vec::new();
        if let Ok(ol) = object_space_light(name, transform, light) {
            let ol = ol.to_array();
            touching = touching_triangles(table, ol);
            if !touching.is_empty() {
                remove_triangles(table, ol, mode, &touching, &mut m);
            }
        }
        Self {
            light,
            mode,
            m,
            silhouette_edges,
            touching,
        }
    }
}

/// `lights` split into the frame's extraction groups ([`FrameInputs::group`]), each in
/// ascending order: one backend call per light with a size (its samples together), and one for
/// all the other lights, as before.
fn groups(frame: &FrameInputs<'_>, lights: &[usize]) -> Vec<Vec<usize>> {
    let mut out: Vec<(usize, Vec<usize>)> = Vec::new();
    for &li in lights {
        let g = frame.group(li);
        match out.iter_mut().find(|(k, _)| *k == g) {
            Some((_, v)) => v.push(li),
            None => out.push((g, vec![li])),
        }
    }
    // The lights of their own share one call, as without lights with a size.
    let (alone, samples): (Vec<_>, Vec<_>) = out.into_iter().partition(|(_, v)| v.len() == 1);
    let alone: Vec<usize> = alone.into_iter().flat_map(|(_, v)| v).collect();
    let mut calls: Vec<Vec<usize>> = samples.into_iter().map(|(_, v)| v).collect();
    if !alone.is_empty() {
        calls.push(alone);
    }
    calls
}

impl HostPipeline {
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
        frame: &FrameInputs<'_>,
        entries: &mut [PlanEntry],
    ) -> Result<Extracted, RenderError> {
        let scene = frame.scene;
        let mode = frame.mode;
        // Plan entries cover every surface; only casters (the first ones) are extracted.
        let n_surfaces = frame.world.surfaces().len();
        let n_obj = self.objects.len();
        let mut silhouette_time = Duration::ZERO;
        let mut m_buf = Multiplicities::default();
        let mut uncertain = 0u64;
        let mut readback_bytes = 0u64;
        let mut stale_by_obj = self.stale_lights(frame, entries);
        // When no object moved and several objects need new silhouettes (a light moved), one
        // call over the whole prepared scene serves them all: no per-object round trips, which
        // is what costs GPU backends most (the paper's OpenCL path lost up to 4x on 100 objects
        // that way). Objects that moved go through their own prepared scene instead, so a moving
        // object never re-uploads the others.
        let batch: Vec<usize> = (0..n_obj)
            .filter(|&oi| !stale_by_obj[oi].is_empty())
            .collect();
        if batch.len() >= 2 && !frame.changes.any() {
            let mut union: Vec<usize> = batch
                .iter()
                .flat_map(|&oi| stale_by_obj[oi].iter().copied())
                .collect();
            union.sort_unstable();
            union.dedup();
            let whole = self.whole_scene(scene)?;
            let offsets = scene.geometry.edge_offsets();
            for group in groups(frame, &union) {
                let lights: Vec<Light> = group.iter().map(|&li| scene.lights[li].light).collect();
                let t = Instant::now();
                uncertain += self
                    .backend
                    .extract(whole, &lights, mode, &mut m_buf)?
                    .uncertain;
                silhouette_time += t.elapsed();
                readback_bytes += 4 * (m_buf.edge_count() * m_buf.light_count()) as u64;
                for &oi in &batch {
                    for (k, &li) in group.iter().enumerate() {
                        let m = m_buf.values(k)[offsets[oi]..offsets[oi + 1]].to_vec();
                        let c = &mut self.objects[oi];
                        let light = scene.lights[li].light;
                        c.lights[li] = Some(LightCache::new(
                            &scene.geometry.objects[oi].name,
                            c.transform,
                            &c.table,
                            light,
                            mode,
                            m,
                        ));
                        if entries[li * n_surfaces + oi].technique != Technique::Culled {
                            entries[li * n_surfaces + oi].silhouette = SilhouetteSource::Extracted;
                        }
                    }
                }
            }
            for &oi in &batch {
                stale_by_obj[oi].clear();
            }
        }
        for (oi, obj) in scene.geometry.objects.iter().enumerate() {
            let stale = &stale_by_obj[oi];
            if stale.is_empty() {
                continue;
            }
            for group in groups(frame, stale) {
                let c = &self.objects[oi];
                let obj_lights = group
                    .iter()
                    .map(|&li| object_space_light(&obj.name, c.transform, scene.lights[li].light))
                    .collect::<Result<Vec<Light>, RenderError>>()?;
                let t = Instant::now();
                uncertain += self
                    .backend
                    .extract(c.prepared, &obj_lights, mode, &mut m_buf)?
                    .uncertain;
                silhouette_time += t.elapsed();
                readback_bytes += 4 * (m_buf.edge_count() * m_buf.light_count()) as u64;
                let c = &mut self.objects[oi];
                for (k, &li) in group.iter().enumerate() {
                    let light = scene.lights[li].light;
                    let m = m_buf.values(k).to_vec();
                    c.lights[li] = Some(LightCache::new(
                        &obj.name,
                        c.transform,
                        &c.table,
                        light,
                        mode,
                        m,
                    ));
                }
            }
        }

        Ok(Extracted {
            time: silhouette_time,
            uncertain,
            readback_bytes,
        })
    }

    /// Per object, the lights whose silhouette must be extracted again (the plan draws it and
    /// the cache holds another light or mode); marks each drawn entry extracted or reused.
    fn stale_lights(&self, frame: &FrameInputs<'_>, entries: &mut [PlanEntry]) -> Vec<Vec<usize>> {
        let scene = frame.scene;
        let n_lights = scene.lights.len();
        let n_surfaces = frame.world.surfaces().len();
        let n_obj = self.objects.len();
        let mut stale_by_obj: Vec<Vec<usize>> = Vec::with_capacity(n_obj);
        for oi in 0..n_obj {
            let needed: Vec<usize> = (0..n_lights)
                .filter(|&li| entries[li * n_surfaces + oi].technique != Technique::Culled)
                .collect();
            let stale: Vec<usize> = needed
            .iter()
            .copied()
            .filter(|&li| {
                !matches!(&self.objects[oi].lights[li], Some(c) if c.light == scene.lights[li].light && c.mode == frame.mode)
            })
            .collect();
            for &li in &needed {
                entries[li * n_surfaces + oi].silhouette = if stale.contains(&li) {
                    SilhouetteSource::Extracted
                } else {
                    SilhouetteSource::Reused
                };
            }
            stale_by_obj.push(stale);
        }
        stale_by_obj
    }

    /// The volume geometry of every light, appended to `volumes`, from the cached silhouettes
    /// (sides) and the triangle signs (caps, z-fail only), and each light's draw ranges: z-pass
    /// sides, then z-fail sides, back caps and counter-clockwise caps, then clockwise caps.
    /// Fills each entry's edge, side and cap counts.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a light that is not finite in an object's space.
    pub(super) fn build_volumes(
        &self,
        frame: &FrameInputs<'_>,
        entries: &mut [PlanEntry],
        volumes: &mut Vec<[f32; 4]>,
    ) -> Result<Vec<LightDraws>, RenderError> {
        let scene = frame.scene;
        let mode = frame.mode;
        let n_lights = scene.lights.len();
        let n_surfaces = frame.world.surfaces().len();
        let mut draws = Vec::with_capacity(n_lights);
        for (li, scene_light) in scene.lights.iter().enumerate() {
            let light = &scene_light.light;
            let l = light.to_array();
            let mut d = LightDraws {
                light: l,
                color: frame.light_colors[li],
                scissor: frame.scissors[li],
                emission: scene_light.emission,
                ..LightDraws::default()
            };
            let mut zfail_objects = Vec::new();
            // Z-pass sides first, then z-fail sides + back caps + ccw caps, then cw caps.
            let start = volumes.len() as u32;
            for (oi, obj) in scene.geometry.objects.iter().enumerate() {
                let e = &mut entries[li * n_surfaces + oi];
                if e.technique == Technique::Culled {
                    continue;
                }
                let c = &self.objects[oi];
                let world = &frame.world.surfaces()[oi].positions;
                let cache = c.lights[li].as_ref().expect("extracted above");
                e.silhouette_edges = cache.silhouette_edges;
                let ol = object_space_light(&obj.name, c.transform, *light)?.to_array();
                if !cache.touching.is_empty() {
                    e.reason
                        .push_str("; triangles touching the light are drawn without a volume");
                }
                if e.technique == Technique::ZPass {
                    e.side_quads = build_sides(&c.table.edges, &cache.m, world, l, volumes);
                } else {
                    zfail_objects.push((oi, ol, cache));
                }
            }
            d.zpass = start..volumes.len() as u32;
            let start = volumes.len() as u32;
            let mut cw_caps = Vec::new();
            for &(oi, ol, cache) in &zfail_objects {
                let e = &mut entries[li * n_surfaces + oi];
                let c = &self.objects[oi];
                let world = &frame.world.surfaces()[oi].positions;
                e.side_quads = build_sides(&c.table.edges, &cache.m, world, l, volumes);
                let caps = build_caps(&c.table, ol, world, l, mode, e.back_cap, &cache.touching);
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
        Ok(draws)
    }
}
