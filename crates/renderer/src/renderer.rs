//! The renderer: a device, a pipeline, and the frame's shared steps below the pipeline (world
//! positions, lighting, the plan, the attachments and their readback).

use crate::frame::{Frame, FrameImage, FrameReport, FrameTime};
use crate::lighting::{self, Exposure};
use crate::pipeline::{FrameInputs, GpuPipeline, HostPipeline, Recording, ShadowPipeline};
use crate::plan::{plan_frame, FramePlan, PlanPolicy};
use crate::raster::{FrameTargets, COLOR_FORMAT};
use crate::world::{World, WorldChanges};
use crate::{Accuracy, RenderDevice, RenderError};
use shadowvol_scenes::Scene;
use shadowvol_silhouette::SilhouetteBackend;
use std::time::Instant;

/// Image size, accuracy mode and plan policy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Accuracy mode of the silhouettes and caps.
    pub mode: Accuracy,
    /// What the planner may choose.
    pub policy: PlanPolicy,
    /// How lights with an emission map to the image ([`crate::lighting`]).
    pub exposure: Exposure,
    /// Limit each light's stencil and lit passes to the screen rectangle of its range or spot
    /// cone ([`crate::plan::light_scissor`]). The image is the same either way.
    pub scissor: bool,
    /// Points sampling each light with a size (`--light-samples`); `None`: the plan's choice
    /// ([`crate::soft::plan_samples`]).
    pub light_samples: Option<u32>,
}

impl RenderOptions {
    /// `width × height`, [`Accuracy::Exact`], [`PlanPolicy::Auto`], [`Exposure::Auto`], scissor
    /// on, the plan's light samples.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            mode: Accuracy::Exact,
            policy: PlanPolicy::Auto,
            exposure: Exposure::Auto,
            scissor: true,
            light_samples: None,
        }
    }
}

/// The renderer: a device, one [`ShadowPipeline`], and what it keeps between frames (world
/// positions, the attachments).
pub struct Renderer {
    device: RenderDevice,
    pipeline: Box<dyn ShadowPipeline>,
    options: RenderOptions,
    world: World,
    /// True when the pipeline must prepare the scene before its next frame.
    unprepared: bool,
    /// The framing camera of a scene without one, kept while nothing moves.
    default_camera: Option<crate::Camera>,
    /// The light meter of [`Exposure::Auto`].
    meter: lighting::ExposureMeter,
    targets: Option<FrameTargets>,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("adapter", &self.device.description)
            .field("pipeline", &self.pipeline.kind())
            .field("backend", &self.pipeline.backend())
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// A renderer drawing with `pipeline` on `device`.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a zero or too large image size.
    pub fn new(
        device: RenderDevice,
        pipeline: Box<dyn ShadowPipeline>,
        options: RenderOptions,
    ) -> Result<Self, RenderError> {
        device.check_size(options.width, options.height)?;
        Ok(Self {
            device,
            pipeline,
            options,
            world: World::default(),
            unprepared: true,
            default_camera: None,
            meter: lighting::ExposureMeter::default(),
            targets: None,
        })
    }

    /// Opens a device ([`RenderDevice::open`]) and draws with the host pipeline over `backend`.
    ///
    /// # Errors
    /// As [`RenderDevice::open`] and [`Renderer::new`].
    pub fn host(
        backend: Box<dyn SilhouetteBackend>,
        options: RenderOptions,
    ) -> Result<Self, RenderError> {
        Self::new(
            RenderDevice::open()?,
            Box::new(HostPipeline::new(backend)),
            options,
        )
    }

    /// Opens a device ([`RenderDevice::open`]) and draws with the GPU pipeline.
    ///
    /// # Errors
    /// As [`RenderDevice::open`] and [`Renderer::new`]; [`RenderError::Unsupported`] naming
    /// what the adapter lacks for the GPU pipeline.
    pub fn gpu(options: RenderOptions) -> Result<Self, RenderError> {
        let device = RenderDevice::open()?;
        if let Some(why) = &device.gpu_pipeline_unsupported {
            return Err(RenderError::Unsupported(why.clone()));
        }
        Self::new(device, Box::new(GpuPipeline::new()), options)
    }

    /// The device.
    #[must_use]
    pub fn device(&self) -> &RenderDevice {
        &self.device
    }

