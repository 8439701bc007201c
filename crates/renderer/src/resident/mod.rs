//! The GPU-resident shadow-volume pass: extraction, sides and caps on the caller's device, in the
//! caller's command encoder, with nothing read back.
//!
//! Per frame the host writes only small inputs ([`ShadowPass::update`]: camera, lights,
//! transforms, the plan's per-(light, object) technique). [`ShadowPass::encode_extract`] records
//! one compute pass, first of the frame: a vertex pass (every vertex to camera-relative world
//! space, read by every draw, so shared vertices are bit-identical), then:
//! 1. a triangle pass: one sign per (light, triangle) in the accuracy mode, in the triangle's
//!    canonical vertex order; exact mode runs the certified filter of the `wgpu` backend and
//!    decides what it cannot certify with exact integer arithmetic on the `f32` bits
//!    (`shaders/exact_int.wgsl`), so no triple goes to the host;
//! 2. an edge pass: each edge sums the parity-signed signs of its opposite vertices' triangles
//!    into `m` (`original`: the naive per-(edge, opposite vertex) sign, the baseline) and appends
//!    `|m|` side records to the light's z-pass or z-fail list; the list lengths are the instance
//!    counts of indirect draws.
//!
//! Then, per light, [`ShadowPass::encode_stencil`] draws the sides instanced from the records
//! (extruded to `w = 0` in the vertex shader) and the caps of z-fail objects from the same
//! triangle signs, into the caller's depth-stencil attachment (two-sided stencil, wrapping
//! increment and decrement), so sides and caps meet by construction. The caller's lit pass then
//! tests stencil == 0; [`ShadowPass::encode_lit`] is a ready one, and
//! [`ShadowPass::encode_prepass`] the depth pre-pass whose depths the front caps match bit for
//! bit.
//!
//! The shaders are the `wgpu` silhouette backend's module (same bindings, sign functions and
//! filter) with `extract.wgsl` appended, and the renderer's `shader.wgsl` with `draw.wgsl`
//! appended. [`twin`] is the CPU port of the new kernels.
//!
//! ```no_run
//! # fn main() -> Result<(), shadowvol_renderer::RenderError> {
//! use shadowvol_renderer::resident::{PassFormats, ShadowPass};
//! let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
//! let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
//!     .map_err(|e| shadowvol_renderer::RenderError::NoAdapter(e.to_string()))?;
//! let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
//!     required_features: ShadowPass::optional_features(&adapter),
//!     required_limits: ShadowPass::required_limits(&adapter)?,
//!     ..Default::default()
//! }))
//! .map_err(|e| shadowvol_renderer::RenderError::Device(e.to_string()))?;
//! let formats = PassFormats {
//!     color: wgpu::TextureFormat::Rgba8Unorm,
//!     ids: None,
//!     depth: wgpu::TextureFormat::Depth24PlusStencil8,
//! };
//! let pass = ShadowPass::new(&adapter, &device, &queue, formats)?;
//! # let _ = pass; Ok(()) }
//! ```
//! `examples/embed.rs` renders a whole frame this way.

pub mod layout;
pub mod twin;

pub use layout::ResidentLayout;

use crate::plan::Technique;
use crate::{Camera, RenderError};
use glam::{Affine3A, DAffine3};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{object_lights, TopologyScene};
use shadowvol_wgpu_compute::shaders;
use shadowvol_wgpu_compute::twin::ExactFilter;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// `resident/extract.wgsl`: the triangle, edge and reset kernels.
pub const EXTRACT_WGSL: &str = include_str!("extract.wgsl");
/// `resident/draw.wgsl`: the vertex-pulling shaders of the surfaces, sides and caps.
pub const DRAW_WGSL: &str = include_str!("draw.wgsl");
/// The renderer's `shader.wgsl` (fragment shaders and the uniforms both pipelines share).
pub const SHADER_WGSL: &str = include_str!("../shader.wgsl");

/// Threads per workgroup of the triangle and edge passes (`RESIDENT_WG`).
const WORKGROUP: u32 = 256;
/// Storage buffers the edge pass binds in one stage.
const STORAGE_BUFFERS: u32 = 10;
/// Byte stride of the per-light uniforms (dynamic offsets).
const LIGHT_STRIDE: u64 = 256;
/// Bytes of one light uniform (`LightU`).
const LIGHT_BYTES: u64 = 80;

/// The compute module: the `wgpu` backend's kernel for `filter`, the integer exact sign, then
/// the resident kernels.
#[must_use]
pub fn extract_source(filter: ExactFilter) -> String {
    let mut s = shaders::module_source(filter);
    s.push('\n');
    s.push_str(shadowvol_wgpu_compute::exact_int::EXACT_INT_WGSL);
    s.push('\n');
    s.push_str(EXTRACT_WGSL);
    s
}

/// The draw module: the renderer's `shader.wgsl`, then the resident vertex shaders.
#[must_use]
pub fn draw_source() -> String {
    format!("{SHADER_WGSL}\n{DRAW_WGSL}")
}

/// The attachment formats the pass draws into.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PassFormats {
    /// The colour target of the pre-pass and the lit pass.
    pub color: wgpu::TextureFormat,
    /// An optional second pre-pass target receiving `[object + 1, triangle]` (`Rg32Uint`).
    pub ids: Option<wgpu::TextureFormat>,
    /// The depth-stencil attachment (a format with a stencil aspect).
    pub depth: wgpu::TextureFormat,
}

/// One frame's small inputs.
#[derive(Debug, Clone, Copy)]
pub struct PassFrame<'a> {
    /// The camera (positions are drawn relative to its eye).
    pub camera: &'a Camera,
    /// Width / height of the target.
    pub aspect: f32,
    /// World lights.
    pub lights: &'a [Light],
    /// Per light: linear RGB colour times gain of its lit pass.
    pub colors: &'a [[f32; 3]],
    /// Per light: what it emits (empty: unit lights).
    pub emission: &'a [shadowvol_scenes::Emission],
    /// Per object: world from object (the scene's objects, in [`ShadowPass::prepare`] order).
    pub transforms: &'a [Affine3A],
    /// Per object: albedo.
    pub albedo: &'a [[f32; 3]],
    /// Per (light, object), light-major: the plan's technique.
    pub techniques: &'a [Technique],
    /// Per light: scissor `[x, y, width, height]` of its stencil and lit passes.
    pub scissors: &'a [Option<[u32; 4]>],
    /// Ambient factor of the pre-pass.
    pub ambient: f32,
    /// Accuracy mode of signs and multiplicities.
    pub mode: Accuracy,
    /// Count silhouette edges, side quads and cap triangles per (light, object) (read them with
    /// [`ShadowPass::read_counts`]; costs atomics, so leave it off in timed frames).
    pub count: bool,
}

