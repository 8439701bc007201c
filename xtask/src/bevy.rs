//! The `bevy` step of `cargo xtask test`: the Bevy plugin crate (`crates/bevy`), which lives
//! outside the workspace with its own toolchain (Rust [`TOOLCHAIN`], what Bevy 0.20 needs).
//!
//! 1. The toolchain: installed with rustup when missing, as root or under CI; otherwise the
//!    step says what to run and warns (a visible skip).
//! 2. In `crates/bevy`, with `cargo +TOOLCHAIN` and the target folder [`target_dir`] (outside
//!    the clone, so that a machine that built Bevy once builds only the plugin again):
//!    `fmt --check`, `clippy --all-targets -D warnings`, `test` (the headless tests on the
//!    machine's adapter, lavapipe in CI), the `headless` example writing a PNG, and
//!    `doc --no-deps` with `-D warnings`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::test::Outcome;

/// The toolchain the Bevy crate builds with (its `rust-toolchain.toml` says the same).
pub const TOOLCHAIN: &str = "1.97.1";

/// The rustup command that installs [`TOOLCHAIN`].
fn install_line() -> String {
    format!("rustup toolchain install {TOOLCHAIN} --profile minimal --component clippy,rustfmt")
}

/// Where the Bevy crate builds: `SHADOWVOL_BEVY_TARGET_DIR`, else
/// `$HOME/.cache/shadowvol/bevy-target`, else `target/bevy` in the clone.
#[must_use]
pub fn target_dir(root: &Path) -> PathBuf {
    if let Some(d) = std::env::var_os("SHADOWVOL_BEVY_TARGET_DIR") {
        return PathBuf::from(d);
    }
    std::env::var_os("HOME").map_or_else(
        || root.join("target").join("bevy"),
        |h| PathBuf::from(h).join(".cache/shadowvol/bevy-target"),
    )
}

fn toolchain_installed() -> bool {
    Command::new("rustup")
        .args(["run", TOOLCHAIN, "rustc", "--version"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// One cargo command in `crates/bevy`: its arguments and an extra environment variable.
type CargoRun<'a> = (&'a [&'a str], Option<(&'a str, &'a str)>);

/// The step: the toolchain (`install`: may install it), then each cargo command; every command
/// runs even after a failure, and the outcome lists the failures.
pub fn step(root: &Path, ci: bool, install: bool) -> Outcome {
    if !crate::drivers::vulkan_present() && !ci {
        return Outcome::Warned(
            "no Vulkan driver for the Bevy tests: the drivers step says what to install".into(),
        );
    }
    if !toolchain_installed() {
        if install || ci {
            println!("$ {}", install_line());
            let ok = Command::new("rustup")
                .args(install_line().split_whitespace().skip(1))
                .status()
                .is_ok_and(|s| s.success());
            if !ok || !toolchain_installed() {
                return Outcome::Failed(format!("`{}` failed", install_line()));
            }
        } else {
            return Outcome::Warned(format!(
                "the Bevy crate needs Rust {TOOLCHAIN}, which is not installed: run `{}`",
                install_line()
            ));
        }
    }
    let dir = root.join("crates/bevy");
    let target = target_dir(root);
    println!("  target folder: {}", target.display());
    let png = target.join("bevy-headless.png");
    let _ = std::fs::remove_file(&png);
    let png_arg = png.to_string_lossy().into_owned();
    let doc_flags = "-D warnings";
    let runs: [CargoRun<'_>; 5] = [
        (&["fmt", "--check"], None),
        (&["clippy", "--all-targets", "--", "-D", "warnings"], None),
        (&["test"], None),
        (&["run", "--example", "headless", "--", &png_arg], None),
        (&["doc", "--no-deps"], Some(("RUSTDOCFLAGS", doc_flags))),
    ];
    let mut failures = Vec::new();
    for (args, env) in runs {
        let line = format!("cargo +{TOOLCHAIN} {}", args.join(" "));
        println!("$ (cd crates/bevy && {line})");
        let mut cmd = Command::new("cargo");
        cmd.current_dir(&dir)
            .arg(format!("+{TOOLCHAIN}"))
            .args(args)
            .env("CARGO_TARGET_DIR", &target)
            // The workspace's cargo and toolchain must not leak into the other toolchain.
            .env_remove("RUSTUP_TOOLCHAIN")
            .env_remove("RUSTC")
            .env_remove("RUSTDOC")
            .env_remove("CARGO")
            // Debian's Vulkan validation layer (1.3.239) reports VUID-vkCmdDraw-commandBuffer-02701
            // (line width) on the stencil passes under Bevy's device only, for a state wgpu does
            // not declare dynamic (docs/BEVY.md); the images match the reference either way.
            .env("WGPU_VALIDATION", "0");
        if let Some((k, v)) = env {
            cmd.env(k, v);
        }
        match cmd.status() {
            Ok(s) if s.success() => {}
            Ok(s) => failures.push(format!("`{line}` failed ({s})")),
            Err(e) => failures.push(format!("cannot run `{line}`: {e}")),
        }
    }
    if failures.is_empty() && !png.is_file() {
        failures.push(format!("the headless example wrote no {}", png.display()));
    }
    if failures.is_empty() {
        Outcome::Passed
    } else {
        Outcome::Failed(failures.join("; "))
    }
}
