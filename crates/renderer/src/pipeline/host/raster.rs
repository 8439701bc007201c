//! The host pipeline's raster: the surfaces and the volumes the host built, drawn from vertex
//! buffers kept between frames ([`HostBuffers`]: the surfaces written where they moved, the
//! volumes written each frame), with the render states every pipeline shares.
//!
//! Passes of a frame:
//! 1. pre-pass: colour = ambient × albedo, ids (surface + 1, triangle), depth (less, write);
//! 2. per light: stencil pass (stencil cleared to 0; two-sided, wrapping; depth test `less`,
//!    no depth write) over z-pass volumes and z-fail volumes; the stencil's copy where the frame
//!    is read back; a lit pass (depth `equal`, stencil `== 0`, additive Lambert).

use crate::pipeline::{light_output, LightPass};
use crate::raster::pipelines::{self, color_target, uniform};
use crate::raster::{
    empty_scissor, light_uniform, states, Attachments, SurfaceVertex, BACKGROUND, COLOR_FORMAT,
    IDS_FORMAT, LIGHT_STRIDE,
};
use crate::{RenderDevice, RenderError};
use shadowvol_gpu::ErrorScopes;
use shadowvol_scenes::Emission;
use std::ops::Range;

/// The draws of one light, as vertex ranges into the frame's volume vertex buffer.
#[derive(Debug, Clone, Default)]
pub(super) struct LightDraws {
    /// Camera-relative light `(x, y, z, w)`.
    pub light: [f32; 4],
    /// Light colour times gain (linear RGB).
    pub color: [f32; 3],
    /// Scissor `[x, y, width, height]` of its stencil and lit passes (`None`: whole image).
    pub scissor: Option<[u32; 4]>,
    /// What it emits: range and cone attenuation in the lit pass (`None`: a unit light).
    pub emission: Option<Emission>,
    /// Z-pass sides (counter-clockwise front faces).
    pub zpass: Range<u32>,
    /// Z-fail sides and back caps and `σ = +1` front caps (counter-clockwise front faces).
    pub zfail_ccw: Range<u32>,
    /// Z-fail `σ = −1` front caps (clockwise front faces).
    pub zfail_cw: Range<u32>,
}

/// Everything the raster needs for one frame.
#[derive(Debug, Clone)]
pub(super) struct RasterInput<'a> {
    /// Column-major `projection * view` of the camera at the origin.
    pub view_proj: [f32; 16],
    /// Eye position (the origin of the camera-relative coordinates).
    pub eye: [f32; 3],
    /// Ambient factor.
    pub ambient: f32,
    /// Surface vertices to draw from [`HostBuffers::surface`] (3 a triangle; none: the passes
    /// clear and draw nothing).
    pub surface_vertices: usize,
    /// All volume vertices of all lights.
    pub volumes: &'a [[f32; 4]],
    /// Per-light draws.
    pub lights: &'a [LightDraws],
    /// Per light: what it draws after its stencil pass (empty: all hard).
    pub passes: &'a [LightPass],
}

/// The host pipeline's render pipelines on one device.
pub(super) struct HostRaster {
    globals_bgl: wgpu::BindGroupLayout,
    light_bgl: wgpu::BindGroupLayout,
    prepass: wgpu::RenderPipeline,
    lit: wgpu::RenderPipeline,
    zpass: wgpu::RenderPipeline,
    zfail_ccw: wgpu::RenderPipeline,
    zfail_cw: wgpu::RenderPipeline,
}

