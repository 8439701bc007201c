//! Starting the backend: finding OpenCL platforms and devices and choosing one, the start-up
//! options, and creating the context, queue and kernel, checked by a self-test run. Errors name
//! what is missing.

use crate::backend::OpenClBackend;
use crate::pipeline::{build_program, KernelSource, GROUP, KERNEL_ENV, KERNEL_NAME, KERNEL_SOURCE};
use crate::NAME;
use opencl3::command_queue::CommandQueue;
use opencl3::context::Context;
use opencl3::device::{
    Device, CL_DEVICE_TYPE_ACCELERATOR, CL_DEVICE_TYPE_ALL, CL_DEVICE_TYPE_CPU, CL_DEVICE_TYPE_GPU,
};
use opencl3::error_codes::{ClError, CL_PLATFORM_NOT_FOUND_KHR, DLOPEN_RUNTIME_LOAD_FAILED};
use opencl3::kernel::Kernel;
use opencl3::platform::get_platforms;
use opencl3::types::cl_device_id;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_silhouette::BackendError;
use shadowvol_silhouette::{Multiplicities, PreparedScenes, SilhouetteBackend, TopologyScene};
use std::mem::ManuallyDrop;
use std::num::NonZeroUsize;

/// The environment variable that selects the device explicitly.
///
/// Format: `P:D` (platform index `P`, device index `D` within that platform, both 0-based, as
/// listed by [`list_devices`] and `clinfo -l`), or any other text, matched case-insensitively as a
/// substring of [`DeviceDesc::match_text`], `"<platform name> / <device name> <type> <platform
/// version>"` (the first match wins), so `pocl`, `cuda`, `H100` or `gpu` all work.
pub const DEVICE_ENV: &str = "SHADOWVOL_OPENCL_DEVICE";

/// One OpenCL device, as found on this machine.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceDesc {
    /// Platform index (0-based, in ICD loader order).
    pub platform_index: usize,
    /// Device index within the platform (0-based).
    pub device_index: usize,
    /// Platform name (for example `"Portable Computing Language"`).
    pub platform_name: String,
    /// Platform version string (for example `"OpenCL 3.0 PoCL 3.1.0 ..."`).
    pub platform_version: String,
    /// Device name.
    pub device_name: String,
    /// `"GPU"`, `"CPU"`, `"accelerator"` or `"other"`.
    pub device_type: &'static str,
    /// Driver version string.
    pub driver_version: String,
    /// True when the device reports `cl_khr_fp64` (or a non-zero double config).
    pub fp64: bool,
    pub(crate) id: cl_device_id,
}

impl DeviceDesc {
    /// The text a name selector is matched against:
    /// `"<platform name> / <device name> <type> <platform version>"`.
    #[must_use]
    pub fn match_text(&self) -> String {
        format!(
            "{} / {} {} {}",
            self.platform_name, self.device_name, self.device_type, self.platform_version
        )
    }

    /// `"<platform> / <device> (<type>, <platform version>, driver <version>, P:D)"`: the text
    /// shown by `shadowvol backends`.
    #[must_use]
    pub fn describe(&self) -> String {
        // Platform versions can be long ("OpenCL 3.0 PoCL 3.1+debian  Linux, None+Asserts, ...");
        // keep the part before the first comma.
        let version = self.platform_version.split(',').next().unwrap_or_default();
        format!(
            "{} / {} ({}, {}, driver {}, device {}:{})",
            self.platform_name,
            self.device_name,
            self.device_type,
            version.split_whitespace().collect::<Vec<_>>().join(" "),
            self.driver_version,
            self.platform_index,
            self.device_index
        )
    }
}

fn unavailable(reason: String) -> BackendError {
    BackendError::Unavailable {
        backend: NAME,
        reason,
    }
}

fn cl_err(what: &str, e: ClError) -> BackendError {
    unavailable(format!("{what} failed: {e} ({})", e.0))
}

/// Lists every device of every OpenCL platform.
///
/// # Errors
/// [`BackendError::Unavailable`] when the ICD loader (`libOpenCL.so.1`) cannot be loaded, when
/// no platform is installed, or when no platform has a device; the message says what to install.
pub fn list_devices() -> Result<Vec<DeviceDesc>, BackendError> {
    let _guard = INIT_LOCK
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    list_devices_locked()
}

