//! The wgpu side: device, pipelines, one frame's passes, readback.
//!
//! Passes of a frame (one command buffer):
//! 1. pre-pass: colour = ambient × albedo, ids (object + 1, triangle), depth (less, write);
//! 2. per light: stencil pass (stencil cleared to 0; two-sided, wrapping; depth test `less`,
//!    no depth write) over z-pass volumes and z-fail volumes; a copy of the stencil aspect to a
//!    buffer (the per-pixel shadow state the metric compares); a lit pass (depth `equal`,
//!    stencil `== 0`, additive Lambert).

use crate::RenderError;
pub(crate) use targets::{map_read, wait};
use targets::{padded_row, FrameTargets};

pub(crate) mod pipelines;
pub(crate) mod states;
mod targets;
use bytemuck::{Pod, Zeroable};
use pipelines::{color_target, uniform};
use std::ops::Range;

/// Vertex of the visible surfaces (non-indexed; flat triangle data repeated on its 3 vertices).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct SurfaceVertex {
    /// World position, `w = 1`.
    pub pos: [f32; 4],
    /// Geometric normal of the triangle in canonical order (`w` unused).
    pub normal: [f32; 4],
    /// Albedo (`a` unused).
    pub albedo: [f32; 4],
    /// `[object + 1, triangle index within the object]`.
    pub ids: [u32; 2],
    /// Padding.
    pub pad: [u32; 2],
}

/// The draws of one light, as vertex ranges into the frame's volume vertex buffer.
#[derive(Debug, Clone, Default)]
pub struct LightDraws {
    /// World light `(x, y, z, w)`.
    pub light: [f32; 4],
    /// Light colour times gain (linear RGB).
    pub color: [f32; 3],
    /// Scissor `[x, y, width, height]` of its stencil and lit passes (`None`: whole image).
    pub scissor: Option<[u32; 4]>,
    /// What it emits: range and cone attenuation in the lit pass (`None`: a unit light).
    pub emission: Option<shadowvol_scenes::Emission>,
    /// Z-pass sides (counter-clockwise front faces).
    pub zpass: Range<u32>,
    /// Z-fail sides and back caps and `σ = +1` front caps (counter-clockwise front faces).
    pub zfail_ccw: Range<u32>,
    /// Z-fail `σ = −1` front caps (clockwise front faces).
    pub zfail_cw: Range<u32>,
}

/// Everything the GPU needs for one frame.
#[derive(Debug, Clone)]
pub struct FrameInput<'a> {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Column-major `projection * view`.
    pub view_proj: [f32; 16],
    /// Eye position.
    pub eye: [f32; 3],
    /// Ambient factor.
    pub ambient: f32,
    /// Surface triangles (3 vertices each).
    pub surface: &'a [SurfaceVertex],
    /// All volume vertices of all lights.
    pub volumes: &'a [[f32; 4]],
    /// Per-light draws.
    pub lights: &'a [LightDraws],
    /// Copy colour, ids and per-light stencil back; without it, only wait for the device.
    pub readback: bool,
}

/// What comes back from the GPU.
#[derive(Debug, Clone, Default)]
pub struct FrameOutput {
    /// RGBA8, row-major, top row first.
    pub color: Vec<u8>,
    /// Per pixel `[object + 1, triangle]`; `[0, _]` is background.
    pub ids: Vec<[u32; 2]>,
    /// Per light, the stencil value of every pixel after its stencil pass.
    pub stencil: Vec<Vec<u8>>,
}

/// A headless wgpu device with the renderer's pipelines.
pub struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    /// Adapter name and backend, in words.
    pub adapter: String,
    /// Depth-stencil format used.
    pub depth_format: wgpu::TextureFormat,
    /// True when z-fail volumes are drawn with `unclipped_depth` (depth clamp).
    pub depth_clamp: bool,
    /// The adapter the device was opened on (the GPU pipeline checks its capabilities).
    pub wgpu_adapter: wgpu::Adapter,
    /// Why the GPU pipeline cannot run on this adapter, if it cannot.
    pub resident_unsupported: Option<String>,
    globals_bgl: wgpu::BindGroupLayout,
    light_bgl: wgpu::BindGroupLayout,
    prepass: wgpu::RenderPipeline,
    lit: wgpu::RenderPipeline,
    zpass: wgpu::RenderPipeline,
    zfail_ccw: wgpu::RenderPipeline,
    zfail_cw: wgpu::RenderPipeline,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
            .field("adapter", &self.adapter)
            .field("depth_format", &self.depth_format)
            .field("depth_clamp", &self.depth_clamp)
            .finish_non_exhaustive()
    }
}

