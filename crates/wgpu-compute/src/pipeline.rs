//! The compute pipelines: the composed WGSL module ([`crate::shaders`]), the bind-group layout
//! shared by both steps, and one pipeline per mode for the edge step and the triangle step.

use crate::device::ErrorScopes;
use crate::twin::ExactFilter;
use crate::{shaders, NAME};
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::BackendError;

/// The bind-group layout, the edge-step pipelines per mode ([`shaders::mode_value`]) and the
/// triangle-step pipelines per mode (`None` for `original`, which has no triangle step).
pub(crate) type Pipelines = (
    wgpu::BindGroupLayout,
    Vec<wgpu::ComputePipeline>,
    Vec<Option<wgpu::ComputePipeline>>,
);

/// Compiles the module for `filter` (with the on-device exact fallback when `exact_on_device`)
/// and builds the bind-group layout and the pipelines of every mode.
///
/// # Errors
/// [`BackendError::Build`] with the captured errors when a shader or pipeline fails.
pub(crate) fn create_pipelines(
    device: &wgpu::Device,
    filter: ExactFilter,
    exact_on_device: bool,
) -> Result<Pipelines, BackendError> {
    let source = shaders::module_source_with(filter, exact_on_device);
    let scope = ErrorScopes::push(device);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shaders/silhouette.wgsl"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("silhouette bindings"),
        entries: &bind_group_layout_entries(),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("silhouette"),
        bind_group_layouts: &[Some(&bind_group_layout)],
        immediate_size: 0,
    });
    let pipeline = |entry: &str, mode: Accuracy| {
        let constants = [(shaders::MODE_CONSTANT, f64::from(shaders::mode_value(mode)))];
        shaders::compute_pipeline(
            device,
            mode.name(),
            &pipeline_layout,
            &module,
            entry,
            &constants,
        )
    };
    let pipelines = Accuracy::ALL
        .iter()
        .map(|&mode| pipeline(shaders::ENTRY_POINT, mode))
        .collect();
    let triangle_pipelines = Accuracy::ALL
        .iter()
        .map(|&mode| {
            (mode != Accuracy::Original).then(|| pipeline(shaders::TRIANGLE_ENTRY_POINT, mode))
        })
        .collect();
    if let Some(e) = scope.pop() {
        return Err(BackendError::Build {
            backend: NAME,
            what: format!("shaders/silhouette.wgsl ({} exact filter)", filter.name()),
            log: e,
        });
    }
    Ok((bind_group_layout, pipelines, triangle_pipelines))
}

pub(crate) fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// Storage buffers the kernels bind in one stage.
pub(crate) const STORAGE_BUFFERS: u32 = 11;

fn bind_group_layout_entries() -> [wgpu::BindGroupLayoutEntry; 12] {
    let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    [
        wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(16),
            },
            count: None,
        },
        storage(1, true),
        storage(2, true),
        storage(3, true),
        storage(4, true),
        storage(5, false),
        storage(6, false),
        storage(7, false),
        storage(8, false),
        storage(9, true),
        storage(10, true),
        storage(11, false),
    ]
}
