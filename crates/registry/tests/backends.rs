//! The registry's backends started for real: `--backend auto`'s choice, and no `error:` line
//! from a run in which nothing failed.
//!
//! They run here rather than as unit tests so that they start Vulkan in a test binary whose
//! `main` is `shadowvol_test_support::run`. Mesa's Vulkan device-select layer, on a machine without a display, prints `error:
//! XDG_RUNTIME_DIR is invalid or not set in the environment.` for every Vulkan instance that
//! enables the Wayland surface extension (wgpu's do), although nothing failed.
//! `shadowvol_test_support::run` turns the layer off first (`NODEVICE_SELECT=1`) where there is
//! no display; this test binary runs itself again without a display to check it.

use shadowvol_registry::{choose_auto, cpu_emulated, AUTO_GPU_ORDER};
use shadowvol_test_support::{main, skip, Outcome};

main!(
    auto_choice_message_names_what_was_skipped,
    the_wgpu_backend_starts,
    a_test_binary_without_a_display_prints_no_error_line
);

/// `--backend auto` names every GPU backend it passed over when it falls back to the host, and
/// the entry it chose starts and is no CPU-emulated device.
fn auto_choice_message_names_what_was_skipped() {
    let choice = choose_auto();
    let msg = choice.message();
    if choice.fell_back() {
        assert!(msg.starts_with("warning: --backend auto"), "{msg}");
        for gpu in AUTO_GPU_ORDER {
            assert!(
                choice.skipped.iter().any(|(n, _)| *n == gpu),
                "{gpu} not reported as skipped: {msg}"
            );
            assert!(msg.contains(&format!("  {gpu}: ")), "{msg}");
        }
    } else {
        assert!(AUTO_GPU_ORDER.contains(&choice.entry.name));
    }
    // The chosen entry starts and is what was chosen.
    let started = choice.entry.start().unwrap();
    assert_eq!(started.info().name, choice.entry.name);
    assert!(cpu_emulated(&started.info()).is_none(), "{msg}");
}

/// Starts the `wgpu` backend (a wgpu instance with every surface extension), or skips visibly.
fn the_wgpu_backend_starts() -> Outcome {
    let entry = shadowvol_registry::find_backend("wgpu").expect("registered");
    if !entry.compiled {
        return Err(skip("the wgpu feature is off"));
    }
    shadowvol_test_support::started("wgpu", entry.start())?;
    Ok(())
}

/// This binary, run again on [`the_wgpu_backend_starts`] without `DISPLAY`, `WAYLAND_DISPLAY`,
/// `XDG_RUNTIME_DIR` and `NODEVICE_SELECT`, passes and prints no line starting with `error`.
fn a_test_binary_without_a_display_prints_no_error_line() -> Outcome {
    the_wgpu_backend_starts()?;
    let out = std::process::Command::new(std::env::current_exe().expect("this test binary"))
        .args(["--exact", "the_wgpu_backend_starts"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .expect("run this test binary again");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stdout}{stderr}");
    assert!(stdout.contains("1 passed"), "{stdout}");
    let errors: Vec<&str> = stdout
        .lines()
        .chain(stderr.lines())
        .filter(|l| l.starts_with("error"))
        .collect();
    assert!(errors.is_empty(), "a passing run printed: {errors:?}");
    Ok(())
}
