//! The pass on a device: what it requires of the adapter, and its shader modules, layouts and
//! pipelines.

use super::*;
use crate::raster::pipelines::{
    bind_group_layout, color_target, pipeline_layout, storage, uniform, RenderPipelines,
};
use crate::raster::states;
use shadowvol_gpu::requirements::{self, RESIDENT};
use shadowvol_gpu::ErrorScopes;

impl ShadowPass {
    /// Features the pass uses when the adapter has them
    /// ([`shadowvol_gpu::requirements::optional_features`]). Request them on the device.
    #[must_use]
    pub fn optional_features(adapter: &wgpu::Adapter) -> wgpu::Features {
        requirements::optional_features(adapter)
    }

    /// Limits to request on the device ([`RESIDENT`]'s), each buffer size at most
    /// [`crate::buffer_cap`] when it is set.
    ///
    /// # Errors
    /// [`RenderError::Unsupported`] naming the limit or capability the adapter lacks.
    pub fn required_limits(adapter: &wgpu::Adapter) -> Result<wgpu::Limits, RenderError> {
        RESIDENT
            .limits(adapter, crate::device::buffer_cap())
            .map_err(RenderError::Unsupported)
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
        RESIDENT
            .check_adapter(adapter)
            .and_then(|()| RESIDENT.check_limits(&device.limits()))
            .map_err(RenderError::Unsupported)?;
        if !formats.depth.has_stencil_aspect() {
            return Err(RenderError::InvalidInput(format!(
                "depth format {:?} has no stencil aspect",
                formats.depth
            )));
        }
        let features = device.features();
        let depth_clamp = features.contains(wgpu::Features::DEPTH_CLIP_CONTROL);
        let filter = ExactFilter::for_device(features.contains(wgpu::Features::SHADER_F64), false);
        let scope = ErrorScopes::push(device);
        // The empty group 1 of the vertex pass and of the pending entry, one layout for both (the
        // vertex pass binds `empty` with it).
        let v1 = bind_group_layout(device, "resident vertices (unused)", &[]);
        let x = ExtractPipelines::new(device, filter, &v1);
        let draw = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("resident draw"),
            source: wgpu::ShaderSource::Wgsl(draw_source().into()),
        });
        let s = SurfacePipelines::new(device, &draw, &v1, &x.v2);
        let d = DrawPipelines::new(device, &draw, formats, depth_clamp);
        if let Some(e) = scope.pop() {
            return Err(RenderError::Device(format!("GPU pipeline creation: {e}")));
        }
        Ok(Self {
            device: device.clone(),
            queue: queue.clone(),
            formats,
            filter,
            depth_clamp,
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            extract: x,
            world: s,
            draw: d,
            surfaces: SurfaceVertices::default(),
        })
    }

    /// Where scenes prepared from now on read their surfaces' vertices (default
    /// [`SurfaceVertices::Auto`]).
    pub fn set_surface_vertices(&mut self, surfaces: SurfaceVertices) {
        self.surfaces = surfaces;
    }

    /// The exact filter the triangle pass runs (`f64` when the device has `SHADER_F64`).
    #[must_use]
    pub fn exact_filter(&self) -> ExactFilter {
        self.filter
    }

    /// True when z-fail volumes are drawn with depth clamp (`DEPTH_CLIP_CONTROL`).
    #[must_use]
    pub fn depth_clamp(&self) -> bool {
        self.depth_clamp
    }
}

/// The extraction's layouts and compute pipelines (the `resident extract` module, built for
/// `filter`): reset, the triangle pass per mode, exact mode's pending pair, the edge pass per
/// mode.
pub(super) struct ExtractPipelines {
    pub(super) c0: wgpu::BindGroupLayout,
    pub(super) c1: wgpu::BindGroupLayout,
    pub(super) v2: wgpu::BindGroupLayout,
    pub(super) reset: wgpu::ComputePipeline,
    pub(super) triangles: Vec<wgpu::ComputePipeline>,
    /// Exact mode with sharing groups: the triangle pass that decides a group's box first.
    pub(super) triangles_shared: wgpu::ComputePipeline,
    /// Exact mode: writes the indirect arguments of `pending`.
    pub(super) pending_args: wgpu::ComputePipeline,
    /// Exact mode: decides the pairs the triangle pass's filter left, with `orient_int`.
    pub(super) pending: wgpu::ComputePipeline,
    pub(super) edges: Vec<wgpu::ComputePipeline>,
    /// Exact mode with sharing groups: the edge pass that extracts a group's lights together.
    pub(super) edges_shared: wgpu::ComputePipeline,
}

