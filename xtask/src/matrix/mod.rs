//! `cargo xtask matrix`: the paper's experiment matrix on every available backend.
//!
//! It builds the release CLI once and drives it as a subprocess through its JSON contract
//! (`shadowvol backends | bench | accuracy | baselines | render --format json`), so what it
//! measures is exactly what a user gets from `cargo build --release`. Every record carries the
//! host, the CPU, the SIMD level, rustc, the git revision, the flags and the device of its
//! backend.
//!
//! Output in `--out DIR` (default `matrix-out`): `tables.md`, `results.json`, `results.csv` and
//! PNG plots (`time_vs_triangles.png`, `time_vs_lights.png`, `accuracy_cost.png`,
//! `individual_vs_baked.png`, `maps_vs_volumes.png`, `memory_per_triangle.png`,
//! `soft_error_vs_time.png`).
//!
//! Where things are, from the command line to the files:
//! - [`args`]: the command line;
//! - [`plan`]: which scenes each table uses, and what one run measures;
//! - [`runner`]: the CLI as a subprocess, the host, one record per measurement ([`progress`]:
//!   the progress bar; [`maps`]: the volumes-against-maps renders; [`soft`]: the soft-shadow
//!   renders);
//! - [`cli`]: the JSON the CLI prints, typed; [`records`]: the matrix's records and
//!   `results.json`, typed;
//! - [`tables`]: `tables.md`; [`csv`]: `results.csv`; the plots are in `crate::plots`.

mod args;
mod cli;
mod csv;
mod maps;
pub(crate) mod maps_table;
mod memory;
pub(crate) mod memory_table;
mod plan;
mod progress;
pub(crate) mod records;
mod runner;
mod soft;
pub(crate) mod soft_table;
mod tables;

#[cfg(test)]
mod soft_tests;
#[cfg(test)]
mod tests;

use args::MODES;
use cli::BackendRow;
use progress::Progress;
use records::{Results, Unavailable};
use runner::{Cli, Matrix};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Entry point of `cargo xtask matrix`.
///
/// # Errors
/// A message when the build fails, the CLI is missing, or the output cannot be written. A
/// backend that fails during a measurement is recorded as a failed record and reported, not
/// fatal.
pub fn run(args: &[String]) -> Result<(), String> {
    let Some(opts) = args::parse_args(args)? else {
        return Ok(());
    };
    let root = crate::project_root();
    if let Some(dir) = &opts.replot {
        return replot(dir);
    }
    let started = Instant::now();
    eprintln!("matrix: building the release CLI (cargo build --release -p shadowvol)");
    let status = Command::new(crate::cargo())
        .current_dir(&root)
        .args(["build", "--release", "-p", "shadowvol"])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err("cargo build --release -p shadowvol failed".into());
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let cli = Cli {
        bin: target.join("release").join("shadowvol"),
        root: root.clone(),
    };
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| format!("cannot create {}: {e}", opts.out.display()))?;
    std::fs::create_dir_all(opts.out.join("renders"))
        .map_err(|e| format!("cannot create {}/renders: {e}", opts.out.display()))?;

    let mut results = Results {
        host: runner::host_info(&root),
        command: std::iter::once("cargo xtask matrix".to_owned())
            .chain(args.iter().cloned())
            .collect::<Vec<_>>()
            .join(" "),
        warmup: Some(opts.warmup),
        quick: opts.quick,
        frames: opts.frames,
        ..Results::default()
    };
    let all: Vec<BackendRow> = cli.json(&["backends", "--format", "json"])?;
    select_backends(&all, opts.backends.as_deref(), &mut results)?;
    eprintln!("matrix: backends: {}", results.backends.join(", "));
    runner::probe_build(&cli, &mut results.host);

    let scenes = runner::scene_names(&cli)?;
    let plan = plan::Plan::new(&opts, &results.backends, &scenes);
    let mut m = Matrix {
        cli,
        opts: opts.clone(),
        results,
        progress: Progress::new(plan.steps()),
    };
    m.run_plan(&plan);
    m.progress.finish();

    let mut results = m.results;
    results.elapsed_s = started.elapsed().as_secs_f64();
    write_outputs(&opts.out, &results, &opts.modes)?;
    eprintln!(
        "matrix: done in {:.0} s; {} records, {} failures; see {}",
        results.elapsed_s,
        results.records.len(),
        results.failures.len(),
        opts.out.join("tables.md").display()
    );
    Ok(())
}

/// Splits the CLI's backends into available (with their devices) and unavailable ones, keeping
/// those named in `--backends` (all without it).
///
/// # Errors
/// When `--backends` names a backend the build lacks, or none is available.
fn select_backends(
    all: &[BackendRow],
    wanted: Option<&[String]>,
    results: &mut Results,
) -> Result<(), String> {
    for b in all {
        if wanted.is_some_and(|w| !w.contains(&b.name)) {
            continue;
        }
        if b.available {
            let device = b.device.clone().unwrap_or_default();
            results.devices.insert(b.name.clone(), device);
            results.backends.push(b.name.clone());
        } else {
            let reason = b.reason.clone().unwrap_or_else(|| "unknown".into());
            eprintln!("matrix: backend {} is unavailable: {reason}", b.name);
            results.unavailable.push(Unavailable {
                name: b.name.clone(),
                reason,
            });
        }
    }
    for s in wanted.unwrap_or_default() {
        if !all.iter().any(|b| b.name == *s) {
            return Err(format!("--backends: no backend named {s:?} in this build"));
        }
    }
    if results.backends.is_empty() {
        return Err("no backend is available".into());
    }
    Ok(())
}

/// `--replot DIR`: rebuilds the tables, CSV and plots from `DIR/results.json`.
fn replot(dir: &Path) -> Result<(), String> {
    let path = dir.join("results.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let results: Results = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a matrix results file: {e}", path.display()))?;
    let modes: Vec<String> = MODES
        .iter()
        .filter(|m| results.records.iter().any(|r| r.mode() == Some(**m)))
        .map(|m| (*m).to_owned())
        .collect();
    write_derived(dir, &results, &modes)?;
    eprintln!(
        "matrix: rewrote the tables, CSV and plots in {}",
        dir.display()
    );
    Ok(())
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Writes `results.json`, then what is derived from it.
fn write_outputs(out: &Path, results: &Results, modes: &[String]) -> Result<(), String> {
    // Through a Value (a sorted map): the records' fields in name order, and a record's own
    // field wins over a host field of the same name.
    let json = serde_json::to_value(results)
        .and_then(|v| serde_json::to_string_pretty(&v))
        .map_err(|e| format!("results.json: {e}"))?;
    write(&out.join("results.json"), &json)?;
    write_derived(out, results, modes)
}

/// Writes what is derived from the records: CSV, tables and plots.
fn write_derived(out: &Path, results: &Results, modes: &[String]) -> Result<(), String> {
    let csv = csv::to_csv(&results.records).map_err(|e| format!("results.csv: {e}"))?;
    write(&out.join("results.csv"), &csv)?;
    write(&out.join("tables.md"), &tables::tables(results, modes))?;
    crate::plots::all(out, &results.records).map_err(|e| format!("plots: {e}"))?;
    Ok(())
}