/// Per-(light, object) counts of one frame, from [`ShadowPass::read_counts`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PassCounts {
    /// `[light * objects + object]`: edges with `m != 0`.
    pub silhouette_edges: Vec<u32>,
    /// `[light * objects + object]`: side quads (`Σ |m|`).
    pub side_quads: Vec<u32>,
    /// `[light * objects + object]`: cap triangles of z-fail objects (`σ ≠ 0`).
    pub cap_triangles: Vec<u32>,
    /// (triangle, light) pairs of exact mode that the filter left to the integer path.
    pub integer_decided: u64,
    /// Per light: z-pass and z-fail side records (the indirect instance counts).
    pub records: Vec<[u32; 2]>,
}

/// The pipelines of the pass on one device.
pub struct ShadowPass {
    device: wgpu::Device,
    queue: wgpu::Queue,
    formats: PassFormats,
    filter: ExactFilter,
    depth_clamp: bool,
    timestamps: bool,
    c0: wgpu::BindGroupLayout,
    c1: wgpu::BindGroupLayout,
    d0: wgpu::BindGroupLayout,
    dl: wgpu::BindGroupLayout,
    v0: wgpu::BindGroupLayout,
    v2: wgpu::BindGroupLayout,
    empty: wgpu::BindGroup,
    vertices: wgpu::ComputePipeline,
    reset: wgpu::ComputePipeline,
    triangles: Vec<wgpu::ComputePipeline>,
    edges: Vec<wgpu::ComputePipeline>,
    /// Pre-pass: `[vertex pulling, vertex buffer]`.
    prepass: [wgpu::RenderPipeline; 2],
    /// Lit pass: `[vertex pulling, vertex buffer]`.
    lit: [wgpu::RenderPipeline; 2],
    s0: wgpu::BindGroupLayout,
    s2: wgpu::BindGroupLayout,
    surfaces: wgpu::ComputePipeline,
    side_zpass: wgpu::RenderPipeline,
    side_zfail: wgpu::RenderPipeline,
    cap_ccw: wgpu::RenderPipeline,
    cap_cw: wgpu::RenderPipeline,
}

impl std::fmt::Debug for ShadowPass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowPass")
            .field("formats", &self.formats)
            .field("filter", &self.filter)
            .field("depth_clamp", &self.depth_clamp)
            .finish_non_exhaustive()
    }
}

