//! The GPU pipeline: the plan's techniques go to the resident pass
//! ([`crate::resident::ShadowPass`]), which extracts, builds and draws the volumes on the device
//! in the frame's command encoder. The host writes only small per-frame inputs; no silhouette
//! backend runs.

use super::{FrameInputs, PassReport, Pipeline, ShadowPipeline};
use crate::plan::{PlanEntry, SilhouetteSource, Technique};
use crate::raster::{Attachments, BACKGROUND, COLOR_FORMAT, IDS_FORMAT};
use crate::resident::{PassFormats, PassFrame, ResidentScene, ShadowPass};
use crate::{RenderDevice, RenderError};
use glam::Affine3A;
use shadowvol_silhouette::PreparedBytes;

/// The GPU pipeline: the plan's techniques go to the resident pass
/// ([`crate::resident::ShadowPass`]), which extracts, builds and draws the volumes on the device
/// in the frame's command encoder. The host writes only small per-frame inputs; no silhouette
/// backend runs.
#[derive(Debug, Default)]
pub struct GpuPipeline {
    pass: Option<ShadowPass>,
    scene: Option<ResidentScene>,
    /// Per surface: its albedo and its world transform (updated when it moves).
    albedo: Vec<[f32; 3]>,
    transforms: Vec<Affine3A>,
    /// Per (light, surface): the plan's technique, rewritten each frame.
    techniques: Vec<Technique>,
}

impl GpuPipeline {
    /// A GPU pipeline; its pass is built on the device at the first
    /// [`ShadowPipeline::prepare`].
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The resident pass and the uploaded scene, once prepared.
    #[must_use]
    pub fn resident(&self) -> Option<(&ShadowPass, &ResidentScene)> {
        self.pass.as_ref().zip(self.scene.as_ref())
    }
}

impl ShadowPipeline for GpuPipeline {
    fn kind(&self) -> Pipeline {
        Pipeline::Gpu
    }

    fn depth_clamp(&self, device: &RenderDevice) -> bool {
        self.pass
            .as_ref()
            .map_or(device.depth_clamp, ShadowPass::depth_clamp)
    }

    fn prepared_bytes(&self) -> PreparedBytes {
        self.scene
            .as_ref()
            .map_or_else(PreparedBytes::default, ResidentScene::bytes)
    }

    fn prepare(
        &mut self,
        device: &RenderDevice,
        scene: &shadowvol_scenes::Scene,
    ) -> Result<(), RenderError> {
        if self.pass.is_none() {
            if let Some(why) = &device.gpu_pipeline_unsupported {
                return Err(RenderError::Unsupported(why.clone()));
            }
            self.pass = Some(ShadowPass::new(
                &device.adapter,
                &device.device,
                &device.queue,
                PassFormats {
                    color: COLOR_FORMAT,
                    ids: Some(IDS_FORMAT),
                    depth: device.depth_format,
                },
            )?);
        }
        let pass = self.pass.as_ref().expect("built above");
        self.scene = None;
        self.scene = Some(pass.prepare(scene)?);
        self.albedo = scene.surfaces().map(|s| s.albedo).collect();
        self.transforms = scene.surfaces().map(|s| s.world_from_object).collect();
        Ok(())
    }

    fn record(
        &mut self,
        _device: &RenderDevice,
        frame: &FrameInputs<'_>,
        plan: &mut [PlanEntry],
        target: &Attachments<'_>,
        enc: &mut wgpu::CommandEncoder,
    ) -> Result<PassReport, RenderError> {
        let (Some(pass), Some(rs)) = (self.pass.as_ref(), self.scene.as_mut()) else {
            return Err(RenderError::InvalidInput(
                "the GPU pipeline records before prepare".to_owned(),
            ));
        };
        for ((t, moved), s) in self
            .transforms
            .iter_mut()
            .zip(&frame.changes.moved)
            .zip(frame.scene.surfaces())
        {
            if *moved {
                *t = s.world_from_object;
            }
        }
        self.techniques.clear();
        self.techniques.extend(plan.iter().map(|e| e.technique));
        let (w, h) = frame.size;
        pass.update(
            rs,
            &PassFrame {
                camera: frame.camera,
                aspect: (f64::from(w) / f64::from(h)) as f32,
                lights: &frame.scene.lights,
                colors: frame.light_colors,
                transforms: &self.transforms,
                albedo: &self.albedo,
                techniques: &self.techniques,
                scissors: frame.scissors,
                ambient: frame.scene.effects.ambient.clamp(0.0, 1.0),
                mode: frame.mode,
                count: frame.count,
            },
        )?;
        pass.encode_extract(enc, rs);
        pass.encode_prepass(
            enc,
            rs,
            target.color,
            target.ids,
            target.depth_stencil,
            BACKGROUND,
        );
        for li in 0..frame.scene.lights.len() {
            pass.encode_stencil(enc, rs, li, target.depth_stencil);
            target.after_stencil(enc, li);
            pass.encode_lit(enc, rs, li, target.color, target.depth_stencil);
        }
        for e in plan.iter_mut().filter(|e| e.technique != Technique::Culled) {
            e.silhouette = SilhouetteSource::Extracted;
        }
        Ok(PassReport::default())
    }

    fn finish(
        &mut self,
        _device: &RenderDevice,
        frame: &FrameInputs<'_>,
        plan: &mut [PlanEntry],
        report: &mut PassReport,
    ) -> Result<(), RenderError> {
        let (Some(pass), Some(rs)) = (self.pass.as_ref(), self.scene.as_ref()) else {
            return Ok(());
        };
        report.gpu_timings = pass.read_timings(rs)?;
        if !frame.count {
            return Ok(());
        }
        let counts = pass.read_counts(rs)?;
        let n = frame.world.surfaces().len();
        for e in plan.iter_mut().filter(|e| e.technique != Technique::Culled) {
            let i = e.light * n + e.object;
            e.silhouette_edges = counts.silhouette_edges[i] as usize;
            e.side_quads = counts.side_quads[i] as usize;
            let front = counts.cap_triangles[i] as usize;
            e.cap_triangles = if e.back_cap { 2 * front } else { front };
        }
        report.uncertain = counts.integer_decided;
        Ok(())
    }
}
