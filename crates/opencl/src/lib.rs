//! The `opencl` silhouette backend: OpenCL C kernels from `kernels/silhouette.cl`, built at run
//! time for the selected device with `opencl3`.
//!
//! * **One enqueue per extraction.** Every object of a prepared scene and every light go into a
//!   single 2-D NDRange (edges × lights). Each edge carries its object index, and the lights are
//!   uploaded per (object, light) in object space, computed by
//!   [`shadowvol_silhouette::object_lights`] so that every backend sees the same `f32` inputs.
//!   There is no per-object synchronisation.
//! * **Many lights.** When the per-light buffers of all lights would exceed the device's largest
//!   allocation or the kernel's 32-bit indices (or [`OpenClOptions::max_lights_per_batch`] is
//!   set), the lights are split into batches of one launch each, with the same result as one
//!   launch; only a scene where one light alone does not fit is a [`BackendError::Limit`].
//! * **Uploaded once.** Positions, edges, OV lists and offsets are uploaded at `prepare`; an
//!   `extract` uploads only the lights (and zeroes the counters).
//! * **Compact output.** The kernel appends `(light * edges + edge, m)` for each silhouette edge
//!   of every light to one list with an atomic counter; only that list (one read, whatever the
//!   number of lights) is read back, scattered and split per light on the host.
//! * **All four modes.** `original`, `robust` and `ordered` evaluate robust-math's `sign_f32`
//!   expression exactly as written (`#pragma OPENCL FP_CONTRACT OFF`), with the canonical order
//!   and parity rules. `exact` runs a certified filter on the device (the `f64` filter of
//!   `orient_filter_f64` when the device has `cl_khr_fp64`, otherwise the `f32` filter of
//!   `orient_filter_f32`); the (edge, OV, light) triples it cannot certify are appended to a
//!   buffer and decided on the host with `orient_exact`, so exact results are bit-identical to the
//!   `cpu` backend. [`ExtractStats::uncertain`] counts them.
//! * **A CPU twin.** [`twin`] is the kernel's logic in Rust, loop for loop, run through the same
//!   layout and host code.
//! * **Bounded waits.** Nothing waits for the device without a limit (no `clFinish`, no blocking
//!   reads or writes): every command is enqueued non-blocking and its event waited for within
//!   [`shadowvol_silhouette::gpu::wait_limit`] (`SHADOWVOL_GPU_TIMEOUT` seconds, default 600; read
//!   at every `extract`), woken by a completion callback and checked by status reads between.
//!   A command that fails is a [`BackendError::Device`] naming it and its decoded status; one
//!   that does not end in time is a `Device` error naming `SHADOWVOL_GPU_TIMEOUT`. The work that
//!   was still running is then *abandoned*: the host memory it uses stays with the backend, and
//!   the next `extract` first waits (within the limit again) for that work to end. If it has,
//!   the backend carries on as usual; if not, that `extract` is a `Device` error saying so.
//!   Dropping the backend never waits (see its `Drop`).
//!
//! # Device selection
//! The first GPU, otherwise the first CPU device, over all platforms in ICD order. The
//! environment variable [`DEVICE_ENV`] (`SHADOWVOL_OPENCL_DEVICE`) chooses explicitly: `P:D`
//! (platform and device indices, as `clinfo -l` lists them) or a case-insensitive substring of
//! `"platform name / device name type platform-version"` (so `pocl`, `cuda`, `gpu` work).
//! [`KERNEL_ENV`] (`SHADOWVOL_OPENCL_KERNEL`) loads the kernel source from a file instead of the
//! built-in copy.
//!
//! # Example
//! ```no_run
//! use shadowvol_opencl::OpenClBackend;
//! use shadowvol_silhouette::{corpus, extract_once, Accuracy, SilhouetteBackend};
//!
//! let mut cl = OpenClBackend::new()?; // BackendError::Unavailable says what is missing
//! println!("{}", cl.info().device);
//! let case = &corpus::cases()[0];
//! let scene = case.scene().expect("corpus meshes are valid");
//! let (m, stats) = extract_once(&mut cl, &scene, &case.lights, Accuracy::Exact)?;
//! println!("{} silhouette edges, {} uncertain", m.silhouette(0).len(), stats.uncertain);
//! # Ok::<(), shadowvol_silhouette::BackendError>(())
//! ```

mod device;
pub mod layout;
pub mod twin;
mod wait;

pub use device::{list_devices, select_device, DeviceDesc, DEVICE_ENV};

use layout::{finish_batch, flat_light_batch, KernelOutput};
use opencl3::command_queue::CommandQueue;
use opencl3::context::Context;
use opencl3::device::Device;
use opencl3::error_codes::ClError;
use opencl3::event::Event;
use opencl3::kernel::Kernel;
use opencl3::memory::{Buffer, ClMem, CL_MEM_COPY_HOST_PTR, CL_MEM_READ_ONLY, CL_MEM_READ_WRITE};
use opencl3::program::Program;
use opencl3::types::{cl_mem_flags, CL_NON_BLOCKING};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::{self, describe_wait_limit, TIMEOUT_ENV};
use shadowvol_silhouette::gpu::{mode_code, SceneLayout, UncertainRecord};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, BackendInfo, ExtractStats, Multiplicities,
    PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::any::Any;
use std::mem::ManuallyDrop;
use std::num::NonZeroUsize;
use std::ops::Range;
use std::path::PathBuf;
use std::ptr;
use std::time::{Duration, Instant};

