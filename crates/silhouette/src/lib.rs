//! The interface every silhouette backend implements, and what all of them share.
//!
//! * [`SilhouetteBackend`]: `prepare` a [`TopologyScene`] once (upload, lay out), then `extract`
//!   per frame: the multiplicity of every edge for every light, in one call.
//! * [`Multiplicities`]: the per-edge, per-light result plus a compact silhouette list.
//! * [`invariant`]: the closed-chain check (`open_vertices`) and comparisons between results.
//! * [`gpu`]: what the GPU backends share (scene layout, mode codes, uncertain records and their
//!   exact resolution, wait limits, light batches).
//! * [`PreparedScenes`] and [`check_lights`]: the prepared-scene store and light-list check
//!   every backend shares.
//! * [`object_lights`]: the one place where world lights become object-space `f32` lights, so
//!   that every backend evaluates bit-identical inputs.
//!
//! ```
//! use shadowvol_silhouette::{TopologyScene, Multiplicities, invariant};
//! use shadowvol_mesh_topology::{EdgeTable, Mesh};
//! use glam::Vec3;
//!
//! let mesh = Mesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! ).unwrap();
//! let scene = TopologyScene::single(EdgeTable::build(&mesh).unwrap());
//! assert_eq!(scene.total_edges(), 6);
//! let m = Multiplicities::zeroed(scene.total_edges(), 1);
//! assert_eq!(invariant::open_vertices_scene(&scene, &m, 0), 0);
//! ```

pub mod gpu;
pub mod invariant;
mod multiplicities;
mod parts;
mod prepared;
mod scene;

pub use multiplicities::{ExtractStats, Multiplicities};
pub use parts::{PartsBackend, PartsEntry, SceneParts, WholeScene};
pub use prepared::{check_lights, PreparedScenes};
pub use scene::{object_light, object_lights, SceneObject, TopologyScene};
pub use shadowvol_mesh_topology::{unique_arc_bytes, vec_bytes};
pub use shadowvol_robust_math::{Accuracy, Light};

use std::time::Duration;

/// Identifies a scene prepared on a backend. Opaque: only [`PreparedScenes::insert`] (that is,
/// a backend's `prepare`) makes one, and an id is never reused by its backend.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PreparedId(u64);

/// What a backend is and what it can do.
#[derive(Debug, Clone, PartialEq)]
pub struct BackendInfo {
    /// Registry name: `cpu`, `simd`, `wgpu`, `opencl`, `vulkan`.
    pub name: &'static str,
    /// The device and driver, in words (for example `"llvmpipe (LLVM 15.0.6, 256 bits), Vulkan"`).
    pub device: String,
    /// The accuracy modes it supports (all four on every backend of this workspace).
    pub modes: Vec<Accuracy>,
    /// Largest number of lights per `extract` call, if limited.
    pub max_lights: Option<usize>,
    /// Free-form details worth recording next to results (SIMD level, f64 support, ...).
    pub details: Vec<(String, String)>,
}

/// What a prepared scene costs a backend, in bytes, beyond the scene's own edge tables (which
/// the caller holds and [`TopologyScene::table_bytes`] counts).
///
/// `host` is the backend's own layout of the scene in host memory (structure-of-arrays copies,
/// flattened records, work lists); `device` is the size of every device buffer the scene keeps
/// (inputs and the result buffers of the last `extract`). On lavapipe and PoCL device memory is
/// host memory, so both show in the process's resident set.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PreparedBytes {
    /// Bytes of host memory the backend keeps for the scene.
    pub host: u64,
    /// Bytes of device buffers the backend keeps for the scene.
    pub device: u64,
}

impl PreparedBytes {
    /// `host + device`.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.host + self.device
    }
}

