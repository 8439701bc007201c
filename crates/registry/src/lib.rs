//! The backend registry: the one list of silhouette backends, and the memory floor they are
//! timed against.
//!
//! `shadowvol backends`, `shadowvol silhouette --backend`, the conformance tests, the benches and
//! `cargo xtask matrix` (through `shadowvol`) all iterate over [`backends`]; none has its own
//! list. This crate depends on the backends and on nothing above them (no renderer, no window),
//! so that tests and benches use it without the viewer.
//!
//! To add a backend, write a crate that exports
//!
//! ```text
//! pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError>
//! ```
//!
//! add it as an optional dependency behind a cargo feature of the same name as the backend in
//! `crates/registry/Cargo.toml` (and pass the feature through in `crates/cli/Cargo.toml` and
//! `tests/Cargo.toml`), and add one `backend!` line to [`backends`], saying whether it runs on
//! the host or on a device.
//!
//! `--backend auto` ([`AUTO`]) is resolved here too, by [`find_backend`]: [`choose_auto`] picks
//! the first backend of [`AUTO_GPU_ORDER`] that runs on a hardware GPU ([`cpu_emulated`] tells
//! llvmpipe, lavapipe, PoCL and other CPU implementations apart), otherwise `simd`, and says on
//! stderr what it skipped and why.
//!
//! [`MemoryFloor`] is **the** memory floor (`floor_ms`): the time to stream the bytes any
//! extraction must touch, measured in the same run as the backends by `shadowvol bench` and by
//! the criterion benches.
//!
//! ```
//! // List the registered backends and start the reference one.
//! let entries = shadowvol_registry::backends();
//! let names: Vec<_> = entries.iter().map(|e| e.name).collect();
//! assert_eq!(names, ["cpu", "simd", "wgpu", "opencl", "vulkan"]);
//! let cpu = entries[0].start().expect("the cpu backend is always available");
//! assert_eq!(cpu.info().name, "cpu");
//! assert!(shadowvol_registry::find_backend("metal").is_err());
//! ```

pub mod floor;

pub use floor::MemoryFloor;

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::{BackendError, BackendInfo, SilhouetteBackend};
use std::sync::mpsc;
use std::time::Duration;

/// The signature every backend crate's `create_backend` has.
pub type CreateFn = fn() -> Result<Box<dyn SilhouetteBackend>, BackendError>;

/// One registered backend.
#[derive(Debug, Clone, Copy)]
pub struct BackendEntry {
    /// The registry name (`cpu`, `simd`, `wgpu`, `opencl`, `vulkan`), used by `--backend`, in
    /// JSON and in test names.
    pub name: &'static str,
    /// Starts the backend: the backend crate's `create_backend`. Returns
    /// [`BackendError::Unavailable`] when the driver or device is missing, or when the backend's
    /// cargo feature is off in this build.
    pub create: CreateFn,
    /// Whether the backend's cargo feature is on in this build. When it is off, `create` only
    /// reports that.
    pub compiled: bool,
    /// Whether it evaluates on the host CPU in Rust (`cpu`, `simd`) rather than on a device:
    /// then its `f32` modes are the reference operations bit for bit (no contraction), and it is
    /// never a GPU for `--backend auto`.
    pub host: bool,
}

impl BackendEntry {
    /// Starts the backend like [`BackendEntry::create`], but turns a panic inside the backend's
    /// start-up (a driver bug) into [`BackendError::Unavailable`] instead of aborting the caller.
    ///
    /// # Errors
    /// [`BackendError::Unavailable`] naming what is missing, or the backend's own error.
    pub fn start(&self) -> Result<Box<dyn SilhouetteBackend>, BackendError> {
        let create = self.create;
        match std::panic::catch_unwind(create) {
            Ok(result) => result,
            Err(payload) => {
                let what = payload
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_owned())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic".to_owned());
                Err(BackendError::Unavailable {
                    backend: self.name,
                    reason: format!("panicked while starting: {what}"),
                })
            }
        }
    }
}

fn create_cpu() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    Ok(Box::new(CpuBackend::new()))
}

