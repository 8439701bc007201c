//! The stateful renderer: caches edge tables and silhouettes between frames, plans, draws.

mod host_frame;
mod resident_frame;

use host_frame::Extracted;

use crate::gpu::{FrameInput, Gpu, SurfaceVertex};
use crate::lighting::{self, Exposure};
use crate::plan::{PlanEntry, PlanPolicy};
use crate::volume::canonical_triangle;
use crate::{Camera, RenderError, RenderScene};
use glam::{Affine3A, DVec3, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{
    object_lights, PreparedId, SceneObject, SilhouetteBackend, TopologyScene,
};
use std::sync::Arc;
use std::time::{Duration, Instant};

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
    /// Keep the frame's shadow-volume vertices in [`Frame::volumes`] (for viewers that draw the
    /// volumes themselves; host pipeline only).
    pub keep_volumes: bool,
    /// Where silhouettes and volumes are built: on the host from the backend's multiplicities,
    /// or on the GPU without readback ([`crate::resident`]).
    pub pipeline: Pipeline,
}

/// Where a frame's silhouettes and shadow volumes are built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Pipeline {
    /// The backend's multiplicities come back to the host, which builds sides and caps and
    /// uploads them (any backend).
    Host,
    /// Extraction, sides and caps on the renderer's device with the [`crate::resident`] pass;
    /// nothing is read back during a frame (the backend is not used).
    Gpu,
}

impl Pipeline {
    /// `"host"` or `"gpu"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Pipeline::Host => "host",
            Pipeline::Gpu => "gpu",
        }
    }
}

/// One frame rendered without reading its image back ([`Renderer::render_timed`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameTime {
    /// Wall time from the start of the call until the device finished, milliseconds.
    pub total_ms: f64,
    /// Bytes brought to the host during the frame: for the host pipeline the multiplicities
    /// every extraction returned (4 bytes per edge and light), for the GPU pipeline 0.
    pub readback_bytes: u64,
    /// GPU pipeline on a device with timestamp queries: the GPU time of each pass (read after
    /// the frame; not counted in `readback_bytes`).
    pub gpu_timings: Option<crate::resident::GpuTimings>,
}

impl RenderOptions {
    /// `width × height`, [`Accuracy::Exact`], [`PlanPolicy::Auto`], [`Exposure::Auto`].
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            mode: Accuracy::Exact,
            policy: PlanPolicy::Auto,
            exposure: Exposure::Auto,
            scissor: true,
            keep_volumes: false,
            pipeline: Pipeline::Host,
        }
    }
}

