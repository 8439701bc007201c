//! The shader modules (committed SPIR-V from the workspace's `shaders/`), the descriptor and
//! pipeline layouts, and the extraction pass: a render pass without attachments and the
//! graphics pipeline that runs the geometry shader with rasterisation discarded.

use crate::device::{device_err, Context};
use ash::vk;
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_silhouette::BackendError;

/// `shaders/edge_points.vert.spv`: one point per (edge, light).
pub(crate) const EDGE_POINTS_VERT: &[u8] = include_bytes!("../../../shaders/edge_points.vert.spv");
/// `shaders/silhouette_gs.geom.spv`: the geometry shader with the `f64` exact filter.
pub(crate) const SILHOUETTE_GS_F64: &[u8] =
    include_bytes!("../../../shaders/silhouette_gs.geom.spv");
/// `shaders/silhouette_gs.f32.geom.spv`: the geometry shader with the `f32` exact filter
/// (compiled with `SHADOWVOL_NO_F64`, for devices without `shaderFloat64`).
pub(crate) const SILHOUETTE_GS_F32: &[u8] =
    include_bytes!("../../../shaders/silhouette_gs.f32.geom.spv");

/// Number of storage-buffer bindings in set 0 (see the shaders).
pub(crate) const BINDINGS: u32 = 6;

/// The push constants of both stages (16 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Push {
    /// [`mode_code`](shadowvol_silhouette::gpu::mode_code) of the pass's mode.
    pub mode: u32,
    pub edge_count: u32,
    pub light_count: u32,
    pub uncertain_capacity: u32,
}

/// The stages the descriptor set and push constants are visible to.
pub(crate) const STAGES: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(
    vk::ShaderStageFlags::VERTEX.as_raw() | vk::ShaderStageFlags::GEOMETRY.as_raw(),
);

/// The layouts, modules and the extraction pipeline, destroyed by [`Pipelines::destroy`].
pub(crate) struct Pipelines {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    modules: Vec<vk::ShaderModule>,
    pub extract_pass: vk::RenderPass,
    pub extract_fb: vk::Framebuffer,
    pub extract: vk::Pipeline,
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

impl Pipelines {
    pub fn new(ctx: &Context) -> Result<Self, BackendError> {
        let mut p = Pipelines {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            modules: Vec::new(),
            extract_pass: vk::RenderPass::null(),
            extract_fb: vk::Framebuffer::null(),
            extract: vk::Pipeline::null(),
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
        self.create_layouts(ctx)?;
        let vs = module(ctx, "shaders/edge_points.vert.spv", EDGE_POINTS_VERT)?;
        self.modules.push(vs);
        let gs = match ctx.filter {
            ExactFilter::F64 => module(ctx, "shaders/silhouette_gs.geom.spv", SILHOUETTE_GS_F64)?,
            ExactFilter::F32 => {
                module(ctx, "shaders/silhouette_gs.f32.geom.spv", SILHOUETTE_GS_F32)?
            }
        };
        self.modules.push(gs);
        self.create_extract_pass(ctx)?;
        self.create_extract_pipeline(ctx, vs, gs)
    }

    /// The descriptor-set layout ([`BINDINGS`] storage buffers) and the pipeline layout with the
    /// [`Push`] constants.
    fn create_layouts(&mut self, ctx: &Context) -> Result<(), BackendError> {
        let d = &ctx.device;
        let bindings: Vec<_> = (0..BINDINGS)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(STAGES)
            })
            .collect();
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(STAGES)
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
        Ok(())
    }

    /// The extraction's render pass (one subpass, no attachments) and its 1 × 1 framebuffer.
    fn create_extract_pass(&mut self, ctx: &Context) -> Result<(), BackendError> {
        let d = &ctx.device;
        let subpass =
            [vk::SubpassDescription::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)];
        // SAFETY: as in `create_layouts`.
        unsafe {
            self.extract_pass = d
                .create_render_pass(
                    &vk::RenderPassCreateInfo::default().subpasses(&subpass),
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
        }
        Ok(())
    }

    /// The extraction pipeline: points from `vs` through the geometry shader `gs`, rasterisation
    /// discarded (dynamic viewport and scissor).
    fn create_extract_pipeline(
        &mut self,
        ctx: &Context,
        vs: vk::ShaderModule,
        gs: vk::ShaderModule,
    ) -> Result<(), BackendError> {
        let d = &ctx.device;
        let stage = |flags, module| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(flags)
                .module(module)
                .name(c"main")
        };
        let stages = [
            stage(vk::ShaderStageFlags::VERTEX, vs),
            stage(vk::ShaderStageFlags::GEOMETRY, gs),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let points = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::POINT_LIST);
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
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let blend = vk::PipelineColorBlendStateCreateInfo::default();
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&points)
            .viewport_state(&viewport_state)
            .rasterization_state(&raster_discard)
            .multisample_state(&multisample)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(self.layout)
            .render_pass(self.extract_pass)
            .subpass(0)];
        // SAFETY: every pointer in `info` refers to locals that outlive the call.
        let created =
            unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
        match created {
            Ok(p) => {
                self.extract = p[0];
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
                    what: "the extraction pipeline (edge_points.vert, silhouette_gs.geom)"
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
            d.destroy_pipeline(self.extract, None);
            d.destroy_framebuffer(self.extract_fb, None);
            d.destroy_render_pass(self.extract_pass, None);
            for m in self.modules.drain(..) {
                d.destroy_shader_module(m, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
        self.extract = vk::Pipeline::null();
        self.extract_fb = vk::Framebuffer::null();
        self.extract_pass = vk::RenderPass::null();
        self.layout = vk::PipelineLayout::null();
        self.set_layout = vk::DescriptorSetLayout::null();
    }
}