    /// The options in effect.
    #[must_use]
    pub fn options(&self) -> RenderOptions {
        self.options
    }

    /// Changes size, mode, policy, exposure or scissor.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a zero or too large image size.
    pub fn set_options(&mut self, options: RenderOptions) -> Result<(), RenderError> {
        self.device.check_size(options.width, options.height)?;
        self.options = options;
        Ok(())
    }

    /// The pipeline that draws the frames.
    #[must_use]
    pub fn pipeline(&self) -> &dyn ShadowPipeline {
        self.pipeline.as_ref()
    }

    /// Draws the next frames with `pipeline` (on the same device), and returns the one it
    /// replaces; the scene is prepared for it at the next frame.
    pub fn set_pipeline(&mut self, pipeline: Box<dyn ShadowPipeline>) -> Box<dyn ShadowPipeline> {
        self.unprepared = true;
        std::mem::replace(&mut self.pipeline, pipeline)
    }

    /// The colour format [`Renderer::render_into`] draws in.
    pub const COLOR_FORMAT: wgpu::TextureFormat = COLOR_FORMAT;

    /// Renders `scene` and reads back the image, the per-pixel ids and each light's stencil.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a bad camera, light or transform,
    /// [`RenderError::Backend`] when extraction fails, [`RenderError::Device`] on GPU failure.
    pub fn render(&mut self, scene: &Scene) -> Result<Frame, RenderError> {
        self.frame(scene, true, None)
    }

    /// Renders `scene` into `color`, a view of a texture on this renderer's device in
    /// [`Renderer::COLOR_FORMAT`], of the options' size, with `RENDER_ATTACHMENT` usage (which
    /// the caller can then sample or present). Nothing is read back but the plan's counts (the
    /// GPU pipeline: a few bytes per light and surface); the frame has no image.
    ///
    /// # Errors
    /// As [`Renderer::render`].
    pub fn render_into(
        &mut self,
        scene: &Scene,
        color: &wgpu::TextureView,
    ) -> Result<Frame, RenderError> {
        self.frame(scene, false, Some(color))
    }

    /// Renders `scene` like [`Renderer::render`] but reads nothing back (no image, ids, stencil
    /// or counts), waits for the device, and returns the wall time: what `render --frames`
    /// measures.
    ///
    /// # Errors
    /// As [`Renderer::render`].
    pub fn render_timed(&mut self, scene: &Scene) -> Result<FrameTime, RenderError> {
        let t0 = Instant::now();
        let frame = self.frame(scene, false, None)?;
        Ok(FrameTime {
            total_ms: t0.elapsed().as_secs_f64() * 1e3,
            readback_bytes: frame.report.readback_bytes,
            gpu_timings: frame.report.gpu_timings,
        })
    }

    /// One frame: world positions, preparation where the surfaces changed, lighting, plan, the
    /// pipeline's passes, and with `readback` the image; `into` draws the colour into the
    /// caller's view (and counts the plan's draws) instead.
    fn frame(
        &mut self,
        scene: &Scene,
        readback: bool,
        into: Option<&wgpu::TextureView>,
    ) -> Result<Frame, RenderError> {
        let t0 = Instant::now();
        let mut setup = self.set_up(scene)?;
        let t_raster = Instant::now();
        let mut report = self.report(&mut setup);
        let image = self.draw(scene, &setup, &mut report, readback, into)?;
        report.timings.raster_ms = ms(t_raster);
        report.timings.prepare_ms = setup.prepare_ms;
        report.timings.total_ms = ms(t0);
        report.light_colors = setup.light_colors;
        report.light_radii = scene.lights.iter().map(|l| l.radius).collect();
        report.samples = setup.samples;
        if let Some(e) = &setup.expanded {
            report.plan = e.merge_plan(std::mem::take(&mut report.plan), scene.lights.len());
        }
        let camera = setup.camera;
        Ok(Frame {
            image,
            report,
            camera,
            volumes: self.pipeline.volumes().to_vec(),
            samples: setup.expanded,
        })
    }