/// Wall times of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    /// Backend `extract` calls (wall time), milliseconds.
    pub silhouette_ms: f64,
    /// Building side quads and caps on the host, milliseconds.
    pub side_building_ms: f64,
    /// Surface geometry, upload, all passes, readback, milliseconds.
    pub raster_ms: f64,
    /// Edge tables built and uploaded (`prepare`) this frame, milliseconds.
    pub prepare_ms: f64,
    /// Whole `render` call, milliseconds.
    pub total_ms: f64,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// A rendered frame: the image, the per-pixel data the reference needs, and the plan.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 pixels, top row first.
    pub rgba: Vec<u8>,
    /// Per pixel `[object + 1, triangle]`, `[0, _]` for background.
    pub ids: Vec<[u32; 2]>,
    /// Per light, per pixel stencil after the light's stencil pass (0 = lit by the volumes).
    pub stencil: Vec<Vec<u8>>,
    /// World-space triangles (the `f32` positions every pass used), per object, canonical order.
    pub triangles: Vec<Vec<[Vec3; 3]>>,
    /// Per object: does it cast shadows (false for receiver-only objects).
    pub casts_shadows: Vec<bool>,
    /// Per object: its albedo.
    pub albedo: Vec<[f32; 3]>,
    /// Per light: the colour times gain its lit pass multiplies by `albedo × attenuation × cos θ`.
    pub light_color: Vec<[f32; 3]>,
    /// The ambient factor of the pre-pass (`albedo × ambient`).
    pub ambient: f32,
    /// Per light: what it emits (empty: unit lights, no attenuation).
    pub emission: Vec<shadowvol_scenes::Emission>,
    /// Output per lux used for the lights with an emission (`None` without any).
    pub exposure: Option<f32>,
    /// Pixels the per-light scissor kept out of the stencil and lit passes, summed over lights
    /// (`width × height` minus each light's rectangle).
    pub scissor_pixels_saved: usize,
    /// Exact mode: evaluations the certified filter could not decide. Host pipeline: (edge,
    /// opposite vertex, light) triples of this frame's extractions, decided by the backend's
    /// exact fallback; GPU pipeline: (triangle, light) pairs, decided on the device with exact
    /// integer arithmetic.
    pub uncertain: u64,
    /// Of those, the ones decided on the host: all of them in the host pipeline, 0 in the GPU
    /// pipeline.
    pub host_resolved: u64,
    /// The pipeline that drew the frame.
    pub pipeline: Pipeline,
    /// GPU pipeline on a device with timestamp queries: the GPU time of each pass.
    pub gpu_timings: Option<crate::resident::GpuTimings>,
    /// With [`RenderOptions::keep_volumes`]: every shadow-volume vertex drawn, as triangles,
    /// relative to the camera's eye (`w = 0`: extruded to infinity); empty otherwise.
    pub volumes: Vec<[f32; 4]>,
    /// The lights.
    pub lights: Vec<Light>,
    /// The camera.
    pub camera: Camera,
    /// The plan, light-major.
    pub plan: Vec<PlanEntry>,
    /// Timings.
    pub timings: Timings,
    /// The accuracy mode.
    pub mode: Accuracy,
    /// The GPU adapter used.
    pub adapter: String,
    /// True when the volumes were drawn with depth clamp.
    pub depth_clamp: bool,
}

impl Frame {
    /// The image as an `image` buffer.
    ///
    /// # Panics
    /// Never for frames produced by [`Renderer::render`].
    #[must_use]
    pub fn image(&self) -> image::RgbaImage {
        image::RgbaImage::from_raw(self.width, self.height, self.rgba.clone())
            .expect("size matches")
    }

    /// Writes the image as PNG.
    ///
    /// # Errors
    /// [`RenderError::Image`] when the file cannot be written.
    pub fn save_png(&self, path: impl AsRef<std::path::Path>) -> Result<(), RenderError> {
        let p = path.as_ref();
        self.image()
            .save_with_format(p, image::ImageFormat::Png)
            .map_err(|e| RenderError::Image {
                path: p.display().to_string(),
                message: e.to_string(),
            })
    }

    /// The plan as text, one line per (light, object).
    #[must_use]
    pub fn explain(&self) -> String {
        let mut s = format!(
            "mode {}; adapter {}; depth clamp {}; infinite far plane\n",
            self.mode,
            self.adapter,
            if self.depth_clamp { "on" } else { "off" }
        );
        for e in &self.plan {
            s.push_str(&e.to_string());
            s.push('\n');
        }
        s
    }
}

/// What a prepared whole scene was built from, per object: its mesh and transform.
type ObjectKey = (Arc<Mesh>, Affine3A);

struct LightCache {
    light: Light,
    mode: Accuracy,
    m: Vec<i32>,
}

struct ObjectCache {
    mesh: Arc<Mesh>,
    table: Arc<EdgeTable>,
    prepared: PreparedId,
    transform: Affine3A,
    world: Vec<Vec3>,
    lights: Vec<Option<LightCache>>,
}

/// The renderer: a GPU device, a silhouette backend and the per-(object, light) silhouette cache.
pub struct Renderer {
    gpu: Gpu,
    backend: Box<dyn SilhouetteBackend>,
    options: RenderOptions,
    cache: Vec<ObjectCache>,
    /// Per object: new mesh or new transform in this frame's `sync_objects`.
    changed: Vec<bool>,
    /// The whole scene prepared at once (real transforms), with the (mesh, transform) of each
    /// object it was prepared for.
    whole: Option<(PreparedId, Vec<ObjectKey>)>,
    /// The GPU pipeline's pass and the scene uploaded to it, built on first use.
    resident: resident_frame::ResidentState,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("gpu", &self.gpu)
            .field("backend", &self.backend.info().name)
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// Opens a GPU device and takes the silhouette backend.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] without a GPU adapter, [`RenderError::Device`] when the device
    /// or pipelines fail, [`RenderError::InvalidInput`] for a zero image size.
    pub fn new(
        backend: Box<dyn SilhouetteBackend>,
        options: RenderOptions,
    ) -> Result<Self, RenderError> {
        check_size(&options)?;
        Ok(Self::with_gpu(Gpu::new()?, backend, options))
    }