/// One registry line: `backend!("name", crate_name, host)` or `backend!("name", crate_name,
/// device)`. The entry calls `crate_name::create_backend()` when the cargo feature `name` is on,
/// and otherwise reports that the backend is not compiled in.
macro_rules! backend {
    ($name:literal, $krate:ident, host) => {
        backend!(@entry $name, $krate, true)
    };
    ($name:literal, $krate:ident, device) => {
        backend!(@entry $name, $krate, false)
    };
    (@entry $name:literal, $krate:ident, $host:expr) => {{
        #[cfg(feature = $name)]
        fn create() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
            $krate::create_backend()
        }
        #[cfg(not(feature = $name))]
        fn create() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
            Err(BackendError::Unavailable {
                backend: $name,
                reason: format!(
                    "not compiled into this build (enable the cargo feature `{}` of the \
                     `shadowvol` package)",
                    $name
                ),
            })
        }
        BackendEntry {
            name: $name,
            create,
            compiled: cfg!(feature = $name),
            host: $host,
        }
    }};
}

/// All backends, in the order `cpu`, `simd`, `wgpu`, `opencl`, `vulkan`.
///
/// Every entry is listed whatever the build's features; [`BackendEntry::compiled`] tells whether
/// it can run. Nothing is started here: call [`BackendEntry::start`].
#[must_use]
pub fn backends() -> Vec<BackendEntry> {
    vec![
        BackendEntry {
            name: "cpu",
            create: create_cpu,
            compiled: true,
            host: true,
        },
        backend!("simd", shadowvol_simd, host),
        backend!("wgpu", shadowvol_wgpu_compute, device),
        backend!("opencl", shadowvol_opencl, device),
        backend!("vulkan", shadowvol_vulkan_geometry, device),
    ]
}

/// The names of all registered backends, in registry order.
#[must_use]
pub fn backend_names() -> Vec<&'static str> {
    backends().iter().map(|e| e.name).collect()
}

/// The `--backend` value that picks a backend automatically (see [`choose_auto`]).
pub const AUTO: &str = "auto";

/// The GPU backends `--backend auto` considers, fastest first, as measured on a hardware GPU
/// that runs all three (NVIDIA H100, docs/GPU.md, median silhouette ms per frame, one light):
/// `opencl` is fastest or level on every scene (sphere-100k 0.10 against wgpu's 0.25, 100
/// spheres of 1k 0.19 against 0.23; sphere-1m 0.44 against 0.41), `wgpu` next, and the
/// geometry-shader pipeline (`vulkan`, 0.39-4.3 ms, rasterising its side quads) last.
pub const AUTO_GPU_ORDER: [&str; 3] = ["opencl", "wgpu", "vulkan"];

/// How long `auto` waits for one backend to start (they start in parallel) before skipping it.
pub const AUTO_START_TIMEOUT: Duration = Duration::from_secs(30);

/// If `info` describes a device that is emulated on the CPU (Mesa llvmpipe/lavapipe/softpipe,
/// SwiftShader, PoCL, WARP, or any device whose reported type is CPU), the reason in words;
/// `None` for a hardware GPU (and for the [`BackendEntry::host`] backends, which are not
/// devices).
///
/// It reads the `device_type` detail where a backend reports one (`opencl`), wgpu's device
/// type in [`BackendInfo::device`] (`"(Vulkan, Cpu; ..."`), and known software driver names.
#[must_use]
pub fn cpu_emulated(info: &BackendInfo) -> Option<String> {
    if backends().iter().any(|e| e.host && e.name == info.name) {
        return None;
    }
    for (k, v) in &info.details {
        if k == "device_type" && v.eq_ignore_ascii_case("cpu") {
            return Some(format!("its device type is CPU ({})", info.device));
        }
    }
    let device = info.device.to_ascii_lowercase();
    if device.contains(", cpu;") || device.contains("(cpu,") {
        return Some(format!("its device type is CPU ({})", info.device));
    }
    const SOFTWARE: [&str; 6] = [
        "llvmpipe",
        "lavapipe",
        "softpipe",
        "swiftshader",
        "portable computing language",
        "microsoft basic render",
    ];
    SOFTWARE
        .iter()
        .find(|s| device.contains(*s))
        .map(|s| format!("{s} is a CPU implementation, not a GPU ({})", info.device))
}

