//! The compute pipelines: the composed WGSL module ([`shadowvol_gpu::shaders`]), the bind-group layout
//! shared by every step, one pipeline per mode for the edge step and the triangle step, and
//! exact mode's on-device resolution of what its filter leaves.

use crate::NAME;
use shadowvol_gpu::{shaders, ErrorScopes};
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::gpu::{mode_code, ExactFilter};
use shadowvol_silhouette::BackendError;
use std::sync::OnceLock;

/// The bind-group layout and the compute pipelines of every mode.
pub(crate) struct Pipelines {
    pub(crate) bind_group_layout: wgpu::BindGroupLayout,
    /// The steps for scenes of one object ([`shaders::SINGLE_OBJECT_CONSTANT`]).
    pub(crate) single_object: StepPipelines,
    /// The steps for scenes of several objects (each id's object found by search).
    pub(crate) objects: StepPipelines,
    /// With `exact_on_device`: what decides on the device the pairs the filter leaves.
    pub(crate) deferred: Option<DeferredExact>,
}

impl Pipelines {
    /// The steps for a scene of `object_count` objects.
    pub(crate) fn steps(&self, object_count: usize) -> &StepPipelines {
        if object_count <= 1 {
            &self.single_object
        } else {
            &self.objects
        }
    }
}

/// The edge and triangle steps of every mode, built with one set of constants.
pub(crate) struct StepPipelines {
    /// The edge step, per mode (indexed by [`mode_code`]); `original`'s reads the scene's OV
    /// vertex list ([`shaders::OV_VERTICES_CONSTANT`]).
    pub(crate) edges: Vec<wgpu::ComputePipeline>,
    /// `original`'s edge step for scenes without the list: each OV through its triangle.
    pub(crate) original_by_triangles: wgpu::ComputePipeline,
    /// The triangle step, per mode; `None` for `original`, which has none. With
    /// `exact_on_device`, exact mode's is built with `DEFER_INT` (see [`DeferredExact`]).
    pub(crate) triangles: Vec<Option<wgpu::ComputePipeline>>,
}

/// Exact mode's integer fallback in a dispatch of its own. Compiled into the triangle step,
/// `orient_int` slows every invocation, even where none reaches it; so exact mode's triangle
/// step appends what its filter leaves to the uncertain list, and `resolve` decides those pairs.
/// The triangle step with the fallback inline serves the batches whose list would not fit the
/// device's storage-binding limit; it is compiled on first need (rare, and on a CPU driver such
/// as lavapipe an `orient_int` pipeline takes tens of milliseconds to build).
pub(crate) struct DeferredExact {
    /// [`shaders::RESOLVE_ENTRY_POINT`], exact mode.
    pub(crate) resolve: wgpu::ComputePipeline,
    /// [`shaders::TRIANGLE_ENTRY_POINT`], exact mode, `orient_int` inline, once built.
    inline_triangles: OnceLock<wgpu::ComputePipeline>,
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
}

impl DeferredExact {
    /// The triangle step with `orient_int` inline, built on the first call.
    ///
    /// # Errors
    /// [`BackendError::Build`] with the captured errors when the pipeline fails.
    pub(crate) fn inline_triangles(
        &self,
        device: &wgpu::Device,
    ) -> Result<&wgpu::ComputePipeline, BackendError> {
        if let Some(p) = self.inline_triangles.get() {
            return Ok(p);
        }
        let scope = ErrorScopes::push(device);
        let built = build(
            device,
            &self.layout,
            &self.module,
            shaders::TRIANGLE_ENTRY_POINT,
            Accuracy::Exact,
            Some(false),
        );
        if let Some(e) = scope.pop() {
            return Err(BackendError::Build {
                backend: NAME,
                what: "shaders/silhouette.wgsl (exact triangle step, integer fallback inline)"
                    .to_string(),
                log: e,
            });
        }
        Ok(self.inline_triangles.get_or_init(|| built))
    }
}

/// One pipeline of the module: `entry` in `mode`, with `DEFER_INT` set where the module has it
/// (`defer_int` is `None` for the module without the device fallback, which has no such
/// constant).
fn build(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    mode: Accuracy,
    defer_int: Option<bool>,
) -> wgpu::ComputePipeline {
    build_with(device, layout, module, (entry, mode, defer_int), &[])
}

/// [`build`] with further pipeline-overridable `constants`.
fn build_with(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (entry, mode, defer_int): (&str, Accuracy, Option<bool>),
    more: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let mut constants = vec![(shaders::MODE_CONSTANT, f64::from(mode_code(mode)))];
    constants.extend_from_slice(more);
    if let Some(defer) = defer_int {
        constants.push((shaders::DEFER_INT_CONSTANT, f64::from(u8::from(defer))));
    }
    shaders::compute_pipeline(device, mode.name(), layout, module, entry, &constants)
}

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
    let pipeline = |entry: &str, mode: Accuracy, defer_int: bool| {
        let defer_int = exact_on_device.then_some(defer_int);
        build(device, &pipeline_layout, &module, entry, mode, defer_int)
    };
    let steps = |single_object: bool| {
        let single = (
            shaders::SINGLE_OBJECT_CONSTANT,
            f64::from(u8::from(single_object)),
        );
        let build = |entry: &str, mode: Accuracy, defer_int: bool, ov_vertices: bool| {
            let key = (entry, mode, exact_on_device.then_some(defer_int));
            let ov = (
                shaders::OV_VERTICES_CONSTANT,
                f64::from(u8::from(ov_vertices)),
            );
            build_with(device, &pipeline_layout, &module, key, &[single, ov])
        };
        StepPipelines {
            edges: Accuracy::ALL
                .iter()
                .map(|&mode| build(shaders::ENTRY_POINT, mode, false, true))
                .collect(),
            original_by_triangles: build(shaders::ENTRY_POINT, Accuracy::Original, false, false),
            triangles: Accuracy::ALL
                .iter()
                .map(|&mode| {
                    (mode != Accuracy::Original).then(|| {
                        let defer = exact_on_device && mode == Accuracy::Exact;
                        build(shaders::TRIANGLE_ENTRY_POINT, mode, defer, false)
                    })
                })
                .collect(),
        }
    };
    let single_object = steps(true);
    let objects = steps(false);
    let resolve =
        exact_on_device.then(|| pipeline(shaders::RESOLVE_ENTRY_POINT, Accuracy::Exact, false));
    if let Some(e) = scope.pop() {
        return Err(BackendError::Build {
            backend: NAME,
            what: format!("shaders/silhouette.wgsl ({} exact filter)", filter.name()),
            log: e,
        });
    }
    Ok(Pipelines {
        bind_group_layout,
        single_object,
        objects,
        deferred: resolve.map(|resolve| DeferredExact {
            resolve,
            inline_triangles: OnceLock::new(),
            module,
            layout: pipeline_layout,
        }),
    })
}

/// Group 0 of `shaders/silhouette.wgsl`: the params (0), the packed tables (1) and their
/// offsets (2), lights (4), multiplicities (5), counters (6), compact lists (7), uncertain pairs
/// (8) and signs (11): 7 storage buffers, within `wgpu::Limits::default()`'s 8.
fn bind_group_layout_entries() -> [wgpu::BindGroupLayoutEntry; 9] {
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
    let uniform = |binding: u32, size: u64| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size),
        },
        count: None,
    };
    [
        uniform(0, 32),
        storage(1, true),
        uniform(2, shadowvol_gpu::TableOffsets::BYTES),
        storage(4, true),
        storage(5, false),
        storage(6, false),
        storage(7, false),
        storage(8, false),
        storage(11, false),
    ]
}