fn storage(
    binding: u32,
    stages: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform(binding: u32, stages: wgpu::ShaderStages, dynamic: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

fn stencil_face(
    pass: wgpu::StencilOperation,
    depth_fail: wgpu::StencilOperation,
) -> wgpu::StencilFaceState {
    wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: depth_fail,
        pass_op: pass,
    }
}

fn mode_index(mode: Accuracy) -> usize {
    shaders::mode_value(mode) as usize
}

impl ShadowPass {
    /// Features the pass uses when the adapter has them: `DEPTH_CLIP_CONTROL` (depth clamp for
    /// z-fail volumes), `SHADER_F64` (the `f64` exact filter) and `TIMESTAMP_QUERY`
    /// ([`ShadowPass::read_timings`]). Request them on the device.
    #[must_use]
    pub fn optional_features(adapter: &wgpu::Adapter) -> wgpu::Features {
        adapter.features()
            & (wgpu::Features::DEPTH_CLIP_CONTROL
                | wgpu::Features::SHADER_F64
                | wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Limits to request on the device: the downlevel defaults, with the adapter's storage
    /// buffer counts and sizes (the pass binds up to 10 storage buffers in one stage).
    ///
    /// # Errors
    /// [`RenderError::Unsupported`] naming the limit or capability the adapter lacks.
    pub fn required_limits(adapter: &wgpu::Adapter) -> Result<wgpu::Limits, RenderError> {
        let a = adapter.limits();
        Self::check_adapter(adapter)?;
        let mut l = wgpu::Limits::downlevel_defaults().using_resolution(a.clone());
        l.max_storage_buffers_per_shader_stage = a.max_storage_buffers_per_shader_stage;
        l.max_storage_buffer_binding_size = a.max_storage_buffer_binding_size;
        l.max_buffer_size = a.max_buffer_size;
        l.max_compute_workgroups_per_dimension = a.max_compute_workgroups_per_dimension;
        Ok(l)
    }

    fn check_adapter(adapter: &wgpu::Adapter) -> Result<(), RenderError> {
        let down = adapter.get_downlevel_capabilities();
        for (flag, name) in [
            (
                wgpu::DownlevelFlags::VERTEX_STORAGE,
                "VERTEX_STORAGE (storage buffers in vertex shaders)",
            ),
            (
                wgpu::DownlevelFlags::INDIRECT_EXECUTION,
                "INDIRECT_EXECUTION (indirect draws)",
            ),
            (wgpu::DownlevelFlags::COMPUTE_SHADERS, "COMPUTE_SHADERS"),
        ] {
            if !down.flags.contains(flag) {
                return Err(RenderError::Unsupported(format!(
                    "the adapter lacks the downlevel capability {name}, which the GPU pipeline needs"
                )));
            }
        }
        Self::check_limits(&adapter.limits())
    }

    fn check_limits(l: &wgpu::Limits) -> Result<(), RenderError> {
        if l.max_storage_buffers_per_shader_stage < STORAGE_BUFFERS {
            return Err(RenderError::Unsupported(format!(
                "max_storage_buffers_per_shader_stage is {}; the GPU pipeline needs {STORAGE_BUFFERS}",
                l.max_storage_buffers_per_shader_stage
            )));
        }
        if l.max_compute_invocations_per_workgroup < WORKGROUP
            || l.max_compute_workgroup_size_x < WORKGROUP
        {
            return Err(RenderError::Unsupported(format!(
                "the device allows {} invocations per workgroup; the GPU pipeline needs {WORKGROUP}",
                l.max_compute_invocations_per_workgroup
            )));
        }
        Ok(())
    }

    /// Builds the pipelines on `device` (opened from `adapter` with
    /// [`ShadowPass::required_limits`], and ideally [`ShadowPass::optional_features`]).
    ///
    /// # Errors
    /// [`RenderError::Unsupported`] naming the missing capability or limit (vertex storage,
    /// indirect draws, storage buffers per stage), [`RenderError::Device`] if a shader or
    /// pipeline fails to build.
    pub fn new(
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        formats: PassFormats,
    ) -> Result<Self, RenderError> {
        Self::check_adapter(adapter)?;
        Self::check_limits(&device.limits())?;
        if !formats.depth.has_stencil_aspect() {
            return Err(RenderError::InvalidInput(format!(
                "depth format {:?} has no stencil aspect",
                formats.depth
            )));
        }
        let features = device.features();
        let depth_clamp = features.contains(wgpu::Features::DEPTH_CLIP_CONTROL);
        let filter = if features.contains(wgpu::Features::SHADER_F64) {
            ExactFilter::F64
        } else {
            ExactFilter::F32
        };
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let compute = wgpu::ShaderStages::COMPUTE;
        // Group 0: the wgpu backend's bindings the resident kernels use.
        let c0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident extract scene"),
            entries: &[
                uniform(0, compute, false),
                storage(1, compute, true),
                storage(2, compute, true),
                storage(3, compute, true),
                storage(4, compute, true),
            ],
        });
        let c1 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident extract frame"),
            entries: &[
                uniform(0, compute, false),
                storage(1, compute, true),
                storage(2, compute, true),
                storage(3, compute, true),
                storage(4, compute, false),
                storage(5, compute, false),
                storage(6, compute, false),
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("resident extract"),
            source: wgpu::ShaderSource::Wgsl(extract_source(filter).into()),
        });
        let c_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("resident extract"),
            bind_group_layouts: &[Some(&c0), Some(&c1)],
            immediate_size: 0,
        });
        let compute_pipeline = |entry: &str, mode: Accuracy| {
            let constants = [(shaders::MODE_CONSTANT, f64::from(shaders::mode_value(mode)))];
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&c_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            })
        };
        let reset = compute_pipeline("resident_reset", Accuracy::Original);
        let triangles = Accuracy::ALL
            .iter()
            .map(|&m| compute_pipeline("resident_triangles", m))
            .collect();
        let edges = Accuracy::ALL
            .iter()
            .map(|&m| compute_pipeline("resident_edges", m))
            .collect();

        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let vs = wgpu::ShaderStages::VERTEX;
        let d0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident draw"),
            entries: &[
                uniform(0, vf, false),
                storage(1, vs, true),
                storage(2, vs, true),
                storage(3, vs, true),
                storage(4, vs, true),
                storage(5, vs, true),
                storage(6, vs, true),
                storage(7, vs, true),
            ],
        });
        let dl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident light"),
            entries: &[uniform(0, vf, true)],
        });
        let draw = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("resident draw"),
            source: wgpu::ShaderSource::Wgsl(draw_source().into()),
        });
        // The vertex pass (a compute entry of the draw module): object-space positions to
        // camera-relative world positions, once per vertex and frame.
        let v0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident vertices"),
            entries: &[
                storage(1, compute, true),
                storage(6, compute, true),
                storage(8, compute, true),
            ],
        });
        let v1 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident vertices (unused)"),
            entries: &[],
        });
        let v2 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident vertices out"),
            entries: &[storage(0, compute, false)],
        });
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident vertices (unused)"),
            layout: &v1,
            entries: &[],
        });
        let v_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("resident vertices"),
            bind_group_layouts: &[Some(&v0), Some(&v1), Some(&v2)],
            immediate_size: 0,
        });
        let vertices = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("resident_vertices"),
            layout: Some(&v_layout),
            module: &draw,
            entry_point: Some("resident_vertices"),
            compilation_options: Default::default(),
            cache: None,
        });
        let s0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident surfaces"),
            entries: &[
                storage(3, compute, true),
                storage(6, compute, true),
                storage(7, compute, true),
            ],
        });
        let s2 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resident surfaces out"),
            entries: &[storage(1, compute, false), uniform(2, compute, false)],
        });
        let s_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("resident surfaces"),
            bind_group_layouts: &[Some(&s0), Some(&v1), Some(&s2)],
            immediate_size: 0,
        });
        let surfaces = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("resident_surfaces"),
            layout: Some(&s_layout),
            module: &draw,
            entry_point: Some("resident_surfaces"),
            compilation_options: Default::default(),
            cache: None,
        });
        let d_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("resident draw"),
            bind_group_layouts: &[Some(&d0), Some(&dl)],
            immediate_size: 0,
        });
        let no_stencil = wgpu::StencilState {
            front: wgpu::StencilFaceState::IGNORE,
            back: wgpu::StencilFaceState::IGNORE,
            read_mask: 0xff,
            write_mask: 0,
        };
        let mut prepass_targets = vec![Some(wgpu::ColorTargetState {
            format: formats.color,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        if let Some(ids) = formats.ids {
            prepass_targets.push(Some(wgpu::ColorTargetState {
                format: ids,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            }));
        }
        let surface_attrs =
            wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4, 2 => Float32x4, 3 => Uint32x2];
        let surface_layout = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<crate::gpu::SurfaceVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &surface_attrs,
        })];
        // Surfaces come from a per-frame vertex buffer the surface pass writes (`vs_surface`,
        // as in the host pipeline), or, where it would not fit one binding, are pulled from the
        // storage buffers (`vs_resident_surface`).
        let make_prepass = |entry: &str, buffers: &[Option<wgpu::VertexBufferLayout<'_>>]| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("resident prepass"),
                layout: Some(&d_layout),
                vertex: wgpu::VertexState {
                    module: &draw,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: formats.depth,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: no_stencil.clone(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &draw,
                    entry_point: Some(if formats.ids.is_some() {
                        "fs_prepass"
                    } else {
                        "fs_prepass_color"
                    }),
                    compilation_options: Default::default(),
                    targets: &prepass_targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let prepass = [
            make_prepass("vs_resident_surface", &[]),
            make_prepass("vs_surface", &surface_layout),
        ];
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let lit_face = wgpu::StencilFaceState {
            compare: wgpu::CompareFunction::Equal,
            fail_op: wgpu::StencilOperation::Keep,
            depth_fail_op: wgpu::StencilOperation::Keep,
            pass_op: wgpu::StencilOperation::Keep,
        };
        let make_lit = |entry: &str, buffers: &[Option<wgpu::VertexBufferLayout<'_>>]| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("resident lit"),
                layout: Some(&d_layout),
                vertex: wgpu::VertexState {
                    module: &draw,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: formats.depth,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Equal),
                    stencil: wgpu::StencilState {
                        front: lit_face,
                        back: lit_face,
                        read_mask: 0xff,
                        write_mask: 0,
                    },
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &draw,
                    entry_point: Some("fs_lit"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: formats.color,
                        blend: Some(wgpu::BlendState {
                            color: additive,
                            alpha: additive,
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let lit = [
            make_lit("vs_resident_surface", &[]),
            make_lit("vs_surface", &surface_layout),
        ];
        use wgpu::StencilOperation::{DecrementWrap as Dec, IncrementWrap as Inc, Keep};
        let volume = |label: &str,
                      entry: &str,
                      unclipped_depth: bool,
                      front_face: wgpu::FrontFace,
                      front: wgpu::StencilFaceState,
                      back: wgpu::StencilFaceState| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&d_layout),
                vertex: wgpu::VertexState {
                    module: &draw,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    front_face,
                    cull_mode: None,
                    unclipped_depth,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: formats.depth,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: wgpu::StencilState {
                        front,
                        back,
                        read_mask: 0xff,
                        write_mask: 0xff,
                    },
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: None,
                multiview_mask: None,
                cache: None,
            })
        };
        // The same stencil rules as the host pipeline (see gpu.rs): z-pass counts the faces in
        // front of the surface with near clipping on; z-fail the faces behind it, with depth
        // clamp where the device has it.
        let ccw = wgpu::FrontFace::Ccw;
        let side_zpass = volume(
            "resident side zpass",
            "vs_resident_side_zpass",
            false,
            ccw,
            stencil_face(Inc, Keep),
            stencil_face(Dec, Keep),
        );
        let zfail = |label, entry, face| {
            volume(
                label,
                entry,
                depth_clamp,
                face,
                stencil_face(Keep, Dec),
                stencil_face(Keep, Inc),
            )
        };
        let side_zfail = zfail("resident side zfail", "vs_resident_side_zfail", ccw);
        let cap_ccw = zfail("resident cap ccw", "vs_resident_cap_ccw", ccw);
        let cap_cw = zfail("resident cap cw", "vs_resident_cap_cw", wgpu::FrontFace::Cw);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Device(format!("GPU pipeline creation: {e}")));
        }
        Ok(Self {
            device: device.clone(),
            queue: queue.clone(),
            formats,
            filter,
            depth_clamp,
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            c0,
            c1,
            d0,
            dl,
            v0,
            v2,
            empty,
            vertices,
            reset,
            triangles,
            edges,
            prepass,
            lit,
            s0,
            s2,
            surfaces,
            side_zpass,
            side_zfail,
            cap_ccw,
            cap_cw,
        })
    }

    /// The exact filter the triangle pass runs (`f64` when the device has `SHADER_F64`).
    #[must_use]
    pub fn filter(&self) -> ExactFilter {
        self.filter
    }

    /// True when z-fail volumes are drawn with depth clamp (`DEPTH_CLIP_CONTROL`).
    #[must_use]
    pub fn depth_clamp(&self) -> bool {
        self.depth_clamp
    }

    /// Uploads `scene` once: object-space positions, edges, opposite vertices, triangles. The
    /// scene's transforms are not used here; each frame gives its own ([`PassFrame::transforms`]).
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when the scene is too large to index with `u32`, or a buffer
    /// exceeds the device's `max_storage_buffer_binding_size`.
    pub fn prepare(&self, scene: &TopologyScene) -> Result<ResidentScene, RenderError> {
        let layout = ResidentLayout::build(scene)?;
        let max = self.device.limits().max_storage_buffer_binding_size;
        let init = |label: &str,
                    bytes: &[u8],
                    usage: wgpu::BufferUsages|
         -> Result<wgpu::Buffer, RenderError> {
            if bytes.len() as u64 > max {
                return Err(RenderError::InvalidInput(format!(
                    "the scene's {label} take {} bytes; the device binds at most {max} (max_storage_buffer_binding_size)",
                    bytes.len()
                )));
            }
            let padded;
            let bytes = if bytes.is_empty() {
                padded = [0u8; 16];
                &padded[..]
            } else {
                bytes
            };
            Ok(self
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytes,
                    usage: usage | wgpu::BufferUsages::STORAGE,
                }))
        };
        let none = wgpu::BufferUsages::empty();
        let positions = init(
            "positions",
            bytemuck::cast_slice(&layout.scene.positions),
            none,
        )?;
        let edges = init("edges", bytemuck::cast_slice(&layout.scene.edges), none)?;
        let ovs = init(
            "opposite vertices",
            bytemuck::cast_slice(&layout.scene.ovs),
            none,
        )?;
        let tris = init("triangles", bytemuck::cast_slice(&layout.tris), none)?;
        let ov_tris = init(
            "opposite-vertex triangles",
            bytemuck::cast_slice(&layout.ov_tris),
            none,
        )?;
        let vertex_objects = init(
            "vertex objects",
            bytemuck::cast_slice(&layout.vertex_objects),
            none,
        )?;
        let world_bytes = 16 * layout.vertex_objects.len().max(1) as u64;
        if world_bytes > max {
            return Err(RenderError::InvalidInput(format!(
                "the scene's world positions take {world_bytes} bytes; the device binds at most {max} (max_storage_buffer_binding_size)"
            )));
        }
        let world = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("world positions"),
            size: world_bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let world_out = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident vertices out"),
            layout: &self.v2,
            entries: &[entry(0, &world)],
        });
        // The surface vertices (3 `SurfaceVertex` per triangle) where the buffer fits the device;
        // the surface pass writes them in chunks that each fit one storage binding.
        let per_tri = 3 * std::mem::size_of::<crate::gpu::SurfaceVertex>() as u64;
        let surface_bytes = per_tri * layout.tri_count() as u64;
        let limits = self.device.limits();
        let align = u64::from(limits.min_storage_buffer_offset_alignment.max(1));
        // Triangles per chunk: fits a binding, and chunk offsets stay aligned.
        let step = align / gcd(align, per_tri);
        let chunk = (max / per_tri) / step * step;
        let surface = (surface_bytes > 0 && surface_bytes <= limits.max_buffer_size && chunk > 0)
            .then(|| {
                let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("surface vertices"),
                    size: surface_bytes,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
                    mapped_at_creation: false,
                });
                let tris = layout.tri_count() as u64;
                let chunks = (0..tris.div_ceil(chunk))
                    .map(|c| {
                        let first = c * chunk;
                        let count = chunk.min(tris - first);
                        let base =
                            self.device
                                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                                    label: Some("resident surfaces chunk"),
                                    contents: bytemuck::cast_slice(&[
                                        first as u32,
                                        count as u32,
                                        0,
                                        0,
                                    ]),
                                    usage: wgpu::BufferUsages::UNIFORM,
                                });
                        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                            label: Some("resident surfaces out"),
                            layout: &self.s2,
                            entries: &[
                                wgpu::BindGroupEntry {
                                    binding: 1,
                                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                        buffer: &buffer,
                                        offset: first * per_tri,
                                        size: std::num::NonZeroU64::new(count * per_tri),
                                    }),
                                },
                                entry(2, &base),
                            ],
                        });
                        (group, count as u32)
                    })
                    .collect();
                (buffer, chunks)
            });
        let uniform = |label: &str, size: u64| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Ok(ResidentScene {
            tri_offsets: layout.tri_offsets.clone(),
            layout: Arc::new(layout),
            positions,
            edges,
            ovs,
            tris,
            ov_tris,
            vertex_objects,
            world,
            world_out,
            surface,
            params: uniform("resident params", 16),
            rparams: uniform("resident frame params", 16),
            globals: uniform("resident globals", 96),
            frame: None,
            state: FrameState {
                lights: 0,
                mode: Accuracy::Exact,
                techniques: Vec::new(),
                scissors: Vec::new(),
            },
        })
    }

    /// Writes one frame's inputs (object-space lights, techniques, camera-relative transforms,
    /// per-light uniforms), growing the per-light buffers when there are more lights than before.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when a slice's length does not match the scene or the lights,
    /// an object-space light is not finite, or the per-light buffers would exceed the device's
    /// `max_storage_buffer_binding_size`.
    pub fn update(&self, rs: &mut ResidentScene, f: &PassFrame<'_>) -> Result<(), RenderError> {
        let objects = rs.layout.object_count();
        let n_lights = f.lights.len();
        let check = |what: &str, got: usize, want: usize| {
            if got == want {
                Ok(())
            } else {
                Err(RenderError::InvalidInput(format!(
                    "GPU pipeline frame: {got} {what}, expected {want}"
                )))
            }
        };
        check("transforms", f.transforms.len(), objects)?;
        check("albedos", f.albedo.len(), objects)?;
        check("techniques", f.techniques.len(), objects * n_lights)?;
        check("light colours", f.colors.len(), n_lights)?;
        check("scissors", f.scissors.len(), n_lights)?;
        if !f.emission.is_empty() {
            check("emissions", f.emission.len(), n_lights)?;
        }
        let slots = n_lights.max(1);
        if rs.frame.as_ref().is_none_or(|b| b.lights < slots) {
            rs.frame = Some(self.frame_buffers(rs, slots)?);
        }
        let fb = rs.frame.as_ref().expect("allocated above");
        let q = &self.queue;
        // Object-space lights, [object * light_count + light], through the one shared
        // conversion (f64, rounded once), as every backend does.
        let topo = TopologyScene {
            objects: f
                .transforms
                .iter()
                .enumerate()
                .map(|(i, &t)| shadowvol_silhouette::SceneObject {
                    name: format!("object {i}"),
                    table: Arc::new(shadowvol_mesh_topology::EdgeTable::default()),
                    world_from_object: t,
                })
                .collect(),
        };
        let ol = object_lights(&topo, f.lights);
        let mut lights: Vec<[f32; 4]> = Vec::with_capacity(objects * n_lights);
        for (oi, row) in ol.iter().enumerate() {
            for l in row {
                if !l.iter().all(|v| v.is_finite()) {
                    return Err(RenderError::InvalidInput(format!(
                        "object {oi}: the light in object space {l:?} is not finite"
                    )));
                }
                lights.push(*l);
            }
        }
        if lights.is_empty() {
            lights.push([0.0; 4]);
        }
        q.write_buffer(&fb.lights_buf, 0, bytemuck::cast_slice(&lights));
        let codes: Vec<u32> = f
            .techniques
            .iter()
            .map(|t| match t {
                Technique::Culled => twin::technique::CULLED,
                Technique::ZPass => twin::technique::ZPASS,
                Technique::ZFail => twin::technique::ZFAIL,
            })
            .collect();
        if !codes.is_empty() {
            q.write_buffer(&fb.technique, 0, bytemuck::cast_slice(&codes));
        }
        // Camera-relative transforms composed in f64 and rounded once, so large world
        // coordinates keep their precision near the eye.
        let eye = f.camera.eye.as_dvec3();
        let mut objs: Vec<[u32; 4]> = Vec::with_capacity(objects * 5);
        for (oi, t) in f.transforms.iter().enumerate() {
            let d = DAffine3::from_cols(
                t.matrix3.x_axis.as_dvec3(),
                t.matrix3.y_axis.as_dvec3(),
                t.matrix3.z_axis.as_dvec3(),
                t.translation.as_dvec3() - eye,
            );
            let m = d.matrix3;
            for r in 0..3 {
                let row = m.row(r);
                let v = [
                    row.x as f32,
                    row.y as f32,
                    row.z as f32,
                    d.translation[r] as f32,
                ];
                objs.push(v.map(f32::to_bits));
            }
            let a = f.albedo[oi];
            objs.push([a[0], a[1], a[2], 1.0].map(f32::to_bits));
            objs.push([rs.tri_offsets[oi], 0, 0, 0]);
        }
        if objs.is_empty() {
            objs.push([0; 4]);
        }
        q.write_buffer(&fb.objects, 0, bytemuck::cast_slice(&objs));
        let edge_count = rs.layout.scene.edge_count() as u32;
        q.write_buffer(
            &rs.params,
            0,
            bytemuck::cast_slice(&[edge_count, n_lights as u32, 0, 0]),
        );
        let tri_count = rs.layout.tri_count() as u32;
        let capacity = rs.layout.capacity() as u32;
        q.write_buffer(
            &rs.rparams,
            0,
            bytemuck::cast_slice(&[tri_count, objects as u32, capacity, u32::from(f.count)]),
        );
        let rel_cam = Camera {
            eye: glam::Vec3::ZERO,
            target: f.camera.target - f.camera.eye,
            ..*f.camera
        };
        let mut globals = [0f32; 24];
        globals[..16].copy_from_slice(&rel_cam.view_proj(f.aspect).to_cols_array());
        globals[20] = f.ambient;
        q.write_buffer(&rs.globals, 0, bytemuck::cast_slice(&globals));
        let mut light_bytes = vec![0u8; slots * LIGHT_STRIDE as usize];
        for (li, light) in f.lights.iter().enumerate() {
            let mut l = light.to_array();
            let w = l[3];
            l[0] -= f.camera.eye.x * w;
            l[1] -= f.camera.eye.y * w;
            l[2] -= f.camera.eye.z * w;
            let draws = crate::gpu::LightDraws {
                light: l,
                color: f.colors[li],
                scissor: f.scissors[li],
                emission: f.emission.get(li).copied(),
                ..Default::default()
            };
            let v = crate::gpu::light_uniform(&draws);
            let draw = [
                li as u32 * capacity,
                capacity,
                li as u32 * tri_count,
                u32::from(w != 0.0),
            ];
            let o = li * LIGHT_STRIDE as usize;
            light_bytes[o..o + 64].copy_from_slice(bytemuck::cast_slice(&v));
            light_bytes[o + 64..o + 80].copy_from_slice(bytemuck::cast_slice(&draw));
        }
        q.write_buffer(&fb.light_u, 0, &light_bytes);
        rs.state = FrameState {
            lights: n_lights,
            mode: f.mode,
            techniques: f.techniques.to_vec(),
            scissors: f.scissors.to_vec(),
        };
        Ok(())
    }

    fn frame_buffers(&self, rs: &ResidentScene, slots: usize) -> Result<FrameBuffers, RenderError> {
        let objects = rs.layout.object_count().max(1);
        let max = self.device.limits().max_storage_buffer_binding_size;
        let sized = |label: &str,
                     size: u64,
                     usage: wgpu::BufferUsages|
         -> Result<wgpu::Buffer, RenderError> {
            if size > max {
                return Err(RenderError::InvalidInput(format!(
                    "the GPU pipeline's {label} for {slots} light(s) take {size} bytes; the device binds at most {max} (max_storage_buffer_binding_size): use fewer lights per frame"
                )));
            }
            Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            }))
        };
        let st = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let s = slots as u64;
        let tri = rs.layout.tri_count().max(1) as u64;
        let lights_buf = sized("object-space lights", 16 * s * objects as u64, st)?;
        let technique = sized("techniques", 4 * s * objects as u64, st)?;
        let readable = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let signs = sized("triangle signs", 4 * s * tri, readable)?;
        let args = sized(
            "indirect draws",
            4 * (8 * s + 1 + 3 * s * objects as u64),
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_SRC,
        )?;
        let records = sized(
            "side records",
            4 * s * rs.layout.capacity() as u64,
            readable,
        )?;
        let objects_buf = sized("objects", 80 * objects as u64, st)?;
        let light_u = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resident lights"),
            size: LIGHT_STRIDE * s,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let c0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident extract scene"),
            layout: &self.c0,
            entries: &[
                entry(0, &rs.params),
                entry(1, &rs.positions),
                entry(2, &rs.edges),
                entry(3, &rs.ovs),
                entry(4, &lights_buf),
            ],
        });
        let c1 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident extract frame"),
            layout: &self.c1,
            entries: &[
                entry(0, &rs.rparams),
                entry(1, &rs.tris),
                entry(2, &rs.ov_tris),
                entry(3, &technique),
                entry(4, &signs),
                entry(5, &args),
                entry(6, &records),
            ],
        });
        let d0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident draw"),
            layout: &self.d0,
            entries: &[
                entry(0, &rs.globals),
                entry(1, &rs.positions),
                entry(2, &rs.edges),
                entry(3, &rs.tris),
                entry(4, &signs),
                entry(5, &records),
                entry(6, &objects_buf),
                entry(7, &rs.world),
            ],
        });
        let s0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident surfaces"),
            layout: &self.s0,
            entries: &[
                entry(3, &rs.tris),
                entry(6, &objects_buf),
                entry(7, &rs.world),
            ],
        });
        let v0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident vertices"),
            layout: &self.v0,
            entries: &[
                entry(1, &rs.positions),
                entry(6, &objects_buf),
                entry(8, &rs.vertex_objects),
            ],
        });
        let dl = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident light"),
            layout: &self.dl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &light_u,
                    offset: 0,
                    size: std::num::NonZeroU64::new(LIGHT_BYTES),
                }),
            }],
        });
        let queries = self.timestamps.then(|| {
            let count = 2 * (2 + 3 * slots as u32);
            let set = self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("resident timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            });
            let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("resident timestamps resolve"),
                size: 8 * u64::from(count),
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve, count)
        });
        Ok(FrameBuffers {
            lights: slots,
            queries,
            lights_buf,
            technique,
            signs,
            args,
            records,
            objects: objects_buf,
            light_u,
            c0,
            c1,
            d0,
            dl,
            v0,
            s0,
        })
    }

    /// Records the frame's compute pass for the inputs last given to [`ShadowPass::update`]: the
    /// vertex pass (camera-relative world positions, which every draw reads), then the reset,
    /// triangle and edge passes. Record it before the frame's draws.
    ///
    /// # Panics
    /// Panics if [`ShadowPass::update`] was never called on `rs`.
    pub fn encode_extract(&self, enc: &mut wgpu::CommandEncoder, rs: &ResidentScene) {
        let fb = rs
            .frame
            .as_ref()
            .expect("ShadowPass::update before encode_extract");
        let n_lights = rs.state.lights as u32;
        let objects = rs.layout.object_count() as u32;
        let max_dim = self
            .device
            .limits()
            .max_compute_workgroups_per_dimension
            .max(1);
        let grid = |items: u32| {
            let groups = items.div_ceil(WORKGROUP).max(1);
            let x = groups.min(max_dim);
            (x, groups.div_ceil(x))
        };
        let slot = TimestampSlot::Extract.index();
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("resident extract"),
            timestamp_writes: fb.queries.as_ref().map(|(set, _, _)| {
                wgpu::ComputePassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(slot),
                    end_of_pass_write_index: Some(slot + 1),
                }
            }),
        });
        // Vertices first: the draws of the frame read their camera-relative positions.
        pass.set_pipeline(&self.vertices);
        pass.set_bind_group(0, &fb.v0, &[]);
        pass.set_bind_group(1, &self.empty, &[]);
        pass.set_bind_group(2, &rs.world_out, &[]);
        let (x, y) = grid(rs.layout.vertex_objects.len() as u32);
        pass.dispatch_workgroups(x, y, 1);
        if let Some((_, chunks)) = &rs.surface {
            pass.set_pipeline(&self.surfaces);
            pass.set_bind_group(0, &fb.s0, &[]);
            for (out, count) in chunks {
                pass.set_bind_group(2, out, &[]);
                let (x, y) = grid(*count);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        pass.set_bind_group(0, &fb.c0, &[]);
        pass.set_bind_group(1, &fb.c1, &[]);
        pass.set_pipeline(&self.reset);
        let total = n_lights * 8 + 1 + 3 * n_lights * objects;
        pass.dispatch_workgroups(total.div_ceil(64).max(1), 1, 1);
        if n_lights == 0 {
            return;
        }
        let mode = mode_index(rs.state.mode);
        let (x, y) = grid(rs.layout.tri_count() as u32);
        pass.set_pipeline(&self.triangles[mode]);
        pass.dispatch_workgroups(x, y, 1);
        let (x, y) = grid(rs.layout.scene.edge_count() as u32);
        pass.set_pipeline(&self.edges[mode]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Records the depth pre-pass (ambient colour, ids when [`PassFormats::ids`] is set), clearing
    /// colour to `clear`, depth to 1 and stencil to 0.
    ///
    /// # Panics
    /// Panics if [`ShadowPass::update`] was never called on `rs`, or `ids` is given without
    /// [`PassFormats::ids`] (or missing with it).
    pub fn encode_prepass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rs: &ResidentScene,
        color: &wgpu::TextureView,
        ids: Option<&wgpu::TextureView>,
        depth: &wgpu::TextureView,
        clear: wgpu::Color,
    ) {
        assert_eq!(
            ids.is_some(),
            self.formats.ids.is_some(),
            "ids target matches PassFormats::ids"
        );
        let fb = rs
            .frame
            .as_ref()
            .expect("ShadowPass::update before encode_prepass");
        let mut attachments = vec![Some(wgpu::RenderPassColorAttachment {
            view: color,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(clear),
                store: wgpu::StoreOp::Store,
            },
        })];
        if let Some(ids) = ids {
            attachments.push(Some(wgpu::RenderPassColorAttachment {
                view: ids,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            }));
        }
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("resident prepass"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: render_ts(fb, TimestampSlot::Prepass),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let tris = rs.layout.tri_count() as u32;
        if tris > 0 {
            pass.set_pipeline(&self.prepass[usize::from(rs.surface.is_some())]);
            if let Some((vertices, _)) = &rs.surface {
                pass.set_vertex_buffer(0, vertices.slice(..));
            }
            pass.set_bind_group(0, &fb.d0, &[]);
            pass.set_bind_group(1, &fb.dl, &[0]);
            pass.draw(0..tris * 3, 0..1);
        }
    }

    /// Records light `light`'s stencil pass into `depth` (its stencil cleared to 0, depth
    /// loaded): z-pass sides, z-fail sides, then the caps of its z-fail objects.
    ///
    /// # Panics
    /// Panics if `light` is not a light of the last [`ShadowPass::update`].
    pub fn encode_stencil(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rs: &ResidentScene,
        light: usize,
        depth: &wgpu::TextureView,
    ) {
        assert!(
            light < rs.state.lights,
            "light {light} of {}",
            rs.state.lights
        );
        let fb = rs
            .frame
            .as_ref()
            .expect("ShadowPass::update before encode_stencil");
        let scissor = rs.state.scissors[light];
        let empty = scissor.is_some_and(|r| r[2] == 0 || r[3] == 0);
        let offset = (light as u64 * LIGHT_STRIDE) as u32;
        // Two passes, sides then caps, so that each has its own timestamps; the first clears
        // the stencil, the second keeps counting into it.
        let begin = |enc: &mut wgpu::CommandEncoder, label, stencil, slot| {
            let mut pass = enc
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(label),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: Some(wgpu::Operations {
                            load: stencil,
                            store: wgpu::StoreOp::Store,
                        }),
                    }),
                    timestamp_writes: render_ts(fb, slot),
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            if let Some([x, y, w, h]) = scissor {
                pass.set_scissor_rect(x, y, w, h);
            }
            pass.set_bind_group(0, &fb.d0, &[]);
            pass.set_bind_group(1, &fb.dl, &[offset]);
            pass
        };
        {
            let mut pass = begin(
                enc,
                "resident sides",
                wgpu::LoadOp::Clear(0),
                TimestampSlot::Sides(light),
            );
            if !empty {
                let base = light as u64 * 32;
                pass.set_pipeline(&self.side_zpass);
                pass.draw_indirect(&fb.args, base);
                pass.set_pipeline(&self.side_zfail);
                pass.draw_indirect(&fb.args, base + 16);
            }
        }
        let mut pass = begin(
            enc,
            "resident caps",
            wgpu::LoadOp::Load,
            TimestampSlot::Caps(light),
        );
        if empty {
            return;
        }
        let objects = rs.layout.object_count();
        let zfail: Vec<usize> = (0..objects)
            .filter(|&o| rs.state.techniques[light * objects + o] == Technique::ZFail)
            .collect();
        let range = |o: usize| (rs.tri_offsets[o], rs.tri_offsets[o + 1]);
        pass.set_pipeline(&self.cap_ccw);
        for &o in &zfail {
            let (a, b) = range(o);
            if b > a {
                pass.draw(a * 6..b * 6, 0..1);
            }
        }
        pass.set_pipeline(&self.cap_cw);
        for &o in &zfail {
            let (a, b) = range(o);
            if b > a {
                pass.draw(a * 3..b * 3, 0..1);
            }
        }
    }

    /// Records light `light`'s additive lit pass into `color` where the stencil is 0.
    ///
    /// # Panics
    /// Panics if `light` is not a light of the last [`ShadowPass::update`].
    pub fn encode_lit(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rs: &ResidentScene,
        light: usize,
        color: &wgpu::TextureView,
        depth: &wgpu::TextureView,
    ) {
        assert!(
            light < rs.state.lights,
            "light {light} of {}",
            rs.state.lights
        );
        let fb = rs
            .frame
            .as_ref()
            .expect("ShadowPass::update before encode_lit");
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("resident lit"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: render_ts(fb, TimestampSlot::Lit(light)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let scissor = rs.state.scissors[light];
        let tris = rs.layout.tri_count() as u32;
        if tris == 0 || scissor.is_some_and(|r| r[2] == 0 || r[3] == 0) {
            return;
        }
        if let Some([x, y, w, h]) = scissor {
            pass.set_scissor_rect(x, y, w, h);
        }
        pass.set_pipeline(&self.lit[usize::from(rs.surface.is_some())]);
        if let Some((vertices, _)) = &rs.surface {
            pass.set_vertex_buffer(0, vertices.slice(..));
        }
        pass.set_stencil_reference(0);
        pass.set_bind_group(0, &fb.d0, &[]);
        pass.set_bind_group(1, &fb.dl, &[(light as u64 * LIGHT_STRIDE) as u32]);
        pass.draw(0..tris * 3, 0..1);
    }

    /// Reads back the counts of the last submitted frame (for tests and the final frame's plan;
    /// this maps a buffer, so never call it between timed frames).
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails or the device does not finish in time.
    pub fn read_counts(&self, rs: &ResidentScene) -> Result<PassCounts, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(PassCounts::default());
        };
        let words = read_buffer(&self.device, &self.queue, &fb.args)?;
        let l = rs.state.lights;
        let objects = rs.layout.object_count();
        let base = 8 * l;
        let mut c = PassCounts {
            integer_decided: u64::from(words[base]),
            records: (0..l)
                .map(|li| [words[li * 8 + 1], words[li * 8 + 5]])
                .collect(),
            ..PassCounts::default()
        };
        for i in 0..l * objects {
            let k = base + 1 + 3 * i;
            c.silhouette_edges.push(words[k]);
            c.side_quads.push(words[k + 1]);
            c.cap_triangles.push(words[k + 2]);
        }
        Ok(c)
    }

    /// The GPU times of the passes of the last submitted frame, from timestamp queries (this maps
    /// a buffer: call it after the frame, not between timed frames). `None` when the device has
    /// no `TIMESTAMP_QUERY` or no frame was recorded.
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails.
    pub fn read_timings(&self, rs: &ResidentScene) -> Result<Option<GpuTimings>, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(None);
        };
        let Some((set, resolve, count)) = &fb.queries else {
            return Ok(None);
        };
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("resident timestamps"),
            });
        enc.resolve_query_set(set, 0..*count, resolve, 0);
        self.queue.submit([enc.finish()]);
        let words = read_buffer(&self.device, &self.queue, resolve)?;
        let ticks: Vec<u64> = words
            .chunks_exact(2)
            .map(|w| u64::from(w[0]) | (u64::from(w[1]) << 32))
            .collect();
        let period_ms = f64::from(self.queue.get_timestamp_period()) * 1e-6;
        let span = |slot: TimestampSlot| {
            let i = slot.index() as usize;
            ticks[i + 1].saturating_sub(ticks[i]) as f64 * period_ms
        };
        let lights = rs.state.lights;
        let sides: f64 = (0..lights).map(|l| span(TimestampSlot::Sides(l))).sum();
        let caps: f64 = (0..lights).map(|l| span(TimestampSlot::Caps(l))).sum();
        let lit: f64 = (0..lights).map(|l| span(TimestampSlot::Lit(l))).sum();
        Ok(Some(GpuTimings {
            extract: span(TimestampSlot::Extract),
            sides,
            caps,
            stencil: sides + caps,
            lighting: span(TimestampSlot::Prepass) + lit,
        }))
    }

    /// Reads back the triangle signs `[light * tri_count + triangle]` of the last submitted frame
    /// (tests only).
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails.
    pub fn read_signs(&self, rs: &ResidentScene) -> Result<Vec<i32>, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(Vec::new());
        };
        let n = rs.state.lights * rs.layout.tri_count();
        let words = read_buffer(&self.device, &self.queue, &fb.signs)?;
        Ok(words[..n].iter().map(|&w| w as i32).collect())
    }

    /// Reads back each light's side records of the last submitted frame, sorted (tests only).
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails.
    pub fn read_records(&self, rs: &ResidentScene) -> Result<Vec<twin::LightRecords>, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(Vec::new());
        };
        let counts = self.read_counts(rs)?;
        let words = read_buffer(&self.device, &self.queue, &fb.records)?;
        let cap = rs.layout.capacity();
        Ok(counts
            .records
            .iter()
            .enumerate()
            .map(|(li, &[zp, zf])| {
                let region = &words[li * cap..(li + 1) * cap];
                let mut zpass = region[..zp as usize].to_vec();
                let mut zfail = region[cap - zf as usize..].to_vec();
                zpass.sort_unstable();
                zfail.sort_unstable();
                twin::LightRecords { zpass, zfail }
            })
            .collect())
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// Copies `buffer` to a mappable one and reads it as `u32` words.
fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u32>, RenderError> {
    let size = buffer.size();
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("resident readback"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("resident readback"),
    });
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    queue.submit([enc.finish()]);
    let bytes = crate::gpu::map_read(device, &staging)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