    /// What the passes draw from: world sync, preparation, camera, checks, exposure, plan.
    fn set_up(&mut self, scene: &Scene) -> Result<FrameSetup, RenderError> {
        let RenderOptions {
            width,
            height,
            policy,
            exposure,
            scissor,
            ..
        } = self.options;
        let t_prep = Instant::now();
        let changes = self.world.sync(scene)?;
        if self.unprepared || changes.surfaces {
            self.pipeline.prepare(&self.device, scene)?;
            self.unprepared = false;
        }
        let prepare_ms = ms(t_prep);
        let camera = self.camera(scene, &changes)?;
        check_effects(scene, exposure)?;
        let aspect = f64::from(width) / f64::from(height);
        let exposure = self
            .meter
            .exposure(scene, &self.world, &changes, &camera, aspect, exposure);
        let light_colors = lighting::light_colors(scene, exposure);
        let samples = if self.pipeline.kind() == crate::Pipeline::Map {
            // Shadow maps read the radius themselves (PCSS); nothing is sampled.
            scene
                .lights
                .iter()
                .map(|l| crate::soft::SamplesChoice {
                    samples: 1,
                    penumbra_px: 0.0,
                    reason: if l.radius > 0.0 {
                        "shadow maps: the filter reads the radius".to_owned()
                    } else {
                        "a point light (radius 0): hard shadows".to_owned()
                    },
                })
                .collect()
        } else {
            crate::soft::choose_samples(
                scene,
                &self.world,
                &camera,
                (width, height),
                self.options.light_samples,
            )
        };
        let counts: Vec<u32> = samples.iter().map(|c| c.samples).collect();
        let expanded = crate::soft::expand(scene, &counts, scene.light_aim());
        let shadow_scene = expanded.as_ref().map_or(scene, |e| &e.scene);
        let mut plan = plan_frame(
            shadow_scene,
            &self.world,
            &camera,
            (width, height),
            policy,
            scissor,
        );
        let mut pass_colors = light_colors.clone();
        if let Some(e) = &expanded {
            e.adjust_plan(&mut plan);
            pass_colors = e.of.iter().map(|&l| light_colors[l]).collect();
        }
        Ok(FrameSetup {
            changes,
            camera,
            exposure,
            light_colors,
            pass_colors,
            plan,
            prepare_ms,
            samples,
            expanded,
        })
    }

    /// The scene's camera, else the framing one (made again when the world changed), validated.
    fn camera(
        &mut self,
        scene: &Scene,
        changes: &WorldChanges,
    ) -> Result<crate::Camera, RenderError> {
        if changes.any() || self.default_camera.is_none() {
            self.default_camera = scene.camera_or_default();
        }
        let camera = scene.camera.or(self.default_camera).ok_or_else(|| {
            RenderError::InvalidInput(format!("scene {:?} has nothing to render", scene.name))
        })?;
        camera.validate()?;
        Ok(camera)
    }