/// What `--backend auto` chose and what it skipped.
#[derive(Debug, Clone)]
pub struct AutoChoice {
    /// The chosen backend: the first hardware GPU backend of [`AUTO_GPU_ORDER`] that starts,
    /// otherwise `simd`, otherwise `cpu`.
    pub entry: BackendEntry,
    /// The chosen backend's device, in words.
    pub device: String,
    /// Each backend passed over and why (GPU backends that are unavailable, emulated on the CPU
    /// or did not start in time; `simd` when it could not start).
    pub skipped: Vec<(&'static str, String)>,
}

impl AutoChoice {
    /// True when `auto` fell back from the GPU backends to a host backend.
    #[must_use]
    pub fn fell_back(&self) -> bool {
        !AUTO_GPU_ORDER.contains(&self.entry.name)
    }

    /// The message `--backend auto` prints on stderr: a warning naming every skipped backend
    /// and why when it fell back to `simd`/`cpu`, a note naming the device otherwise.
    #[must_use]
    pub fn message(&self) -> String {
        let skipped = self
            .skipped
            .iter()
            .map(|(n, why)| format!("  {n}: {why}"))
            .collect::<Vec<_>>()
            .join("\n");
        if self.fell_back() {
            format!(
                "warning: --backend auto: no hardware GPU backend is available, falling back to \
                 {} ({}); skipped:\n{skipped}",
                self.entry.name, self.device
            )
        } else if skipped.is_empty() {
            format!(
                "note: --backend auto: using {} ({})",
                self.entry.name, self.device
            )
        } else {
            format!(
                "note: --backend auto: using {} ({}); skipped:\n{skipped}",
                self.entry.name, self.device
            )
        }
    }
}

/// Starts every backend in `entries` on its own thread and waits at most `timeout` for each;
/// returns, per entry, its device or why it can't be used.
fn probe(entries: &[BackendEntry], timeout: Duration) -> Vec<Result<BackendInfo, String>> {
    let pending: Vec<_> = entries
        .iter()
        .map(|&entry| {
            let (tx, rx) = mpsc::channel();
            std::thread::spawn(move || {
                let _ = tx.send(entry.start().map(|b| b.info()));
            });
            rx
        })
        .collect();
    pending
        .into_iter()
        .map(|rx| match rx.recv_timeout(timeout) {
            Ok(Ok(info)) => Ok(info),
            Ok(Err(BackendError::Unavailable { reason, .. })) => {
                Err(format!("unavailable: {reason}"))
            }
            Ok(Err(e)) => Err(format!("failed to start: {e}")),
            Err(_) => Err(format!("did not start within {} s", timeout.as_secs())),
        })
        .collect()
}

/// Chooses the backend for `--backend auto`: the first backend of [`AUTO_GPU_ORDER`] that
/// starts on a hardware GPU (see [`cpu_emulated`]), otherwise `simd`, otherwise `cpu`. Backends
/// are started in parallel to find out (each at most [`AUTO_START_TIMEOUT`]) and dropped again;
/// the caller starts the chosen entry.
#[must_use]
pub fn choose_auto() -> AutoChoice {
    let all = backends();
    let by_name = |n: &str| all.iter().copied().find(|e| e.name == n);
    let gpus: Vec<BackendEntry> = AUTO_GPU_ORDER.iter().filter_map(|n| by_name(n)).collect();
    let mut candidates = gpus.clone();
    candidates.extend(by_name("simd"));
    let results = probe(&candidates, AUTO_START_TIMEOUT);
    let mut skipped = Vec::new();
    for (entry, result) in candidates.iter().zip(results) {
        let is_gpu = gpus.iter().any(|g| g.name == entry.name);
        match result {
            Ok(info) => match cpu_emulated(&info) {
                Some(why) if is_gpu => skipped.push((entry.name, why)),
                _ => {
                    return AutoChoice {
                        entry: *entry,
                        device: info.device,
                        skipped,
                    }
                }
            },
            Err(why) => skipped.push((entry.name, why)),
        }
    }
    let cpu = by_name("cpu").expect("the registry always has cpu");
    AutoChoice {
        entry: cpu,
        device: CpuBackend::new().info().device,
        skipped,
    }
}

/// A `--backend` value that names no registered backend.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownBackend {
    /// The value as given.
    pub name: String,
}

impl std::fmt::Display for UnknownBackend {
    /// `unknown backend "NAME"; known backends: cpu, simd, ..., or auto`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "unknown backend {:?}; known backends: {}, or {AUTO}",
            self.name,
            backend_names().join(", ")
        )
    }
}

impl std::error::Error for UnknownBackend {}

