//! Errors of the command line and their exit codes.

use shadowvol_scenes::obj::LoadError;
use shadowvol_scenes::SceneError;
use shadowvol_silhouette::BackendError;

/// Exit code for a usage error (bad arguments), as clap uses.
pub const EXIT_USAGE: u8 = 2;
/// Exit code for every other failure (bad input file, unavailable backend, device error).
pub const EXIT_FAILURE: u8 = 1;

/// An error of a `shadowvol` subcommand. The message names the problem and where it is.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The arguments are wrong (unknown backend, no light, ...). Exit code 2.
    #[error("{0}")]
    Usage(String),
    /// An OBJ file could not be loaded (unreadable file, malformed content). Exit code 1.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// A scene (glTF, OBJ or preset) could not be loaded: unreadable or malformed file,
    /// unsupported extension, unknown preset. Exit code 1.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A backend failed to start or to run. Exit code 1.
    #[error(transparent)]
    Backend(#[from] BackendError),
    /// Writing the output failed (for example a closed pipe). Exit code 1.
    #[error("cannot write output: {0}")]
    Output(#[from] std::io::Error),
    /// Anything else, in words. Exit code 1.
    #[error("{0}")]
    Other(String),
}

impl From<shadowvol_registry::UnknownBackend> for CliError {
    /// A `--backend` value that names no backend is a usage error.
    fn from(e: shadowvol_registry::UnknownBackend) -> Self {
        CliError::Usage(e.to_string())
    }
}

impl CliError {
    /// The process exit code for this error: [`EXIT_USAGE`] or [`EXIT_FAILURE`].
    #[must_use]
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Usage(_) => EXIT_USAGE,
            _ => EXIT_FAILURE,
        }
    }

    /// True when the error is a closed output pipe (`shadowvol ... | head`), which is not a
    /// failure of the command.
    #[must_use]
    pub fn is_broken_pipe(&self) -> bool {
        matches!(self, CliError::Output(e) if e.kind() == std::io::ErrorKind::BrokenPipe)
    }
}