/// Which pass a pair of timestamps belongs to.
#[derive(Debug, Clone, Copy)]
enum TimestampSlot {
    Extract,
    Prepass,
    Sides(usize),
    Caps(usize),
    Lit(usize),
}

impl TimestampSlot {
    fn index(self) -> u32 {
        2 * match self {
            TimestampSlot::Extract => 0,
            TimestampSlot::Prepass => 1,
            TimestampSlot::Sides(l) => 2 + 3 * l as u32,
            TimestampSlot::Caps(l) => 3 + 3 * l as u32,
            TimestampSlot::Lit(l) => 4 + 3 * l as u32,
        }
    }
}

fn render_ts(
    fb: &FrameBuffers,
    slot: TimestampSlot,
) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
    fb.queries
        .as_ref()
        .map(|(set, _, _)| wgpu::RenderPassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(slot.index()),
            end_of_pass_write_index: Some(slot.index() + 1),
        })
}

/// GPU times of one frame's passes, milliseconds, from timestamp queries.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct GpuTimings {
    /// The extraction compute pass (reset, triangle pass, edge pass).
    pub extract: f64,
    /// The side passes of every light.
    pub sides: f64,
    /// The cap passes of every light.
    pub caps: f64,
    /// Sides and caps: the whole stencil passes.
    pub stencil: f64,
    /// The depth pre-pass and every light's lit pass.
    pub lighting: f64,
}

