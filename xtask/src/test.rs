//! `cargo xtask test`: everything CI checks, in one command, with a summary.
//!
//! Steps (all run, even after a failure, so one run shows every problem):
//!
//! 1. **drivers** ([`crate::drivers`]): the Vulkan loader and Mesa's lavapipe ICD, the OpenCL
//!    ICD loader and PoCL, Mesa's EGL (the renderer's OpenGL test), `glslangValidator`, the
//!    Khronos Vulkan validation layer (the vulkan backend's validation test runs with it), Xvfb
//!    and the X11 client libraries (the viewer's window test). When one is missing and we are
//!    root, they are installed with apt-get; when we are not root, the exact command is printed
//!    and the run goes on (the GPU backends then skip visibly), unless `CI=true`, where a
//!    missing driver is a failure.
//! 2. **fmt**: `cargo fmt --all -- --check`.
//! 3. **size**: no file over 800 lines before its tests, no function body over 120 lines
//!    ([`crate::size`]); each offender is printed as `path:line`.
//! 4. **clippy**: `cargo clippy --workspace --all-targets -- -D warnings`.
//! 5. **docs**: `RUSTDOCFLAGS=-D warnings cargo doc --workspace --no-deps` (a broken intra-doc
//!    link or malformed doc comment fails; `-D warnings` is added to any `RUSTDOCFLAGS` set).
//! 6. **test**: `cargo test --workspace` (with `CI=true`, the conformance tests fail for a backend
//!    that cannot start instead of skipping it).
//! 7. **example**: `cargo run -p shadowvol-renderer --example embed -- OUT --check [--maps]`: the
//!    embedding example renders on its own device, once with volumes and once with shadow maps,
//!    and each image's shadows are checked against the ray-traced reference. Without a wgpu adapter it warns (a visible skip), under `CI=true` it
//!    fails.
//! 8. **bevy**: the Bevy plugin crate (`crates/bevy`, outside the workspace, Rust 1.97.1):
//!    toolchain installed with rustup as root or under CI; fmt, clippy, its headless tests on
//!    lavapipe, its `headless` example and its docs ([`crate::bevy`]). Without a Vulkan driver
//!    it warns (a visible skip), under `CI=true` it fails.
//! 9. **shaders**: `cargo xtask shaders --check` (the committed SPIR-V matches the GLSL).
//! 10. **gpu-crates**: every GPU backend crate has the core files and at most two of its own
//!     ([`crate::gpu_crates`]).
//! 11. **fuzz**: each fuzz target (`fuzz/`, its own workspace) built and run for [`FUZZ_SECONDS`]
//!     seconds on its seed corpus with `cargo fuzz run --dev --sanitizer none` (stable Rust is
//!     enough). A missing `cargo-fuzz` is installed with `cargo install` under CI or as root;
//!     otherwise the targets are only `cargo check`ed and the step says what to install and
//!     warns. Under CI a `cargo-fuzz` that still is not there fails the step.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// The steps, in the order they run (the names `--skip` takes).
const STEPS: [&str; 11] = [
    "drivers",
    "fmt",
    "size",
    "clippy",
    "docs",
    "test",
    "example",
    "bevy",
    "shaders",
    "gpu-crates",
    "fuzz",
];

/// Seconds each fuzz target runs in the `fuzz` step: enough to load and run its seeds and some
/// mutations, cheap on two cores.
const FUZZ_SECONDS: u32 = 4;

/// Bytes the fuzz targets' memory checks may plan for (`SHADOWVOL_MEMORY_LIMIT`): 1 GiB, below
/// libFuzzer's 2 GB RSS limit.
const FUZZ_MEMORY_LIMIT: u64 = 1 << 30;