impl ExtractPipelines {
    fn new(device: &wgpu::Device, filter: ExactFilter, v1: &wgpu::BindGroupLayout) -> Self {
        let compute = wgpu::ShaderStages::COMPUTE;
        // Group 0: the wgpu backend's bindings the resident kernels use (its packed tables and
        // their offsets, lights and signs).
        let c0 = bind_group_layout(
            device,
            "resident extract scene",
            &[
                uniform(0, compute, false),
                storage(1, compute, true),
                uniform(2, compute, false),
                storage(4, compute, true),
                storage(11, compute, false),
            ],
        );
        let c1 = bind_group_layout(
            device,
            "resident extract frame",
            &[
                uniform(0, compute, false),
                storage(3, compute, true),
                storage(5, compute, false),
                storage(6, compute, false),
            ],
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("resident extract"),
            source: wgpu::ShaderSource::Wgsl(extract_source(filter).into()),
        });
        let c_layout = pipeline_layout(device, "resident extract", &[&c0, &c1]);
        // Group 2 of the vertex pass (its output) and of the pending-arguments entry.
        let v2 = bind_group_layout(
            device,
            "resident group 2: one read-write buffer",
            &[storage(0, compute, false)],
        );
        // Group 2: the pending dispatch's arguments (written by one entry, read as indirect
        // arguments by the next, so never bound while they are read).
        let args_layout = pipeline_layout(device, "resident pending args", &[&c0, &c1, &v2]);
        let pending_layout = pipeline_layout(device, "resident pending", &[&c0, &c1, v1]);
        let max_x = device.limits().max_compute_workgroups_per_dimension.max(1);
        let compute_pipeline =
            |entry: &str, layout: &wgpu::PipelineLayout, mode: Accuracy, defer: bool| {
                let constants = [
                    (shaders::MODE_CONSTANT, f64::from(mode_code(mode))),
                    (shaders::TOUCH_SIGNS_CONSTANT, 1.0),
                    (shaders::DEFER_INT_CONSTANT, f64::from(u8::from(defer))),
                    ("PENDING_GROUPS_X", f64::from(max_x)),
                ];
                shaders::compute_pipeline(device, entry, layout, &module, entry, &constants)
            };
        let per_mode = |entry: &str, defer_exact: bool| {
            Accuracy::ALL
                .iter()
                .map(|&m| {
                    compute_pipeline(entry, &c_layout, m, defer_exact && m == Accuracy::Exact)
                })
                .collect()
        };
        Self {
            reset: compute_pipeline("resident_reset", &c_layout, Accuracy::Original, false),
            // Exact mode's triangle pass leaves `orient_int` out (DEFER_INT); `pending` decides
            // what its filter leaves.
            triangles: per_mode("resident_triangles", true),
            triangles_shared: compute_pipeline(
                "resident_triangles_shared",
                &c_layout,
                Accuracy::Exact,
                true,
            ),
            pending_args: compute_pipeline(
                "resident_pending_args",
                &args_layout,
                Accuracy::Exact,
                false,
            ),
            pending: compute_pipeline("resident_pending", &pending_layout, Accuracy::Exact, false),
            edges: per_mode("resident_edges", false),
            edges_shared: compute_pipeline(
                "resident_edges_shared",
                &c_layout,
                Accuracy::Exact,
                false,
            ),
            c0,
            c1,
            v2,
        }
    }
}

/// The vertex and surface passes (compute entries of the draw module, no constants):
/// object-space positions to camera-relative world positions, once per vertex and frame, and the
/// surface vertices from them.
pub(super) struct SurfacePipelines {
    pub(super) v0: wgpu::BindGroupLayout,
    pub(super) empty: wgpu::BindGroup,
    pub(super) vertices: wgpu::ComputePipeline,
    pub(super) s0: wgpu::BindGroupLayout,
    pub(super) s2: wgpu::BindGroupLayout,
    pub(super) surfaces: wgpu::ComputePipeline,
}

