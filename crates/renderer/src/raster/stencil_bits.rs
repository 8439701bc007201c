//! A frame's stencil read back through a colour target, for devices that cannot copy a stencil
//! aspect to a buffer (wgpu's `DEPTH_TEXTURE_AND_BUFFER_COPIES`, which OpenGL lacks): one
//! full-screen draw per stencil bit adds the bit's value into an 8-bit target where the bit is
//! set, and the target is copied instead. The bytes read back are the stencil values, the same
//! as a direct copy.

use super::states;

/// `shaders/render_stencil_bits.wgsl`: the full-screen triangle and the per-bit fragment.
pub const STENCIL_BITS_WGSL: &str = include_str!("../../../../shaders/render_stencil_bits.wgsl");

/// The colour format the stencil is copied into (one byte a pixel, blended exactly).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

/// The eight per-bit pipelines and the target they draw into.
pub(crate) struct StencilBits {
    /// Pipeline `i` passes where stencil bit `i` is set and adds `1 << i`.
    pipelines: Vec<wgpu::RenderPipeline>,
    target: wgpu::Texture,
    view: wgpu::TextureView,
}

impl StencilBits {
    /// The pipelines for stencils in `depth_format` and a `w` x `h` target.
    pub(crate) fn new(
        device: &wgpu::Device,
        depth_format: wgpu::TextureFormat,
        (w, h): (u32, u32),
    ) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shaders/render_stencil_bits.wgsl"),
            source: wgpu::ShaderSource::Wgsl(STENCIL_BITS_WGSL.into()),
        });
        let layout = super::pipelines::pipeline_layout(device, "stencil-bits", &[]);
        let pipelines = (0..8u32)
            .map(|bit| pipeline(device, &layout, &module, depth_format, bit))
            .collect();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let target = super::texture_2d(device, "stencil-bits", w, h, FORMAT, usage);
        Self {
            pipelines,
            view: target.create_view(&Default::default()),
            target,
        }
    }

    /// Records the draws that turn the stencil of `depth` into the stencil values in
    /// [`StencilBits::target`] (cleared first; depth and stencil are only read).
    pub(crate) fn encode(&self, enc: &mut wgpu::CommandEncoder, depth: &wgpu::TextureView) {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("stencil-bits"),
            color_attachments: &[states::cleared(&self.view, wgpu::Color::TRANSPARENT)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: None,
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        for (bit, pipeline) in self.pipelines.iter().enumerate() {
            pass.set_pipeline(pipeline);
            pass.set_stencil_reference(1 << bit);
            pass.draw(0..3, 0..1);
        }
    }

    /// The target holding the stencil values after [`StencilBits::encode`].
    pub(crate) fn target(&self) -> &wgpu::Texture {
        &self.target
    }
}

/// The pipeline of stencil bit `bit`: passes where the bit is set, adds `1 << bit`, writes no
/// depth and no stencil.
fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    depth_format: wgpu::TextureFormat,
    bit: u32,
) -> wgpu::RenderPipeline {
    let face = states::stencil_op(wgpu::CompareFunction::Equal, wgpu::StencilOperation::Keep);
    let depth = states::stencil_only_depth(depth_format, face, 1 << bit, 0);
    fullscreen(device, Some(layout), module, depth, Some(bit))
}

/// The full-screen triangle of `module` (`vs_fullscreen`) over `depth`, with the fragment
/// `fs_stencil_bit` of bit `bit` adding into an [`FORMAT`] target, or with no fragment stage
/// and no colour where `bit` is `None`.
pub(super) fn fullscreen(
    device: &wgpu::Device,
    layout: Option<&wgpu::PipelineLayout>,
    module: &wgpu::ShaderModule,
    depth: wgpu::DepthStencilState,
    bit: Option<u32>,
) -> wgpu::RenderPipeline {
    let constants = bit.map(|b| [("BIT", f64::from(b))]);
    let options = wgpu::PipelineCompilationOptions {
        constants: constants.as_ref().map_or(&[], |c| &c[..]),
        ..Default::default()
    };
    let targets = [super::pipelines::color_target(
        FORMAT,
        Some(states::additive()),
    )];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("stencil-bit"),
        layout,
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_fullscreen"),
            compilation_options: options.clone(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(depth),
        multisample: wgpu::MultisampleState::default(),
        fragment: bit.map(|_| wgpu::FragmentState {
            module,
            entry_point: Some("fs_stencil_bit"),
            compilation_options: options,
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}