    /// A renderer over `gpu`, with empty caches.
    fn with_gpu(gpu: Gpu, backend: Box<dyn SilhouetteBackend>, options: RenderOptions) -> Self {
        Self {
            gpu,
            backend,
            options,
            cache: Vec::new(),
            changed: Vec::new(),
            whole: None,
            resident: resident_frame::ResidentState::default(),
        }
    }

    /// The options in effect.
    #[must_use]
    pub fn options(&self) -> RenderOptions {
        self.options
    }

    /// Changes size, mode or policy; cached silhouettes of another mode are not reused.
    pub fn set_options(&mut self, options: RenderOptions) {
        self.options = options;
    }

    /// Why this renderer's adapter cannot run [`Pipeline::Gpu`] (a missing capability or
    /// limit, named), or `None` when it can.
    #[must_use]
    pub fn gpu_pipeline_unsupported(&self) -> Option<&str> {
        self.gpu.resident_unsupported.as_deref()
    }

    /// The GPU adapter, in words.
    #[must_use]
    pub fn adapter(&self) -> &str {
        &self.gpu.adapter
    }

    /// Renders `scene`: plan, silhouettes (reused where nothing moved), volumes, passes.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a bad camera or light, [`RenderError::Mesh`] for an
    /// invalid mesh, [`RenderError::Backend`] when extraction fails, [`RenderError::Device`] on
    /// GPU failure.
    pub fn render(&mut self, scene: &RenderScene) -> Result<Frame, RenderError> {
        let (frame, _) = self.frame(scene, true, None)?;
        Ok(frame.expect("a frame with readback has its image"))
    }