/// The fuzz targets and their seed folders (relative to `fuzz/`), as in `fuzz/run_all.sh`.
const FUZZ_TARGETS: &[(&str, &[&str])] = &[
    (
        "obj_loader",
        &[
            "../crates/scenes/tests/data",
            "../crates/cli/tests/data/malformed",
            "../assets",
        ],
    ),
    (
        "gltf_loader",
        &[
            "../crates/scenes/tests/data",
            "../crates/cli/tests/data/malformed",
            "../crates/scenes/tests/data/real",
        ],
    ),
    ("stl_loader", &["../crates/scenes/tests/data/real"]),
    ("ply_loader", &["../crates/scenes/tests/data/real"]),
    ("meshopt_decode", &[]),
    ("draco_decode", &["seeds/draco_decode"]),
    ("topology", &[]),
    ("exact_predicate", &[]),
    ("pipeline", &[]),
    ("simd_differential", &[]),
];

const USAGE: &str =
    "cargo xtask test [--no-drivers] [--skip STEP]... [-p PACKAGE]... [-- CARGO_TEST_ARGS...]

Runs, in order, and prints a summary:
  drivers  check Vulkan loader + lavapipe, OpenCL loader + PoCL, glslangValidator;
           install them with apt-get when missing and running as root
  fmt      cargo fmt --all -- --check
  size     no file over 800 lines before its tests, no function body over 120 lines
           (crates/*/src, xtask/src, tests, benches); prints each offender as path:line
  clippy   cargo clippy --workspace --all-targets -- -D warnings
  docs     RUSTDOCFLAGS=\"-D warnings\" cargo doc --workspace --no-deps
  test     cargo test --workspace [CARGO_TEST_ARGS]
  example  cargo run -p shadowvol-renderer --example embed -- OUT --check [--maps]: the embedding
           example on its own device, its shadows checked against the ray-traced
           reference (a warning without a wgpu adapter; a failure under CI=true)
  bevy     the Bevy plugin (crates/bevy, Rust 1.97.1, its own target folder
           $SHADOWVOL_BEVY_TARGET_DIR or ~/.cache/shadowvol/bevy-target): rustup installs
           the toolchain as root or under CI; fmt, clippy, headless tests against the
           exact reference, the headless example, docs (a warning without the toolchain
           or a Vulkan driver; a failure under CI=true)
  shaders  cargo xtask shaders --check
  gpu-crates  every GPU backend crate (wgpu-compute, vulkan-geometry, opencl) has the
           core files (lib, backend, device, layout, pipeline, dispatch, resolve, twin)
           and at most two files of its own in src/
  fuzz     build and run each fuzz target a few seconds on its seeds (cargo fuzz run
           --dev --sanitizer none); cargo-fuzz is installed with cargo install when
           missing under CI or as root; otherwise the targets are only checked and the
           step says what to install (`cargo install cargo-fuzz`)

Options:
  --no-drivers   same as --skip drivers
  --skip STEP    skip a step (drivers, fmt, size, clippy, docs, test, example, bevy,
                 shaders, gpu-crates, fuzz); repeatable
  -p PACKAGE     clippy, docs and test only PACKAGE instead of --workspace; repeatable

Environment:
  CI=true        a missing driver, and a backend that cannot start, fail instead of skipping
                 (CI=1 and any case of true mean the same, as in every test)
";

/// Outcome of one step.
pub(crate) enum Outcome {
    Passed,
    Warned(String),
    Failed(String),
    Skipped,
}

struct Step {
    name: &'static str,
    outcome: Outcome,
    time: Duration,
}

/// The command line of `cargo xtask test`.
struct Options {
    /// Steps to skip.
    skip: Vec<String>,
    /// Arguments after `--`, for `cargo test`.
    test_args: Vec<String>,
    /// `-p` packages (empty: the workspace).
    packages: Vec<String>,
}

impl Options {
    /// Parses `args`; `None` for `--help`.
    fn parse(args: &[String]) -> Result<Option<Self>, String> {
        let mut o = Self {
            skip: Vec::new(),
            test_args: Vec::new(),
            packages: Vec::new(),
        };
        let mut it = args.iter();
        while let Some(a) = it.next() {
            match a.as_str() {
                "-h" | "--help" => return Ok(None),
                "--no-drivers" => o.skip.push("drivers".into()),
                "--skip" => {
                    let step = it.next().ok_or("--skip needs a step name")?;
                    if !STEPS.contains(&step.as_str()) {
                        return Err(format!("unknown step {step:?} for --skip\n\n{USAGE}"));
                    }
                    o.skip.push(step.clone());
                }
                "-p" | "--package" => {
                    o.packages
                        .push(it.next().ok_or("-p needs a package name")?.clone());
                }
                "--" => o.test_args.extend(it.by_ref().cloned()),
                other => return Err(format!("unknown argument {other:?}\n\n{USAGE}")),
            }
        }
        Ok(Some(o))
    }
}

/// Runs `cargo xtask test`.
///
/// # Errors
/// When an argument is unknown or any step failed (after all steps ran).
pub fn run(args: &[String]) -> Result<(), String> {
    let Some(Options {
        skip,
        test_args,
        packages,
    }) = Options::parse(args)?
    else {
        print!("{USAGE}");
        return Ok(());
    };
    let root = crate::project_root();
    let ci = crate::ci::is_ci();
    println!("xtask test: workspace {}, CI={ci}", root.display());

    // `--workspace`, or `-p A -p B` when packages were named.
    let scope: Vec<String> = if packages.is_empty() {
        vec!["--workspace".to_owned()]
    } else {
        packages
            .iter()
            .flat_map(|p| ["-p".to_owned(), p.clone()])
            .collect()
    };
    let scope: Vec<&str> = scope.iter().map(String::as_str).collect();
    let mut steps = Vec::new();
    let mut step = |name: &'static str, f: &mut dyn FnMut() -> Outcome| {
        if skip.iter().any(|s| s == name) {
            steps.push(Step {
                name,
                outcome: Outcome::Skipped,
                time: Duration::ZERO,
            });
            return;
        }
        println!("\n==> {name}");
        let start = Instant::now();
        let outcome = f();
        steps.push(Step {
            name,
            outcome,
            time: start.elapsed(),
        });
    };

    step("drivers", &mut || crate::drivers::drivers(ci));
    step("fmt", &mut || {
        cargo_step(&root, &["fmt", "--all", "--", "--check"], &[])
    });
    step("size", &mut || match crate::size::check(&root) {
        Ok(()) => Outcome::Passed,
        Err(e) => Outcome::Failed(e),
    });
    step("clippy", &mut || {
        let mut a = vec!["clippy"];
        a.extend(&scope);
        a.extend(["--all-targets", "--", "-D", "warnings"]);
        cargo_step(&root, &a, &[])
    });
    step("docs", &mut || {
        let mut a = vec!["doc"];
        a.extend(&scope);
        a.push("--no-deps");
        let flags = rustdocflags(std::env::var("RUSTDOCFLAGS").ok().as_deref());
        cargo_step(&root, &a, &[("RUSTDOCFLAGS", &flags)])
    });
    let mut counts = TestCounts::default();
    step("test", &mut || {
        // --no-fail-fast: one failing test binary must not hide the others' results.
        let mut a = vec!["test", "--no-fail-fast"];
        a.extend(&scope);
        if !test_args.is_empty() {
            a.push("--");
            a.extend(test_args.iter().map(String::as_str));
        }
        cargo_test_step(&root, &a, &mut counts)
    });
    step("example", &mut || embed_example(&root, ci));
    step("bevy", &mut || {
        crate::bevy::step(&root, ci, crate::drivers::is_root())
    });
    step(
        "shaders",
        &mut || match crate::shaders::run(&["--check".to_owned()]) {
            Ok(()) => Outcome::Passed,
            Err(e) => Outcome::Failed(e),
        },
    );
    step(
        "gpu-crates",
        &mut || match crate::gpu_crates::check(&root) {
            Ok(report) => {
                println!("{report}");
                Outcome::Passed
            }
            Err(e) => Outcome::Failed(e),
        },
    );
    step("fuzz", &mut || fuzz(&root, ci));

    let failed = print_summary(&steps, &counts);
    if failed == 0 {
        Ok(())
    } else {
        Err(format!("{failed} step(s) failed"))
    }
}

/// Prints each step's outcome and time, the step counts, and the test counts with every skip
/// and its reason; returns the number of failed steps.
fn print_summary(steps: &[Step], counts: &TestCounts) -> usize {
    println!("\n==> summary");
    let mut failed = 0;
    for s in steps {
        let (word, detail) = match &s.outcome {
            Outcome::Passed => ("ok", String::new()),
            Outcome::Warned(w) => ("WARN", w.clone()),
            Outcome::Failed(e) => {
                failed += 1;
                ("FAILED", e.clone())
            }
            Outcome::Skipped => ("skipped", String::new()),
        };
        let first_line = detail.lines().next().unwrap_or("");
        println!(
            "  {:10} {:8} {:>8.1} s  {first_line}",
            s.name,
            word,
            s.time.as_secs_f64()
        );
    }
    let passed = steps
        .iter()
        .filter(|s| matches!(s.outcome, Outcome::Passed | Outcome::Warned(_)))
        .count();
    let skipped = steps
        .iter()
        .filter(|s| matches!(s.outcome, Outcome::Skipped))
        .count();
    println!("xtask steps: {passed} passed, {failed} failed, {skipped} skipped");
    if counts.binaries > 0 {
        println!(
            "({} test binaries; ignored tests are visible skips, listed with their reason)",
            counts.binaries
        );
        println!(
            "tests: {} passed, {} failed, {} skipped",
            counts.passed, counts.failed, counts.ignored
        );
        for (name, why) in &counts.skips {
            println!("  skipped {name}: {why}");
        }
    }
    failed
}

/// `RUSTDOCFLAGS` for the docs step: the caller's, then `-D warnings`.
fn rustdocflags(current: Option<&str>) -> String {
    match current.map(str::trim) {
        Some(c) if !c.is_empty() => format!("{c} -D warnings"),
        _ => "-D warnings".to_owned(),
    }
}

/// Runs `cargo ARGS` in the workspace root, streaming its output.
fn cargo_step(root: &Path, args: &[&str], env: &[(&str, &str)]) -> Outcome {
    let vars: String = env.iter().map(|(k, v)| format!("{k}={v:?} ")).collect();
    let line = format!("{vars}cargo {}", args.join(" "));
    println!("$ {line}");
    let mut cmd = Command::new(crate::cargo());
    cmd.current_dir(root).args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    match cmd.status() {
        Ok(s) if s.success() => Outcome::Passed,
        Ok(s) => Outcome::Failed(format!("`{line}` failed ({s})")),
        Err(e) => Outcome::Failed(format!("cannot run `{line}`: {e}")),
    }
}

/// The `example` step: the embedding example, run as a user runs it, with `--check`, with the
/// volumes and then with `--maps`.
fn embed_example(root: &Path, ci: bool) -> Outcome {
    for (png, extra) in [
        ("embed-example.png", None),
        ("embed-example-maps.png", Some("--maps")),
    ] {
        let outcome = embed_example_run(root, ci, png, extra);
        if !matches!(outcome, Outcome::Passed) {
            return outcome;
        }
    }
    Outcome::Passed
}

/// One run of the embedding example, writing `png` in the target folder, with `extra`.
fn embed_example_run(root: &Path, ci: bool, png: &str, extra: Option<&str>) -> Outcome {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| root.join("target"), std::path::PathBuf::from);
    let out = target.join(png);
    let out = out.to_string_lossy();
    let mut args = vec![
        "run",
        "-p",
        "shadowvol-renderer",
        "--example",
        "embed",
        "--",
        &out,
        "--check",
    ];
    args.extend(extra);
    let line = format!("cargo {}", args.join(" "));
    println!("$ {line}");
    let output = match Command::new(crate::cargo())
        .current_dir(root)
        .args(args)
        .output()
    {
        Ok(o) => o,
        Err(e) => return Outcome::Failed(format!("cannot run `{line}`: {e}")),
    };
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    print!("{stdout}");
    eprint!("{stderr}");
    example_outcome(output.status.success(), &stderr, ci, &line)
}

/// How the example's exit reads: a missing adapter is a warning outside CI (the GPU tests skip
/// visibly for the same reason), every other failure fails the step, and so does a successful
/// run that printed a line starting with `error` (a newcomer reads it as a failure: Mesa's
/// `error: XDG_RUNTIME_DIR ...` without a display, which `NODEVICE_SELECT` now silences).
fn example_outcome(success: bool, stderr: &str, ci: bool, line: &str) -> Outcome {
    if success {
        return match stderr.lines().find(|l| l.starts_with("error")) {
            Some(error) => {
                Outcome::Failed(format!("`{line}` succeeded but printed `{}`", error.trim()))
            }
            None => Outcome::Passed,
        };
    }
    let no_adapter = stderr.lines().find(|l| l.contains("no GPU adapter"));
    match no_adapter {
        Some(why) if !ci => Outcome::Warned(format!(
            "the embed example did not run ({}); install a Vulkan driver: {}",
            why.trim(),
            crate::drivers::install_command()
        )),
        _ => Outcome::Failed(format!(
            "`{line}` failed: {}",
            stderr.lines().last().unwrap_or("").trim()
        )),
    }
}

/// Totals of the `test result:` lines of every test binary, and the ignored tests by name.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
struct TestCounts {
    binaries: u64,
    passed: u64,
    failed: u64,
    ignored: u64,
    /// `(test, reason)` of every ignored test: a visible skip (libtest-mimic prints
    /// `test NAME ... ignored (REASON)`, libtest `test NAME ... ignored, REASON`).
    skips: Vec<(String, String)>,
}

impl TestCounts {
    /// Adds one line of a test binary's output: an ignored test's line, or a summary line
    /// (`test result: ok. 3 passed; 0 failed; 1 ignored; ...`); other lines are left alone.
    fn add_line(&mut self, line: &str) {
        if let Some((name, outcome)) = line
            .trim()
            .strip_prefix("test ")
            .and_then(|r| r.split_once(" ... "))
        {
            if let Some(why) = outcome.trim().strip_prefix("ignored") {
                let why = why.trim();
                let why = why
                    .strip_prefix('(')
                    .and_then(|w| w.strip_suffix(')'))
                    .or_else(|| why.strip_prefix(", "))
                    .unwrap_or(why);
                self.skips.push((name.trim().to_owned(), why.to_owned()));
            }
            return;
        }
        let Some(rest) = line.trim().strip_prefix("test result: ") else {
            return;
        };
        self.binaries += 1;
        for part in rest.split(';') {
            let mut words = part.split_whitespace().rev();
            let (Some(what), Some(n)) = (words.next(), words.next()) else {
                continue;
            };
            let Ok(n) = n.parse::<u64>() else { continue };
            match what {
                "passed" => self.passed += n,
                "failed" => self.failed += n,
                "ignored" => self.ignored += n,
                _ => {}
            }
        }
    }
}

/// Runs `cargo test ...`, streaming its output and adding up the `test result:` lines.
fn cargo_test_step(root: &Path, args: &[&str], counts: &mut TestCounts) -> Outcome {
    use std::io::BufRead;
    let line = format!("cargo {}", args.join(" "));
    println!("$ {line}");
    let child = Command::new(crate::cargo())
        .current_dir(root)
        .args(args)
        .stdout(std::process::Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => return Outcome::Failed(format!("cannot run `{line}`: {e}")),
    };
    if let Some(out) = child.stdout.take() {
        for l in std::io::BufReader::new(out).lines().map_while(Result::ok) {
            println!("{l}");
            counts.add_line(&l);
        }
    }
    match child.wait() {
        Ok(s) if s.success() => Outcome::Passed,
        Ok(s) => Outcome::Failed(format!("`{line}` failed ({s})")),
        Err(e) => Outcome::Failed(format!("cannot wait for `{line}`: {e}")),
    }
}

/// Whether `cargo fuzz` can run here.
fn cargo_fuzz_available() -> bool {
    Command::new(crate::cargo())
        .args(["fuzz", "--version"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The `fuzz` step: the targets must compile, and each must run its seeds without a crash.
fn fuzz(root: &Path, ci: bool) -> Outcome {
    let dir = root.join("fuzz");
    if !cargo_fuzz_available() && (ci || crate::drivers::is_root()) {
        // Like the drivers: installed where CI or root runs, so a fresh machine needs nothing.
        println!("$ cargo install cargo-fuzz --locked");
        let installed = Command::new(crate::cargo())
            .args(["install", "cargo-fuzz", "--locked"])
            .status()
            .is_ok_and(|s| s.success());
        if !installed {
            eprintln!("cargo install cargo-fuzz failed");
        }
    }
    if !cargo_fuzz_available() {
        // At least the targets must compile.
        let manifest = dir.join("Cargo.toml");
        let manifest = manifest.to_string_lossy();
        let check = ["check", "--manifest-path", &manifest, "--bins"];
        if let Outcome::Failed(e) = cargo_step(root, &check, &[]) {
            return Outcome::Failed(e);
        }
        let msg = "cargo-fuzz is not installed, so the fuzz targets were only checked: \
                   install it with `cargo install cargo-fuzz` (stable Rust is enough)";
        return if ci {
            Outcome::Failed(format!("{msg} (CI is set, so this fails)"))
        } else {
            Outcome::Warned(msg.to_owned())
        };
    }
    // Every target built first (a debug build: cheaper than release, and more than `cargo
    // check`), so that a target that does not compile is reported as such, not as a crash.
    println!("$ (cd fuzz && cargo fuzz build --dev --sanitizer none)");
    match Command::new(crate::cargo())
        .current_dir(&dir)
        .args(["fuzz", "build", "--dev", "--sanitizer", "none"])
        .status()
    {
        Ok(s) if s.success() => {}
        Ok(s) => {
            return Outcome::Failed(format!(
                "the fuzz targets do not build ({s}; the compiler's errors are above)"
            ))
        }
        Err(e) => return Outcome::Failed(format!("cannot run cargo fuzz build: {e}")),
    }
    // New inputs go to a scratch corpus per target (libFuzzer writes to the first folder), so
    // the seed folders stay as they are.
    let scratch = std::env::temp_dir().join(format!("shadowvol-fuzz-{}", std::process::id()));
    let mut failures = Vec::new();
    for (target, seeds) in FUZZ_TARGETS {
        let corpus = scratch.join(target);
        if let Err(e) = std::fs::create_dir_all(&corpus) {
            return Outcome::Failed(format!("cannot create {}: {e}", corpus.display()));
        }
        let corpus = corpus.to_string_lossy().into_owned();
        let time = format!("-max_total_time={FUZZ_SECONDS}");
        let mut args = vec![
            "fuzz",
            "run",
            "--dev",
            "--sanitizer",
            "none",
            target,
            &corpus,
        ];
        args.extend(seeds.iter().copied());
        args.extend(["--", &time]);
        println!("$ (cd fuzz && cargo {})", args.join(" "));
        // libFuzzer stops at 2 GB of RSS; the loaders' memory checks get a smaller budget, so
        // an input that declares a huge allocation is refused with an error, as it would be on a
        // machine without that much memory.
        let status = Command::new(crate::cargo())
            .current_dir(&dir)
            .args(&args)
            .env("SHADOWVOL_MEMORY_LIMIT", FUZZ_MEMORY_LIMIT.to_string())
            .status();
        match status {
            Ok(s) if s.success() => {}
            Ok(s) => failures.push(format!(
                "{target} ({s}; the input is in fuzz/artifacts/{target}/)"
            )),
            Err(e) => failures.push(format!("{target}: cannot run cargo fuzz: {e}")),
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    if failures.is_empty() {
        Outcome::Passed
    } else {
        Outcome::Failed(format!("fuzz targets failed: {}", failures.join("; ")))
    }
}

#[cfg(test)]
mod tests {
    use super::{example_outcome, rustdocflags, Outcome, TestCounts, FUZZ_TARGETS, STEPS, USAGE};

    #[test]
    fn every_fuzz_target_is_run_and_its_seeds_exist() {
        let fuzz = crate::project_root().join("fuzz");
        let manifest = std::fs::read_to_string(fuzz.join("Cargo.toml")).unwrap();
        let bins = manifest
            .lines()
            .filter_map(|l| l.trim().strip_prefix("name = \""))
            .filter_map(|l| l.strip_suffix('"'))
            .filter(|n| *n != "shadowvol-fuzz")
            .collect::<Vec<_>>();
        assert!(bins.len() >= 9, "{bins:?}");
        for b in &bins {
            assert!(
                FUZZ_TARGETS.iter().any(|(t, _)| t == b),
                "fuzz target {b} is not run by the fuzz step"
            );
        }
        for (t, seeds) in FUZZ_TARGETS {
            assert!(bins.contains(t), "{t} is not a fuzz target");
            for s in *seeds {
                assert!(fuzz.join(s).is_dir(), "{t}: no seed folder {s}");
            }
        }
    }

    #[test]
    fn docs_step_denies_warnings_on_top_of_the_callers_flags() {
        assert_eq!(rustdocflags(None), "-D warnings");
        assert_eq!(rustdocflags(Some(" ")), "-D warnings");
        assert_eq!(
            rustdocflags(Some("--cfg docsrs")),
            "--cfg docsrs -D warnings"
        );
    }

    #[test]
    fn the_example_skips_only_for_a_missing_adapter_and_never_under_ci() {
        let no_gpu = "embed: no GPU adapter: no adapter found\n";
        assert!(matches!(
            example_outcome(true, "", true, "x"),
            Outcome::Passed
        ));
        assert!(matches!(
            example_outcome(false, no_gpu, false, "x"),
            Outcome::Warned(w) if w.contains("no GPU adapter") && w.contains("apt-get")
        ));
        assert!(matches!(
            example_outcome(false, no_gpu, true, "x"),
            Outcome::Failed(_)
        ));
        let mesa = "error: XDG_RUNTIME_DIR is invalid or not set in the environment.\n";
        assert!(matches!(
            example_outcome(true, mesa, false, "x"),
            Outcome::Failed(e) if e.contains("XDG_RUNTIME_DIR")
        ));
        let artifacts = "embed: 900 artifact pixels against the reference: over 0.05 %\n";
        assert!(matches!(
            example_outcome(false, artifacts, false, "x"),
            Outcome::Failed(e) if e.contains("900 artifact pixels")
        ));
    }

    #[test]
    fn every_step_is_in_the_usage() {
        for s in STEPS {
            assert!(
                USAGE
                    .lines()
                    .any(|l| l.trim_start().starts_with(&format!("{s} "))),
                "step {s} is not listed in the usage"
            );
        }
    }

    #[test]
    fn libtest_summaries_are_added_up() {
        let mut c = TestCounts::default();
        c.add_line("test result: ok. 74 passed; 0 failed; 288 ignored; 0 measured; 0 filtered out; finished in 0.01s");
        c.add_line("running 3 tests");
        c.add_line("test a_test   ... ignored (opencl backend unavailable: no platform)");
        c.add_line("test b_test ... ignored, needs the assets");
        c.add_line("test c_test ... ok");
        c.add_line(
            "test result: FAILED. 1 passed; 2 failed; 0 ignored; 0 measured; 0 filtered out",
        );
        assert_eq!(
            c,
            TestCounts {
                binaries: 2,
                passed: 75,
                failed: 2,
                ignored: 288,
                skips: vec![
                    (
                        "a_test".into(),
                        "opencl backend unavailable: no platform".into()
                    ),
                    ("b_test".into(), "needs the assets".into()),
                ],
            }
        );
    }
}