/// The backend's registry name.
pub const NAME: &str = "opencl";

/// The built-in kernel source (`kernels/silhouette.cl`, embedded at compile time).
pub const KERNEL_SOURCE: &str = include_str!("../../../kernels/silhouette.cl");

/// Name of the kernel entry point in the source.
pub const KERNEL_NAME: &str = "silhouette";

/// Environment variable: path of a `.cl` file to build instead of [`KERNEL_SOURCE`].
pub const KERNEL_ENV: &str = "SHADOWVOL_OPENCL_KERNEL";

/// Work-group width along the edge dimension (edges are padded to a multiple of it).
const GROUP: usize = 64;

/// Initial capacity of the uncertain-record buffer (records); it grows when a run needs more.
const INITIAL_UNCERTAIN_CAPACITY: usize = 4096;

/// Where the kernel source comes from.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum KernelSource {
    /// [`KERNEL_SOURCE`], embedded at compile time.
    #[default]
    Builtin,
    /// A file read when the backend starts.
    Path(PathBuf),
    /// Source text given directly (tests use it to check build-error reporting).
    Text(String),
}

/// How to start an [`OpenClBackend`].
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct OpenClOptions {
    /// Device selector in the [`DEVICE_ENV`] format; `None` picks the first GPU, else the first
    /// CPU device.
    pub device: Option<String>,
    /// The kernel source.
    pub kernel: KernelSource,
    /// Use the `f32` filter in exact mode even when the device has `cl_khr_fp64`.
    pub force_f32_filter: bool,
    /// At most this many lights per kernel launch. `None` (the default) lets only the device's
    /// limits split the lights (see [`OpenClBackend`]); a small value forces an `extract` into
    /// several launches, for tests. The result does not depend on it.
    pub max_lights_per_batch: Option<NonZeroUsize>,
}

impl OpenClOptions {
    /// Options from the environment: [`DEVICE_ENV`] for the device and [`KERNEL_ENV`] for the
    /// kernel path (both optional).
    #[must_use]
    pub fn from_env() -> Self {
        let non_empty = |v: String| (!v.trim().is_empty()).then_some(v);
        Self {
            device: std::env::var(DEVICE_ENV).ok().and_then(non_empty),
            kernel: std::env::var(KERNEL_ENV)
                .ok()
                .and_then(non_empty)
                .map_or(KernelSource::Builtin, |p| KernelSource::Path(p.into())),
            force_f32_filter: false,
            max_lights_per_batch: None,
        }
    }
}

/// Device buffers of one prepared scene.
struct Prepared {
    scene: TopologyScene,
    layout: SceneLayout,
    pos: Buffer<f32>,
    edges: Buffer<u32>,
    ovs: Buffer<u32>,
    /// Per-frame buffers, grown on demand: (buffer, capacity in elements).
    lights: Option<(Buffer<f32>, usize)>,
    counts: Option<(Buffer<u32>, usize)>,
    sil: Option<(Buffer<i32>, usize)>,
    unc: Option<(Buffer<u32>, usize)>,
    unc_records: usize,
}

/// Device work that a wait gave up on (it timed out or a command failed before the rest ended),
/// with the host memory its commands may still read or write.
struct Pending {
    /// The last command of the abandoned submission. The queue is in order, so once this has
    /// ended (finished or failed), nothing of the submission touches host memory any more.
    last: Event,
    /// What that command was, for messages.
    what: &'static str,
    /// Host memory the commands use (light data, read-back targets), kept alive until `last`
    /// has ended, and leaked by `Drop` if it never does.
    _host: Vec<Box<dyn Any + Send>>,
}

/// Static zeros for the counter reset: a non-blocking write reads them whenever it runs.
static ZEROS: [u32; 2] = [0; 2];

/// What one light batch of an `extract` came to.
enum Batch {
    /// Its rows of the result are filled.
    Done,
    /// Its uncertain records (exact mode) need more than the device's largest allocation; the
    /// batch has two or more lights and is to be split. Its rows are untouched.
    TooManyUncertain,
}

/// The OpenCL backend. See the crate documentation.
///
/// An `extract` runs one kernel launch per batch of lights: as many lights as fit the device's
/// largest allocation (`CL_DEVICE_MAX_MEM_ALLOC_SIZE`: the silhouette list takes 8 bytes per
/// edge and light, the light buffer 16 bytes per object and light) and the kernel's 32-bit
/// indices, and at most [`OpenClOptions::max_lights_per_batch`]. Usually that is all of them;
/// the result is the same however they are split.
pub struct OpenClBackend {
    device: DeviceDesc,
    use_f64: bool,
    kernel_origin: String,
    /// `CL_DEVICE_MAX_MEM_ALLOC_SIZE`, bytes.
    max_alloc: u64,
    max_lights_per_batch: Option<NonZeroUsize>,
    /// Light batches (kernel launches, not counting reruns after the uncertain-record buffer
    /// grew) of the last `extract`.
    last_batches: usize,
    /// Launch with a fixed work-group size of [`GROUP`] × 1.
    fixed_group: bool,
    // Released by `Drop` (scenes, kernel, program, queue, then the context), or leaked while
    // abandoned work has not ended.
    kernel: ManuallyDrop<Kernel>,
    program: ManuallyDrop<Program>,
    queue: ManuallyDrop<CommandQueue>,
    context: ManuallyDrop<Context>,
    scenes: ManuallyDrop<PreparedScenes<Prepared>>,
    /// Work abandoned by a wait that gave up; the next `extract` waits for it first.
    pending: Option<Pending>,
}