impl HostRaster {
    /// The pipelines on `rd`: depth clamp for the z-fail volumes where the device has it.
    ///
    /// # Errors
    /// [`RenderError::Device`] when a pipeline cannot be created.
    pub(super) fn new(rd: &RenderDevice) -> Result<Self, RenderError> {
        let device = &rd.device;
        let depth_format = rd.depth_format;
        let depth_clamp = rd.depth_clamp;
        let scope = ErrorScopes::push(device);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shaders/render_raster.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                include_str!("../../../../../shaders/render_raster.wgsl").into(),
            ),
        });
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let globals_bgl = pipelines::bind_group_layout(device, "globals", &[uniform(0, vf, false)]);
        let light_bgl = pipelines::bind_group_layout(device, "light", &[uniform(0, vf, true)]);
        let layout = pipelines::pipeline_layout(device, "renderer", &[&globals_bgl, &light_bgl]);
        let surface_layout = [Some(states::surface_layout())];
        let volume_attrs = wgpu::vertex_attr_array![0 => Float32x4];
        let volume_layout = [Some(wgpu::VertexBufferLayout {
            array_stride: 16,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &volume_attrs,
        })];
        let make = pipelines::RenderPipelines {
            device,
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
        if let Some(err) = scope.pop() {
            return Err(RenderError::Device(format!("pipeline creation: {err}")));
        }
        Ok(Self {
            globals_bgl,
            light_bgl,
            prepass,
            lit,
            zpass,
            zfail_ccw,
            zfail_cw,
        })
    }

    /// The buffers and bind groups kept between frames, for surfaces of `surface_vertices`
    /// vertices in all and `lights` lights (both may grow later).
    ///
    /// # Errors
    /// [`RenderError::TooLarge`] when not even one triangle's vertices fit the device's
    /// `max_buffer_size`, [`RenderError::Device`] when the device cannot make them (out of
    /// memory).
    pub(super) fn buffers(
        &self,
        device: &wgpu::Device,
        surface_vertices: u32,
        lights: usize,
    ) -> Result<HostBuffers, RenderError> {
        let scope = ErrorScopes::push(device);
        let buffers = self.make_buffers(device, surface_vertices, lights);
        if let Some(err) = scope.pop() {
            return Err(RenderError::Device(format!(
                "the host pipeline's buffers: {err}"
            )));
        }
        buffers
    }

    /// [`HostRaster::buffers`] without the error scope.
    fn make_buffers(
        &self,
        device: &wgpu::Device,
        surface_vertices: u32,
        lights: usize,
    ) -> Result<HostBuffers, RenderError> {
        let globals = uniform_buffer(device, "globals", GLOBALS_BYTES);
        let globals_bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &self.globals_bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let light_slots = lights.max(1);
        let (lights, lights_bg) = self.light_buffer(device, light_slots);
        Ok(HostBuffers {
            globals,
            globals_bg,
            light_slots,
            lights,
            lights_bg,
            light_bytes: Vec::new(),
            surface: Chunks::with_capacity::<SurfaceVertex>(device, "surface", surface_vertices)?,
            volumes: Chunks::with_capacity::<[f32; 4]>(device, "volumes", 3)?,
        })
    }

    /// A uniform buffer of `slots` lights, [`LIGHT_STRIDE`] apart, and its bind group (one
    /// light bound at a time, by dynamic offset).
    fn light_buffer(&self, device: &wgpu::Device, slots: usize) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = uniform_buffer(device, "lights", slots as u64 * LIGHT_STRIDE);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light"),
            layout: &self.light_bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffer,
                    offset: 0,
                    size: std::num::NonZeroU64::new(96),
                }),
            }],
        });
        (buffer, bind_group)
    }

    /// Records one frame into `enc` and `target`: the frame's uniforms and volumes are written
    /// into `buffers` (grown where they do not fit), the surfaces drawn as `buffers` holds them,
    /// and the passes recorded. The writes reach the device at the next submission, before
    /// `enc`'s commands.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when `target` has no ids attachment, [`RenderError::TooLarge`]
    /// when not even one triangle's vertices fit the device's `max_buffer_size`.
    pub(super) fn record(
        &self,
        rd: &RenderDevice,
        buffers: &mut HostBuffers,
        enc: &mut wgpu::CommandEncoder,
        target: &Attachments<'_>,
        input: &RasterInput<'_>,
    ) -> Result<(), RenderError> {
        let ids = target.ids.ok_or_else(|| {
            RenderError::InvalidInput(
                "the host pipeline draws surface ids: give it an ids attachment".to_owned(),
            )
        })?;
        self.write_frame(rd, buffers, input)?;
        let frame = FrameRecording {
            raster: self,
            target,
            ids,
            bindings: buffers,
            surface_vertices: input.surface_vertices,
        };
        frame.prepass(enc);
        for (li, l) in input.lights.iter().enumerate() {
            frame.stencil_pass(enc, li, l);
            target.after_stencil(enc, li);
            let pass = input.passes.get(li).copied().unwrap_or(LightPass::Hard);
            light_output(pass, target, enc, |enc, color| {
                frame.lit_pass(enc, li, l, color);
            })?;
        }
        Ok(())
    }

    /// Writes the frame's globals (`projection * view`, eye, ambient), every light's uniform
    /// and the volume vertices into `buffers`.
    fn write_frame(
        &self,
        rd: &RenderDevice,
        buffers: &mut HostBuffers,
        input: &RasterInput<'_>,
    ) -> Result<(), RenderError> {
        let (device, queue) = (&rd.device, &rd.queue);
        let mut globals = [0f32; 24];
        globals[..16].copy_from_slice(&input.view_proj);
        globals[16..19].copy_from_slice(&input.eye);
        globals[20] = input.ambient;
        queue.write_buffer(&buffers.globals, 0, bytemuck::cast_slice(&globals));

        let n_lights = input.lights.len().max(1);
        if n_lights > buffers.light_slots {
            (buffers.lights, buffers.lights_bg) = self.light_buffer(device, n_lights);
            buffers.light_slots = n_lights;
        }
        let bytes = &mut buffers.light_bytes;
        bytes.clear();
        bytes.resize(n_lights * LIGHT_STRIDE as usize, 0);
        for (i, l) in input.lights.iter().enumerate() {
            let v = light_uniform(l.light, l.color, l.emission.as_ref());
            let o = i * LIGHT_STRIDE as usize;
            bytes[o..o + v.len() * 4].copy_from_slice(bytemuck::cast_slice(&v));
        }
        queue.write_buffer(&buffers.lights, 0, bytes);

        let need = u32::try_from(input.volumes.len()).map_err(|_| {
            RenderError::TooLarge(format!(
                "{} volume vertices; a frame draws at most {}",
                input.volumes.len(),
                u32::MAX
            ))
        })?;
        if need > buffers.volumes.capacity {
            let grown = need.max(buffers.volumes.capacity.saturating_mul(2));
            buffers.volumes = Chunks::with_capacity::<[f32; 4]>(device, "volumes", grown)?;
        }
        buffers.volumes.write(queue, 0, input.volumes);
        Ok(())
    }
}

