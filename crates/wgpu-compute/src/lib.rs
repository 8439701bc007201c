//! The `wgpu` silhouette backend: WGSL compute shaders, all objects and many lights per dispatch,
//! all four accuracy modes, and an exact mode that is bit-identical to the `cpu` backend.
//!
//! # How it works
//! * [`SilhouetteBackend::prepare`] uploads the scene's edge tables, every object concatenated
//!   with global ids, in their own form
//!   ([`TableBuffer`](shadowvol_silhouette::gpu::TableBuffer): positions, each edge's ends, CSR
//!   offsets, each opposite vertex as a reference `4 t + r` to its triangle `t`, the triangles in
//!   canonical vertex order, and each object's bases), written in chunks straight from the
//!   tables, with no host copy. A kernel finds an edge's or a triangle's object by binary search
//!   over the bases.
//! * [`SilhouetteBackend::extract`] uploads only the object-space lights (from
//!   [`shadowvol_silhouette::object_lights`], an `objects × lights` table) and runs
//!   `shaders/silhouette.wgsl` once for all objects and up to
//!   [`WgpuOptions::max_lights_per_batch`] lights, in two steps (the thesis' method): the
//!   `triangles` step evaluates one sign per (triangle, light) in the mode, then the `extract`
//!   step gives each edge, for every light, the sum of its opposite vertices' triangle signs
//!   times their parities (`original` skips the first step and evaluates each (edge, OV) pair
//!   naively: it is the baseline). The edge step writes the per-edge multiplicity and appends
//!   `(edge, m)` to the light's compact silhouette list with an atomic counter. The list lengths
//!   and an adaptive prefix of every list come back in the same submission (one round trip);
//!   longer lists, and with [`WgpuOptions::full_readback`] the whole multiplicity buffer, in a
//!   second. The device buffers stay available through [`WgpuBackend::gpu_results`]. The
//!   renderer's GPU-resident pass appends its kernels to the same module and calls the same
//!   functions (`triangle_sign_traced`, `edge_multiplicity`); this backend is the readback
//!   variant of that code.
//! * `original`, `robust`, `ordered` evaluate robust-math's `sign_f32` expression operation for
//!   operation with the canonical-order and parity rules. WGSL cannot forbid FMA contraction, so
//!   these modes may differ from the CPU in rare last-bit cases; `robust` and `ordered` stay
//!   consistent (closed chains) either way, because each triangle is evaluated once, in one
//!   order, for all its edges.
//! * `exact` runs a certified filter on the device: `f64` when the device has `SHADER_F64`
//!   (bound [`shadowvol_gpu::shaders::GPU_F64_FILTER_EPS`] = 8 × robust-math's `F64_FILTER_EPS`, margin for
//!   contraction), else robust-math's `f32` filter (`F32_FILTER_EPS`, its range checks, `w` in
//!   {0, 1} only) plus
//!   two device guards ([`shadowvol_gpu::shaders::GPU_F32_INPUT_MAX`], [`shadowvol_gpu::shaders::GPU_F32_PERM_MIN`]).
//!   Subnormal inputs are never certified. By default
//!   ([`WgpuOptions::exact_on_device`]) the `(triangle, light)` pairs the filter cannot
//!   certify are decided on the device by `orient_int` (`shaders/exact_int.wgsl`): integer
//!   arithmetic on the
//!   `f32` bits, exact for every finite input, so nothing is resolved on the host and
//!   [`ExtractStats::uncertain`](shadowvol_silhouette::ExtractStats::uncertain) is 0. The
//!   triangle step appends those pairs to a list and a dispatch of their own
//!   ([`shadowvol_gpu::shaders::RESOLVE_ENTRY_POINT`]) decides them, since `orient_int` compiled into the
//!   triangle step slows every invocation; a batch whose pairs would not fit the largest list
//!   the device binds runs the triangle step with `orient_int` inline instead. With it
//!   off they go to an append buffer ([`UncertainTriangle`]); the host decides the three
//!   `(edge, OV, light)` triples of each with `orient_exact`, patches the values and lists (on
//!   the host and on the device) and counts the triples in `uncertain`.
//! * Timings: [`ExtractStats::upload`](shadowvol_silhouette::ExtractStats::upload) is the light/parameter upload (and any buffer
//!   (re)allocation), `compute` is submit-to-completion of the dispatch (with the copies of the
//!   counts and list prefixes), `readback` zeroing the host result, mapping and any second round
//!   trip, `host_resolve` the exact decisions, list sorting and the device patch.
//!
//! [`twin`] is a CPU port of the kernels with the same loop structure, for pinning down
//! failures in tests; the backend never calls it. The exact filter's precision is
//! [`ExactFilter`](shadowvol_silhouette::gpu::ExactFilter), as on the other GPU backends.
//!
//! ```no_run
//! // Needs a wgpu adapter (for example Mesa lavapipe: `apt install mesa-vulkan-drivers`).
//! use shadowvol_silhouette::{extract_once, Accuracy, SilhouetteBackend};
//! use shadowvol_test_support::corpus;
//!
//! let mut backend = shadowvol_wgpu_compute::create_backend()?;
//! println!("{}", backend.info().device);
//! let case = &corpus::cases()[0];
//! let scene = case.scene().expect("corpus scenes are valid");
//! let (m, stats) = extract_once(backend.as_mut(), &scene, &case.lights, Accuracy::Exact)?;
//! println!("silhouette of light 0: {:?}; uncertain: {}", m.silhouette(0), stats.uncertain);
//! # Ok::<(), shadowvol_silhouette::BackendError>(())
//! ```

mod backend;
mod device;
mod dispatch;
mod layout;
mod pipeline;
mod resolve;
pub mod twin;

pub use backend::{GpuResults, WgpuBackend};
pub use device::WgpuOptions;
pub use resolve::UncertainTriangle;

use shadowvol_silhouette::{BackendError, SilhouetteBackend};

/// The registry name of this backend.
pub const NAME: &str = "wgpu";

/// Starts the `wgpu` backend with default options ([`WgpuBackend::new`]).
///
/// # Errors
/// [`BackendError::Unavailable`] naming what is missing (no adapter: install a Vulkan driver such
/// as Mesa's lavapipe, `mesa-vulkan-drivers`), [`BackendError::Build`] if the shaders do not
/// compile on the device.
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Ok(Box::new(WgpuBackend::new(WgpuOptions::default())?))
}

/// Compiles the README's examples as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