    /// Records, submits and reads back the pipeline's passes; a failed frame drops the targets.
    fn draw(
        &mut self,
        scene: &Scene,
        setup: &FrameSetup,
        report: &mut FrameReport,
        readback: bool,
        into: Option<&wgpu::TextureView>,
    ) -> Result<Option<FrameImage>, RenderError> {
        let RenderOptions {
            width,
            height,
            mode,
            ..
        } = self.options;
        let shadow_scene = setup.expanded.as_ref().map_or(scene, |e| &e.scene);
        let n_lights = shadow_scene.lights.len();
        if !self
            .targets
            .as_ref()
            .is_some_and(|t| t.fits((width, height), n_lights, readback))
        {
            self.targets = Some(FrameTargets::new(
                &self.device.device,
                self.device.depth_format,
                (width, height),
                n_lights,
                readback,
                self.device.stencil_copies,
            ));
        }
        let is_map = self.pipeline.kind() == crate::Pipeline::Map;
        // The map pipeline writes each light's fractional visibility where the frame is read
        // back (its stencil holds only the map test).
        let soft_lights = match setup.expanded.as_ref() {
            Some(e) => e.soft_lights,
            None if is_map && readback => n_lights,
            None => 0,
        };
        if let Some(t) = self.targets.as_mut() {
            let slots = if readback { soft_lights } else { 0 };
            if soft_lights == 0 {
                t.soft = None;
            } else if !t
                .soft
                .as_ref()
                .is_some_and(|s| s.fits((width, height), slots))
            {
                t.soft = Some(crate::raster::soft::SoftTargets::new(
                    &self.device.device,
                    self.device.depth_format,
                    (width, height),
                    slots,
                ));
            }
        }
        let inputs = FrameInputs {
            device: &self.device,
            scene: shadow_scene,
            world: &self.world,
            changes: &setup.changes,
            camera: &setup.camera,
            size: (width, height),
            mode,
            scissors: &setup.plan.scissors,
            light_colors: &setup.pass_colors,
            count: readback || into.is_some(),
            passes: setup.expanded.as_ref().map_or(&[], |e| &e.passes),
        };
        let targets = self.targets.as_ref().expect("made above");
        let attachments = targets.attachments(into);
        let pipeline = &mut self.pipeline;
        let device = &self.device;
        let drawn = device
            .submit("frame", |enc| {
                pipeline.record(
                    &inputs,
                    Recording {
                        report: &mut *report,
                        target: &attachments,
                        enc,
                    },
                )?;
                if into.is_none() {
                    targets.copy_color_ids(enc);
                }
                Ok(())
            })
            .and_then(|()| targets.read(&device.device))
            .and_then(|image| {
                let Some(mut image) = image else {
                    return Ok(None);
                };
                let counts = match &targets.soft {
                    Some(soft) => soft.read(&device.device)?,
                    None => Vec::new(),
                };
                image.visibility = if is_map && counts.len() == n_lights {
                    counts
                } else {
                    crate::frame::visibilities(&image, setup.expanded.as_ref(), &counts)
                };
                Ok(Some(image))
            });
        let image = match drawn {
            Ok(image) => image,
            Err(e) => {
                // A failed or timed-out frame may leave its readback buffers mapped or in use:
                // the next frame makes new targets.
                self.targets = None;
                return Err(e);
            }
        };
        pipeline.finish(&inputs, report)?;
        report.shadow_maps = pipeline
            .maps()
            .iter()
            .map(|m| m.as_ref().map(crate::maps::LightMap::summary))
            .collect();
        Ok(image)
    }

    /// The frame's report before its passes: what draws it, the plan (taken from `setup`), the
    /// exposure; the pipeline and [`Renderer::frame`] fill in the rest.
    fn report(&self, setup: &mut FrameSetup) -> FrameReport {
        let (width, height) = (self.options.width, self.options.height);
        let pipeline = &self.pipeline;
        let mut report = FrameReport::new(pipeline.kind(), self.options.mode);
        report.backend = pipeline.backend().map(str::to_owned);
        report.adapter.clone_from(&self.device.description);
        report.scissor_pixels_saved = setup.plan.scissor_pixels_saved(width, height);
        report.plan = std::mem::take(&mut setup.plan.entries);
        report.exposure = setup.exposure;
        report.uncertain_unit = pipeline.uncertain_unit();
        report.depth_clamp = pipeline.depth_clamp(&self.device);
        report
    }
}

/// What a frame's passes are drawn from, worked out before them by [`Renderer::set_up`].
struct FrameSetup {
    /// What changed in the world since the last frame.
    changes: WorldChanges,
    /// The camera drawn from.
    camera: crate::Camera,
    /// The exposure factor (`None`: no light has an emission).
    exposure: Option<f32>,
    /// Per light: its colour at that exposure.
    light_colors: Vec<[f32; 3]>,
    /// Per light the pipeline draws (the expanded scene's, when lights have several samples):
    /// its colour.
    pass_colors: Vec<[f32; 3]>,
    /// Per scene light: its samples and why.
    samples: Vec<crate::soft::SamplesChoice>,
    /// The scene with its lights expanded into samples, when any light has several.
    expanded: Option<crate::soft::Expanded>,
    /// Techniques and scissors; the pipeline fills in the entries' counts.
    plan: FramePlan,
    /// Time in world sync and scene preparation, milliseconds.
    prepare_ms: f64,
}

/// Checks the ambient factor (in `[0, 1]`) and the lights' emissions under `exposure`.
fn check_effects(scene: &Scene, exposure: Exposure) -> Result<(), RenderError> {
    let ambient = scene.effects.ambient;
    if !(ambient.is_finite() && (0.0..=1.0).contains(&ambient)) {
        return Err(RenderError::InvalidInput(format!(
            "ambient is {ambient}; it must be in [0, 1]"
        )));
    }
    lighting::validate(scene, exposure).map_err(RenderError::InvalidInput)
}

/// Milliseconds since `t`.
fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
