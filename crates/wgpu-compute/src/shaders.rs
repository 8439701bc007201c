//! The WGSL sources (from the workspace's `shaders/` folder) and how modules are composed.

use crate::twin::ExactFilter;

/// `shaders/silhouette.wgsl`: the kernel, complete with the `f32` exact filter.
pub const SILHOUETTE_WGSL: &str = include_str!("../../../shaders/silhouette.wgsl");

/// `shaders/exact_f64.wgsl`: the `f64` exact filter, appended for devices with `SHADER_F64`.
pub const EXACT_F64_WGSL: &str = include_str!("../../../shaders/exact_f64.wgsl");

/// Every WGSL file of this crate as `(file name, source)`; each is a valid module on its own.
pub const FILES: [(&str, &str); 2] = [
    ("silhouette.wgsl", SILHOUETTE_WGSL),
    ("exact_f64.wgsl", EXACT_F64_WGSL),
];

/// The edge step's entry point (every mode).
pub const ENTRY_POINT: &str = "extract";

/// The pipeline-overridable constant that selects the mode (0 original, 1 robust, 2 ordered,
/// 3 exact).
pub const MODE_CONSTANT: &str = "MODE";

/// The entry point of the triangle step (robust, ordered and exact modes), dispatched before
/// [`ENTRY_POINT`].
pub const TRIANGLE_ENTRY_POINT: &str = "triangles";

/// The entry point that decides, on the device, the `(triangle, light)` pairs a triangle step
/// built with [`DEFER_INT_CONSTANT`] appended to the uncertain list (exact mode with
/// [`WgpuOptions::exact_on_device`](crate::WgpuOptions::exact_on_device)), dispatched between
/// [`TRIANGLE_ENTRY_POINT`] and [`ENTRY_POINT`]. It loops over the list with a grid stride.
pub const RESOLVE_ENTRY_POINT: &str = "resolve_uncertain";

/// The pipeline-overridable constant (a `bool`, default `false`) that makes `edge_multiplicity`
/// skip triangles the triangle step marked as touching the light (the renderer's resident pass
/// sets it).
pub const TOUCH_SIGNS_CONSTANT: &str = "TOUCH_SIGNS";

/// Threads per workgroup (`WORKGROUP_SIZE` in the kernel).
pub const WORKGROUP_SIZE: u32 = 256;

const F32_CALL: &str = "return filter_f32(a, b, l, o); // @exact-filter";
const F64_CALL: &str = "return filter_f64(a, b, l, o); // @exact-filter";

/// The module source the backend compiles for `filter`: the kernel as is for
/// [`ExactFilter::F32`]; for [`ExactFilter::F64`], the kernel with its marked filter call
/// switched to `filter_f64` and `exact_f64.wgsl` appended.
///
/// # Panics
/// Panics if the marker line is missing from the kernel (a test checks that it is there once).
#[must_use]
pub fn module_source(filter: ExactFilter) -> String {
    match filter {
        ExactFilter::F32 => SILHOUETTE_WGSL.to_owned(),
        ExactFilter::F64 => {
            assert_eq!(
                SILHOUETTE_WGSL.matches(F32_CALL).count(),
                1,
                "shaders/silhouette.wgsl must contain the marked filter call exactly once"
            );
            let mut s = SILHOUETTE_WGSL.replace(F32_CALL, F64_CALL);
            s.push('\n');
            s.push_str(EXACT_F64_WGSL);
            s
        }
    }
}

const HOST_FALLBACK: &str = "return UNCERTAIN; // @exact-int";
/// Name of the override constant of `shaders/exact_int.wgsl` that leaves the integer fallback out
/// of a pipeline: with `DEFER_INT` true, `device_exact` returns `UNCERTAIN` and the compiler drops
/// `orient_int` from that pipeline (the GPU pipeline's triangle pass runs it in a dispatch of its
/// own, only for the pairs the filter leaves).
pub const DEFER_INT_CONSTANT: &str = "DEFER_INT";
const INT_FALLBACK: &str =
    "if DEFER_INT { return UNCERTAIN; } return orient_int(a, b, l, o); // @exact-int";

/// The module for `filter` as [`module_source`] builds it; with `device_exact`, the marked
/// fallback of `device_exact` switched to `orient_int` and `shaders/exact_int.wgsl` appended, so
/// exact mode decides every triple on the device and none goes to the host.
///
/// # Panics
/// Panics if a marker line is missing from the kernel (tests check that each is there once).
#[must_use]
pub fn module_source_with(filter: ExactFilter, device_exact: bool) -> String {
    let s = module_source(filter);
    if !device_exact {
        return s;
    }
    assert_eq!(
        s.matches(HOST_FALLBACK).count(),
        1,
        "shaders/silhouette.wgsl must contain the marked host fallback exactly once"
    );
    let mut s = s.replace(HOST_FALLBACK, INT_FALLBACK);
    s.push('\n');
    s.push_str(crate::exact_int::EXACT_INT_WGSL);
    s
}

/// The compute pipeline of `entry` in `module` under `layout`, with the pipeline-overridable
/// `constants` set. Workgroup memory is not zero-initialised: the kernels write their workgroup
/// variables before reading them.
#[must_use]
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            zero_initialize_workgroup_memory: false,
        },
        cache: None,
    })
}

/// The `MODE` value of an accuracy mode.
#[must_use]
pub fn mode_value(mode: shadowvol_robust_math::Accuracy) -> u32 {
    use shadowvol_robust_math::Accuracy;
    match mode {
        Accuracy::Original => 0,
        Accuracy::Robust => 1,
        Accuracy::Ordered => 2,
        Accuracy::Exact => 3,
    }
}
