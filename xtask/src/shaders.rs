//! `cargo xtask shaders [--check]`: regenerates the committed SPIR-V of the GLSL shaders.
//!
//! Every `shaders/*.vert`, `*.geom`, `*.frag` and `*.comp` is compiled with `glslangValidator -V
//! --target-env vulkan1.1` to the file of the same name plus `.spv` (for example
//! `shaders/silhouette_gs.geom` → `shaders/silhouette_gs.geom.spv`). [`VARIANTS`] lists the extra
//! outputs compiled from the same source with preprocessor definitions (the f32-only geometry
//! shader for devices without `shaderFloat64`).
//!
//! With `--check` nothing is written: each shader is compiled into a temporary folder and the
//! command fails, listing the files, when a committed `.spv` is missing or differs from a fresh
//! compile (the header's generator word, which names the glslang build, is ignored).

use std::path::{Path, PathBuf};
use std::process::Command;

/// Extra outputs: (source file name in `shaders/`, output file name, `-D` definitions).
pub const VARIANTS: &[(&str, &str, &[&str])] = &[(
    "silhouette_gs.geom",
    "silhouette_gs.f32.geom.spv",
    &["SHADOWVOL_NO_F64"],
)];

/// GLSL stages compiled by this command, by file extension.
pub const STAGES: &[&str] = &["vert", "geom", "frag", "comp"];

/// One compilation job.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Job {
    /// The GLSL source.
    pub source: PathBuf,
    /// The committed SPIR-V it produces.
    pub output: PathBuf,
    /// Preprocessor definitions (`-D`).
    pub defines: Vec<String>,
}

/// The workspace's `shaders/` folder.
#[must_use]
pub fn shaders_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from("shaders"), |root| root.join("shaders"))
}

/// Lists the jobs for the shaders in `dir`, sorted by output name.
///
/// # Errors
/// When `dir` cannot be read, or a variant's source is missing.
pub fn jobs(dir: &Path) -> Result<Vec<Job>, String> {
    let entries =
        std::fs::read_dir(dir).map_err(|e| format!("cannot read {}: {e}", dir.display()))?;
    let mut jobs = Vec::new();
    for entry in entries {
        let path = entry
            .map_err(|e| format!("cannot read {}: {e}", dir.display()))?
            .path();
        let is_stage = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| STAGES.contains(&e));
        if !is_stage || !path.is_file() {
            continue;
        }
        let mut output = path.clone().into_os_string();
        output.push(".spv");
        jobs.push(Job {
            source: path,
            output: PathBuf::from(output),
            defines: Vec::new(),
        });
    }
    for (source, output, defines) in VARIANTS {
        let source = dir.join(source);
        if !source.is_file() {
            return Err(format!(
                "shader variant {output}: source {} is missing",
                source.display()
            ));
        }
        jobs.push(Job {
            source,
            output: dir.join(output),
            defines: defines.iter().map(|d| (*d).to_owned()).collect(),
        });
    }
    jobs.sort_by(|a, b| a.output.cmp(&b.output));
    Ok(jobs)
}

/// Compiles one job's source to `output` with glslangValidator.
///
/// # Errors
/// When glslangValidator is missing or reports an error (its log is included).
pub fn compile(job: &Job, output: &Path) -> Result<(), String> {
    let mut cmd = Command::new("glslangValidator");
    cmd.arg("-V").arg("--target-env").arg("vulkan1.1");
    for d in &job.defines {
        cmd.arg(format!("-D{d}"));
    }
    cmd.arg(&job.source).arg("-o").arg(output);
    let out = cmd.output().map_err(|e| {
        format!(
            "cannot run glslangValidator ({e}); install it (Debian/Ubuntu: apt-get install glslang-tools)"
        )
    })?;
    if !out.status.success() {
        return Err(format!(
            "glslangValidator failed on {}:\n{}{}",
            job.source.display(),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(())
}

/// SPIR-V equality ignoring the header's generator word (word 2).
#[must_use]
pub fn same_spirv(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() || a.len() < 20 {
        return a == b;
    }
    a[..8] == b[..8] && a[12..] == b[12..]
}

/// Runs `cargo xtask shaders [--check]`.
///
/// # Errors
/// On an unknown argument, a compile error, or (with `--check`) stale or missing SPIR-V.
pub fn run(args: &[String]) -> Result<(), String> {
    let mut check = false;
    for a in args {
        match a.as_str() {
            "--check" => check = true,
            "-h" | "--help" => {
                println!(
                    "cargo xtask shaders [--check]\n  regenerates shaders/*.{{vert,geom,frag,comp}}.spv with glslangValidator;\n  --check fails when a committed .spv is stale or missing"
                );
                return Ok(());
            }
            other => return Err(format!("xtask shaders: unknown argument {other:?}")),
        }
    }
    let dir = shaders_dir();
    let jobs = jobs(&dir)?;
    if jobs.is_empty() {
        return Err(format!("no GLSL shaders found in {}", dir.display()));
    }
    if !check {
        for job in &jobs {
            compile(job, &job.output)?;
            println!(
                "compiled {} -> {}",
                job.source.display(),
                job.output.display()
            );
        }
        return Ok(());
    }
    let tmp = std::env::temp_dir().join(format!("shadowvol-shaders-check-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).map_err(|e| format!("cannot create {}: {e}", tmp.display()))?;
    let result = check_all(&jobs, &tmp);
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

fn check_all(jobs: &[Job], tmp: &Path) -> Result<(), String> {
    let mut stale = Vec::new();
    for (i, job) in jobs.iter().enumerate() {
        let fresh_path = tmp.join(format!("{i}.spv"));
        compile(job, &fresh_path)?;
        let fresh = std::fs::read(&fresh_path)
            .map_err(|e| format!("cannot read {}: {e}", fresh_path.display()))?;
        match std::fs::read(&job.output) {
            Ok(committed) if same_spirv(&committed, &fresh) => {}
            Ok(_) => stale.push(format!("{} (stale)", job.output.display())),
            Err(_) => stale.push(format!("{} (missing)", job.output.display())),
        }
    }
    if stale.is_empty() {
        println!("{} SPIR-V files up to date", jobs.len());
        Ok(())
    } else {
        Err(format!(
            "SPIR-V out of date; run `cargo xtask shaders` and commit:\n  {}",
            stale.join("\n  ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generator_word_is_ignored_but_code_is_not() {
        let a: Vec<u8> = (0u8..40).collect();
        let mut b = a.clone();
        b[9] ^= 1; // generator word
        assert!(same_spirv(&a, &b));
        b[30] ^= 1;
        assert!(!same_spirv(&a, &b));
    }

    #[test]
    fn every_stage_source_has_a_job() {
        let jobs = jobs(&shaders_dir()).unwrap();
        assert!(jobs
            .iter()
            .any(|j| j.output.ends_with("silhouette_gs.geom.spv") && j.defines.is_empty()));
        assert!(jobs
            .iter()
            .any(|j| j.output.ends_with("silhouette_gs.f32.geom.spv") && !j.defines.is_empty()));
    }
}