impl SurfacePipelines {
    fn new(
        device: &wgpu::Device,
        draw: &wgpu::ShaderModule,
        v1: &wgpu::BindGroupLayout,
        v2: &wgpu::BindGroupLayout,
    ) -> Self {
        let compute = wgpu::ShaderStages::COMPUTE;
        let draw_compute = |label: &str, entry: &str, groups: &[&wgpu::BindGroupLayout]| {
            let layout = pipeline_layout(device, label, groups);
            shaders::compute_pipeline(device, entry, &layout, draw, entry, &[])
        };
        let v0 = bind_group_layout(
            device,
            "resident vertices",
            &[
                storage(1, compute, true),
                storage(6, compute, true),
                uniform(9, compute, false),
            ],
        );
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident vertices (unused)"),
            layout: v1,
            entries: &[],
        });
        let vertices = draw_compute("resident vertices", "resident_vertices", &[&v0, v1, v2]);
        let s0 = bind_group_layout(
            device,
            "resident surfaces",
            &[
                storage(1, compute, true),
                storage(6, compute, true),
                storage(7, compute, true),
                uniform(9, compute, false),
            ],
        );
        let s2 = bind_group_layout(
            device,
            "resident surfaces out",
            &[storage(1, compute, false), uniform(2, compute, false)],
        );
        let surfaces = draw_compute("resident surfaces", "resident_surfaces", &[&s0, v1, &s2]);
        Self {
            v0,
            empty,
            vertices,
            s0,
            s2,
            surfaces,
        }
    }
}

/// The render pipelines of the draw module: the pre-pass and lit pass (each from the surface
/// vertex buffer or from the storage buffers), the z-pass and z-fail sides and the caps.
pub(super) struct DrawPipelines {
    pub(super) d0: wgpu::BindGroupLayout,
    pub(super) dl: wgpu::BindGroupLayout,
    /// Pre-pass: `[vertex pulling, vertex buffer]`.
    pub(super) prepass: [wgpu::RenderPipeline; 2],
    /// Lit pass: `[vertex pulling, vertex buffer]`.
    pub(super) lit: [wgpu::RenderPipeline; 2],
    pub(super) side_zpass: wgpu::RenderPipeline,
    pub(super) side_zfail: wgpu::RenderPipeline,
    pub(super) cap_ccw: wgpu::RenderPipeline,
    pub(super) cap_cw: wgpu::RenderPipeline,
}

impl DrawPipelines {
    fn new(
        device: &wgpu::Device,
        draw: &wgpu::ShaderModule,
        formats: PassFormats,
        depth_clamp: bool,
    ) -> Self {
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let vs = wgpu::ShaderStages::VERTEX;
        let d0 = bind_group_layout(
            device,
            "resident draw",
            &[
                uniform(0, vf, false),
                storage(1, vs, true),
                storage(4, vs, true),
                storage(5, vs, true),
                storage(6, vs, true),
                storage(7, vs, true),
                storage(12, vs, true),
                uniform(9, vs, false),
            ],
        );
        let dl = bind_group_layout(device, "resident light", &[uniform(0, vf, true)]);
        let d_layout = pipeline_layout(device, "resident draw", &[&d0, &dl]);
        let make = RenderPipelines {
            device,
            layout: &d_layout,
            module: draw,
            depth: formats.depth,
        };
        let mut prepass_targets = vec![color_target(formats.color, None)];
        if let Some(ids) = formats.ids {
            prepass_targets.push(color_target(ids, None));
        }
        let prepass_fs = if formats.ids.is_some() {
            "fs_prepass"
        } else {
            "fs_prepass_color"
        };
        let surface_layout = [Some(states::surface_layout())];
        // Surfaces come from the per-frame vertex buffer the surface pass writes (`vs_surface`,
        // as in the host pipeline), or, where that buffer would exceed `max_buffer_size`, are
        // pulled from the storage buffers (`vs_resident_surface`).
        let prepass = [
            make.prepass(
                "resident prepass",
                "vs_resident_surface",
                &[],
                prepass_fs,
                &prepass_targets,
            ),
            make.prepass(
                "resident prepass",
                "vs_surface",
                &surface_layout,
                prepass_fs,
                &prepass_targets,
            ),
        ];
        let lit = [
            make.lit("resident lit", "vs_resident_surface", &[], formats.color),
            make.lit("resident lit", "vs_surface", &surface_layout, formats.color),
        ];
        // The same stencil rules as the host pipeline (see gpu.rs): z-pass counts the faces in
        // front of the surface with near clipping on; z-fail the faces behind it, with depth
        // clamp where the device has it.
        let ccw = wgpu::FrontFace::Ccw;
        let side_zpass = make.volume(
            "resident side zpass",
            "vs_resident_side_zpass",
            &[],
            false,
            ccw,
            states::zpass_faces(),
        );
        let zfail = |label, entry, face| {
            make.volume(label, entry, &[], depth_clamp, face, states::zfail_faces())
        };
        Self {
            side_zpass,
            side_zfail: zfail("resident side zfail", "vs_resident_side_zfail", ccw),
            cap_ccw: zfail("resident cap ccw", "vs_resident_cap_ccw", ccw),
            cap_cw: zfail("resident cap cw", "vs_resident_cap_cw", wgpu::FrontFace::Cw),
            prepass,
            lit,
            d0,
            dl,
        }
    }
}
