//! Shader modules, descriptor layout, render passes and the three graphics pipelines.

use crate::device::{device_err, unavailable, Context};
use ash::vk;
use shadowvol_silhouette::BackendError;

pub(crate) const EDGE_POINTS_VERT: &[u8] = include_bytes!("../../../shaders/edge_points.vert.spv");
pub(crate) const DEPTH_PREPASS_VERT: &[u8] =
    include_bytes!("../../../shaders/depth_prepass.vert.spv");
pub(crate) const SILHOUETTE_GS_F64: &[u8] =
    include_bytes!("../../../shaders/silhouette_gs.geom.spv");
pub(crate) const SILHOUETTE_GS_F32: &[u8] =
    include_bytes!("../../../shaders/silhouette_gs.f32.geom.spv");
pub(crate) const SILHOUETTE_GS_EXTRACT_F64: &[u8] =
    include_bytes!("../../../shaders/silhouette_gs.extract.geom.spv");
pub(crate) const SILHOUETTE_GS_EXTRACT_F32: &[u8] =
    include_bytes!("../../../shaders/silhouette_gs.extract.f32.geom.spv");

/// Number of storage-buffer bindings in set 0 (see the shaders).
pub(crate) const BINDINGS: u32 = 10;

/// The push constants shared by every stage (24 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Push {
    pub mode: u32,
    pub edge_count: u32,
    pub light_count: u32,
    pub uncertain_capacity: u32,
    pub emit: u32,
    /// 0: side quads of edges; 1: caps of triangles (z-fail).
    pub pass: u32,
}

pub(crate) struct Pipelines {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    modules: Vec<vk::ShaderModule>,
    pub extract_pass: vk::RenderPass,
    pub extract_fb: vk::Framebuffer,
    pub extract: vk::Pipeline,
    pub render_pass: vk::RenderPass,
    pub depth: vk::Pipeline,
    /// Sides, z-pass stencil ops.
    pub stencil: vk::Pipeline,
    /// Sides, z-fail stencil ops.
    pub stencil_zfail: vk::Pipeline,
    /// Caps, z-fail stencil ops, depth-biased away from the camera.
    pub caps_zfail: vk::Pipeline,
    pub depth_format: vk::Format,
}

fn module(ctx: &Context, name: &str, bytes: &[u8]) -> Result<vk::ShaderModule, BackendError> {
    let words =
        ash::util::read_spv(&mut std::io::Cursor::new(bytes)).map_err(|e| BackendError::Build {
            backend: "vulkan",
            what: name.to_owned(),
            log: format!("invalid SPIR-V: {e} (run `cargo xtask shaders`)"),
        })?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: valid SPIR-V words and device.
    unsafe { ctx.device.create_shader_module(&info, None) }.map_err(|e| BackendError::Build {
        backend: "vulkan",
        what: name.to_owned(),
        log: format!("vkCreateShaderModule: {e}"),
    })
}

fn pick_depth_format(ctx: &Context) -> Result<vk::Format, BackendError> {
    let need =
        vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT | vk::FormatFeatureFlags::TRANSFER_SRC;
    for f in [
        vk::Format::D32_SFLOAT_S8_UINT,
        vk::Format::D24_UNORM_S8_UINT,
    ] {
        // SAFETY: plain query.
        let props = unsafe {
            ctx.instance
                .get_physical_device_format_properties(ctx.physical, f)
        };
        if props.optimal_tiling_features.contains(need) {
            return Ok(f);
        }
    }
    Err(unavailable(
        "no depth/stencil format (D32_SFLOAT_S8_UINT or D24_UNORM_S8_UINT) usable as an attachment \
         and copy source",
    ))
}

impl Pipelines {
    pub fn new(ctx: &Context) -> Result<Self, BackendError> {
        let mut p = Pipelines {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            modules: Vec::new(),
            extract_pass: vk::RenderPass::null(),
            extract_fb: vk::Framebuffer::null(),
            extract: vk::Pipeline::null(),
            render_pass: vk::RenderPass::null(),
            depth: vk::Pipeline::null(),
            stencil: vk::Pipeline::null(),
            stencil_zfail: vk::Pipeline::null(),
            caps_zfail: vk::Pipeline::null(),
            depth_format: vk::Format::UNDEFINED,
        };
        match p.build(ctx) {
            Ok(()) => Ok(p),
            Err(e) => {
                p.destroy(ctx);
                Err(e)
            }
        }
    }