/// Errors from a backend. Each names the backend and what is missing or went wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BackendError {
    /// The backend cannot start here: no driver, no device, a missing feature.
    #[error("{backend} backend unavailable: {reason}")]
    Unavailable {
        /// Backend name.
        backend: &'static str,
        /// What is missing, in words, with what to install where possible.
        reason: String,
    },
    /// The mode is not supported by this backend or device.
    #[error("{backend} backend does not support mode {mode}: {reason}")]
    UnsupportedMode {
        /// Backend name.
        backend: &'static str,
        /// The mode asked for.
        mode: Accuracy,
        /// Why.
        reason: String,
    },
    /// `extract` was called with an id that `prepare` did not return.
    #[error("{backend} backend: unknown prepared scene {id:?}")]
    UnknownScene {
        /// Backend name.
        backend: &'static str,
        /// The id given.
        id: PreparedId,
    },
    /// A shader or kernel failed to build; `log` is the compiler's output.
    #[error("{backend} backend: {what} failed to build:\n{log}")]
    Build {
        /// Backend name.
        backend: &'static str,
        /// What failed (file or entry point).
        what: String,
        /// The compiler's log.
        log: String,
    },
    /// The device failed at run time (device lost, out of memory, driver error).
    #[error("{backend} backend: device error: {message}")]
    Device {
        /// Backend name.
        backend: &'static str,
        /// The driver's message.
        message: String,
    },
    /// The scene or lights exceed a limit of the backend (buffer size, light count).
    #[error("{backend} backend: limit exceeded: {message}")]
    Limit {
        /// Backend name.
        backend: &'static str,
        /// Which limit, with the numbers.
        message: String,
    },
    /// The input is invalid (for example no lights).
    #[error("invalid input: {0}")]
    InvalidInput(String),
}

/// A silhouette-extraction backend.
///
/// Implementations keep uploaded scenes between calls. `extract` must produce, for each light `l`
/// and each global edge `e` (edges of all objects concatenated in object order), the
/// multiplicity `m(e)` under the convention of [`shadowvol_robust_math`], evaluated on the
/// object-space lights from [`object_lights`]. In [`Accuracy::Exact`] the result is
/// bit-identical on every backend.
pub trait SilhouetteBackend {
    /// Name, device and capabilities.
    fn info(&self) -> BackendInfo;

    /// Uploads a scene (all objects) once and returns its id.
    ///
    /// # Errors
    /// [`BackendError::Limit`] when it does not fit, [`BackendError::Device`] on driver failure.
    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError>;

    /// Computes multiplicities for all `lights` (world space) in one call, resizing `out` to
    /// `scene.total_edges()` × `lights.len()`, and fills its compact silhouette lists.
    ///
    /// # Errors
    /// * [`BackendError::UnknownScene`]: `id` was not returned by this backend's `prepare`, or
    ///   was released;
    /// * [`BackendError::InvalidInput`]: an empty light list, or a bad setting the call reads
    ///   (for example a malformed `SHADOWVOL_GPU_TIMEOUT`);
    /// * [`BackendError::UnsupportedMode`]: the device cannot run `mode`;
    /// * [`BackendError::Limit`]: even one light does not fit the device's buffers or indices
    ///   (more lights are split into batches, so only the size of one light's work counts);
    /// * [`BackendError::Device`]: a driver or device failure, a wait past
    ///   [`gpu::wait_limit`], or device output that cannot be right.
    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError>;

    /// What the prepared scene `id` holds beyond the scene's edge tables: the backend's host
    /// layout and its device buffers ([`PreparedBytes`]), in bytes.
    ///
    /// # Errors
    /// [`BackendError::UnknownScene`] when `id` was not returned by `prepare` or was released.
    fn prepared_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError>;

    /// Frees a prepared scene. The default does nothing.
    fn release(&mut self, id: PreparedId) {
        let _ = id;
    }
}

/// Convenience: prepare and extract once, returning the result and its statistics.
///
/// # Errors
/// Any error of [`SilhouetteBackend::prepare`] or [`SilhouetteBackend::extract`].
pub fn extract_once(
    backend: &mut dyn SilhouetteBackend,
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
) -> Result<(Multiplicities, ExtractStats), BackendError> {
    let id = backend.prepare(scene)?;
    let mut out = Multiplicities::default();
    let stats = backend.extract(id, lights, mode, &mut out)?;
    backend.release(id);
    Ok((out, stats))
}

/// Times a closure, returning its result and the elapsed wall time.
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let t = std::time::Instant::now();
    let r = f();
    (r, t.elapsed())
}

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
