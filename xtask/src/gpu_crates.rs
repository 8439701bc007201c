//! The `gpu-crates` step of `cargo xtask test`: the GPU backend crates share one set of core
//! files, as wgpu-hal's backends do, so that a reader who knows one backend finds the same step
//! in the same file of the others.
//!
//! Every crate of [`CRATES`] must have each file of [`CORE`] in its `src/`, and at most
//! [`MAX_OWN`] entries of its own there besides (a module file, a module folder, or any other
//! file; `foo.rs` and `foo/` count once).

use std::collections::BTreeSet;
use std::path::Path;

/// The GPU backend crates, as folders under `crates/`.
pub const CRATES: [&str; 3] = ["wgpu-compute", "vulkan-geometry", "opencl"];

/// The core files every GPU backend crate has, and the role each plays.
pub const CORE: [(&str, &str); 8] = [
    (
        "lib.rs",
        "the public surface: crate docs, re-exports, NAME, create_backend",
    ),
    (
        "backend.rs",
        "the backend type and its SilhouetteBackend impl",
    ),
    (
        "device.rs",
        "start-up: the device, its limits, options, errors naming what is missing",
    ),
    (
        "layout.rs",
        "the prepared scene's device buffers, lights per batch",
    ),
    ("pipeline.rs", "shader modules or program, pipelines"),
    (
        "dispatch.rs",
        "one extract: upload, submit, bounded wait, readback",
    ),
    (
        "resolve.rs",
        "the host side: device output into Multiplicities, exact decisions",
    ),
    ("twin.rs", "the CPU twin of the kernels, for tests"),
];

/// Most entries of its own a GPU backend crate may have in `src/` besides [`CORE`].
pub const MAX_OWN: usize = 2;

/// Checks one crate's `src/` entries (file and folder names): every [`CORE`] file present, at
/// most [`MAX_OWN`] others. Returns the crate's own entries.
///
/// # Errors
/// A message naming the crate and the missing core files or the extra entries.
pub fn check_entries(krate: &str, entries: &[String]) -> Result<Vec<String>, String> {
    let present: BTreeSet<&str> = entries.iter().map(String::as_str).collect();
    let missing: Vec<&str> = CORE
        .iter()
        .map(|(file, _)| *file)
        .filter(|file| !present.contains(file))
        .collect();
    // Module names: `foo.rs` and the folder `foo/` are one module.
    let own: BTreeSet<String> = entries
        .iter()
        .filter(|e| !CORE.iter().any(|(file, _)| file == e))
        .map(|e| e.strip_suffix(".rs").unwrap_or(e).to_owned())
        .collect();
    let own: Vec<String> = own.into_iter().collect();
    let mut problems = Vec::new();
    if !missing.is_empty() {
        problems.push(format!("lacks the core file(s) {}", missing.join(", ")));
    }
    if own.len() > MAX_OWN {
        problems.push(format!(
            "has {} entries of its own ({}), at most {MAX_OWN} are allowed: fold them into the \
             core files",
            own.len(),
            own.join(", ")
        ));
    }
    if problems.is_empty() {
        Ok(own)
    } else {
        Err(format!("crates/{krate}/src {}", problems.join("; ")))
    }
}

/// Checks every crate of [`CRATES`] under `root` (the workspace). Returns one line per crate
/// naming its own entries.
///
/// # Errors
/// One line per crate that breaks the rule (or whose `src/` cannot be read).
pub fn check(root: &Path) -> Result<String, String> {
    let mut report = Vec::new();
    let mut errors = Vec::new();
    for krate in CRATES {
        let src = root.join("crates").join(krate).join("src");
        let entries = match std::fs::read_dir(&src) {
            Ok(dir) => dir
                .filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect::<Vec<_>>(),
            Err(e) => {
                errors.push(format!("cannot read {}: {e}", src.display()));
                continue;
            }
        };
        match check_entries(krate, &entries) {
            Ok(own) if own.is_empty() => report.push(format!("{krate}: the core files only")),
            Ok(own) => report.push(format!("{krate}: the core files and {}", own.join(", "))),
            Err(e) => errors.push(e),
        }
    }
    if errors.is_empty() {
        Ok(report.join("\n"))
    } else {
        Err(errors.join("\n"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(names: &[&str]) -> Vec<String> {
        names.iter().map(|n| (*n).to_owned()).collect()
    }

    fn core_and(extra: &[&str]) -> Vec<String> {
        let mut v: Vec<&str> = CORE.iter().map(|(file, _)| *file).collect();
        v.extend(extra);
        entries(&v)
    }

    #[test]
    fn core_files_and_two_own_pass() {
        assert_eq!(
            check_entries("x", &core_and(&[])).unwrap(),
            Vec::<String>::new()
        );
        assert_eq!(
            check_entries("x", &core_and(&["shaders.rs", "wait.rs"])).unwrap(),
            ["shaders", "wait"]
        );
        // A module file and its folder are one entry.
        assert_eq!(
            check_entries("x", &core_and(&["kernel.rs", "kernel", "wait.rs"])).unwrap(),
            ["kernel", "wait"]
        );
    }

    #[test]
    fn a_missing_core_file_fails() {
        let mut e = core_and(&[]);
        e.retain(|f| f != "resolve.rs" && f != "twin.rs");
        let err = check_entries("opencl", &e).unwrap_err();
        assert!(err.contains("crates/opencl/src"), "{err}");
        assert!(err.contains("resolve.rs, twin.rs"), "{err}");
    }

    #[test]
    fn a_third_own_entry_fails() {
        let err =
            check_entries("wgpu-compute", &core_and(&["a.rs", "b.rs", "c.wgsl"])).unwrap_err();
        assert!(err.contains("3 entries of its own (a, b, c.wgsl)"), "{err}");
    }

    #[test]
    fn the_workspace_follows_the_rule() {
        let report = check(&crate::project_root()).unwrap();
        assert_eq!(report.lines().count(), CRATES.len(), "{report}");
    }
}
