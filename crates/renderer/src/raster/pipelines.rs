//! The descriptors every pipeline builds its layouts and render pipelines from (the host
//! pipeline's raster, the resident pass), over the render states of [`super::states`].

use super::states;

/// A buffer binding of a bind-group layout: storage, read-only or not.
pub(crate) fn storage(
    binding: u32,
    stages: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(
        binding,
        stages,
        wgpu::BufferBindingType::Storage { read_only },
        false,
    )
}

/// A buffer binding of a bind-group layout: uniform, with a dynamic offset or not.
pub(crate) fn uniform(
    binding: u32,
    stages: wgpu::ShaderStages,
    dynamic: bool,
) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, stages, wgpu::BufferBindingType::Uniform, dynamic)
}

fn buffer_entry(
    binding: u32,
    stages: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
    has_dynamic_offset: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A uniform buffer of `size` bytes that the host writes each frame.
pub(crate) fn uniform_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A bind-group layout of `entries`.
pub(crate) fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries,
    })
}

/// A pipeline layout of the bind groups `groups` (group `i` is `groups[i]`), no immediates.
pub(crate) fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().copied().map(Some).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

/// A colour target written whole, without blending or with `blend`.
pub(crate) fn color_target(
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// What the render pipelines of one pass share: the device, the pipeline layout, the shader
/// module of every stage and the depth-stencil format.
pub(crate) struct RenderPipelines<'a> {
    /// The device the pipelines are created on.
    pub(crate) device: &'a wgpu::Device,
    /// The layout of every pipeline.
    pub(crate) layout: &'a wgpu::PipelineLayout,
    /// The module of the vertex and fragment entry points.
    pub(crate) module: &'a wgpu::ShaderModule,
    /// The depth-stencil attachment's format.
    pub(crate) depth: wgpu::TextureFormat,
}

/// The vertex buffers a vertex entry point reads.
type Buffers<'b> = &'b [Option<wgpu::VertexBufferLayout<'b>>];

impl RenderPipelines<'_> {
    /// The depth pre-pass ([`states::prepass_depth`]): `vs` over `buffers`, `fs` into
    /// `targets`.
    pub(crate) fn prepass(
        &self,
        label: &str,
        vs: &str,
        buffers: Buffers<'_>,
        fs: &str,
        targets: &[Option<wgpu::ColorTargetState>],
    ) -> wgpu::RenderPipeline {
        let depth = states::prepass_depth(self.depth);
        self.surface(label, vs, buffers, depth, fs, targets)
    }

    /// A lit pass ([`states::lit_depth`]): `vs` over `buffers`, `fs_lit` added
    /// ([`states::additive`]) into one colour target of `color`.
    pub(crate) fn lit(
        &self,
        label: &str,
        vs: &str,
        buffers: Buffers<'_>,
        color: wgpu::TextureFormat,
    ) -> wgpu::RenderPipeline {
        let depth = states::lit_depth(self.depth);
        let targets = [color_target(color, Some(states::additive()))];
        self.surface(label, vs, buffers, depth, "fs_lit", &targets)
    }

    /// A shadow-volume draw ([`states::volume_depth`] with the stencil `faces`): `vs` over
    /// `buffers`, both faces drawn, `front_face` counted as front, no fragment stage; with
    /// `unclipped_depth`, depth clamp instead of depth clipping.
    pub(crate) fn volume(
        &self,
        label: &str,
        vs: &str,
        buffers: Buffers<'_>,
        unclipped_depth: bool,
        front_face: wgpu::FrontFace,
        faces: (wgpu::StencilFaceState, wgpu::StencilFaceState),
    ) -> wgpu::RenderPipeline {
        let primitive = wgpu::PrimitiveState {
            front_face,
            cull_mode: None,
            unclipped_depth,
            ..Default::default()
        };
        let depth = states::volume_depth(self.depth, faces);
        self.create(label, vs, buffers, primitive, depth, None)
    }

    /// A surface draw: `vs` over `buffers` with `depth`, `fs` into `targets`.
    pub(crate) fn surface(
        &self,
        label: &str,
        vs: &str,
        buffers: Buffers<'_>,
        depth: wgpu::DepthStencilState,
        fs: &str,
        targets: &[Option<wgpu::ColorTargetState>],
    ) -> wgpu::RenderPipeline {
        let fragment = wgpu::FragmentState {
            module: self.module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets,
        };
        let primitive = wgpu::PrimitiveState::default();
        self.create(label, vs, buffers, primitive, depth, Some(fragment))
    }

    /// A render pipeline of these shaders and layout, with `primitive`, `depth` and the optional
    /// `fragment` stage.
    pub(crate) fn create(
        &self,
        label: &str,
        vs: &str,
        buffers: Buffers<'_>,
        primitive: wgpu::PrimitiveState,
        depth: wgpu::DepthStencilState,
        fragment: Option<wgpu::FragmentState<'_>>,
    ) -> wgpu::RenderPipeline {
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(self.layout),
                vertex: wgpu::VertexState {
                    module: self.module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive,
                depth_stencil: Some(depth),
                multisample: wgpu::MultisampleState::default(),
                fragment,
                multiview_mask: None,
                cache: None,
            })
    }
}