/// What the last [`ShadowPass::update`] set, for the draws.
#[derive(Debug, Clone)]
struct FrameState {
    lights: usize,
    mode: Accuracy,
    techniques: Vec<Technique>,
    scissors: Vec<Option<[u32; 4]>>,
}

/// Buffers sized by the number of lights, and the bind groups over them.
struct FrameBuffers {
    lights: usize,
    /// With `TIMESTAMP_QUERY`: begin/end of the extraction, the pre-pass, and per light its
    /// side, cap and lit passes (see `TimestampSlot`), and the buffer they resolve into.
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, u32)>,
    lights_buf: wgpu::Buffer,
    technique: wgpu::Buffer,
    signs: wgpu::Buffer,
    args: wgpu::Buffer,
    records: wgpu::Buffer,
    objects: wgpu::Buffer,
    light_u: wgpu::Buffer,
    c0: wgpu::BindGroup,
    c1: wgpu::BindGroup,
    d0: wgpu::BindGroup,
    dl: wgpu::BindGroup,
    v0: wgpu::BindGroup,
    s0: wgpu::BindGroup,
}

/// A scene uploaded by [`ShadowPass::prepare`], with its per-frame buffers.
pub struct ResidentScene {
    layout: Arc<ResidentLayout>,
    tri_offsets: Vec<u32>,
    positions: wgpu::Buffer,
    edges: wgpu::Buffer,
    ovs: wgpu::Buffer,
    tris: wgpu::Buffer,
    ov_tris: wgpu::Buffer,
    vertex_objects: wgpu::Buffer,
    world: wgpu::Buffer,
    world_out: wgpu::BindGroup,
    /// The per-frame surface vertex buffer and the bind groups of its chunks with their
    /// triangle counts (`None`: vertex pulling).
    surface: Option<(wgpu::Buffer, Vec<(wgpu::BindGroup, u32)>)>,
    params: wgpu::Buffer,
    rparams: wgpu::Buffer,
    globals: wgpu::Buffer,
    frame: Option<FrameBuffers>,
    state: FrameState,
}

impl std::fmt::Debug for ResidentScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ResidentScene")
            .field("triangles", &self.layout.tri_count())
            .field("edges", &self.layout.scene.edge_count())
            .field("objects", &self.layout.object_count())
            .finish_non_exhaustive()
    }
}

impl ResidentScene {
    /// The uploaded layout (for the CPU twin).
    #[must_use]
    pub fn layout(&self) -> &ResidentLayout {
        &self.layout
    }
}