/// Serialises platform enumeration and backend start-up within the process: some drivers
/// (PoCL 3.1) are not thread-safe while they initialise their devices.
pub(crate) static INIT_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// [`list_devices`] for a caller that holds [`INIT_LOCK`].
pub(crate) fn list_devices_locked() -> Result<Vec<DeviceDesc>, BackendError> {
    let platforms = match get_platforms() {
        Ok(p) => p,
        Err(e) if e.0 == DLOPEN_RUNTIME_LOAD_FAILED => {
            return Err(unavailable(
                "no OpenCL ICD loader: libOpenCL.so.1 could not be loaded (install \
                 ocl-icd-libopencl1 and a driver such as pocl-opencl-icd, or point \
                 OPENCL_DYLIB_PATH at libOpenCL)"
                    .to_owned(),
            ))
        }
        Err(e) if e.0 == CL_PLATFORM_NOT_FOUND_KHR => Vec::new(),
        Err(e) => return Err(cl_err("clGetPlatformIDs", e)),
    };
    if platforms.is_empty() {
        return Err(unavailable(
            "the OpenCL ICD loader found no platform (no driver registered in \
             /etc/OpenCL/vendors; install a driver such as pocl-opencl-icd)"
                .to_owned(),
        ));
    }
    let mut out = Vec::new();
    for (pi, platform) in platforms.iter().enumerate() {
        let platform_name = platform
            .name()
            .unwrap_or_else(|_| "unknown platform".into());
        let platform_version = platform.version().unwrap_or_default();
        // A platform without devices answers CL_DEVICE_NOT_FOUND: treat it as empty.
        let ids = platform.get_devices(CL_DEVICE_TYPE_ALL).unwrap_or_default();
        for (di, &id) in ids.iter().enumerate() {
            let dev = Device::new(id);
            let ty = dev.dev_type().unwrap_or(0);
            let device_type = if ty & CL_DEVICE_TYPE_GPU != 0 {
                "GPU"
            } else if ty & CL_DEVICE_TYPE_CPU != 0 {
                "CPU"
            } else if ty & CL_DEVICE_TYPE_ACCELERATOR != 0 {
                "accelerator"
            } else {
                "other"
            };
            let extensions = dev.extensions().unwrap_or_default();
            let fp64 = extensions.split_whitespace().any(|x| x == "cl_khr_fp64")
                || dev.double_fp_config().unwrap_or(0) != 0;
            out.push(DeviceDesc {
                platform_index: pi,
                device_index: di,
                platform_name: platform_name.trim().to_owned(),
                platform_version: platform_version.trim().to_owned(),
                device_name: dev
                    .name()
                    .unwrap_or_else(|_| "unknown device".into())
                    .trim()
                    .to_owned(),
                device_type,
                driver_version: dev.driver_version().unwrap_or_default().trim().to_owned(),
                fp64,
                id,
            });
        }
    }
    if out.is_empty() {
        let names: Vec<String> = platforms
            .iter()
            .map(|p| p.name().unwrap_or_default())
            .collect();
        return Err(unavailable(format!(
            "OpenCL platform(s) {names:?} found, but none has a device"
        )));
    }
    Ok(out)
}

