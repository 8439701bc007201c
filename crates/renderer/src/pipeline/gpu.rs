//! The GPU pipeline: the plan's techniques go to the resident pass
//! ([`crate::resident::ShadowPass`]), which extracts, builds and draws the volumes on the device
//! in the frame's command encoder. The host writes only small per-frame inputs; no silhouette
//! backend runs.

use super::{FrameInputs, Pipeline, Recording, ShadowPipeline};
use crate::frame::{FrameReport, GpuTimings};
use crate::plan::{SilhouetteSource, Technique};
use crate::raster::{BACKGROUND, COLOR_FORMAT, IDS_FORMAT};
use crate::resident::{PassFormats, PassFrame, ResidentScene, ShadowPass, SurfaceVertices};
use crate::{RenderDevice, RenderError};
use glam::Affine3A;
use shadowvol_silhouette::{PreparedBytes, SceneParts};

/// The GPU pipeline: the plan's techniques go to the resident pass
/// ([`crate::resident::ShadowPass`]), which extracts, builds and draws the volumes on the device
/// in the frame's command encoder. The host writes only small per-frame inputs; no silhouette
/// backend runs.
#[derive(Debug, Default)]
pub struct GpuPipeline {
    pass: Option<ShadowPass>,
    /// The uploaded scene: one part, or several where one would exceed a storage binding.
    parts: Vec<Part>,
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

    /// The resident pass and the uploaded scene, once prepared; `None` for a scene uploaded in
    /// parts (one beyond a storage binding of the device).
    #[must_use]
    pub fn resident(&self) -> Option<(&ShadowPass, &ResidentScene)> {
        match self.parts.as_slice() {
            [one] => self.pass.as_ref().map(|p| (p, &one.rs)),
            _ => None,
        }
    }

    /// Uploads `scene` in parts ([`SceneParts`]) of whole triangles that each fit the device's
    /// storage bindings. The largest binding of a part of `N` triangles is its packed tables
    /// ([`shadowvol_gpu::TablePacking`]): at most `3 N` vertices (a soup) and `3 N` edges, and
    /// `3 N` OV slots, so positions 36 bytes a triangle, edge ends 24, OV offsets 12, OV
    /// references 12, triangles 12 and vertex objects 12: 108 bytes a triangle, besides the
    /// object bases (16 bytes an object); its world positions (48) and a light's side records
    /// (12) are smaller.
    fn prepare_parts(
        pass: &ShadowPass,
        device: &RenderDevice,
        scene: &shadowvol_scenes::Scene,
    ) -> Result<Vec<Part>, RenderError> {
        let limits = device.device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let objects = 16 * (scene.surfaces().count() as u64 + 1);
        let budget = (limit.saturating_sub(64 + objects) / 108).max(1) as usize;
        let parts = SceneParts::split(&scene.surface_geometry(), budget);
        // Each part's table is built, uploaded and dropped in turn.
        (0..parts.len())
            .zip(&parts.sources)
            .map(|(k, sources)| {
                let part = parts.part(k).map_err(|source| RenderError::Mesh {
                    object: format!("part {k} of the scene"),
                    source,
                })?;
                let mut rs = pass.prepare_topology(&part)?;
                rs.ids = sources
                    .iter()
                    .map(|&(o, first)| [o as u32, first])
                    .collect();
                Ok(Part {
                    rs,
                    objects: sources.iter().map(|&(o, _)| o).collect(),
                })
            })
            .collect()
    }
}