pub(crate) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const IDS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;
const LIGHT_STRIDE: u64 = 256;

/// The shader's `LightU`: position, colour, then `emit = (inverse square 0/1, 1 / range or 0,
/// cone scale, cone offset)` and `spot = (axis, 1 for a cone)` (see `fs_lit`).
pub(crate) fn light_uniform(l: &LightDraws) -> [f32; 16] {
    let mut v = [0f32; 16];
    v[..4].copy_from_slice(&l.light);
    v[4..7].copy_from_slice(&l.color);
    v[7] = 1.0;
    if let (Some(e), true) = (l.emission, l.light[3] != 0.0) {
        v[8] = 1.0;
        v[9] = e.range.map_or(0.0, |r| 1.0 / r);
        if let Some(s) = e.spot {
            let (scale, offset) = s.scale_offset();
            v[10] = scale;
            v[11] = offset;
            v[12..15].copy_from_slice(&s.direction.normalize().to_array());
            v[15] = 1.0;
        }
    }
    v
}

impl Gpu {
    /// Opens the first adapter wgpu finds (any backend; `WGPU_BACKEND` etc. are honoured) and
    /// builds the pipelines.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when there is no adapter, [`RenderError::Device`] when the
    /// device or a pipeline cannot be created.
    pub fn new() -> Result<Self, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| {
            RenderError::NoAdapter(format!(
                "{e}; install a Vulkan driver (for example Mesa's lavapipe, package mesa-vulkan-drivers)"
            ))
        })?;
        let info = adapter.get_info();
        let (features, limits) = Self::requirements(&adapter);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadowvol-renderer"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(format!("request_device on {}: {e}", info.name)))?;
        Self::on_device(adapter, device, queue)
    }

    /// The features and limits to open a device on `adapter` with, for every pipeline the
    /// adapter can run: depth clamp and a 32-bit float depth where it has them, and the GPU
    /// pipeline's limits and features where it has those (otherwise downlevel defaults, and
    /// only the host pipeline runs).
    #[must_use]
    pub fn requirements(adapter: &wgpu::Adapter) -> (wgpu::Features, wgpu::Limits) {
        let features = adapter.features();
        let mut required = wgpu::Features::empty();
        for f in [
            wgpu::Features::DEPTH_CLIP_CONTROL,
            wgpu::Features::DEPTH32FLOAT_STENCIL8,
        ] {
            if features.contains(f) {
                required |= f;
            }
        }
        required |= crate::resident::ShadowPass::optional_features(adapter);
        let limits = crate::resident::ShadowPass::required_limits(adapter).unwrap_or_else(|_| {
            wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits())
        });
        (required, limits)
    }

    /// The renderer's pipelines on a device the caller opened on `adapter` (for example the
    /// device of a window, whose surface then shows frames drawn by
    /// [`crate::Renderer::render_into`] without a copy through the host). Open it with
    /// [`Gpu::requirements`] to get every pipeline the adapter can run; depth clamp and the
    /// 32-bit float depth are used when the device has them, and the GPU pipeline runs when
    /// the device's limits allow it.
    ///
    /// # Errors
    /// [`RenderError::Device`] when a pipeline cannot be created.
    pub fn on_device(
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Self, RenderError> {
        let info = adapter.get_info();
        let features = device.features();
        let depth_clamp = features.contains(wgpu::Features::DEPTH_CLIP_CONTROL);
        let depth_format = if features.contains(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
            wgpu::TextureFormat::Depth32FloatStencil8
        } else {
            wgpu::TextureFormat::Depth24PlusStencil8
        };
        let resident = crate::resident::ShadowPass::required_limits(&adapter).and_then(|l| {
            if l.check_limits(&device.limits()) {
                Ok(())
            } else {
                Err(RenderError::Unsupported(
                    "the device was opened with lower limits than the GPU pipeline needs \
                     (open it with Renderer::device_requirements)"
                        .to_owned(),
                ))
            }
        });
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shaders/render_raster.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                include_str!("../../../shaders/render_raster.wgsl").into(),
            ),
        });
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let globals_bgl =
            pipelines::bind_group_layout(&device, "globals", &[uniform(0, vf, false)]);
        let light_bgl = pipelines::bind_group_layout(&device, "light", &[uniform(0, vf, true)]);
        let layout = pipelines::pipeline_layout(&device, "renderer", &[&globals_bgl, &light_bgl]);
        let surface_layout = [Some(states::surface_layout())];
        let volume_attrs = wgpu::vertex_attr_array![0 => Float32x4];
        let volume_layout = [Some(wgpu::VertexBufferLayout {
            array_stride: 16,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &volume_attrs,
        })];
        let make = pipelines::RenderPipelines {
            device: &device,
            layout: &layout,
            module: &module,
            depth: depth_format,
        };
        let prepass = make.prepass(
            "prepass",
            "vs_surface",
            &surface_layout,
            "fs_prepass",
            &[
                color_target(COLOR_FORMAT, None),
                color_target(IDS_FORMAT, None),
            ],
        );
        let lit = make.lit("lit", "vs_surface", &surface_layout, COLOR_FORMAT);
        let volume_pipeline = |label, unclipped_depth, front_face, faces| {
            make.volume(
                label,
                "vs_volume",
                &volume_layout,
                unclipped_depth,
                front_face,
                faces,
            )
        };
        // Z-pass: count the volume faces in front of the surface (front +1, back -1). Near
        // clipping stays on: the count then starts at the near plane, which is exactly what the
        // near-clip volume test proves to be outside the volume (with depth clamp the count
        // would start at the eye instead).
        let zpass = volume_pipeline("zpass", false, wgpu::FrontFace::Ccw, states::zpass_faces());
        // Z-fail: count the faces behind the surface (back +1, front -1); depth clamp where the
        // device has it, so no part of a volume is lost to clipping.
        let zfail_ccw = volume_pipeline(
            "zfail-ccw",
            depth_clamp,
            wgpu::FrontFace::Ccw,
            states::zfail_faces(),
        );
        let zfail_cw = volume_pipeline(
            "zfail-cw",
            depth_clamp,
            wgpu::FrontFace::Cw,
            states::zfail_faces(),
        );
        if let Some(err) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Device(format!("pipeline creation: {err}")));
        }
        Ok(Self {
            device,
            queue,
            adapter: format!("{} ({:?}, {})", info.name, info.backend, info.driver_info),
            depth_format,
            depth_clamp,
            wgpu_adapter: adapter,
            resident_unsupported: resident.err().map(|e| e.to_string()),
            globals_bgl,
            light_bgl,
            prepass,
            lit,
            zpass,
            zfail_ccw,
            zfail_cw,
        })
    }

    /// [`RenderError::InvalidInput`] unless both sides of a `w` x `h` image are in
    /// `1..=max_texture_dimension_2d`.
    fn check_size(&self, w: u32, h: u32) -> Result<(), RenderError> {
        let max = self.device.limits().max_texture_dimension_2d;
        if w == 0 || h == 0 || w > max || h > max {
            return Err(RenderError::InvalidInput(format!(
                "image size {w}x{h}: each side must be in 1..={max}"
            )));
        }
        Ok(())
    }

    /// Renders one frame and reads back colour, ids and per-light stencil.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a zero or too large size, [`RenderError::Device`] on
    /// validation or device errors.
    pub fn render(&self, input: &FrameInput<'_>) -> Result<Option<FrameOutput>, RenderError> {
        let (w, h) = (input.width, input.height);
        self.check_size(w, h)?;
        let device = &self.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        use wgpu::util::DeviceExt;

        let mut globals = [0f32; 24];
        globals[..16].copy_from_slice(&input.view_proj);
        globals[16..19].copy_from_slice(&input.eye);
        globals[20] = input.ambient;
        let globals_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("globals"),
            contents: bytemuck::cast_slice(&globals),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let n_lights = input.lights.len().max(1);
        let mut light_bytes = vec![0u8; n_lights * LIGHT_STRIDE as usize];
        for (i, l) in input.lights.iter().enumerate() {
            let v = light_uniform(l);
            let o = i * LIGHT_STRIDE as usize;
            light_bytes[o..o + v.len() * 4].copy_from_slice(bytemuck::cast_slice(&v));
        }
        let light_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights"),
            contents: &light_bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let globals_bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &self.globals_bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals_buf.as_entire_binding(),
            }],
        });
        let light_bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light"),
            layout: &self.light_bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &light_buf,
                    offset: 0,
                    size: std::num::NonZeroU64::new(96),
                }),
            }],
        });
        let padded_surface;
        let surface: &[SurfaceVertex] = if input.surface.is_empty() {
            padded_surface = [SurfaceVertex::zeroed()];
            &padded_surface
        } else {
            input.surface
        };
        let surface_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("surface"),
            contents: bytemuck::cast_slice(surface),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let padded_vol;
        let volumes: &[[f32; 4]] = if input.volumes.is_empty() {
            padded_vol = [[0f32; 4]];
            &padded_vol
        } else {
            input.volumes
        };
        let volume_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("volumes"),
            contents: bytemuck::cast_slice(volumes),
            usage: wgpu::BufferUsages::VERTEX,
        });

        let t = self.frame_targets(w, h, input.lights.len(), input.readback);
        let (color_view, ids_view, depth_view) = (&t.color_view, &t.ids_view, &t.depth_view);

        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        {
            let background = wgpu::Color {
                r: 0.02,
                g: 0.02,
                b: 0.04,
                a: 1.0,
            };
            let color = [
                states::cleared(color_view, background),
                states::cleared(ids_view, wgpu::Color::TRANSPARENT),
            ];
            let mut pass = states::begin_prepass(&mut enc, "prepass", &color, depth_view, None);
            if !input.surface.is_empty() {
                pass.set_pipeline(&self.prepass);
                pass.set_bind_group(0, &globals_bg, &[]);
                pass.set_bind_group(1, &light_bg, &[0]);
                pass.set_vertex_buffer(0, surface_buf.slice(..));
                pass.draw(0..input.surface.len() as u32, 0..1);
            }
        }
        for (li, l) in input.lights.iter().enumerate() {
            let offset = (li as u64 * LIGHT_STRIDE) as u32;
            {
                let mut pass = states::begin_stencil_pass(
                    &mut enc,
                    "stencil",
                    depth_view,
                    wgpu::LoadOp::Clear(0),
                    l.scissor,
                    None,
                );
                pass.set_bind_group(0, &globals_bg, &[]);
                pass.set_bind_group(1, &light_bg, &[offset]);
                pass.set_vertex_buffer(0, volume_buf.slice(..));
                for (pipe, range) in [
                    (&self.zpass, &l.zpass),
                    (&self.zfail_ccw, &l.zfail_ccw),
                    (&self.zfail_cw, &l.zfail_cw),
                ] {
                    if !range.is_empty() && !l.scissor.is_some_and(|r| r[2] == 0 || r[3] == 0) {
                        pass.set_pipeline(pipe);
                        pass.draw(range.clone(), 0..1);
                    }
                }
            }
            t.copy_stencil(&mut enc, li);
            {
                let mut pass = states::begin_lit_pass(
                    &mut enc, "lit", color_view, depth_view, l.scissor, None,
                );
                if !input.surface.is_empty() && !l.scissor.is_some_and(|r| r[2] == 0 || r[3] == 0) {
                    pass.set_pipeline(&self.lit);
                    pass.set_stencil_reference(0);
                    pass.set_bind_group(0, &globals_bg, &[]);
                    pass.set_bind_group(1, &light_bg, &[offset]);
                    pass.set_vertex_buffer(0, surface_buf.slice(..));
                    pass.draw(0..input.surface.len() as u32, 0..1);
                }
            }
        }
        t.copy_color_ids(&mut enc);
        self.finish(enc, scope, oom, &t)
    }

    /// Maps `buffer`, strips row padding and returns `images` images of `w_bytes` × `h` bytes.
    fn read(
        &self,
        buffer: &wgpu::Buffer,
        padded_row: u32,
        w_bytes: u32,
        h: u32,
        images: usize,
    ) -> Result<Vec<u8>, RenderError> {
        let data = map_read(&self.device, buffer)?;
        let mut out = Vec::with_capacity((w_bytes * h) as usize * images);
        for img in 0..images {
            for y in 0..h as usize {
                let o = (img * h as usize + y) * padded_row as usize;
                out.extend_from_slice(&data[o..o + w_bytes as usize]);
            }
        }
        Ok(out)
    }
}