impl Drop for OpenClBackend {
    /// Never waits for the device. When abandoned work has still not ended, everything it may
    /// use is leaked rather than released: the host memory it may read or write, and the
    /// buffers, kernel, program, queue and context (OpenCL would keep them alive until the work
    /// ends anyway, but a driver may block in a release while a kernel hangs). Otherwise they
    /// are released as usual.
    fn drop(&mut self) {
        if let Some(p) = self.pending.take() {
            if !wait::has_ended(&p.last) {
                std::mem::forget(p);
                return;
            }
        }
        // SAFETY: each field is dropped once, here, and not used afterwards.
        unsafe {
            ManuallyDrop::drop(&mut self.scenes);
            ManuallyDrop::drop(&mut self.kernel);
            ManuallyDrop::drop(&mut self.program);
            ManuallyDrop::drop(&mut self.queue);
            ManuallyDrop::drop(&mut self.context);
        }
    }
}

impl std::fmt::Debug for OpenClBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenClBackend")
            .field("device", &self.device.describe())
            .field("exact_filter", &if self.use_f64 { "f64" } else { "f32" })
            .field("kernel", &self.kernel_origin)
            .field("scenes", &self.scenes.len())
            .finish_non_exhaustive()
    }
}

fn device_error(what: &str, e: ClError) -> BackendError {
    BackendError::Device {
        backend: NAME,
        message: format!("{what}: {e} ({})", e.0),
    }
}

/// Starts the `opencl` backend with [`OpenClOptions::from_env`].
///
/// # Errors
/// [`BackendError::Unavailable`] naming what is missing (the ICD loader `libOpenCL.so.1`, a
/// platform, a device, or a device matching [`DEVICE_ENV`]); [`BackendError::Build`] with the
/// compiler's log if the kernel does not build; otherwise as [`OpenClBackend::with_options`].
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Ok(Box::new(OpenClBackend::with_options(
        OpenClOptions::from_env(),
    )?))
}

/// Creates a buffer holding a copy of `data` (at least one element: OpenCL has no empty buffers).
fn upload<T: Copy + Default>(
    context: &Context,
    flags: cl_mem_flags,
    data: &[T],
    what: &str,
) -> Result<Buffer<T>, BackendError> {
    let one = [T::default()];
    let data = if data.is_empty() { &one[..] } else { data };
    // SAFETY: `data` is valid for `data.len()` elements; COPY_HOST_PTR copies it before return.
    unsafe {
        Buffer::<T>::create(
            context,
            flags | CL_MEM_COPY_HOST_PTR,
            data.len(),
            data.as_ptr().cast_mut().cast(),
        )
    }
    .map_err(|e| device_error(&format!("uploading {what} ({} elements)", data.len()), e))
}

/// Makes sure `slot` holds a read-write buffer of at least `len` elements.
fn ensure<T>(
    context: &Context,
    slot: &mut Option<(Buffer<T>, usize)>,
    len: usize,
    what: &str,
) -> Result<(), BackendError> {
    let len = len.max(1);
    if slot.as_ref().is_some_and(|(_, cap)| *cap >= len) {
        return Ok(());
    }
    // SAFETY: no host pointer; the buffer is written by the device or by enqueued writes.
    let buf = unsafe { Buffer::<T>::create(context, CL_MEM_READ_WRITE, len, ptr::null_mut()) }
        .map_err(|e| device_error(&format!("allocating {what} ({len} elements)"), e))?;
    *slot = Some((buf, len));
    Ok(())
}

/// Builds `source` for `device` and returns the program, or [`BackendError::Build`] with the
/// compiler's log.
fn build_program(
    context: &Context,
    device: &DeviceDesc,
    source: &str,
    options: &str,
    origin: &str,
) -> Result<Program, BackendError> {
    let mut program =
        Program::create_from_source(context, source).map_err(|e| BackendError::Build {
            backend: NAME,
            what: origin.to_owned(),
            log: format!("clCreateProgramWithSource failed: {e} ({})", e.0),
        })?;
    if let Err(e) = program.build(&[device.id], options) {
        let log = program
            .get_build_log(device.id)
            .unwrap_or_else(|le| format!("(no build log: {le})"));
        return Err(BackendError::Build {
            backend: NAME,
            what: format!(
                "{origin} (options {options:?}, device {})",
                device.device_name
            ),
            log: format!("clBuildProgram failed: {e} ({})\n{}", e.0, log.trim_end()),
        });
    }
    Ok(program)
}

impl OpenClBackend {
    /// Starts the backend on the default device (first GPU, else first CPU) with the built-in
    /// kernel, ignoring the environment.
    ///
    /// # Errors
    /// As [`OpenClBackend::with_options`].
    pub fn new() -> Result<Self, BackendError> {
        Self::with_options(OpenClOptions::default())
    }

