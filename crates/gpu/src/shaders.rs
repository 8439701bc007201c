//! The WGSL sources (from the workspace's `shaders/` folder), their constants, and how modules
//! are composed.

use shadowvol_robust_math::F64_FILTER_EPS;
use shadowvol_silhouette::gpu::ExactFilter;

/// `shaders/silhouette.wgsl`: the kernel, complete with the `f32` exact filter.
pub const SILHOUETTE_WGSL: &str = include_str!("../../../shaders/silhouette.wgsl");

/// `shaders/exact_f64.wgsl`: the `f64` exact filter, appended for devices with `SHADER_F64`.
pub const EXACT_F64_WGSL: &str = include_str!("../../../shaders/exact_f64.wgsl");

/// `shaders/exact_int.wgsl`: a standalone module (no bindings, no entry point) whose public
/// function is `fn orient_int(a: vec3<f32>, b: vec3<f32>, l: vec4<f32>, o: vec3<f32>) -> i32`,
/// the exact sign `-1`, `0` or `+1` with integer arithmetic only; its helpers are prefixed
/// `xi_`, its constants `XI_`, so it can be concatenated with other modules.
/// [`module_source_with`] appends it for exact mode on the device.
pub const EXACT_INT_WGSL: &str = include_str!("../../../shaders/exact_int.wgsl");

/// Relative bound of the device's `f64` filter: 8 × robust-math's [`F64_FILTER_EPS`].
///
/// `F64_FILTER_EPS` (1e-15) covers the `9u` of the straight evaluation. WGSL cannot forbid FMA
/// contraction or reassociation; both remove roundings without adding any, so the straight
/// bound still holds, and the factor 8 is margin for them (and for drivers). A larger bound only
/// sends more near-degenerate triples to the exact fallback. Must equal `GPU_F64_FILTER_EPS` in
/// `shaders/exact_f64.wgsl` (a test checks it).
pub const GPU_F64_FILTER_EPS: f64 = 8.0 * F64_FILTER_EPS;

/// Largest input magnitude (positions and light components) the device's `f32` filter accepts:
/// 2^39, so that no difference or product overflows before the range checks (WGSL leaves the
/// result of an overflowing operation indeterminate). WGSL `F32_INPUT_MAX_BITS` holds its bits.
pub const GPU_F32_INPUT_MAX: f32 = 549_755_813_888.0; // 2^39

/// Smallest non-zero permanent the device's `f32` filter certifies: 2^-60. A device may flush
/// subnormal intermediates to zero (only the terms `(p - q) * d` can become subnormal under the
/// range checks); each flush moves `det` by less than 2^-126, far below `F32_FILTER_EPS × 2^-60`.
/// WGSL `F32_PERM_MIN`.
pub const GPU_F32_PERM_MIN: f32 = 1.0 / 1_152_921_504_606_846_976.0; // 2^-60

/// The sign value of a triangle the renderer's resident pass marks as touching the light (a
/// vertex exactly at the point light): it has no volume, and with [`TOUCH_SIGNS_CONSTANT`] set
/// `edge_multiplicity` skips it. WGSL `TOUCH`.
pub const TOUCH: i32 = 2;

/// The edge step's entry point (every mode).
pub const ENTRY_POINT: &str = "extract";

/// The pipeline-overridable constant that selects the mode: the mode's
/// [`mode_code`](shadowvol_silhouette::gpu::mode_code).
pub const MODE_CONSTANT: &str = "MODE";

/// The entry point of the triangle step (robust, ordered and exact modes), dispatched before
/// [`ENTRY_POINT`].
pub const TRIANGLE_ENTRY_POINT: &str = "triangles";

/// The entry point that decides, on the device, the `(triangle, light)` pairs a triangle step
/// built with [`DEFER_INT_CONSTANT`] appended to the uncertain list (exact mode with
/// `WgpuOptions::exact_on_device` of the `wgpu` backend), dispatched between
/// [`TRIANGLE_ENTRY_POINT`] and [`ENTRY_POINT`]. It loops over the list with a grid stride.
pub const RESOLVE_ENTRY_POINT: &str = "resolve_uncertain";

/// The pipeline-overridable constant (a `bool`, default `false`) that makes `edge_multiplicity`
/// skip triangles the triangle step marked as touching the light (the renderer's resident pass
/// sets it).
pub const TOUCH_SIGNS_CONSTANT: &str = "TOUCH_SIGNS";

/// The pipeline-overridable constant (a `bool`, default `false`) that makes `original`'s edge
/// step read each OV from the scene's OV vertex list (a table of the packed buffer) instead of
/// through its triangle; the backend sets it for scenes that have the list.
pub const OV_VERTICES_CONSTANT: &str = "OV_VERTICES";

/// The pipeline-overridable constant (a `bool`, default `false`) that makes the kernels' object
/// search return object 0 at compile time; the backend builds a set of pipelines with it for
/// scenes of one object.
pub const SINGLE_OBJECT_CONSTANT: &str = "SINGLE_OBJECT";

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
        ExactFilter::F64 => splice(SILHOUETTE_WGSL, (F32_CALL, F64_CALL), EXACT_F64_WGSL),
    }
}

/// `src` with its one `marker` line replaced by `with`, then `append` after it.
///
/// # Panics
/// If `src` does not contain `marker` exactly once.
fn splice(src: &str, (marker, with): (&str, &str), append: &str) -> String {
    assert_eq!(
        src.matches(marker).count(),
        1,
        "shaders/silhouette.wgsl must contain the line `{marker}` exactly once"
    );
    let mut s = src.replace(marker, with);
    s.push('\n');
    s.push_str(append);
    s
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
    splice(&s, (HOST_FALLBACK, INT_FALLBACK), EXACT_INT_WGSL)
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