/// Chooses a device from `devices`.
///
/// With `selector` (see [`DEVICE_ENV`] for the format) the matching device; without, the first
/// GPU, otherwise the first CPU device.
///
/// # Errors
/// [`BackendError::Unavailable`] when nothing matches, listing the devices there are.
pub fn select_device(
    devices: &[DeviceDesc],
    selector: Option<&str>,
) -> Result<DeviceDesc, BackendError> {
    let listing = || {
        devices
            .iter()
            .map(|d| {
                format!(
                    "{}:{} {} / {}",
                    d.platform_index, d.device_index, d.platform_name, d.device_name
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    if let Some(sel) = selector.map(str::trim).filter(|s| !s.is_empty()) {
        if let Some((p, d)) = sel.split_once(':') {
            if let (Ok(p), Ok(d)) = (p.trim().parse::<usize>(), d.trim().parse::<usize>()) {
                return devices
                    .iter()
                    .find(|x| x.platform_index == p && x.device_index == d)
                    .cloned()
                    .ok_or_else(|| {
                        unavailable(format!(
                            "{DEVICE_ENV}={sel:?}: there is no device {p}:{d}; devices: {}",
                            listing()
                        ))
                    });
            }
        }
        let needle = sel.to_lowercase();
        return devices
            .iter()
            .find(|x| x.match_text().to_lowercase().contains(&needle))
            .cloned()
            .ok_or_else(|| {
                unavailable(format!(
                    "{DEVICE_ENV}={sel:?} matches no device (expected \"P:D\" indices or a \
                     substring of \"platform / device type version\"); devices: {}",
                    listing()
                ))
            });
    }
    devices
        .iter()
        .find(|d| d.device_type == "GPU")
        .or_else(|| devices.iter().find(|d| d.device_type == "CPU"))
        .cloned()
        .ok_or_else(|| {
            unavailable(format!(
                "no OpenCL GPU or CPU device (set {DEVICE_ENV} to choose another); devices: {}",
                listing()
            ))
        })
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

pub(crate) fn device_error(what: &str, e: ClError) -> BackendError {
    BackendError::Device {
        backend: NAME,
        message: format!("{what}: {e} ({})", e.0),
    }
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
        let _guard = INIT_LOCK
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let devices = list_devices_locked()?;
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
        let filter = ExactFilter::for_device(device.fp64, options.force_f32_filter);
        let build_options = match filter {
            ExactFilter::F64 => "-DSHADOWVOL_EXACT_F64=1",
            ExactFilter::F32 => "",
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
            filter,
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
            entries: PreparedScenes::new(NAME),
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
                .map(|o| {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dev(p: usize, d: usize, platform: &str, name: &str, ty: &'static str) -> DeviceDesc {
        DeviceDesc {
            platform_index: p,
            device_index: d,
            platform_name: platform.to_owned(),
            platform_version: "OpenCL 3.0 test, extra".to_owned(),
            device_name: name.to_owned(),
            device_type: ty,
            driver_version: "1".to_owned(),
            fp64: true,
            id: ptr::null_mut(),
        }
    }

    use std::ptr;

    fn devices() -> Vec<DeviceDesc> {
        vec![
            dev(0, 0, "Portable Computing Language", "pthread-cpu", "CPU"),
            dev(1, 0, "Accel Platform", "fpga", "accelerator"),
            dev(1, 1, "NVIDIA CUDA", "NVIDIA H100", "GPU"),
            dev(2, 0, "Intel", "Arc GPU", "GPU"),
        ]
    }

    #[test]
    fn default_prefers_the_first_gpu_then_the_first_cpu() {
        let d = devices();
        assert_eq!(select_device(&d, None).unwrap().device_name, "NVIDIA H100");
        assert_eq!(
            select_device(&d, Some("  ")).unwrap().device_name,
            "NVIDIA H100"
        );
        let cpu_only: Vec<_> = d
            .iter()
            .filter(|x| x.device_type != "GPU")
            .cloned()
            .collect();
        assert_eq!(
            select_device(&cpu_only, None).unwrap().device_name,
            "pthread-cpu"
        );
        let accel_only: Vec<_> = d
            .iter()
            .filter(|x| x.device_type == "accelerator")
            .cloned()
            .collect();
        let err = select_device(&accel_only, None).unwrap_err().to_string();
        assert!(
            err.contains("no OpenCL GPU or CPU device")
                && err.contains("1:0 Accel Platform / fpga"),
            "{err}"
        );
    }

    #[test]
    fn selector_by_indices_or_name_substring() {
        let d = devices();
        assert_eq!(
            select_device(&d, Some("0:0")).unwrap().device_name,
            "pthread-cpu"
        );
        assert_eq!(
            select_device(&d, Some(" 2 : 0 ")).unwrap().device_name,
            "Arc GPU"
        );
        assert!(select_device(&d, Some("pocl")).is_err());
        assert_eq!(
            select_device(&d, Some("gpu")).unwrap().device_name,
            "NVIDIA H100"
        );
        assert_eq!(
            select_device(&d, Some("portable")).unwrap().device_name,
            "pthread-cpu"
        );
        assert_eq!(
            select_device(&d, Some("cuda / nvidia"))
                .unwrap()
                .device_name,
            "NVIDIA H100"
        );
        assert_eq!(
            select_device(&d, Some("FPGA")).unwrap().device_type,
            "accelerator"
        );
        for bad in ["3:0", "0:1", "nothing-like-this"] {
            let err = select_device(&d, Some(bad)).unwrap_err().to_string();
            assert!(
                err.contains(DEVICE_ENV)
                    && err.contains(bad)
                    && err.contains("2:0 Intel / Arc GPU"),
                "{err}"
            );
        }
    }

    #[test]
    fn description_names_platform_device_and_indices() {
        let s = dev(1, 1, "NVIDIA CUDA", "NVIDIA H100", "GPU").describe();
        assert_eq!(
            s,
            "NVIDIA CUDA / NVIDIA H100 (GPU, OpenCL 3.0 test, driver 1, device 1:1)"
        );
    }
}