/// One uploaded part of the scene and, per object of it, the scene's surface it draws.
#[derive(Debug)]
struct Part {
    rs: ResidentScene,
    objects: Vec<usize>,
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
        let mut b = PreparedBytes::default();
        for p in &self.parts {
            let pb = p.rs.bytes();
            b.host += pb.host + shadowvol_silhouette::vec_bytes(&p.objects);
            b.device += pb.device;
        }
        b
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
        // One choice for the whole scene, which may be uploaded in parts.
        let tris = scene.surfaces().map(|s| s.table.triangles.len()).sum();
        let pass = self.pass.as_mut().expect("built above");
        pass.set_surface_vertices(SurfaceVertices::from_env()?.resolve(tris));
        let pass = &*pass;
        self.parts.clear();
        self.parts = match pass.prepare(scene) {
            Ok(rs) => vec![Part {
                rs,
                objects: (0..scene.surfaces().count()).collect(),
            }],
            Err(RenderError::TooLarge(_)) => Self::prepare_parts(pass, device, scene)?,
            Err(e) => return Err(e),
        };
        self.albedo = scene.surfaces().map(|s| s.albedo).collect();
        self.transforms = scene.surfaces().map(|s| s.world_from_object).collect();
        Ok(())
    }

    fn record(&mut self, frame: &FrameInputs<'_>, rec: Recording<'_>) -> Result<(), RenderError> {
        let (report, target, enc) = (rec.report, rec.target, rec.enc);
        let plan = &mut report.plan;
        let Some(pass) = self.pass.as_ref().filter(|_| !self.parts.is_empty()) else {
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
        let n = self.transforms.len();
        let lights = frame.scene.lights.len();
        let sample_groups = frame.sample_groups();
        for part in &mut self.parts {
            // This part's objects' inputs, from their surfaces' (the identity for one part).
            let transforms: Vec<Affine3A> =
                part.objects.iter().map(|&o| self.transforms[o]).collect();
            let albedo: Vec<[f32; 3]> = part.objects.iter().map(|&o| self.albedo[o]).collect();
            let techniques: Vec<Technique> = (0..lights)
                .flat_map(|l| part.objects.iter().map(move |&o| l * n + o))
                .map(|i| self.techniques[i])
                .collect();
            pass.update(
                &mut part.rs,
                &PassFrame {
                    camera: frame.camera,
                    aspect: (f64::from(w) / f64::from(h)) as f32,
                    lights: &frame.scene.lights,
                    colors: frame.light_colors,
                    transforms: &transforms,
                    albedo: &albedo,
                    techniques: &techniques,
                    scissors: frame.scissors,
                    ambient: frame.scene.effects.ambient.clamp(0.0, 1.0),
                    mode: frame.mode,
                    count: frame.count,
                    sample_groups: &sample_groups,
                },
            )?;
            pass.encode_extract(enc, &part.rs);
        }
        // The first part clears the targets; the others draw over it, into the same depth and
        // stencil, so that the volumes of every part count for every pixel.
        for (k, part) in self.parts.iter().enumerate() {
            let clear = (k == 0).then_some(BACKGROUND);
            let (color, ids) = (target.color, target.ids);
            pass.encode_prepass(enc, &part.rs, color, ids, target.depth_stencil, clear);
        }
        for li in 0..lights {
            for (k, part) in self.parts.iter().enumerate() {
                let stencil = if k == 0 {
                    wgpu::LoadOp::Clear(0)
                } else {
                    wgpu::LoadOp::Load
                };
                pass.encode_stencil(enc, &part.rs, li, target.depth_stencil, stencil);
            }
            target.after_stencil(enc, li);
            super::light_output(frame.pass(li), target, enc, |enc, color| {
                for part in &self.parts {
                    pass.encode_lit(enc, &part.rs, li, color, target.depth_stencil);
                }
            })?;
        }
        for e in plan.iter_mut().filter(|e| e.technique != Technique::Culled) {
            e.silhouette = SilhouetteSource::Extracted;
        }
        Ok(())
    }

    fn finish(
        &mut self,
        frame: &FrameInputs<'_>,
        out: &mut FrameReport,
    ) -> Result<(), RenderError> {
        let Some(pass) = self.pass.as_ref() else {
            return Ok(());
        };
        let mut timings: Option<GpuTimings> = None;
        for part in &self.parts {
            if let Some(t) = pass.read_timings(&part.rs)? {
                let sum = timings.get_or_insert_with(GpuTimings::default);
                sum.extract += t.extract;
                sum.sides += t.sides;
                sum.caps += t.caps;
                sum.stencil += t.stencil;
                sum.lighting += t.lighting;
                sum.shadow_maps += t.shadow_maps;
            }
        }
        out.gpu_timings = timings;
        out.scene_parts = self.parts.len();
        out.surface_vertices = self
            .parts
            .first()
            .map(|p| p.rs.surface_vertices().to_owned());
        if !frame.count {
            return Ok(());
        }
        let plan = &mut out.plan;
        let n = frame.world.surfaces().len();
        debug_assert_eq!(
            plan.len(),
            frame.scene.lights.len() * n,
            "one entry per (light, surface)"
        );
        for e in plan.iter_mut() {
            e.silhouette_edges = 0;
            e.side_quads = 0;
            e.cap_triangles = 0;
        }
        out.uncertain = 0;
        for part in &self.parts {
            let counts = pass.read_counts(&part.rs)?;
            let m = part.objects.len();
            for (k, &o) in part.objects.iter().enumerate() {
                for l in 0..frame.scene.lights.len() {
                    let e = &mut plan[l * n + o];
                    if e.technique == Technique::Culled {
                        continue;
                    }
                    let i = l * m + k;
                    e.silhouette_edges += counts.silhouette_edges[i] as usize;
                    e.side_quads += counts.side_quads[i] as usize;
                    let front = counts.cap_triangles[i] as usize;
                    e.cap_triangles += if e.back_cap { 2 * front } else { front };
                }
            }
            out.uncertain += counts.integer_decided;
        }
        Ok(())
    }
}
