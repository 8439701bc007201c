//! `cargo xtask`: project automation (the alias lives in `.cargo/config.toml`).
//!
//! Each subcommand is a module with `pub fn run(args: &[String]) -> Result<(), String>` and one
//! line in [`COMMANDS`]. Shared helpers for the modules: [`project_root`], [`cargo`] and
//! [`next_value`].
//!
//! ```text
//! cargo xtask test            drivers, fmt, sizes, clippy, docs, workspace tests, SPIR-V check
//! cargo xtask matrix          the paper's experiment matrix on every available backend
//! cargo xtask shaders         regenerate the committed SPIR-V (--check: verify it)
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

mod bevy;
mod ci;
mod drivers;
mod figures;
mod gpu_crates;
mod matrix;
mod plots;
mod shaders;
mod size;
mod test;

/// A subcommand's entry point: its arguments (after the subcommand name) to a result whose error
/// is printed as `error: ...`.
type RunFn = fn(&[String]) -> Result<(), String>;

/// The subcommands: name, one-line help, entry point. Add a module and a line here.
const COMMANDS: &[(&str, &str, RunFn)] = &[
    (
        "test",
        "drivers check/install, fmt, sizes, clippy, workspace tests, SPIR-V check; summary",
        test::run,
    ),
    (
        "matrix",
        "run the paper's experiment matrix on every available backend (tables, CSV, JSON, plots)",
        matrix::run,
    ),
    (
        "shaders",
        "regenerate shaders/*.spv with glslangValidator (--check: fail when stale or missing)",
        shaders::run,
    ),
    (
        "figures",
        "regenerate docs/images (Figure 1 redone: original/robust/exact renders, artifact counts)",
        figures::run,
    ),
];

/// The workspace root (the parent of `xtask/`).
#[must_use]
pub fn project_root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .map_or_else(|| manifest.clone(), std::path::Path::to_path_buf)
}

/// The cargo that runs us (`$CARGO`), or `cargo` from `PATH`.
#[must_use]
pub fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned())
}

/// The value of option `name`: the next argument of `it`.
///
/// # Errors
/// `NAME needs a value`, then `usage`, when there is no next argument.
pub fn next_value(
    it: &mut std::slice::Iter<'_, String>,
    name: &str,
    usage: &str,
) -> Result<String, String> {
    it.next()
        .cloned()
        .ok_or_else(|| format!("{name} needs a value\n\n{usage}"))
}

fn usage() -> String {
    let mut s = String::from(
        "cargo xtask <COMMAND> [ARGS...]\n\nProject automation for shadowvol.\n\nCommands:\n",
    );
    let width = COMMANDS.iter().map(|c| c.0.len()).max().unwrap_or(0);
    for (name, help, _) in COMMANDS {
        s.push_str(&format!("  {name:width$}  {help}\n"));
    }
    s.push_str("\n`cargo xtask <COMMAND> --help` shows a command's options.\n");
    s
}

/// On a machine without a display (`DISPLAY` and `WAYLAND_DISPLAY` unset or empty), turns Mesa's
/// Vulkan device-select layer off (`NODEVICE_SELECT=1`, unless it is set) for every process
/// xtask starts: cargo, the test binaries, the examples, the Bevy step. Without a display the
/// layer prints `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` for every
/// wgpu instance although nothing failed. The rule of
/// `shadowvol_silhouette::gpu::quiet_without_display`, which xtask does not depend on (it builds
/// none of the workspace's crates); runs first, before any thread.
fn quiet_children_without_display() {
    let shown = |name| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    let quiet = !shown("DISPLAY") && !shown("WAYLAND_DISPLAY");
    if quiet && std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

fn main() -> ExitCode {
    quiet_children_without_display();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(name) = args.first() else {
        eprint!("{}", usage());
        return ExitCode::from(2);
    };
    if matches!(name.as_str(), "-h" | "--help" | "help") {
        print!("{}", usage());
        return ExitCode::SUCCESS;
    }
    let Some((_, _, run)) = COMMANDS.iter().find(|c| c.0 == name) else {
        eprintln!("error: unknown xtask command {name:?}\n\n{}", usage());
        return ExitCode::from(2);
    };
    match run(&args[1..]) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