    /// Starts the backend: finds the device, creates a context and queue, builds the kernel and
    /// runs it once on a tetrahedron (a self-test, waited for within
    /// [`shadowvol_silhouette::gpu::wait_limit`]).
    ///
    /// # Errors
    /// [`BackendError::Unavailable`] when there is no ICD loader, platform or (matching) device,
    /// or the kernel file cannot be read; [`BackendError::Build`] with the compiler's log when
    /// the kernel does not build; [`BackendError::Device`] when the driver fails or the self-test
    /// does not finish within the limit; [`BackendError::InvalidInput`] when
    /// `SHADOWVOL_GPU_TIMEOUT` is set but is not a positive number of seconds.
    pub fn with_options(options: OpenClOptions) -> Result<Self, BackendError> {
        // Some drivers (PoCL 3.1) crash when threads enumerate and initialise devices at once.
        let _guard = device::INIT_LOCK
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let devices = device::list_devices_locked()?;
        let device = select_device(&devices, options.device.as_deref())?;
        let (source, origin) = match &options.kernel {
            KernelSource::Builtin => (
                KERNEL_SOURCE.to_owned(),
                "kernels/silhouette.cl (built in)".to_owned(),
            ),
            KernelSource::Path(p) => (
                std::fs::read_to_string(p).map_err(|e| BackendError::Unavailable {
                    backend: NAME,
                    reason: format!("cannot read kernel source {}: {e}", p.display()),
                })?,
                p.display().to_string(),
            ),
            KernelSource::Text(t) => (t.clone(), "kernel source text".to_owned()),
        };
        let dev = Device::new(device.id);
        let max_alloc = dev.max_mem_alloc_size().unwrap_or(128 << 20);
        let context = Context::from_device(&dev).map_err(|e| {
            device_error(&format!("creating a context on {}", device.describe()), e)
        })?;
        #[allow(deprecated)] // clCreateCommandQueue: also works on OpenCL 1.2 platforms.
        let queue = CommandQueue::create_default(&context, 0)
            .map_err(|e| device_error("creating a command queue", e))?;
        let use_f64 = device.fp64 && !options.force_f32_filter;
        let build_options = if use_f64 {
            "-DSHADOWVOL_EXACT_F64=1"
        } else {
            ""
        };
        let program = build_program(&context, &device, &source, build_options, &origin)?;
        let kernel = Kernel::create(&program, KERNEL_NAME).map_err(|e| BackendError::Build {
            backend: NAME,
            what: origin.clone(),
            log: format!("the program has no kernel {KERNEL_NAME:?}: {e} ({})", e.0),
        })?;
        // A fixed work-group size where the kernel allows it, so that the warm-up below compiles
        // the same variant that later runs use (PoCL compiles per work-group size at the first
        // enqueue; without the warm-up the first extract would report that as compute time).
        let fixed_group = Device::new(device.id)
            .max_work_group_size()
            .is_ok_and(|n| n >= GROUP)
            && kernel
                .get_work_group_size(device.id)
                .is_ok_and(|n| n >= GROUP);
        let mut backend = Self {
            device,
            use_f64,
            kernel_origin: origin,
            max_alloc,
            max_lights_per_batch: options.max_lights_per_batch,
            last_batches: 0,
            fixed_group,
            kernel: ManuallyDrop::new(kernel),
            program: ManuallyDrop::new(program),
            queue: ManuallyDrop::new(queue),
            context: ManuallyDrop::new(context),
            scenes: ManuallyDrop::new(PreparedScenes::new(NAME)),
            pending: None,
        };
        backend.warm_up()?;
        Ok(backend)
    }