    fn build(&mut self, ctx: &Context) -> Result<(), BackendError> {
        let d = &ctx.device;
        self.depth_format = pick_depth_format(ctx)?;
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::GEOMETRY;
        let bindings: Vec<_> = (0..BINDINGS)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(stages)
            .offset(0)
            .size(std::mem::size_of::<Push>().next_multiple_of(4) as u32)];
        // SAFETY: valid device; every created handle is stored in `self` and destroyed by
        // `destroy` (also on the error paths).
        unsafe {
            self.set_layout = d
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .map_err(|e| device_err("vkCreateDescriptorSetLayout", e))?;
            let layouts = [self.set_layout];
            self.layout = d
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default()
                        .set_layouts(&layouts)
                        .push_constant_ranges(&ranges),
                    None,
                )
                .map_err(|e| device_err("vkCreatePipelineLayout", e))?;
        }
        let vs_edge = module(ctx, "shaders/edge_points.vert.spv", EDGE_POINTS_VERT)?;
        self.modules.push(vs_edge);
        let vs_depth = module(ctx, "shaders/depth_prepass.vert.spv", DEPTH_PREPASS_VERT)?;
        self.modules.push(vs_depth);
        let gs = if ctx.use_f64 {
            module(ctx, "shaders/silhouette_gs.geom.spv", SILHOUETTE_GS_F64)?
        } else {
            module(ctx, "shaders/silhouette_gs.f32.geom.spv", SILHOUETTE_GS_F32)?
        };
        self.modules.push(gs);
        let gs_extract = if ctx.use_f64 {
            module(
                ctx,
                "shaders/silhouette_gs.extract.geom.spv",
                SILHOUETTE_GS_EXTRACT_F64,
            )?
        } else {
            module(
                ctx,
                "shaders/silhouette_gs.extract.f32.geom.spv",
                SILHOUETTE_GS_EXTRACT_F32,
            )?
        };
        self.modules.push(gs_extract);

        // Render passes.
        let subpass_empty =
            [vk::SubpassDescription::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)];
        let ds_attachment = [vk::AttachmentDescription::default()
            .format(self.depth_format)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .stencil_load_op(vk::AttachmentLoadOp::CLEAR)
            .stencil_store_op(vk::AttachmentStoreOp::STORE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)];
        let ds_ref = vk::AttachmentReference::default()
            .attachment(0)
            .layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
        let subpass_ds = [vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .depth_stencil_attachment(&ds_ref)];
        let tests = vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
            | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        let deps = [
            vk::SubpassDependency::default()
                .src_subpass(vk::SUBPASS_EXTERNAL)
                .dst_subpass(0)
                .src_stage_mask(tests)
                .dst_stage_mask(tests)
                .src_access_mask(vk::AccessFlags::empty())
                .dst_access_mask(
                    vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ
                        | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
                ),
            vk::SubpassDependency::default()
                .src_subpass(0)
                .dst_subpass(vk::SUBPASS_EXTERNAL)
                .src_stage_mask(tests)
                .dst_stage_mask(vk::PipelineStageFlags::TRANSFER)
                .src_access_mask(vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE)
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ),
        ];
        // SAFETY: as above.
        unsafe {
            self.extract_pass = d
                .create_render_pass(
                    &vk::RenderPassCreateInfo::default().subpasses(&subpass_empty),
                    None,
                )
                .map_err(|e| device_err("vkCreateRenderPass", e))?;
            self.extract_fb = d
                .create_framebuffer(
                    &vk::FramebufferCreateInfo::default()
                        .render_pass(self.extract_pass)
                        .width(1)
                        .height(1)
                        .layers(1),
                    None,
                )
                .map_err(|e| device_err("vkCreateFramebuffer", e))?;
            self.render_pass = d
                .create_render_pass(
                    &vk::RenderPassCreateInfo::default()
                        .attachments(&ds_attachment)
                        .subpasses(&subpass_ds)
                        .dependencies(&deps),
                    None,
                )
                .map_err(|e| device_err("vkCreateRenderPass", e))?;
        }

        let stage = |flags, module| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(flags)
                .module(module)
                .name(c"main")
        };
        let (vertex, geometry) = (vk::ShaderStageFlags::VERTEX, vk::ShaderStageFlags::GEOMETRY);
        let gs_stages = [stage(vertex, vs_edge), stage(geometry, gs)];
        let extract_stages = [stage(vertex, vs_edge), stage(geometry, gs_extract)];
        let depth_stages = [stage(vertex, vs_depth)];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let points = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::POINT_LIST);
        let triangles = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport_state = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let raster_discard = vk::PipelineRasterizationStateCreateInfo::default()
            .rasterizer_discard_enable(true)
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .depth_clamp_enable(ctx.caps.depth_clamp)
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        // Front caps lie on their own triangle: bias them away so they always fail the depth test
        // there (they can only be at or behind the visible surface).
        let raster_caps = raster
            .depth_bias_enable(true)
            .depth_bias_constant_factor(16.0)
            .depth_bias_slope_factor(2.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let blend = vk::PipelineColorBlendStateCreateInfo::default();
        let depth_write = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::LESS);
        let stencil_op = |pass, depth_fail| {
            vk::StencilOpState::default()
                .fail_op(vk::StencilOp::KEEP)
                .pass_op(pass)
                .depth_fail_op(depth_fail)
                .compare_op(vk::CompareOp::ALWAYS)
                .compare_mask(0xff)
                .write_mask(0xff)
                .reference(0)
        };
        // A stencil pass over the sides: depth test `less` without writes, the two-sided
        // stencil counting by `(pass, depth_fail)` of the front and of the back faces.
        let counting = |(front_pass, front_fail), (back_pass, back_fail)| {
            vk::PipelineDepthStencilStateCreateInfo::default()
                .depth_test_enable(true)
                .depth_write_enable(false)
                .depth_compare_op(vk::CompareOp::LESS)
                .stencil_test_enable(true)
                .front(stencil_op(front_pass, front_fail))
                .back(stencil_op(back_pass, back_fail))
        };
        let (inc, dec, keep) = (
            vk::StencilOp::INCREMENT_AND_WRAP,
            vk::StencilOp::DECREMENT_AND_WRAP,
            vk::StencilOp::KEEP,
        );
        // z-pass: count the sides in front of the visible surface, +1 front, -1 back (wrapping).
        let stencil_state = counting((inc, keep), (dec, keep));
        // z-fail (Carmack's reverse): count the faces behind the visible surface.
        let zfail_state = counting((keep, dec), (keep, inc));
        // The states every pipeline shares; each sets its stages, assembly and rasterisation
        // (and depth-stencil state, except extraction) on top.
        let (layout, render_pass) = (self.layout, self.render_pass);
        let shared = || {
            vk::GraphicsPipelineCreateInfo::default()
                .vertex_input_state(&vertex_input)
                .viewport_state(&viewport_state)
                .multisample_state(&multisample)
                .color_blend_state(&blend)
                .dynamic_state(&dynamic)
                .layout(layout)
                .render_pass(render_pass)
                .subpass(0)
        };
        let sides = || shared().stages(&gs_stages).input_assembly_state(&points);
        let infos = [
            shared()
                .stages(&extract_stages)
                .input_assembly_state(&points)
                .rasterization_state(&raster_discard)
                .render_pass(self.extract_pass),
            shared()
                .stages(&depth_stages)
                .input_assembly_state(&triangles)
                .rasterization_state(&raster)
                .depth_stencil_state(&depth_write),
            sides()
                .rasterization_state(&raster)
                .depth_stencil_state(&stencil_state),
            sides()
                .rasterization_state(&raster)
                .depth_stencil_state(&zfail_state),
            sides()
                .rasterization_state(&raster_caps)
                .depth_stencil_state(&zfail_state),
        ];
        // SAFETY: every pointer in `infos` refers to locals that outlive the call.
        let created =
            unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &infos, None) };
        match created {
            Ok(p) => {
                self.extract = p[0];
                self.depth = p[1];
                self.stencil = p[2];
                self.stencil_zfail = p[3];
                self.caps_zfail = p[4];
                Ok(())
            }
            Err((p, e)) => {
                for pipe in p {
                    if pipe != vk::Pipeline::null() {
                        // SAFETY: created above, unused.
                        unsafe { d.destroy_pipeline(pipe, None) };
                    }
                }
                Err(BackendError::Build {
                    backend: "vulkan",
                    what: "graphics pipelines (silhouette_gs.geom, edge_points.vert, depth_prepass.vert)"
                        .to_owned(),
                    log: format!("vkCreateGraphicsPipelines: {e}"),
                })
            }
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        let d = &ctx.device;
        // SAFETY: the device is idle; null handles are ignored by Vulkan.
        unsafe {
            for p in [
                self.extract,
                self.depth,
                self.stencil,
                self.stencil_zfail,
                self.caps_zfail,
            ] {
                d.destroy_pipeline(p, None);
            }
            d.destroy_framebuffer(self.extract_fb, None);
            d.destroy_render_pass(self.extract_pass, None);
            d.destroy_render_pass(self.render_pass, None);
            for m in self.modules.drain(..) {
                d.destroy_shader_module(m, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
        self.extract = vk::Pipeline::null();
        self.depth = vk::Pipeline::null();
        self.stencil = vk::Pipeline::null();
        self.stencil_zfail = vk::Pipeline::null();
        self.caps_zfail = vk::Pipeline::null();
        self.extract_fb = vk::Framebuffer::null();
        self.extract_pass = vk::RenderPass::null();
        self.render_pass = vk::RenderPass::null();
        self.layout = vk::PipelineLayout::null();
        self.set_layout = vk::DescriptorSetLayout::null();
    }
}