impl Gpu {
    /// The GPU pipeline's pass on this device, with the renderer's formats.
    ///
    /// # Errors
    /// [`RenderError::Unsupported`] naming what the adapter lacks; [`RenderError::Device`] if a
    /// pipeline fails to build.
    pub fn shadow_pass(&self) -> Result<crate::resident::ShadowPass, RenderError> {
        if let Some(why) = &self.resident_unsupported {
            return Err(RenderError::Unsupported(why.clone()));
        }
        crate::resident::ShadowPass::new(
            &self.wgpu_adapter,
            &self.device,
            &self.queue,
            crate::resident::PassFormats {
                color: COLOR_FORMAT,
                ids: Some(IDS_FORMAT),
                depth: self.depth_format,
            },
        )
    }

    /// Renders one frame of the GPU pipeline (pre-pass, extraction, per light stencil and lit
    /// passes) from the inputs last given to [`crate::resident::ShadowPass::update`]; with
    /// `readback`, colour, ids and per-light stencil come back, otherwise it only waits. With
    /// `into`, the colour goes to that view (the renderer's colour format, the frame's size)
    /// instead of the renderer's own target.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a bad size, [`RenderError::Device`] on device errors.
    pub fn render_resident(
        &self,
        pass: &crate::resident::ShadowPass,
        rs: &crate::resident::ResidentScene,
        (w, h): (u32, u32),
        lights: usize,
        readback: bool,
        into: Option<&wgpu::TextureView>,
    ) -> Result<Option<FrameOutput>, RenderError> {
        self.check_size(w, h)?;
        let device = &self.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let t = self.frame_targets(w, h, lights, readback);
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("resident frame"),
        });
        let color_view = into.unwrap_or(&t.color_view);
        pass.encode_extract(&mut enc, rs);
        pass.encode_prepass(
            &mut enc,
            rs,
            color_view,
            Some(&t.ids_view),
            &t.depth_view,
            wgpu::Color {
                r: 0.02,
                g: 0.02,
                b: 0.04,
                a: 1.0,
            },
        );
        for li in 0..lights {
            pass.encode_stencil(&mut enc, rs, li, &t.depth_view);
            t.copy_stencil(&mut enc, li);
            pass.encode_lit(&mut enc, rs, li, color_view, &t.depth_view);
        }
        t.copy_color_ids(&mut enc);
        self.finish(enc, scope, oom, &t)
    }

    /// The frame's attachments and, with `readback`, the buffers its images are copied to.
    fn frame_targets(&self, w: u32, h: u32, lights: usize, readback: bool) -> FrameTargets {
        let size = wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let tex = |label: &str, format: wgpu::TextureFormat| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
            crate::resident::texture_2d(&self.device, label, w, h, format, usage)
        };
        let color = tex("color", COLOR_FORMAT);
        let ids = tex("ids", IDS_FORMAT);
        let depth = tex("depth-stencil", self.depth_format);
        let buffer = |label: &str, bytes_per_px: u32, count: usize| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: u64::from(padded_row(w, bytes_per_px)) * u64::from(h) * count.max(1) as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        };
        FrameTargets {
            size,
            lights,
            color_view: color.create_view(&Default::default()),
            ids_view: ids.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            readbacks: readback.then(|| {
                [
                    buffer("color-readback", 4, 1),
                    buffer("ids-readback", 8, 1),
                    buffer("stencil-readback", 1, lights),
                ]
            }),
            color,
            ids,
            depth,
        }
    }

    /// Submits `enc`, turns the error scopes into errors, and reads the images back (with
    /// readback buffers) or waits for the device.
    fn finish(
        &self,
        enc: wgpu::CommandEncoder,
        scope: wgpu::ErrorScopeGuard,
        oom: wgpu::ErrorScopeGuard,
        t: &FrameTargets,
    ) -> Result<Option<FrameOutput>, RenderError> {
        self.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(oom.pop()) {
            return Err(RenderError::Device(format!("out of memory: {e}")));
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Device(format!("validation: {e}")));
        }
        let Some([color_rb, ids_rb, stencil_rb]) = &t.readbacks else {
            wait(&self.device)?;
            return Ok(None);
        };
        let (w, h) = (t.size.width, t.size.height);
        let color = self.read(color_rb, padded_row(w, 4), w * 4, h, 1)?;
        let ids_bytes = self.read(ids_rb, padded_row(w, 8), w * 8, h, 1)?;
        let stencil_bytes = if t.lights == 0 {
            Vec::new()
        } else {
            self.read(stencil_rb, padded_row(w, 1), w, h, t.lights)?
        };
        let ids = ids_bytes
            .chunks_exact(8)
            .map(|c| {
                [
                    u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                    u32::from_le_bytes([c[4], c[5], c[6], c[7]]),
                ]
            })
            .collect();
        let px = (w * h) as usize;
        Ok(Some(FrameOutput {
            color,
            ids,
            stencil: stencil_bytes
                .chunks_exact(px.max(1))
                .map(<[u8]>::to_vec)
                .collect(),
        }))
    }
}
