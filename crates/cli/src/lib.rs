//! The library behind the `shadowvol` command line.
//!
//! It holds what the subcommands, the conformance tests, the benches and `cargo xtask matrix`
//! share, so that none of them keeps its own copy:
//!
//! * [`backends`], [`find_backend`], [`MemoryFloor`]: **the** backend registry and memory floor,
//!   re-exported from [`shadowvol_registry`] (the crate the conformance tests and the benches
//!   use without this one's viewer). Adding a backend means one new crate and one line there.
//! * [`load_input`]: the one function that turns a command-line mesh argument (`.obj`, `.gltf`,
//!   `.glb`, `.stl`, `.ply` or a preset name; [`INPUT_FORMATS`] describes them) into one world-space [`Mesh`] and the input's own lights.
//! * [`report`]: the silhouette report that `shadowvol silhouette --format json` prints (the JSON
//!   contract of DESIGN.md).
//! * [`mode_parser`]: the values of `--mode`, parsed straight into [`Accuracy`] (the one type
//!   of the accuracy mode; there is no command-line copy of it).
//! * [`memory`]: the JSON's `peak_rss_bytes` and `table_bytes`.
//! * [`CliError`]: errors with their exit codes (2 for usage, 1 for everything else).
//!
//! ```
//! // List the registered backends and try to start the reference one.
//! let entries = shadowvol::backends();
//! let names: Vec<_> = entries.iter().map(|e| e.name).collect();
//! assert_eq!(names, ["cpu", "simd", "wgpu", "opencl", "vulkan"]);
//! let cpu = entries[0].start().expect("the cpu backend is always available");
//! assert_eq!(cpu.info().name, "cpu");
//! ```
//!
//! [`Mesh`]: shadowvol_mesh_topology::Mesh

pub mod error;
pub mod input;
pub mod light_size;
pub mod memory;
pub mod report;

pub use error::CliError;
pub use input::{bounds_too_large, load_input, load_scene, Input, INPUT_FORMATS};
pub use light_size::LightSizeArgs;
pub use shadowvol_registry as registry;
pub use shadowvol_registry::{backend_names, backends, find_backend, BackendEntry, MemoryFloor};
pub use shadowvol_silhouette::gpu::{quiet_without_display, NODEVICE_SELECT};

use shadowvol_robust_math::Accuracy;

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

/// Output format of a subcommand.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Human-readable text.
    #[default]
    Text,
    /// JSON on one line, in the shapes of the CLI contract (scripts depend on them).
    Json,
}

/// The values of `--mode`: every [`Accuracy`] by its name, each with its help text, parsed into
/// [`Accuracy`]. Use it as `#[arg(long, value_parser = shadowvol::mode_parser())]` on a field of
/// type `Accuracy` (or `Vec<Accuracy>` with a delimiter).
#[must_use]
pub fn mode_parser() -> impl clap::builder::TypedValueParser<Value = Accuracy> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(Accuracy::ALL.map(|mode| {
        PossibleValue::new(mode.name()).help(match mode {
            Accuracy::Original => {
                "Kim et al. 2008 as stated: each (edge, opposite vertex) in f32 on its own; can \
                 crack"
            }
            Accuracy::Robust => {
                "Pečiva et al. 2013: the three sides of each triangle in f32; disagreement counts 0"
            }
            Accuracy::Ordered => {
                "One f32 evaluation per triangle in canonical vertex order; consistent, 1/3 of \
                 robust"
            }
            Accuracy::Exact => {
                "The exact sign of the determinant; consistent, correct, identical on every \
                 backend"
            }
        })
    }))
    .try_map(|name| name.parse::<Accuracy>())
}
