//! `cargo xtask figures`: regenerate `docs/images/` — the paper's Figure 1 redone: `original` /
//! `robust` / `exact` renders of hard scenes (edge-on frustum, bunny offset by 1e4, UV sphere
//! with the light at a pole, town), each with its artifact count against the ray-traced
//! reference.
//!
//! The work is done by the renderer's `figure1` example (so that xtask itself stays light to
//! build); this command runs it with the right arguments. It needs a GPU adapter (lavapipe is
//! enough). The images are figures, not test references: nothing is compared against them.

use crate::{cargo, project_root};
use std::process::Command;

const HELP: &str =
    "cargo xtask figures [--size N] [--scenes a,b,...] [--profile P] [--out DIR]\n\n\
Regenerates docs/images/figure1*.{png,md,json}: original / robust / exact renders of the hard\n\
scenes with their artifact counts (crates/renderer/examples/figure1.rs).\n\n\
Options:\n  \
--size N       image size of each panel (default 256)\n  \
--scenes LIST  only these: edge-on-frustum, bunny-1e4, uv-sphere-pole, town (default all)\n  \
--profile P    cargo profile to build the example with (default release)\n  \
--out DIR      output directory (default docs/images)\n";

/// Runs the command.
///
/// # Errors
/// A message when an argument is bad or the example fails (no GPU adapter, build error).
pub fn run(args: &[String]) -> Result<(), String> {
    let root = project_root();
    let mut size = "256".to_owned();
    let mut scenes: Option<String> = None;
    let mut profile = "release".to_owned();
    let mut out = root.join("docs").join("images");
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| crate::next_value(&mut it, name, HELP);
        match a.as_str() {
            "-h" | "--help" => {
                print!("{HELP}");
                return Ok(());
            }
            "--size" => {
                size = value("--size")?;
                let n: u32 = size.parse().map_err(|e| format!("--size {size:?}: {e}"))?;
                if !(16..=4096).contains(&n) {
                    return Err(format!("--size {n}: must be in 16..=4096"));
                }
            }
            "--scenes" => scenes = Some(value("--scenes")?),
            "--profile" => profile = value("--profile")?,
            "--out" => out = std::path::PathBuf::from(value("--out")?),
            other => return Err(format!("unknown argument {other:?}\n\n{HELP}")),
        }
    }
    let mut cmd = Command::new(cargo());
    cmd.current_dir(&root).args([
        "run",
        "--profile",
        &profile,
        "-p",
        "shadowvol-renderer",
        "--example",
        "figure1",
        "--",
    ]);
    cmd.arg(&out).args(["--size", &size]);
    if let Some(s) = &scenes {
        cmd.args(["--scenes", s]);
    }
    eprintln!("running {cmd:?}");
    let status = cmd.status().map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("the figure1 example failed ({status})"));
    }
    eprintln!("figures written to {}", out.display());
    Ok(())
}