/// The byte size of the globals uniform: `projection * view`, eye, ambient.
const GLOBALS_BYTES: u64 = 96;

/// A uniform buffer of `size` bytes written by the queue.
fn uniform_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// What the host pipeline keeps on the device between frames: the uniforms and their bind
/// groups, the surfaces' vertices (laid out in `prepare`, written where a surface moved) and a
/// volume buffer that grows to the largest frame's volumes.
pub(super) struct HostBuffers {
    /// The globals uniform and its bind group.
    globals: wgpu::Buffer,
    globals_bg: wgpu::BindGroup,
    /// The per-light uniforms, [`LIGHT_STRIDE`] apart, and their bind group (dynamic offset).
    lights: wgpu::Buffer,
    lights_bg: wgpu::BindGroup,
    /// Lights the uniform buffer holds.
    light_slots: usize,
    /// The lights' uniform bytes, kept so that a frame does not allocate them.
    light_bytes: Vec<u8>,
    /// Every surface's triangles, at the ranges the pipeline laid out.
    pub surface: Chunks,
    /// The frame's volume vertices (all lights).
    volumes: Chunks,
}

impl HostBuffers {
    /// Bytes these buffers hold on the device.
    pub(super) fn device_bytes(&self) -> u64 {
        self.globals.size() + self.lights.size() + self.surface.bytes() + self.volumes.bytes()
    }
}

/// Triangle-list vertices in consecutive vertex buffers, each at most the device's
/// `max_buffer_size` and holding whole triangles: a scene's 2.9 GB of surface vertices on a
/// device whose buffers hold 2 GiB. Drawing a range draws its part in each buffer, in order, so
/// the primitives reach the rasteriser in the same order as from one buffer.
pub(super) struct Chunks {
    /// Each buffer and the index of its first vertex.
    parts: Vec<(wgpu::Buffer, u32)>,
    /// Vertices per full buffer (a multiple of 3).
    per_buffer: u32,
    /// Vertices the buffers hold in all.
    capacity: u32,
    /// Bytes per vertex.
    stride: u64,
}

impl Chunks {
    /// Room for `capacity` vertices of `T` (at least 3) in as few buffers as the device's
    /// `max_buffer_size` allows, written with [`Chunks::write`].
    ///
    /// # Errors
    /// [`RenderError::TooLarge`] when one triangle's vertices do not fit one buffer.
    fn with_capacity<T: bytemuck::Pod>(
        device: &wgpu::Device,
        label: &str,
        capacity: u32,
    ) -> Result<Self, RenderError> {
        let stride = std::mem::size_of::<T>() as u64;
        let fit = device.limits().max_buffer_size / stride / 3 * 3;
        let per_buffer = u32::try_from(fit).unwrap_or(u32::MAX / 3 * 3);
        if per_buffer == 0 {
            return Err(RenderError::TooLarge(format!(
                "a triangle's {label} vertices take {} bytes; the device allows buffers of at most {} (max_buffer_size)",
                3 * stride,
                device.limits().max_buffer_size
            )));
        }
        let capacity = capacity.max(3);
        let parts = (0..capacity)
            .step_by(per_buffer as usize)
            .map(|first| {
                let n = u64::from(per_buffer.min(capacity - first));
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: n * stride,
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                (buffer, first)
            })
            .collect();
        Ok(Self {
            parts,
            per_buffer,
            capacity,
            stride,
        })
    }

    /// Bytes the buffers hold.
    fn bytes(&self) -> u64 {
        u64::from(self.capacity) * self.stride
    }

