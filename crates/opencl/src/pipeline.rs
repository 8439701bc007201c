//! The kernel program: its source (built in, a file or text), the work-group width, and
//! building it for the device with the compiler's log on failure.

use crate::device::DeviceDesc;
use crate::NAME;
use opencl3::context::Context;
use opencl3::program::Program;
use shadowvol_silhouette::BackendError;
use std::path::PathBuf;

/// The built-in kernel source (`kernels/silhouette.cl`, embedded at compile time).
pub const KERNEL_SOURCE: &str = include_str!("../../../kernels/silhouette.cl");

/// Name of the kernel entry point in the source.
pub const KERNEL_NAME: &str = "silhouette";

/// Environment variable: path of a `.cl` file to build instead of [`KERNEL_SOURCE`].
pub const KERNEL_ENV: &str = "SHADOWVOL_OPENCL_KERNEL";

/// Work-group width along the edge dimension (edges are padded to a multiple of it).
pub(crate) const GROUP: usize = 64;

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

/// Builds `source` for `device` and returns the program, or [`BackendError::Build`] with the
/// compiler's log.
pub(crate) fn build_program(
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