    /// Runs the kernel once on a tetrahedron in exact mode and checks the result against the
    /// scalar definition: compiles the driver's work-group variant and proves the device works.
    fn warm_up(&mut self) -> Result<(), BackendError> {
        let mesh = shadowvol_mesh_topology::Mesh {
            positions: vec![
                glam::Vec3::ZERO,
                glam::Vec3::X,
                glam::Vec3::Y,
                glam::Vec3::Z,
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        };
        let table = shadowvol_mesh_topology::EdgeTable::build(&mesh)
            .map_err(|e| BackendError::InvalidInput(format!("warm-up mesh: {e}")))?;
        let light = Light::point(glam::Vec3::new(2.0, 3.0, 5.0));
        let mut want = vec![0i32; table.edges.len()];
        for (e, w) in want.iter_mut().enumerate() {
            let [a, b] = table.edges[e];
            *w = table
                .ovs_of(e)
                .iter()
                .map(|&o| {
                    i32::from(shadowvol_robust_math::ov_sign(
                        Accuracy::Exact,
                        &table.positions,
                        a,
                        b,
                        o,
                        light.to_array(),
                    ))
                })
                .sum();
        }
        let scene = TopologyScene::single(table);
        let id = self.prepare(&scene)?;
        let mut out = Multiplicities::default();
        let result = self.extract(id, &[light], Accuracy::Exact, &mut out);
        self.release(id);
        result?;
        if out.values(0) != want.as_slice() {
            return Err(BackendError::Device {
                backend: NAME,
                message: format!(
                    "self-test failed on {}: the kernel gave {:?} for a tetrahedron, expected {want:?}",
                    self.device.describe(),
                    out.values(0)
                ),
            });
        }
        Ok(())
    }

    /// How long a wait spins before it sleeps: [`wait::GPU_SPIN`], or nothing on a CPU device,
    /// whose worker threads need the cores (see the `wait` module).
    fn spin(&self) -> Duration {
        if self.device.device_type == "CPU" {
            Duration::ZERO
        } else {
            wait::GPU_SPIN
        }
    }

    /// The device in use.
    #[must_use]
    pub fn device(&self) -> &DeviceDesc {
        &self.device
    }

    /// True when exact mode filters in `f64` on the device, false for the `f32` filter.
    #[must_use]
    pub fn uses_f64_filter(&self) -> bool {
        self.use_f64
    }

    /// How many light batches (kernel launches, not counting reruns after the uncertain-record
    /// buffer grew) the last `extract` ran; for tests of the light splitting.
    #[doc(hidden)]
    #[must_use]
    pub fn batches_of_last_extract_for_tests(&self) -> usize {
        self.last_batches
    }

    /// Pretends the device's largest allocation is `bytes` from now on (checks and batch sizes
    /// only; nothing is allocated differently), so that tests can reach the device limits.
    #[doc(hidden)]
    pub fn set_max_alloc_for_tests(&mut self, bytes: u64) {
        self.max_alloc = bytes;
    }

    /// The most records the uncertain-record buffer (12 bytes each) may hold: the device's
    /// largest allocation, at least 1.
    fn max_uncertain_records(&self) -> usize {
        usize::try_from(self.max_alloc / (UncertainRecord::WORDS as u64 * 4))
            .unwrap_or(usize::MAX)
            .max(1)
    }

    /// Lights per kernel launch for a scene of `edges` edges (at least 1), `objects` objects
    /// and `ovs` opposite-vertex slots: as many as the silhouette list (8 bytes per edge and
    /// light) and the light buffer (16 bytes per object and light) allow within the device's
    /// largest allocation, with `light * edges + edge` and the uncertain-record counter (at most
    /// one per OV slot and light) within `u32`, and at most
    /// [`OpenClOptions::max_lights_per_batch`].
    ///
    /// # Errors
    /// [`BackendError::Limit`] with the numbers when not even one light fits.
    fn lights_per_batch(
        &self,
        edges: usize,
        objects: usize,
        ovs: usize,
    ) -> Result<usize, BackendError> {
        let sil = 8 * edges as u64;
        let light = 16 * objects as u64;
        let index = u64::from(u32::MAX);
        let n = shadowvol_silhouette::gpu::lights_per_batch(
            &[
                (self.max_alloc, sil),
                (self.max_alloc, light),
                (index, edges as u64),
                (index, ovs as u64),
            ],
            self.max_lights_per_batch,
        );
        if n == 0 {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "one light alone does not fit a kernel launch: its silhouette list needs \
                     {sil} bytes for {edges} edges and its light buffer {light} bytes for \
                     {objects} objects, but the device's largest allocation is {} bytes; split \
                     the scene",
                    self.max_alloc
                ),
            });
        }
        Ok(n)
    }

    fn check_alloc(&self, what: &str, bytes: usize, hint: &str) -> Result<(), BackendError> {
        if bytes as u64 > self.max_alloc {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "{what} needs {bytes} bytes, more than the device's largest allocation \
                     ({} bytes){hint}",
                    self.max_alloc
                ),
            });
        }
        Ok(())
    }

    /// Flushes the queue and waits for `events` in order (they were enqueued in this order on
    /// the in-order queue), all within `limit` from now, and returns the instant each was seen
    /// finished. `enqueued` is the result of enqueueing them: after a failed enqueue the commands
    /// already enqueued are waited for all the same and the enqueue error is returned.
    ///
    /// On any error, if the last command has not ended, `host` is called to take the host memory
    /// the commands use, which is kept in [`OpenClBackend::pending`] until the command ends.
    /// `events` is left empty.
    ///
    /// # Errors
    /// [`BackendError::Device`]: a failed flush, a command that ended with an error (decoded),
    /// a status query that failed, or a deadline that passed (naming [`TIMEOUT_ENV`]).
    fn wait_for(
        &mut self,
        events: &mut Vec<(&'static str, Event)>,
        enqueued: Result<(), BackendError>,
        limit: Duration,
        host: impl FnOnce() -> Vec<Box<dyn Any + Send>>,
    ) -> Result<Vec<Instant>, BackendError> {
        let waited = self.await_events(events, limit);
        let result = enqueued.and(waited);
        if result.is_err() {
            if let Some((what, last)) = events.pop() {
                if !wait::has_ended(&last) {
                    self.pending = Some(Pending {
                        last,
                        what,
                        _host: host(),
                    });
                }
            }
        }
        events.clear();
        result
    }

    /// The waiting part of [`OpenClBackend::wait_for`].
    fn await_events(
        &self,
        events: &[(&'static str, Event)],
        limit: Duration,
    ) -> Result<Vec<Instant>, BackendError> {
        if events.is_empty() {
            return Ok(Vec::new());
        }
        self.queue
            .flush()
            .map_err(|e| device_error("flushing the command queue", e))?;
        let deadline = wait::deadline_after(limit);
        let mut times = Vec::with_capacity(events.len());
        for (what, event) in events {
            match wait::wait(event, deadline, self.spin()) {
                wait::Outcome::Complete => times.push(Instant::now()),
                wait::Outcome::Failed(status) => {
                    return Err(BackendError::Device {
                        backend: NAME,
                        message: format!(
                            "{what} failed on the device with {} ({status})",
                            ClError(status)
                        ),
                    })
                }
                wait::Outcome::QueryFailed(e) => {
                    return Err(device_error(&format!("querying the status of {what}"), e))
                }
                wait::Outcome::TimedOut => {
                    return Err(BackendError::Device {
                        backend: NAME,
                        message: format!(
                            "the device did not finish {what} within {}; raise \
                             {TIMEOUT_ENV} for larger scenes or slower devices. The next extract on this backend first \
                             waits (as long again) for the unfinished work",
                            describe_wait_limit(limit),
                        ),
                    })
                }
            }
        }
        Ok(times)
    }

    /// Waits (within `limit`) for work abandoned by an earlier call, and frees the host memory
    /// it held once it has ended.
    ///
    /// # Errors
    /// [`BackendError::Device`] when it has still not ended, or its status cannot be read.
    fn settle(&mut self, limit: Duration) -> Result<(), BackendError> {
        let Some(p) = &self.pending else {
            return Ok(());
        };
        // Ignore a flush error here: the status query below reports the state either way.
        let _ = self.queue.flush();
        match wait::wait(&p.last, wait::deadline_after(limit), self.spin()) {
            // A failed command has ended too; if the device is broken, new work reports it.
            wait::Outcome::Complete | wait::Outcome::Failed(_) => {
                self.pending = None;
                Ok(())
            }
            wait::Outcome::QueryFailed(e) => Err(device_error(
                &format!(
                    "querying the status of {} left unfinished by an earlier extract",
                    p.what
                ),
                e,
            )),
            wait::Outcome::TimedOut => Err(BackendError::Device {
                backend: NAME,
                message: format!(
                    "the device has still not finished {} left by an earlier extract that timed \
                     out, within another {}; this backend runs no new work until it does",
                    p.what,
                    describe_wait_limit(limit)
                ),
            }),
        }
    }

    /// Writes the lights and zeroed counters, runs the kernel and reads the two counters into
    /// `counts`: three submissions, each waited for within `limit`. Returns their (upload,
    /// compute, readback) times.
    ///
    /// On an error, `flat_l` or `counts` may have been moved into [`OpenClBackend::pending`]
    /// (left empty): their memory stays with a command that had not ended.
    fn run_once(
        &mut self,
        id: PreparedId,
        flat_l: &mut Vec<f32>,
        counts: &mut Vec<u32>,
        num_lights: usize,
        mode: Accuracy,
        limit: Duration,
    ) -> Result<(Duration, Duration, Duration), BackendError> {
        let mut events = Vec::with_capacity(1);
        let t = Instant::now();
        let p = self.scenes.get_mut(id)?;
        let (lights_buf, _) = p.lights.as_mut().expect("ensured by extract");
        let (counts_buf, _) = p.counts.as_mut().expect("ensured by extract");
        // SAFETY: non-blocking writes into buffers at least that large, from `ZEROS` (static)
        // and `flat_l`, which `wait_for` keeps alive until the writes have ended (moving it into
        // `pending` if it stops waiting before that).
        let enqueued = unsafe {
            self.queue
                .enqueue_write_buffer(lights_buf, CL_NON_BLOCKING, 0, flat_l, &[])
                .map_err(|e| device_error("writing lights", e))
                .and_then(|e| {
                    events.push(("writing the lights", e));
                    self.queue
                        .enqueue_write_buffer(counts_buf, CL_NON_BLOCKING, 0, &ZEROS, &[])
                        .map_err(|e| device_error("zeroing counters", e))
                })
                .map(|e| events.push(("zeroing the counters", e)))
        };
        self.wait_for(&mut events, enqueued, limit, || {
            vec![Box::new(std::mem::take(flat_l))]
        })?;
        let upload = t.elapsed();

        let t = Instant::now();
        let p = self.scenes.get(id)?;
        // SAFETY: the kernel uses device buffers only, which `p` keeps alive.
        let enqueued = unsafe {
            enqueue_kernel(
                &self.queue,
                &self.kernel,
                self.fixed_group,
                p,
                num_lights,
                mode,
            )
        }
        .map(|e| events.push(("the silhouette kernel", e)));
        self.wait_for(&mut events, enqueued, limit, Vec::new)?;
        let compute = t.elapsed();

        let t = Instant::now();
        let p = self.scenes.get(id)?;
        let (counts_buf, _) = p.counts.as_ref().expect("ensured by extract");
        // SAFETY: a non-blocking read, no larger than the buffer, into `counts`, which
        // `wait_for` keeps alive and untouched until the read has ended (moving it into
        // `pending` if it stops waiting before that).
        let enqueued = unsafe {
            self.queue
                .enqueue_read_buffer(counts_buf, CL_NON_BLOCKING, 0, counts, &[])
                .map_err(|e| device_error("reading counters", e))
        }
        .map(|e| events.push(("reading the counters", e)));
        self.wait_for(&mut events, enqueued, limit, || {
            vec![Box::new(std::mem::take(counts))]
        })?;
        Ok((upload, compute, t.elapsed()))
    }
}

impl OpenClBackend {
    /// One kernel launch over the lights `batch` of `obj_lights` (rerun while the
    /// uncertain-record buffer grows): uploads their object-space lights, runs the kernel, reads
    /// back the silhouette list and uncertain records, and fills the batch's rows of `out`
    /// (already reset to the scene's edges and all lights), adding the times and the uncertain
    /// count to `stats`. Every wait is bounded by `limit`, as in [`OpenClBackend::run_once`].
    ///
    /// Returns [`Batch::TooManyUncertain`] instead when the batch has two or more lights and its
    /// uncertain records need more than the device's largest allocation.
    ///
    /// # Errors
    /// [`BackendError::Device`] when a command fails, a wait times out, or the output is
    /// malformed; [`BackendError::Limit`] when the uncertain records of a single light do not
    /// fit the device's largest allocation.
    #[allow(clippy::too_many_arguments)]
    fn extract_batch(
        &mut self,
        id: PreparedId,
        obj_lights: &[Vec<[f32; 4]>],
        batch: Range<usize>,
        mode: Accuracy,
        limit: Duration,
        out: &mut Multiplicities,
        stats: &mut ExtractStats,
    ) -> Result<Batch, BackendError> {
        let t = Instant::now();
        let num_lights = batch.len();
        let mut flat_l = flat_light_batch(obj_lights, batch.clone())?;
        let max_records = self.max_uncertain_records();
        let edges = {
            let ctx = &self.context;
            let p = self.scenes.get_mut(id)?;
            let edges = p.layout.edge_count();
            ensure(ctx, &mut p.lights, flat_l.len(), "the light buffer")?;
            ensure(ctx, &mut p.counts, 2, "the counters")?;
            ensure(
                ctx,
                &mut p.sil,
                2 * edges * num_lights,
                "the silhouette lists",
            )?;
            let initial = INITIAL_UNCERTAIN_CAPACITY.min(max_records);
            if mode == Accuracy::Exact && p.unc_records < initial {
                ensure(
                    ctx,
                    &mut p.unc,
                    UncertainRecord::WORDS * initial,
                    "the uncertain records",
                )?;
                p.unc_records = initial;
            } else if p.unc.is_none() {
                ensure(
                    ctx,
                    &mut p.unc,
                    UncertainRecord::WORDS,
                    "the uncertain records",
                )?;
                p.unc_records = 1;
            }
            edges
        };
        stats.upload += t.elapsed();
        let mut counts = vec![0u32; 2];
        loop {
            let (up, comp, read) =
                self.run_once(id, &mut flat_l, &mut counts, num_lights, mode, limit)?;
            stats.upload += up;
            stats.compute += comp;
            stats.readback += read;
            let p = self.scenes.get(id)?;
            let needed = counts[0] as usize;
            // (The buffer never exceeds the largest allocation; the `min` matters only when
            // tests lower the pretended limit after the buffer grew.)
            if needed <= p.unc_records.min(max_records) {
                break;
            }
            if needed > max_records {
                if num_lights > 1 {
                    return Ok(Batch::TooManyUncertain);
                }
                return Err(BackendError::Limit {
                    backend: NAME,
                    message: format!(
                        "exact mode left {needed} (edge, OV, light) records of light {} \
                         uncertain; they need {} bytes, more than the device's largest \
                         allocation ({} bytes); split the scene",
                        batch.start,
                        (needed * UncertainRecord::WORDS * 4) as u64,
                        self.max_alloc
                    ),
                });
            }
            // More uncertain records than the buffer holds: grow it and run again.
            let records = needed.next_power_of_two().min(max_records);
            let ctx = &self.context;
            let p = self.scenes.get_mut(id)?;
            ensure(
                ctx,
                &mut p.unc,
                UncertainRecord::WORDS * records,
                "the uncertain records",
            )?;
            p.unc_records = records;
        }
        let t = Instant::now();
        let p = self.scenes.get(id)?;
        // At most one entry per (edge, light): a larger count is a device fault, caught by
        // `finish_batch` when fewer entries than counted come back.
        let mut raw_sil = vec![0i32; 2 * (counts[1] as usize).min(edges * num_lights)];
        let mut raw_unc = vec![0u32; UncertainRecord::WORDS * counts[0] as usize];
        let mut events = Vec::with_capacity(2);
        let (sil_buf, _) = p.sil.as_ref().expect("ensured");
        let (unc_buf, _) = p.unc.as_ref().expect("ensured");
        // SAFETY: non-blocking reads into slices that `wait_for` keeps alive and untouched until
        // the reads have ended (moving them into `pending` when it stops waiting before that);
        // the lengths lie inside the buffers.
        let enqueued = unsafe {
            (|| {
                if !raw_sil.is_empty() {
                    events.push((
                        "reading the silhouette list",
                        self.queue
                            .enqueue_read_buffer(sil_buf, CL_NON_BLOCKING, 0, &mut raw_sil, &[])
                            .map_err(|e| device_error("reading the silhouette list", e))?,
                    ));
                }
                if !raw_unc.is_empty() {
                    events.push((
                        "reading the uncertain records",
                        self.queue
                            .enqueue_read_buffer(unc_buf, CL_NON_BLOCKING, 0, &mut raw_unc, &[])
                            .map_err(|e| device_error("reading uncertain records", e))?,
                    ));
                }
                Ok(())
            })()
        };
        self.wait_for(&mut events, enqueued, limit, || {
            vec![
                Box::new(std::mem::take(&mut raw_sil)),
                Box::new(std::mem::take(&mut raw_unc)),
            ]
        })?;
        stats.readback += t.elapsed();
        let t = Instant::now();
        let output = KernelOutput {
            silhouettes: raw_sil
                .chunks_exact(2)
                .map(|c| (c[0] as u32, c[1]))
                .collect(),
            uncertain: UncertainRecord::read_all(&raw_unc),
            counts,
        };
        stats.uncertain += output.uncertain.len() as u64;
        let p = self.scenes.get(id)?;
        finish_batch(&p.layout, obj_lights, batch, output, out, NAME)?;
        stats.host_resolve += t.elapsed();
        Ok(Batch::Done)
    }
}

/// Sets the kernel's arguments for prepared scene `p` and enqueues it over (edges × lights).
///
/// # Safety
/// The kernel must be [`KERNEL_NAME`] of [`KERNEL_SOURCE`] (or a source with the same
/// signature), and `p`'s buffers must stay alive until the kernel has ended (dropping them is
/// fine in OpenCL: a released buffer lives on until the commands using it have finished).
unsafe fn enqueue_kernel(
    queue: &CommandQueue,
    k: &Kernel,
    fixed_group: bool,
    p: &Prepared,
    num_lights: usize,
    mode: Accuracy,
) -> Result<Event, BackendError> {
    let edges = p.layout.edge_count();
    let set = |i: u32, r: Result<(), ClError>| {
        r.map_err(|e| device_error(&format!("setting kernel argument {i}"), e))
    };
    let (lights_buf, _) = p.lights.as_ref().expect("ensured by extract");
    let (counts_buf, _) = p.counts.as_ref().expect("ensured by extract");
    let (sil_buf, _) = p.sil.as_ref().expect("ensured by extract");
    let (unc_buf, _) = p.unc.as_ref().expect("ensured by extract");
    let (ne, nl, code, cap) = (
        edges as u32,
        num_lights as u32,
        mode_code(mode),
        p.unc_records as u32,
    );
    // SAFETY: argument types and order match `silhouette` in kernels/silhouette.cl.
    unsafe {
        set(0, k.set_arg(0, &p.pos.get()))?;
        set(1, k.set_arg(1, &p.edges.get()))?;
        set(2, k.set_arg(2, &p.ovs.get()))?;
        set(3, k.set_arg(3, &lights_buf.get()))?;
        set(4, k.set_arg(4, &ne))?;
        set(5, k.set_arg(5, &nl))?;
        set(6, k.set_arg(6, &code))?;
        set(7, k.set_arg(7, &counts_buf.get()))?;
        set(8, k.set_arg(8, &sil_buf.get()))?;
        set(9, k.set_arg(9, &unc_buf.get()))?;
        set(10, k.set_arg(10, &cap))?;
        let global = [edges.div_ceil(GROUP) * GROUP, num_lights];
        let local = [GROUP, 1];
        let local_ptr = if fixed_group {
            local.as_ptr()
        } else {
            ptr::null()
        };
        queue
            .enqueue_nd_range_kernel(k.get(), 2, ptr::null(), global.as_ptr(), local_ptr, &[])
            .map_err(|e| device_error("enqueueing the silhouette kernel", e))
    }
}

impl SilhouetteBackend for OpenClBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: NAME,
            device: self.device.describe(),
            modes: Accuracy::ALL.to_vec(),
            max_lights: None,
            details: vec![
                ("platform".to_owned(), self.device.platform_name.clone()),
                (
                    "platform_version".to_owned(),
                    self.device.platform_version.clone(),
                ),
                ("device_type".to_owned(), self.device.device_type.to_owned()),
                ("driver".to_owned(), self.device.driver_version.clone()),
                (
                    "exact_filter".to_owned(),
                    if self.use_f64 {
                        "f64 (cl_khr_fp64)"
                    } else {
                        "f32"
                    }
                    .to_owned(),
                ),
                ("kernel".to_owned(), self.kernel_origin.clone()),
            ],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        let layout = SceneLayout::build(scene, NAME)?;
        let edge_words = layout.edges.as_flattened();
        let hint = "; split the scene";
        self.check_alloc("the position buffer", layout.positions.len() * 4, hint)?;
        self.check_alloc("the edge buffer", edge_words.len() * 4, hint)?;
        self.check_alloc("the OV buffer", layout.ovs.len() * 4, hint)?;
        let ro = CL_MEM_READ_ONLY;
        let prepared = Prepared {
            pos: upload(&self.context, ro, &layout.positions, "positions")?,
            edges: upload(&self.context, ro, edge_words, "edges")?,
            ovs: upload(&self.context, ro, &layout.ovs, "opposite vertices")?,
            scene: scene.clone(),
            layout,
            lights: None,
            counts: None,
            sil: None,
            unc: None,
            unc_records: 0,
        };
        Ok(self.scenes.insert(prepared))
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        let limit = gpu::wait_limit()?;
        self.scenes.get(id)?;
        check_lights(lights)?;
        self.settle(limit)?;
        self.last_batches = 0;
        let p = self.scenes.get(id)?;
        let num_lights = lights.len();
        let edges = p.layout.edge_count();
        if edges == 0 {
            out.reset(0, num_lights);
            return Ok(ExtractStats::default());
        }
        let mut per_launch =
            self.lights_per_batch(edges, p.layout.object_count(), p.layout.ovs.len())?;
        // Per-frame host preparation (object-space lights) counts as upload.
        let prep_start = Instant::now();
        let obj_lights = object_lights(&p.scene, lights);
        out.reset(edges, num_lights);
        let mut stats = ExtractStats {
            upload: prep_start.elapsed(),
            ..ExtractStats::default()
        };
        let mut first = 0;
        while first < num_lights {
            let batch = first..(first + per_launch).min(num_lights);
            match self.extract_batch(
                id,
                &obj_lights,
                batch.clone(),
                mode,
                limit,
                out,
                &mut stats,
            )? {
                Batch::Done => {
                    first = batch.end;
                    self.last_batches += 1;
                }
                // Only returned for batches of two or more lights.
                Batch::TooManyUncertain => per_launch = batch.len() / 2,
            }
        }
        Ok(stats)
    }

    fn release(&mut self, id: PreparedId) {
        self.scenes.remove(id);
    }
}

/// Compiles the README's example as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