    /// Queues the write of `vertices` from vertex `first` on, across the buffers they fall in.
    ///
    /// # Panics
    /// Panics when `T` is not the vertex type of [`Chunks::with_capacity`] or the vertices run
    /// past the capacity.
    pub(super) fn write<T: bytemuck::Pod>(&self, queue: &wgpu::Queue, first: u32, vertices: &[T]) {
        assert_eq!(std::mem::size_of::<T>() as u64, self.stride, "vertex type");
        let end = u64::from(first) + vertices.len() as u64;
        assert!(
            end <= u64::from(self.capacity),
            "vertices past the capacity"
        );
        let end = end as u32;
        for (buffer, start) in &self.parts {
            let lo = first.max(*start);
            let hi = end.min(start.saturating_add(self.per_buffer));
            if lo < hi {
                let part = &vertices[(lo - first) as usize..(hi - first) as usize];
                queue.write_buffer(
                    buffer,
                    u64::from(lo - start) * self.stride,
                    bytemuck::cast_slice(part),
                );
            }
        }
    }

    /// Draws the vertices `range` with the pass's current pipeline and bindings.
    fn draw(&self, pass: &mut wgpu::RenderPass<'_>, range: std::ops::Range<u32>) {
        for (buffer, first) in &self.parts {
            let lo = range.start.max(*first);
            let hi = range.end.min(first.saturating_add(self.per_buffer));
            if lo < hi {
                pass.set_vertex_buffer(0, buffer.slice(..));
                pass.draw(lo - first..hi - first, 0..1);
            }
        }
    }
}

/// One frame being recorded, so that each pass needs only the encoder and its light.
struct FrameRecording<'a> {
    raster: &'a HostRaster,
    target: &'a Attachments<'a>,
    ids: &'a wgpu::TextureView,
    bindings: &'a HostBuffers,
    /// Surface vertices to draw (none: the passes clear and draw nothing).
    surface_vertices: usize,
}

impl FrameRecording<'_> {
    /// The pre-pass: colour, ids and depth cleared, then the surfaces' ambient, ids and depth.
    fn prepass(&self, enc: &mut wgpu::CommandEncoder) {
        let color = [
            states::cleared(self.target.color, BACKGROUND),
            states::cleared(self.ids, wgpu::Color::TRANSPARENT),
        ];
        let mut pass = states::begin_prepass(
            enc,
            "prepass",
            &color,
            self.target.depth_stencil,
            true,
            None,
        );
        if self.surface_vertices != 0 {
            pass.set_pipeline(&self.raster.prepass);
            pass.set_bind_group(0, &self.bindings.globals_bg, &[]);
            pass.set_bind_group(1, &self.bindings.lights_bg, &[0]);
            self.bindings
                .surface
                .draw(&mut pass, 0..self.surface_vertices as u32);
        }
    }

    /// Light `li`'s stencil pass: its z-pass and z-fail volumes counted in a cleared stencil.
    fn stencil_pass(&self, enc: &mut wgpu::CommandEncoder, li: usize, l: &LightDraws) {
        let mut pass = states::begin_stencil_pass(
            enc,
            "stencil",
            self.target.depth_stencil,
            wgpu::LoadOp::Clear(0),
            l.scissor,
            None,
        );
        pass.set_bind_group(0, &self.bindings.globals_bg, &[]);
        pass.set_bind_group(1, &self.bindings.lights_bg, &[light_offset(li)]);
        let raster = self.raster;
        for (pipe, range) in [
            (&raster.zpass, &l.zpass),
            (&raster.zfail_ccw, &l.zfail_ccw),
            (&raster.zfail_cw, &l.zfail_cw),
        ] {
            if !range.is_empty() && !empty_scissor(l.scissor) {
                pass.set_pipeline(pipe);
                self.bindings.volumes.draw(&mut pass, range.clone());
            }
        }
    }

    /// Light `li`'s lit pass: its Lambert term added into `color` where the stencil is 0.
    fn lit_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        li: usize,
        l: &LightDraws,
        color: &wgpu::TextureView,
    ) {
        let mut pass = states::begin_lit_pass(
            enc,
            "lit",
            color,
            self.target.depth_stencil,
            l.scissor,
            None,
        );
        if self.surface_vertices != 0 && !empty_scissor(l.scissor) {
            pass.set_pipeline(&self.raster.lit);
            pass.set_stencil_reference(0);
            pass.set_bind_group(0, &self.bindings.globals_bg, &[]);
            pass.set_bind_group(1, &self.bindings.lights_bg, &[light_offset(li)]);
            self.bindings
                .surface
                .draw(&mut pass, 0..self.surface_vertices as u32);
        }
    }
}

/// The dynamic offset of light `li`'s uniform.
fn light_offset(li: usize) -> u32 {
    (li as u64 * LIGHT_STRIDE) as u32
}