/// The entry named `name` (case-insensitive, surrounding spaces ignored). `auto` ([`AUTO`])
/// runs [`choose_auto`], prints its [`AutoChoice::message`] on stderr and returns the chosen
/// entry, so every command that takes `--backend` accepts it.
///
/// # Errors
/// [`UnknownBackend`] naming the unknown backend; its message lists the known ones.
pub fn find_backend(name: &str) -> Result<BackendEntry, UnknownBackend> {
    let wanted = name.trim().to_ascii_lowercase();
    if wanted == AUTO {
        let choice = choose_auto();
        eprintln!("{}", choice.message());
        return Ok(choice.entry);
    }
    backends()
        .into_iter()
        .find(|e| e.name == wanted)
        .ok_or_else(|| UnknownBackend {
            name: name.to_owned(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_order_and_lookup() {
        assert_eq!(backend_names(), ["cpu", "simd", "wgpu", "opencl", "vulkan"]);
        assert_eq!(find_backend(" CPU ").unwrap().name, "cpu");
        let err = find_backend("metal").unwrap_err();
        assert_eq!(err.name, "metal");
        assert!(err.to_string().contains("unknown backend \"metal\""));
        assert!(err.to_string().contains("cpu, simd, wgpu, opencl, vulkan"));
    }

    fn info(name: &'static str, device: &str, details: &[(&str, &str)]) -> BackendInfo {
        BackendInfo {
            name,
            device: device.to_owned(),
            modes: Vec::new(),
            max_lights: None,
            details: details
                .iter()
                .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
                .collect(),
        }
    }

    #[test]
    fn cpu_emulated_devices_are_recognised() {
        // The strings the backends report on this machine (lavapipe, PoCL).
        let lavapipe_wgpu = info(
            "wgpu",
            "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu; driver llvmpipe Mesa 22.3.6 (LLVM 15.0.6))",
            &[],
        );
        let pocl = info(
            "opencl",
            "Portable Computing Language / pthread-haswell-AMD EPYC (CPU, OpenCL 3.0 PoCL 3.1+debian Linux, driver 3.1+debian, device 0:0)",
            &[("device_type", "CPU")],
        );
        let lavapipe_vk = info(
            "vulkan",
            "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan 1.3.230, driver version 0x1), geometry shader",
            &[],
        );
        for i in [&lavapipe_wgpu, &pocl, &lavapipe_vk] {
            let why = cpu_emulated(i).unwrap_or_else(|| panic!("{} not recognised", i.device));
            assert!(why.contains(&i.device), "{why}");
        }
        // Hardware GPUs as their drivers name them.
        for i in [
            info(
                "wgpu",
                "NVIDIA GeForce RTX 4090 (Vulkan, DiscreteGpu; driver NVIDIA 550.54.14)",
                &[],
            ),
            info(
                "opencl",
                "NVIDIA CUDA / NVIDIA H100 80GB HBM3 (GPU, OpenCL 3.0 CUDA 12.4.89, driver 550.54.15, device 0:0)",
                &[("device_type", "GPU")],
            ),
            info(
                "vulkan",
                "AMD Radeon RX 7900 XTX (RADV NAVI31) (Vulkan 1.3.255, driver version 0x5c00004), geometry shader",
                &[],
            ),
            info("simd", "host CPU, 2 threads, avx2 lanes", &[]),
        ] {
            assert_eq!(cpu_emulated(&i), None, "{}", i.device);
        }
    }

    #[test]
    fn cpu_always_starts() {
        let cpu = find_backend("cpu").unwrap().start().unwrap();
        assert_eq!(cpu.info().name, "cpu");
    }

    #[test]
    fn host_backends_are_cpu_and_simd() {
        let host: Vec<_> = backends()
            .into_iter()
            .filter(|e| e.host)
            .map(|e| e.name)
            .collect();
        assert_eq!(host, ["cpu", "simd"]);
    }

    #[test]
    fn features_match_compiled_flags() {
        let e = backends();
        assert_eq!(e[1].compiled, cfg!(feature = "simd"));
        assert_eq!(e[2].compiled, cfg!(feature = "wgpu"));
        assert_eq!(e[3].compiled, cfg!(feature = "opencl"));
        assert_eq!(e[4].compiled, cfg!(feature = "vulkan"));
        for entry in e.iter().filter(|e| !e.compiled) {
            let err = entry.start().err().unwrap();
            assert!(err.to_string().contains("not compiled into this build"));
        }
    }
}