    /// Opens the renderer on a device the caller opened on `adapter`, for example a window's,
    /// so that [`Renderer::render_into`] draws into the caller's textures. Open the device with
    /// [`Renderer::device_requirements`] for every pipeline the adapter can run.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a zero image size, [`RenderError::Device`] when the
    /// pipelines cannot be created.
    pub fn on_device(
        backend: Box<dyn SilhouetteBackend>,
        options: RenderOptions,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Self, RenderError> {
        check_size(&options)?;
        Ok(Self::with_gpu(
            Gpu::on_device(adapter, device, queue)?,
            backend,
            options,
        ))
    }

    /// The features and limits to open a device on `adapter` with, for
    /// [`Renderer::on_device`]: depth clamp and 32-bit float depth where the adapter has them,
    /// and the GPU pipeline's needs where it can run it.
    #[must_use]
    pub fn device_requirements(adapter: &wgpu::Adapter) -> (wgpu::Features, wgpu::Limits) {
        Gpu::requirements(adapter)
    }

    /// The colour format [`Renderer::render_into`] draws in.
    pub const COLOR_FORMAT: wgpu::TextureFormat = crate::gpu::COLOR_FORMAT;

    /// Renders `scene` with the GPU pipeline into `color`, a view of a texture on this
    /// renderer's device in [`Renderer::COLOR_FORMAT`], of the options' size, with
    /// `RENDER_ATTACHMENT` usage (which the caller can then sample or present). Nothing is read
    /// back but the plan's counts (a few bytes per light and object); the returned frame has
    /// the plan, counts and timings, and empty `rgba`, `ids` and `stencil`.
    ///
    /// # Errors
    /// [`RenderError::Unsupported`] unless the options' pipeline is [`Pipeline::Gpu`] and the
    /// device can run it; otherwise as [`Renderer::render`].
    pub fn render_into(
        &mut self,
        scene: &RenderScene,
        color: &wgpu::TextureView,
    ) -> Result<Frame, RenderError> {
        if self.options.pipeline != Pipeline::Gpu {
            return Err(RenderError::Unsupported(
                "render_into draws the GPU pipeline only; set RenderOptions::pipeline to Gpu"
                    .to_owned(),
            ));
        }
        let (frame, _) = self.frame(scene, false, Some(color))?;
        Ok(frame.expect("render_into returns its frame"))
    }

    /// Renders `scene` like [`Renderer::render`] but reads nothing back (no image, ids or
    /// stencil, and in the GPU pipeline nothing at all), waits for the device, and returns the
    /// wall time: what `render --frames` measures.
    ///
    /// # Errors
    /// As [`Renderer::render`].
    pub fn render_timed(&mut self, scene: &RenderScene) -> Result<FrameTime, RenderError> {
        let t0 = Instant::now();
        let (_, readback_bytes) = self.frame(scene, false, None)?;
        let total_ms = ms(t0.elapsed());
        Ok(FrameTime {
            total_ms,
            readback_bytes,
            gpu_timings: self.last_gpu_timings()?,
        })
    }

    /// One frame; with `readback` the image and per-pixel data come back as a [`Frame`]; with
    /// `into` (GPU pipeline) the colour goes to that view and a frame without images returns.
    /// Returns the frame and the bytes brought to the host besides the image.
    fn frame(
        &mut self,
        scene: &RenderScene,
        readback: bool,
        into: Option<&wgpu::TextureView>,
    ) -> Result<(Option<Frame>, u64), RenderError> {
        let t0 = Instant::now();
        scene.camera.validate()?;
        if !(scene.ambient.is_finite() && (0.0..=1.0).contains(&scene.ambient)) {
            return Err(RenderError::InvalidInput(format!(
                "ambient is {}; it must be in [0, 1]",
                scene.ambient
            )));
        }
        let RenderOptions {
            width,
            height,
            mode,
            exposure,
            keep_volumes,
            pipeline,
            ..
        } = self.options;
        lighting::validate(scene, exposure).map_err(RenderError::InvalidInput)?;
        let exposure = lighting::exposure_factor(scene, exposure);
        let colors = lighting::light_colors(scene, exposure);
        let aspect = f64::from(width) / f64::from(height);

        // 1. Edge tables, world positions, cache invalidation.
        let t_prep = Instant::now();
        self.sync_objects(scene)?;
        let prepare_time = t_prep.elapsed();

        // 2. Plan.
        let (mut entries, scissors) = self.plan_frame(scene, aspect);

        if pipeline == Pipeline::Gpu {
            return self.frame_gpu(
                scene,
                resident_frame::Planned {
                    entries,
                    scissors,
                    colors,
                    exposure,
                    t0,
                    prepare_time,
                },
                readback,
                into,
            );
        }

        // 3. Silhouettes.
        let Extracted {
            time: silhouette_time,
            uncertain,
            readback_bytes,
        } = self.extract_silhouettes(scene, &mut entries)?;

        // 4. Volumes.
        let t_build = Instant::now();
        let (mut volumes, mut draws) =
            self.build_volumes(scene, &mut entries, &colors, &scissors)?;
        // Camera-relative coordinates for the GPU: every finite vertex (surface and volume) is
        // shifted by the same f32 subtraction, so shared vertices stay bit-identical and depth
        // precision no longer suffers from large world coordinates (the 1e4-offset scenes).
        // Extrusion directions (w = 0) do not depend on the origin.
        let origin = scene.camera.eye;
        for v in &mut volumes {
            if v[3] != 0.0 {
                v[0] -= origin.x;
                v[1] -= origin.y;
                v[2] -= origin.z;
            }
        }
        for d in &mut draws {
            let w = d.light[3];
            d.light[0] -= origin.x * w;
            d.light[1] -= origin.y * w;
            d.light[2] -= origin.z * w;
        }
        let build_time = t_build.elapsed();

        // 5. Surfaces and passes.
        let t_raster = Instant::now();
        let mut surface = Vec::new();
        let mut triangles = Vec::with_capacity(scene.objects.len());
        for (oi, obj) in scene.objects.iter().enumerate() {
            let c = &self.cache[oi];
            let mut tris = Vec::with_capacity(if readback { c.table.triangles.len() } else { 0 });
            for (ti, t) in c.table.triangles.iter().enumerate() {
                let k = canonical_triangle(*t);
                let p = [
                    c.world[k[0] as usize],
                    c.world[k[1] as usize],
                    c.world[k[2] as usize],
                ];
                let n = (p[1] - p[0]).cross(p[2] - p[0]);
                for v in p {
                    let v = v - origin;
                    surface.push(SurfaceVertex {
                        pos: [v.x, v.y, v.z, 1.0],
                        normal: [n.x, n.y, n.z, 0.0],
                        albedo: [obj.albedo[0], obj.albedo[1], obj.albedo[2], 1.0],
                        ids: [oi as u32 + 1, ti as u32],
                        pad: [0; 2],
                    });
                }
                if readback {
                    tris.push(p);
                }
            }
            triangles.push(tris);
        }
        let out = self.gpu.render(&FrameInput {
            width,
            height,
            view_proj: Camera {
                eye: Vec3::ZERO,
                target: scene.camera.target - origin,
                ..scene.camera
            }
            .view_proj(aspect as f32)
            .to_cols_array(),
            eye: [0.0; 3],
            ambient: scene.ambient,
            surface: &surface,
            volumes: &volumes,
            lights: &draws,
            readback,
        })?;
        let raster_time = t_raster.elapsed();
        let Some(out) = out else {
            return Ok((None, readback_bytes));
        };

        Ok((
            Some(Frame {
                width,
                height,
                rgba: out.color,
                ids: out.ids,
                stencil: out.stencil,
                triangles,
                casts_shadows: scene.objects.iter().map(|o| o.casts_shadows).collect(),
                albedo: scene.objects.iter().map(|o| o.albedo).collect(),
                light_color: colors,
                ambient: scene.ambient,
                emission: scene.emission.clone(),
                exposure,
                scissor_pixels_saved: scissor_pixels_saved(&scissors, width, height),
                uncertain,
                host_resolved: uncertain,
                pipeline,
                gpu_timings: None,
                volumes: if keep_volumes { volumes } else { Vec::new() },
                lights: scene.lights.clone(),
                camera: scene.camera,
                plan: entries,
                timings: Timings {
                    silhouette_ms: ms(silhouette_time),
                    side_building_ms: ms(build_time),
                    raster_ms: ms(raster_time),
                    prepare_ms: ms(prepare_time),
                    total_ms: ms(t0.elapsed()),
                },
                mode,
                adapter: self.gpu.adapter.clone(),
                depth_clamp: self.gpu.depth_clamp,
            }),
            readback_bytes,
        ))
    }

    /// Brings the per-object cache in line with the scene: new meshes get an edge table and a
    /// prepared backend scene; moved objects get new world positions and lose their silhouettes.
    fn sync_objects(&mut self, scene: &RenderScene) -> Result<(), RenderError> {
        let n_lights = scene.lights.len();
        self.changed.clear();
        self.changed.resize(scene.objects.len(), false);
        // Drop objects beyond the scene.
        while self.cache.len() > scene.objects.len() {
            let c = self.cache.pop().expect("non-empty");
            self.backend.release(c.prepared);
        }
        for (oi, obj) in scene.objects.iter().enumerate() {
            if !obj.world_from_object.is_finite()
                || obj.world_from_object.matrix3.determinant() == 0.0
            {
                return Err(RenderError::InvalidInput(format!(
                    "object {:?}: transform is not finite and invertible",
                    obj.name
                )));
            }
            let same_mesh = self
                .cache
                .get(oi)
                .is_some_and(|c| Arc::ptr_eq(&c.mesh, &obj.mesh));
            if !same_mesh {
                let table =
                    Arc::new(
                        EdgeTable::build(&obj.mesh).map_err(|source| RenderError::Mesh {
                            object: obj.name.clone(),
                            source,
                        })?,
                    );
                let topo = TopologyScene {
                    objects: vec![SceneObject {
                        name: obj.name.clone(),
                        table: table.clone(),
                        world_from_object: Affine3A::IDENTITY,
                    }],
                };
                let prepared = self.backend.prepare(&topo)?;
                let world = world_positions(&table, obj.world_from_object);
                let entry = ObjectCache {
                    mesh: obj.mesh.clone(),
                    table,
                    prepared,
                    transform: obj.world_from_object,
                    world,
                    lights: Vec::new(),
                };
                self.changed[oi] = true;
                if oi < self.cache.len() {
                    let old = std::mem::replace(&mut self.cache[oi], entry);
                    self.backend.release(old.prepared);
                } else {
                    self.cache.push(entry);
                }
            }
            let c = &mut self.cache[oi];
            if c.transform != obj.world_from_object {
                self.changed[oi] = true;
                c.transform = obj.world_from_object;
                c.world = world_positions(&c.table, obj.world_from_object);
                c.lights.clear();
            }
            c.lights.resize_with(n_lights, || None);
        }
        Ok(())
    }
}

impl Renderer {
    /// The whole scene (every object with its transform) prepared on the backend, re-prepared
    /// only when an object's mesh or transform differs from the last preparation.
    fn whole_scene(&mut self, scene: &RenderScene) -> Result<PreparedId, RenderError> {
        let current = |k: &[ObjectKey], cache: &[ObjectCache]| {
            k.len() == cache.len()
                && k.iter()
                    .zip(cache)
                    .all(|((m, t), c)| Arc::ptr_eq(m, &c.mesh) && *t == c.transform)
        };
        if let Some((id, key)) = &self.whole {
            if current(key, &self.cache) {
                return Ok(*id);
            }
        }
        if let Some((id, _)) = self.whole.take() {
            self.backend.release(id);
        }
        let topo = TopologyScene {
            objects: self
                .cache
                .iter()
                .zip(&scene.objects)
                .map(|(c, o)| SceneObject {
                    name: o.name.clone(),
                    table: c.table.clone(),
                    world_from_object: c.transform,
                })
                .collect(),
        };
        let id = self.backend.prepare(&topo)?;
        let key = self
            .cache
            .iter()
            .map(|c| (c.mesh.clone(), c.transform))
            .collect();
        self.whole = Some((id, key));
        Ok(id)
    }
}

/// World positions of the welded vertices: the object transform applied in `f32` once.
/// A zero image size is an input error (before any device is opened).
fn check_size(options: &RenderOptions) -> Result<(), RenderError> {
    if options.width == 0 || options.height == 0 {
        return Err(RenderError::InvalidInput(format!(
            "image size {}x{}: both sides must be at least 1",
            options.width, options.height
        )));
    }
    Ok(())
}

fn world_positions(table: &EdgeTable, t: Affine3A) -> Vec<Vec3> {
    table
        .positions
        .iter()
        .map(|&p| t.transform_point3(p))
        .collect()
}

fn bounds_f64(points: &[Vec3]) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.min(p.as_dvec3());
        hi = hi.max(p.as_dvec3());
    }
    (lo, hi)
}

/// The object-space lights through [`object_lights`] (the one shared conversion), as `Light`s.
fn object_space_lights(
    name: &str,
    table: &Arc<EdgeTable>,
    transform: Affine3A,
    lights: &[Light],
) -> Result<Vec<Light>, RenderError> {
    let topo = TopologyScene {
        objects: vec![SceneObject {
            name: name.to_owned(),
            table: table.clone(),
            world_from_object: transform,
        }],
    };
    object_lights(&topo, lights)[0]
        .iter()
        .map(|&l| {
            Light::try_from(l).map_err(|e| {
                RenderError::InvalidInput(format!(
                    "object {name:?}: light in object space {l:?}: {e}"
                ))
            })
        })
        .collect()
}

/// Pixels the per-light scissors keep out of the stencil and lit passes, summed over lights.
fn scissor_pixels_saved(scissors: &[Option<[u32; 4]>], width: u32, height: u32) -> usize {
    scissors
        .iter()
        .flatten()
        .map(|r| (width * height - r[2] * r[3]) as usize)
        .sum()
}
