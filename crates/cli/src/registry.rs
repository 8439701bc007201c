//! The backend registry: the one list of silhouette backends.
//!
//! `shadowvol backends`, `shadowvol silhouette --backend`, the conformance tests, the benches and
//! `cargo xtask matrix` all iterate over [`backends`]; none has its own list. To add a backend,
//! write a crate that exports
//!
//! ```text
//! pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError>
//! ```
//!
//! add it as an optional dependency behind a cargo feature of the same name as the backend in
//! `crates/cli/Cargo.toml` (and pass the feature through in `tests/Cargo.toml`), and add one
//! `backend!` line to [`backends`].

use crate::CliError;
use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::{BackendError, SilhouetteBackend};

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

/// One registry line: `backend!("name", crate_name)`. The entry calls
/// `crate_name::create_backend()` when the cargo feature `name` is on, and otherwise reports
/// that the backend is not compiled in.
macro_rules! backend {
    ($name:literal, $krate:ident) => {{
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
        },
        backend!("simd", shadowvol_simd),
        backend!("wgpu", shadowvol_wgpu_compute),
        backend!("opencl", shadowvol_opencl),
        backend!("vulkan", shadowvol_vulkan_geometry),
    ]
}

/// The names of all registered backends, in registry order.
#[must_use]
pub fn backend_names() -> Vec<&'static str> {
    backends().iter().map(|e| e.name).collect()
}

/// The entry named `name` (case-insensitive, surrounding spaces ignored).
///
/// # Errors
/// [`CliError::Usage`] naming the unknown backend and listing the known ones.
pub fn find_backend(name: &str) -> Result<BackendEntry, CliError> {
    let wanted = name.trim().to_ascii_lowercase();
    backends()
        .into_iter()
        .find(|e| e.name == wanted)
        .ok_or_else(|| {
            CliError::Usage(format!(
                "unknown backend {name:?}; known backends: {}",
                backend_names().join(", ")
            ))
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
        assert_eq!(err.exit_code(), crate::error::EXIT_USAGE);
        assert!(err.to_string().contains("unknown backend \"metal\""));
        assert!(err.to_string().contains("cpu, simd, wgpu, opencl, vulkan"));
    }

    #[test]
    fn cpu_always_starts() {
        let cpu = find_backend("cpu").unwrap().start().unwrap();
        assert_eq!(cpu.info().name, "cpu");
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
