//! `shadowvol view` in a real window: under Xvfb on this machine's Vulkan driver, `--frames`
//! renders, writes a screenshot whose shadow matches `render` of the same camera and light, and
//! reports; without a display it exits 1 naming DISPLAY and WAYLAND_DISPLAY.

mod common;

use common::BIN;
use shadowvol_test_support::{main, skip, Outcome, Skip};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

main!(
    view_under_xvfb_matches_render,
    view_with_maps_matches_render_with_maps,
    view_without_a_display_exits_1_naming_the_variables
);

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shadowvol-view-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn mesh() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/tests/data/real/reference.obj")
        .display()
        .to_string()
}

/// A virtual X server for the test's lifetime.
struct Xvfb {
    child: Child,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts Xvfb on a free display, or a visible skip when it is not installed; under CI a
/// missing Xvfb fails the test ([`shadowvol_test_support::skip`]).
fn xvfb() -> Result<Xvfb, Skip> {
    let found = Command::new("Xvfb")
        .arg("-help")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok();
    if !found {
        return Err(skip("Xvfb is not installed (Debian: apt-get install xvfb)"));
    }
    for n in 0..20 {
        let num = 60 + (std::process::id() as usize + n * 7) % 400;
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{num}"));
        if socket.exists() || Path::new(&format!("/tmp/.X{num}-lock")).exists() {
            continue;
        }
        let child = Command::new("Xvfb")
            .args([
                &format!(":{num}"),
                "-screen",
                "0",
                "1024x768x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start Xvfb");
        let x = Xvfb {
            child,
            display: format!(":{num}"),
        };
        let t = Instant::now();
        while t.elapsed() < Duration::from_secs(10) {
            if socket.exists() {
                return Ok(x);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    panic!("Xvfb did not start on any display");
}

fn rgba(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

fn view_under_xvfb_matches_render() -> Outcome {
    view_matches_render("xvfb", &[], "gpu")
}

/// With `--shadows map` the view draws with the map pipeline, as `render --shadows map` does.
fn view_with_maps_matches_render_with_maps() -> Outcome {
    view_matches_render("xvfb-maps", &["--shadows", "map"], "map")
}

/// `view MESH EXTRA --frames 5 --screenshot` under Xvfb reports `pipeline` and shows what
/// `render MESH EXTRA` draws.
fn view_matches_render(name: &str, extra: &[&str], pipeline: &str) -> Outcome {
    let x = xvfb()?;
    let dir = scratch(name);
    let shot = dir.join("shot.png");
    let out = Command::new(BIN)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .args([
            "view",
            &mesh(),
            "--size",
            "256x192",
            "--frames",
            "5",
            "--format",
            "json",
        ])
        .args(extra)
        .arg("--screenshot")
        .arg(&shot)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    if !out.status.success() {
        common::no_adapter("view", &stderr)?;
    }
    assert!(out.status.success(), "view failed:\n{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["frames"], 5, "{v}");
    // The view and the render below run the same pipeline.
    assert_eq!(v["pipeline"], pipeline, "{v}");
    assert!(v["fps"].as_f64().unwrap() > 0.0 && v["median_ms"].as_f64().unwrap() > 0.0);
    assert!(!v["adapter"].as_str().unwrap().is_empty());
    assert_eq!(
        v["screenshot"].as_str().unwrap(),
        shot.display().to_string()
    );
    eprintln!("view under Xvfb: {v}");

    let reference = dir.join("render.png");
    let r = common::run(
        &[
            &[
                "render",
                &mesh(),
                "--size",
                "256x192",
                "--out",
                reference.to_str().unwrap(),
            ][..],
            extra,
        ]
        .concat(),
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let (a, b) = (rgba(&shot), rgba(&reference));
    assert_eq!(a.dimensions(), b.dimensions());
    let differing = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 8))
        .count();
    let total = (a.width() * a.height()) as usize;
    // The orbit camera rebuilds the eye from angles in f32, so a few edge pixels may move.
    assert!(
        differing * 200 <= total,
        "{differing} of {total} pixels differ between view and render"
    );
    // The shadow is there: pixels darker than the lit ground.
    let dark = a
        .pixels()
        .filter(|p| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]) < 200)
        .count();
    assert!(
        dark > total / 100,
        "no shadow in the screenshot ({dark} dark pixels)"
    );
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

fn view_without_a_display_exits_1_naming_the_variables() -> Outcome {
    let out = Command::new(BIN)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .args(["view", &mesh(), "--frames", "1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("DISPLAY") && stderr.contains("WAYLAND_DISPLAY"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
    Ok(())
}
