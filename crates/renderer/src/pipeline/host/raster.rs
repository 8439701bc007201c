//! The host pipeline's raster: the surfaces and the volumes the host built, drawn from vertex
//! buffers uploaded each frame, with the render states every pipeline shares.
//!
//! Passes of a frame:
//! 1. pre-pass: colour = ambient × albedo, ids (surface + 1, triangle), depth (less, write);
//! 2. per light: stencil pass (stencil cleared to 0; two-sided, wrapping; depth test `less`,
//!    no depth write) over z-pass volumes and z-fail volumes; the stencil's copy where the frame
//!    is read back; a lit pass (depth `equal`, stencil `== 0`, additive Lambert).

use crate::raster::pipelines::{self, color_target, uniform};
use crate::raster::{
    empty_scissor, light_uniform, states, Attachments, SurfaceVertex, BACKGROUND, COLOR_FORMAT,
    IDS_FORMAT, LIGHT_STRIDE,
};
use crate::{RenderDevice, RenderError};
use bytemuck::Zeroable;
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
    /// Surface triangles (3 vertices each).
    pub surface: &'a [SurfaceVertex],
    /// All volume vertices of all lights.
    pub volumes: &'a [[f32; 4]],
    /// Per-light draws.
    pub lights: &'a [LightDraws],
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

    /// Records one frame into `enc` and `target`: buffers for `input` are created and filled
    /// here, the passes recorded.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when `target` has no ids attachment.
    pub(super) fn record(
        &self,
        device: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        target: &Attachments<'_>,
        input: &RasterInput<'_>,
    ) -> Result<(), RenderError> {
        let bindings = self.bindings(device, input)?;
        let ids = target.ids.ok_or_else(|| {
            RenderError::InvalidInput(
                "the host pipeline draws surface ids: give it an ids attachment".to_owned(),
            )
        })?;
        let frame = FrameRecording {
            raster: self,
            target,
            ids,
            bindings,
            surface_vertices: input.surface.len(),
        };
        frame.prepass(enc);
        for (li, l) in input.lights.iter().enumerate() {
            frame.stencil_pass(enc, li, l);
            target.after_stencil(enc, li);
            frame.lit_pass(enc, li, l);
        }
        Ok(())
    }

    /// The frame's uniforms and vertex buffers; empty lists are padded to one zero vertex.
    ///
    /// # Errors
    /// [`RenderError::TooLarge`] when not even one triangle's vertices fit the device's
    /// `max_buffer_size`.
    fn bindings(
        &self,
        device: &wgpu::Device,
        input: &RasterInput<'_>,
    ) -> Result<FrameBindings, RenderError> {
        let padded_surface;
        let surface: &[SurfaceVertex] = if input.surface.is_empty() {
            padded_surface = [SurfaceVertex::zeroed()];
            &padded_surface
        } else {
            input.surface
        };
        let padded_vol;
        let volumes: &[[f32; 4]] = if input.volumes.is_empty() {
            padded_vol = [[0f32; 4]];
            &padded_vol
        } else {
            input.volumes
        };
        Ok(FrameBindings {
            globals: self.globals_bind_group(device, input),
            lights: self.lights_bind_group(device, input.lights),
            surface: Chunks::new(device, "surface", surface)?,
            volumes: Chunks::new(device, "volumes", volumes)?,
        })
    }

    /// The globals uniform (`projection * view`, eye, ambient) and its bind group.
    fn globals_bind_group(
        &self,
        device: &wgpu::Device,
        input: &RasterInput<'_>,
    ) -> wgpu::BindGroup {
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
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &self.globals_bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals_buf.as_entire_binding(),
            }],
        })
    }

    /// Every light's uniform, [`LIGHT_STRIDE`] apart, bound one at a time by dynamic offset.
    fn lights_bind_group(&self, device: &wgpu::Device, lights: &[LightDraws]) -> wgpu::BindGroup {
        use wgpu::util::DeviceExt;
        let n_lights = lights.len().max(1);
        let mut light_bytes = vec![0u8; n_lights * LIGHT_STRIDE as usize];
        for (i, l) in lights.iter().enumerate() {
            let v = light_uniform(l.light, l.color, l.emission.as_ref());
            let o = i * LIGHT_STRIDE as usize;
            light_bytes[o..o + v.len() * 4].copy_from_slice(bytemuck::cast_slice(&v));
        }
        let light_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights"),
            contents: &light_bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
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
        })
    }
}

/// The buffers and bind groups of one frame's [`RasterInput`], shared by all its passes.
struct FrameBindings {
    /// The globals uniform's bind group.
    globals: wgpu::BindGroup,
    /// The per-light uniforms' bind group (dynamic offset: the light's).
    lights: wgpu::BindGroup,
    /// Surface triangles (at least one vertex).
    surface: Chunks,
    /// All lights' volume vertices (at least one).
    volumes: Chunks,
}

/// Triangle-list vertices in consecutive vertex buffers, each at most the device's
/// `max_buffer_size` and holding whole triangles: a scene's 2.9 GB of surface vertices on a
/// device whose buffers hold 2 GiB. Drawing a range draws its part in each buffer, in order, so
/// the primitives reach the rasteriser in the same order as from one buffer.
struct Chunks {
    /// Each buffer and the index of its first vertex.
    parts: Vec<(wgpu::Buffer, u32)>,
    /// Vertices per full buffer (a multiple of 3).
    per_buffer: u32,
}

impl Chunks {
    /// `vertices` in as few buffers as the device's `max_buffer_size` allows.
    ///
    /// # Errors
    /// [`RenderError::TooLarge`] when one triangle's vertices do not fit one buffer.
    fn new<T: bytemuck::Pod>(
        device: &wgpu::Device,
        label: &str,
        vertices: &[T],
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
        let parts = vertices
            .chunks(per_buffer as usize)
            .enumerate()
            .map(|(k, c)| {
                let buffer = crate::raster::vertex_buffer(
                    device,
                    label,
                    bytemuck::cast_slice(c),
                    wgpu::BufferUsages::empty(),
                )?;
                Ok((buffer, k as u32 * per_buffer))
            })
            .collect::<Result<_, RenderError>>()?;
        Ok(Self { parts, per_buffer })
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
    bindings: FrameBindings,
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
            pass.set_bind_group(0, &self.bindings.globals, &[]);
            pass.set_bind_group(1, &self.bindings.lights, &[0]);
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
        pass.set_bind_group(0, &self.bindings.globals, &[]);
        pass.set_bind_group(1, &self.bindings.lights, &[light_offset(li)]);
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

    /// Light `li`'s lit pass: its Lambert term added where the stencil is 0.
    fn lit_pass(&self, enc: &mut wgpu::CommandEncoder, li: usize, l: &LightDraws) {
        let mut pass = states::begin_lit_pass(
            enc,
            "lit",
            self.target.color,
            self.target.depth_stencil,
            l.scissor,
            None,
        );
        if self.surface_vertices != 0 && !empty_scissor(l.scissor) {
            pass.set_pipeline(&self.raster.lit);
            pass.set_stencil_reference(0);
            pass.set_bind_group(0, &self.bindings.globals, &[]);
            pass.set_bind_group(1, &self.bindings.lights, &[light_offset(li)]);
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
