//! The renderer's GPU pipeline: the plan's techniques go to the [`crate::resident`] pass, which
//! extracts, builds and draws the volumes on the device in one submission.

use super::{ms, Frame, RenderOptions, Renderer};
use crate::plan::{PlanEntry, SilhouetteSource, Technique};
use crate::resident::{PassFrame, ResidentScene, ShadowPass};
use crate::volume::canonical_triangle;
use crate::{RenderError, RenderScene};
use glam::Affine3A;
use shadowvol_mesh_topology::Mesh;
use shadowvol_silhouette::{SceneObject, TopologyScene};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What the shared first steps of a frame (objects, plan) hand to the pipeline.
pub(super) struct Planned {
    pub entries: Vec<PlanEntry>,
    pub scissors: Vec<Option<[u32; 4]>>,
    pub colors: Vec<[f32; 3]>,
    pub exposure: Option<f32>,
    pub t0: Instant,
    pub prepare_time: Duration,
}

/// The pass, built on first use, and the scene uploaded to it with the meshes it was built from.
#[derive(Default)]
pub(super) struct ResidentState {
    pass: Option<ShadowPass>,
    scene: Option<(ResidentScene, Vec<Arc<Mesh>>)>,
}

impl Renderer {
    /// The GPU times of the last GPU-pipeline frame, where the device has timestamp queries.
    pub(super) fn last_gpu_timings(
        &self,
    ) -> Result<Option<crate::resident::GpuTimings>, RenderError> {
        match (&self.resident.pass, &self.resident.scene) {
            (Some(pass), Some((rs, _))) if self.options.pipeline == super::Pipeline::Gpu => {
                pass.read_timings(rs)
            }
            _ => Ok(None),
        }
    }

    /// One frame of the GPU pipeline. Returns the frame (with `readback`) and the bytes read
    /// back besides the final image and the plan's counts: always 0.
    pub(super) fn frame_gpu(
        &mut self,
        scene: &RenderScene,
        planned: Planned,
        readback: bool,
        into: Option<&wgpu::TextureView>,
    ) -> Result<(Option<Frame>, u64), RenderError> {
        let RenderOptions {
            width,
            height,
            mode,
            pipeline,
            ..
        } = self.options;
        let Planned {
            mut entries,
            scissors,
            colors,
            exposure,
            t0,
            prepare_time,
        } = planned;
        if self.resident.pass.is_none() {
            self.resident.pass = Some(self.gpu.shadow_pass()?);
        }
        let t_prep = Instant::now();
        let meshes: Vec<Arc<Mesh>> = self.cache.iter().map(|c| c.mesh.clone()).collect();
        let current = matches!(&self.resident.scene, Some((_, k))
            if k.len() == meshes.len() && k.iter().zip(&meshes).all(|(a, b)| Arc::ptr_eq(a, b)));
        if !current {
            self.resident.scene = None;
            let topo = TopologyScene {
                objects: self
                    .cache
                    .iter()
                    .zip(&scene.objects)
                    .map(|(c, o)| SceneObject {
                        name: o.name.clone(),
                        table: c.table.clone(),
                        world_from_object: Affine3A::IDENTITY,
                    })
                    .collect(),
            };
            let pass = self.resident.pass.as_ref().expect("built above");
            self.resident.scene = Some((pass.prepare(&topo)?, meshes));
        }
        let prepare_time = prepare_time + t_prep.elapsed();
        let pass = self.resident.pass.as_ref().expect("built above");
        let (rs, _) = self.resident.scene.as_mut().expect("uploaded above");
        let techniques: Vec<Technique> = entries.iter().map(|e| e.technique).collect();
        let transforms: Vec<Affine3A> = self.cache.iter().map(|c| c.transform).collect();
        let albedo: Vec<[f32; 3]> = scene.objects.iter().map(|o| o.albedo).collect();
        let aspect = (f64::from(width) / f64::from(height)) as f32;
        pass.update(
            rs,
            &PassFrame {
                camera: &scene.camera,
                aspect,
                lights: &scene.lights,
                colors: &colors,
                emission: &scene.emission,
                transforms: &transforms,
                albedo: &albedo,
                techniques: &techniques,
                scissors: &scissors,
                ambient: scene.ambient,
                mode,
                count: readback || into.is_some(),
            },
        )?;
        let t_raster = Instant::now();
        let out = self.gpu.render_resident(
            pass,
            rs,
            (width, height),
            scene.lights.len(),
            readback,
            into,
        )?;
        let raster_time = t_raster.elapsed();
        let out = match out {
            Some(out) => out,
            None if into.is_some() => crate::gpu::FrameOutput::default(),
            None => return Ok((None, 0)),
        };
        let counts = pass.read_counts(rs)?;
        let n_obj = scene.objects.len();
        for e in &mut entries {
            if e.technique == Technique::Culled {
                continue;
            }
            let i = e.light * n_obj + e.object;
            e.silhouette = SilhouetteSource::Extracted;
            e.silhouette_edges = counts.silhouette_edges[i] as usize;
            e.side_quads = counts.side_quads[i] as usize;
            let front = counts.cap_triangles[i] as usize;
            e.cap_triangles = if e.back_cap { 2 * front } else { front };
        }
        let triangles = self
            .cache
            .iter()
            .map(|c| {
                c.table
                    .triangles
                    .iter()
                    .map(|t| canonical_triangle(*t).map(|k| c.world[k as usize]))
                    .collect()
            })
            .collect();
        Ok((
            Some(Frame {
                width,
                height,
                rgba: out.color,
                ids: out.ids,
                stencil: out.stencil,
                triangles,
                casts_shadows: scene.objects.iter().map(|o| o.casts_shadows).collect(),
                albedo,
                light_color: colors,
                ambient: scene.ambient,
                emission: scene.emission.clone(),
                exposure,
                scissor_pixels_saved: super::scissor_pixels_saved(&scissors, width, height),
                uncertain: counts.integer_decided,
                host_resolved: 0,
                pipeline,
                gpu_timings: pass.read_timings(rs)?,
                volumes: Vec::new(),
                lights: scene.lights.clone(),
                camera: scene.camera,
                plan: entries,
                timings: super::Timings {
                    silhouette_ms: 0.0,
                    side_building_ms: 0.0,
                    raster_ms: ms(raster_time),
                    prepare_ms: ms(prepare_time),
                    total_ms: ms(t0.elapsed()),
                },
                mode,
                adapter: self.gpu.adapter.clone(),
                depth_clamp: pass.depth_clamp(),
            }),
            0,
        ))
    }
}
