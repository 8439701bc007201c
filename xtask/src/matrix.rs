//! `cargo xtask matrix`: the paper's experiment matrix on every available backend.
//!
//! It builds the release CLI once and drives it as a subprocess through its JSON contract
//! (`shadowvol backends | bench | accuracy | render --format json`), so what it measures is
//! exactly what a user gets from `cargo build --release`. Every record carries the host, the
//! CPU, the SIMD level, rustc, the git revision, the flags and the device of its backend.
//!
//! Output in `--out DIR` (default `matrix-out`): `tables.md`, `results.json`, `results.csv` and
//! PNG plots (`time_vs_triangles.png`, `time_vs_lights.png`, `accuracy_cost.png`,
//! `individual_vs_baked.png`).

use serde_json::{json, Map, Value};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const USAGE: &str = "\
cargo xtask matrix [--quick] [--out DIR] [--backends LIST] [--modes LIST] [--frames N]

Runs the paper's experiment matrix with the release `shadowvol` binary on every available
backend and writes DIR/tables.md, DIR/results.json, DIR/results.csv and PNG plots.

  --quick          every table and scene, fewer frames and smaller images (about 10 minutes on a
                   2-core machine with lavapipe and PoCL)
  --out DIR        output folder (default: matrix-out)
  --backends LIST  comma-separated backend names (default: all available)
  --modes LIST     comma-separated accuracy modes (default: original,robust,ordered,exact)
  --frames N       timed frames per measurement (default: 30, or 5 with --quick)
  --replot DIR     measure nothing: rewrite DIR/tables.md, DIR/results.csv and the plots from
                   DIR/results.json (after a change to the tables or plots)
";

/// The accuracy modes in table order.
const MODES: [&str; 4] = ["original", "robust", "ordered", "exact"];

/// Table 1 of the paper: FPS robust / original, 2013 hardware (GPU columns: GF650Ti, AMD7950,
/// HD3000, HD4000), ~10^5-10^6 triangles.
const PAPER_T1: &str = "\
| platform | GF650Ti | AMD7950 | HD3000 | HD4000 |
|---|---|---|---|---|
| CPU | 4.9 / 5.0 | 12.9 / 13.9 | 9.9 / 11.2 | 6.3 / 5.9 |
| AVX+OMP | 4.9 / 5.1 | 11.8 / 13.5 | 10.0 / 12.4 | 6.6 / 8.6 |
| GS | 30 / 40 | 92 / 98 | n/a | 4.4 / 8.7 |
| OpenCL | 42 / 41 | 83 / 80 | n/a | 7.6 / 7.7 |
";

/// Table 2 of the paper (FPS, robust): individual bunnies / baked bunnies / individual spheres /
/// baked spheres, ~6.5*10^5 triangles.
const PAPER_T2: &str = "\
| platform | scene | GF650Ti | AMD7950 | HD3000 | HD4000 |
|---|---|---|---|---|---|
| CPU | bunnies ind. / baked | 4.9 / 5.0 | 12.9 / 7.8 | 9.9 / 11.0 | 6.3 / 5.4 |
| CPU | spheres ind. / baked | 5.5 / 5.5 | 13.3 / 9.6 | 12.2 / 10 | 9.6 / 5.5 |
| AVX+OMP | bunnies ind. / baked | 4.9 / 5.1 | 12.9 / 4.3 | 9.9 / 6.2 | 6.3 / 6.0 |
| AVX+OMP | spheres ind. / baked | 5.5 / 5.5 | 12.8 / 5.2 | 12.8 / 5.1 | 11.9 / 6.2 |
| GS | bunnies ind. / baked | 30 / 30 | 92 / 95 | n/a | 4.4 / n/a |
| GS | spheres ind. / baked | 34 / 34 | 156 / 124 | n/a | 6.0 / n/a |
| OpenCL | bunnies ind. / baked | 42 / 52 | 83 / 96 | n/a | 8.1 / 8.2 |
| OpenCL | spheres ind. / baked | 54 / 67 | 142 / 147 | n/a | 11.3 / 6.0 |
";

/// Table 3 of the paper (FPS): sphere 10^6 / sphere 10^5 / 100 spheres of 10^4 / 100 of 10^3.
const PAPER_T3: &str = "\
| platform | scene | GF650Ti | AMD7950 | HD3000 | HD4000 |
|---|---|---|---|---|---|
| CPU | sphere 1M / 100k | 3.9 / 35 | 5.1 / 81 | 5.3 / 34 | 37 / 20 |
| CPU | 100x10k / 100x1k | 3.4 / 27 | 8.4 / 61 | 6.5 / 32 | 4.4 / 18.5 |
| AVX+OMP | sphere 1M / 100k | 3.9 / 35 | 5.7 / 81 | 4.9 / 32 | 4.2 / 23 |
| AVX+OMP | 100x10k / 100x1k | 3.4 / 28 | 9.3 / 63 | 6.7 / 34 | 5.0 / 24 |
| GS | sphere 1M / 100k | 23 / 165 | 85 / 650 | n/a | 3.7 / 15 |
| GS | 100x10k / 100x1k | 18.7 / 100 | 84 / 482 | n/a | 3.1 / 19.3 |
| OpenCL | sphere 1M / 100k | 43 / 192 | 91 / 430 | n/a | 6.0 / 19.3 |
| OpenCL | 100x10k / 100x1k | 13.4 / 26 | 22 / 54 | n/a | 4.4 / 9.1 |
";

/// Toy Wars notes: silhouette times (ms) of the seed's algorithms (PSP-era hardware).
const PAPER_TOYWARS: &str = "\
| model | classic | fast (64) | fast (8) | connectivity |
|---|---|---|---|---|
| Dino | 9000 | 160 | 49 | 31 |
| Dragon | 2100 | 270 | 44 | 13 |
";

/// Options of one matrix run.
#[derive(Debug, Clone)]
struct Options {
    quick: bool,
    out: PathBuf,
    backends: Option<Vec<String>>,
    modes: Vec<String>,
    frames: u32,
    /// Untimed warm-up frames per measurement (3, or 1 with `--quick`).
    warmup: u32,
    /// `--replot DIR`: rewrite the tables and plots of an earlier run.
    replot: Option<PathBuf>,
}

fn parse_args(args: &[String]) -> Result<Option<Options>, String> {
    let mut o = Options {
        quick: false,
        out: PathBuf::from("matrix-out"),
        backends: None,
        modes: MODES.iter().map(|s| (*s).to_owned()).collect(),
        frames: 0,
        warmup: 3,
        replot: None,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{name} needs a value\n\n{USAGE}"))
        };
        match a.as_str() {
            "-h" | "--help" => {
                print!("{USAGE}");
                return Ok(None);
            }
            "--quick" => o.quick = true,
            "--out" => o.out = PathBuf::from(value("--out")?),
            "--replot" => o.replot = Some(PathBuf::from(value("--replot")?)),
            "--backends" => {
                o.backends = Some(split_list(&value("--backends")?));
            }
            "--modes" => {
                let modes = split_list(&value("--modes")?);
                for m in &modes {
                    if !MODES.contains(&m.as_str()) {
                        return Err(format!(
                            "unknown mode {m:?} in --modes; expected some of {}",
                            MODES.join(",")
                        ));
                    }
                }
                o.modes = modes;
            }
            "--frames" => {
                let v = value("--frames")?;
                o.frames = v
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or_else(|| format!("--frames {v:?}: expected a positive integer"))?;
            }
            other => return Err(format!("unknown argument {other:?}\n\n{USAGE}")),
        }
    }
    if o.frames == 0 {
        o.frames = if o.quick { 5 } else { 30 };
    }
    if o.quick {
        o.warmup = 1;
    }
    Ok(Some(o))
}

fn split_list(s: &str) -> Vec<String> {
    s.split(',')
        .map(|x| x.trim().to_owned())
        .filter(|x| !x.is_empty())
        .collect()
}

/// Entry point of `cargo xtask matrix`.
///
/// # Errors
/// A message when the build fails, the CLI is missing, or the output cannot be written. A
/// backend that fails during a measurement is recorded as a failed record and reported, not
/// fatal.
pub fn run(args: &[String]) -> Result<(), String> {
    let Some(opts) = parse_args(args)? else {
        return Ok(());
    };
    let root = crate::project_root();
    if let Some(dir) = &opts.replot {
        return replot(dir, root);
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

    let mut host = host_info(&root);
    let backends_json = cli.json(&["backends", "--format", "json"])?;
    let all: Vec<Value> = backends_json.as_array().cloned().unwrap_or_default();
    let mut devices = BTreeMap::new();
    let mut available = Vec::new();
    let mut unavailable = Vec::new();
    for b in &all {
        let name = b["name"].as_str().unwrap_or("?").to_owned();
        if let Some(sel) = &opts.backends {
            if !sel.contains(&name) {
                continue;
            }
        }
        if b["available"].as_bool() == Some(true) {
            devices.insert(name.clone(), b["device"].as_str().unwrap_or("").to_owned());
            available.push(name);
        } else {
            let reason = b["reason"].as_str().unwrap_or("unknown").to_owned();
            eprintln!("matrix: backend {name} is unavailable: {reason}");
            unavailable.push((name, reason));
        }
    }
    if let Some(sel) = &opts.backends {
        for s in sel {
            if !all.iter().any(|b| b["name"].as_str() == Some(s)) {
                return Err(format!("--backends: no backend named {s:?} in this build"));
            }
        }
    }
    if available.is_empty() {
        return Err("no backend is available".into());
    }
    eprintln!("matrix: backends: {}", available.join(", "));
    probe_build(&cli, &mut host);

    let scenes = scene_names(&cli)?;
    let plan = Plan::new(&opts, &available, &scenes);
    let mut m = Matrix {
        cli,
        command: std::iter::once("cargo xtask matrix".to_owned())
            .chain(args.iter().cloned())
            .collect::<Vec<_>>()
            .join(" "),
        opts: opts.clone(),
        host,
        devices,
        records: Vec::new(),
        failures: Vec::new(),
        progress: Progress::new(plan.steps()),
    };
    m.run_plan(&plan);
    m.progress.finish();

    let elapsed = started.elapsed().as_secs_f64();
    m.write_outputs(&available, &unavailable, elapsed)?;
    eprintln!(
        "matrix: done in {elapsed:.0} s; {} records, {} failures; see {}",
        m.records.len(),
        m.failures.len(),
        opts.out.join("tables.md").display()
    );
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Running the CLI

struct Cli {
    bin: PathBuf,
    root: PathBuf,
}

impl Cli {
    /// Runs the CLI and parses its stdout as JSON.
    fn json(&self, args: &[&str]) -> Result<Value, String> {
        let out = Command::new(&self.bin)
            .current_dir(&self.root)
            .args(args)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", self.bin.display()))?;
        if !out.status.success() {
            let err = String::from_utf8_lossy(&out.stderr);
            let last: Vec<&str> = err.lines().rev().take(6).collect();
            return Err(format!(
                "`shadowvol {}` failed ({}): {}",
                args.join(" "),
                out.status,
                last.into_iter().rev().collect::<Vec<_>>().join(" | ")
            ));
        }
        serde_json::from_slice(&out.stdout)
            .map_err(|e| format!("`shadowvol {}` printed invalid JSON: {e}", args.join(" ")))
    }
}

// ---------------------------------------------------------------------------------------------
// Host information

fn command_line(cmd: &str, args: &[&str], root: &Path) -> String {
    Command::new(cmd)
        .args(args)
        .current_dir(root)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_else(|| "unknown".into())
}

fn host_info(root: &Path) -> Map<String, Value> {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut rev = command_line("git", &["rev-parse", "--short=12", "HEAD"], root);
    if !command_line(
        "git",
        &["status", "--porcelain", "--untracked-files=no"],
        root,
    )
    .is_empty()
        && rev != "unknown"
    {
        rev.push_str("-dirty");
    }
    let mut m = Map::new();
    m.insert("host".into(), json!(command_line("uname", &["-n"], root)));
    m.insert("os".into(), json!(command_line("uname", &["-sr"], root)));
    m.insert("cpu".into(), json!(cpu));
    m.insert("cores".into(), json!(cores));
    m.insert("rustc".into(), json!(command_line("rustc", &["-V"], root)));
    m.insert("git_rev".into(), json!(rev));
    m.insert(
        "rustflags".into(),
        json!(std::env::var("RUSTFLAGS").unwrap_or_default()),
    );
    m.insert("profile".into(), json!("release"));
    m
}

/// `--replot DIR`: rebuilds the tables, CSV and plots from `DIR/results.json`.
fn replot(dir: &Path, root: PathBuf) -> Result<(), String> {
    let path = dir.join("results.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let v: Value = serde_json::from_str(&text)
        .map_err(|e| format!("{}: invalid JSON: {e}", path.display()))?;
    let strings = |k: &str| -> Vec<String> {
        v[k].as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(str::to_owned))
                    .collect()
            })
            .unwrap_or_default()
    };
    let available = strings("backends");
    let unavailable: Vec<(String, String)> = v["unavailable"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|u| {
                    (
                        u["name"].as_str().unwrap_or("?").to_owned(),
                        u["reason"].as_str().unwrap_or("?").to_owned(),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    let records: Vec<Value> = v["records"].as_array().cloned().unwrap_or_default();
    let modes: Vec<String> = MODES
        .iter()
        .filter(|m| records.iter().any(|r| r["mode"] == **m))
        .map(|m| (*m).to_owned())
        .collect();
    let m = Matrix {
        cli: Cli {
            bin: PathBuf::new(),
            root,
        },
        command: v["command"]
            .as_str()
            .unwrap_or("cargo xtask matrix")
            .to_owned(),
        opts: Options {
            quick: v["quick"].as_bool().unwrap_or(false),
            out: dir.to_path_buf(),
            backends: None,
            modes,
            frames: v["frames"].as_u64().unwrap_or(0) as u32,
            warmup: v["warmup"]
                .as_u64()
                .unwrap_or(if v["quick"] == true { 1 } else { 3 }) as u32,
            replot: None,
        },
        host: v["host"].as_object().cloned().unwrap_or_default(),
        devices: v["devices"]
            .as_object()
            .map(|d| {
                d.iter()
                    .map(|(k, x)| (k.clone(), x.as_str().unwrap_or("").to_owned()))
                    .collect()
            })
            .unwrap_or_default(),
        records,
        failures: strings("failures"),
        progress: Progress::new(1),
    };
    m.write_derived(
        &available,
        &unavailable,
        v["elapsed_s"].as_f64().unwrap_or(0.0),
    )?;
    eprintln!(
        "matrix: rewrote the tables, CSV and plots in {}",
        dir.display()
    );
    Ok(())
}

/// The presets of the CLI (`shadowvol scenes --format json`); fails when a scene the tables
/// need is missing, before anything is measured.
fn scene_names(cli: &Cli) -> Result<Vec<String>, String> {
    let v = cli.json(&["scenes", "--format", "json"])?;
    let names: Vec<String> = v
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|s| s["name"].as_str().map(str::to_owned))
                .collect()
        })
        .unwrap_or_default();
    let needed = std::iter::once(T1_SCENE)
        .chain(T2_SCENES)
        .chain(T3_SCENES)
        .chain(TRI_SCENES)
        .chain([LIGHT_SCENE])
        .chain(RENDER_SCENES_EXTRA)
        .chain(TOYWARS_SCENES);
    let missing: BTreeSet<&str> = needed.filter(|n| !names.iter().any(|x| x == n)).collect();
    if !missing.is_empty() {
        return Err(format!(
            "`shadowvol scenes` lacks presets the matrix needs: {}",
            missing.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    if !names.iter().any(|n| n.starts_with("hard-")) {
        return Err("`shadowvol scenes` lists no hard-* preset to render".into());
    }
    Ok(names)
}

/// Asks the release CLI what it was built with (target features, profile) and which SIMD
/// level the `simd` backend picks at run time, with one tiny `bench` run; adds them to `host`.
fn probe_build(cli: &Cli, host: &mut Map<String, Value>) {
    let probe = cli.json(&[
        "bench",
        "--scene",
        "hard-tetrahedron",
        "--backend",
        "simd",
        "--mode",
        "original",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--format",
        "json",
    ]);
    let (level, features, profile) = match &probe {
        Ok(v) => (
            v["records"][0]["details"]["simd_level"]
                .as_str()
                .unwrap_or("unknown")
                .to_owned(),
            v["host"]["compile_target_features"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(Value::as_str)
                        .collect::<Vec<_>>()
                        .join("+")
                })
                .unwrap_or_default(),
            v["host"]["profile"]
                .as_str()
                .unwrap_or("release")
                .to_owned(),
        ),
        Err(e) => (
            format!("unknown (simd probe failed: {e})"),
            String::new(),
            "release".to_owned(),
        ),
    };
    let rustflags = host
        .get("rustflags")
        .and_then(Value::as_str)
        .unwrap_or("")
        .to_owned();
    host.insert("simd_level".into(), json!(level));
    host.insert("compile_target_features".into(), json!(features));
    host.insert("profile".into(), json!(profile));
    host.insert(
        "flags".into(),
        json!(format!(
            "cargo build --release; RUSTFLAGS={rustflags:?}; compile-time target features: {}",
            if features.is_empty() {
                "none beyond the target default"
            } else {
                &features
            }
        )),
    );
}

// ---------------------------------------------------------------------------------------------
// The plan

/// Which scene each table uses.
const T1_SCENE: &str = "sphere-1m";
const T2_SCENES: [&str; 4] = [
    "bunnies-10-individual",
    "bunnies-10-baked",
    "spheres-10-individual",
    "spheres-10-baked",
];
const T3_SCENES: [&str; 4] = [
    "sphere-1m",
    "sphere-100k",
    "spheres-100x10k",
    "spheres-100x1k",
];
/// Scenes for time against triangles (10^3 .. 10^6).
const TRI_SCENES: [&str; 4] = ["sphere-1k", "sphere-10k", "sphere-100k", "sphere-1m"];
/// Scene for time against lights.
const LIGHT_SCENE: &str = "sphere-100k";
/// Scenes rendered against the ray-traced reference for artifact counts: every `hard-*` preset
/// that `shadowvol scenes` lists (the corpus grows; the matrix follows it), then these.
const RENDER_SCENES_EXTRA: [&str; 1] = ["town"];
/// Scenes of the Toy Wars table (closed manifold meshes, which the seeds' algorithms need).
const TOYWARS_SCENES: [&str; 2] = ["bunny", "bunny-subdivided"];

struct Plan {
    backends: Vec<String>,
    modes: Vec<String>,
    light_counts: Vec<u32>,
    render_scenes: Vec<String>,
    render_size: &'static str,
    toywars_scenes: Vec<&'static str>,
}

impl Plan {
    fn new(o: &Options, backends: &[String], scenes: &[String]) -> Self {
        Self {
            backends: backends.to_vec(),
            modes: o.modes.clone(),
            light_counts: if o.quick {
                vec![1, 2, 4, 8]
            } else {
                (1..=8).collect()
            },
            render_scenes: scenes
                .iter()
                .filter(|s| s.starts_with("hard-"))
                .cloned()
                .chain(RENDER_SCENES_EXTRA.iter().map(|s| (*s).to_owned()))
                .collect(),
            render_size: if o.quick { "160x120" } else { "320x240" },
            toywars_scenes: TOYWARS_SCENES.to_vec(),
        }
    }

    /// Progress steps; must follow [`Matrix::run_plan`]: one per bench call (all backends
    /// at once), render, accuracy call (per backend) and baselines call.
    fn steps(&self) -> u64 {
        let b = self.backends.len() as u64;
        let m = self.modes.len() as u64;
        let tri = TRI_SCENES.iter().filter(|s| **s != T1_SCENE).count() as u64;
        let t3 = T3_SCENES
            .iter()
            .filter(|s| **s != T1_SCENE && !TRI_SCENES.contains(s))
            .count() as u64;
        let lights = self
            .light_counts
            .iter()
            .filter(|&&n| !(n == 1 && TRI_SCENES.contains(&LIGHT_SCENE)))
            .count() as u64;
        1 + b * m
            + T2_SCENES.len() as u64
            + tri
            + t3
            + lights
            + b
            + self.render_scenes.len() as u64 * b * m
            + self.toywars_scenes.len() as u64
    }
}

// ---------------------------------------------------------------------------------------------
// Progress bar (stderr; no dependency)

struct Progress {
    total: u64,
    done: u64,
    start: Instant,
}

impl Progress {
    fn new(total: u64) -> Self {
        Self {
            total: total.max(1),
            done: 0,
            start: Instant::now(),
        }
    }

    fn step(&mut self, what: &str) {
        self.done += 1;
        let frac = self.done as f64 / self.total as f64;
        let width = 30;
        let filled = ((frac * width as f64) as usize).min(width);
        let elapsed = self.start.elapsed().as_secs_f64();
        let eta = if self.done > 0 {
            elapsed / self.done as f64 * (self.total - self.done.min(self.total)) as f64
        } else {
            0.0
        };
        eprint!(
            "\r[{}{}] {}/{} {:>4.0}s eta {:>4.0}s  {:<48.48}",
            "#".repeat(filled),
            ".".repeat(width - filled),
            self.done,
            self.total,
            elapsed,
            eta,
            what
        );
    }

    fn finish(&self) {
        eprintln!();
    }
}

// ---------------------------------------------------------------------------------------------
// Measurements

struct Matrix {
    cli: Cli,
    /// The command line of the run, for the tables.
    command: String,
    opts: Options,
    host: Map<String, Value>,
    devices: BTreeMap<String, String>,
    records: Vec<Value>,
    failures: Vec<String>,
    progress: Progress,
}

impl Matrix {
    fn frames(&self) -> String {
        self.opts.frames.to_string()
    }

    /// Adds host, device and experiment fields to a record and stores it.
    fn push(&mut self, experiment: &str, mut rec: Map<String, Value>) {
        rec.insert("experiment".into(), json!(experiment));
        // Backend details (for example simd_level) become columns of their own.
        if let Some(Value::Object(d)) = rec.remove("details") {
            for (k, v) in d {
                rec.entry(format!("detail_{k}")).or_insert(v);
            }
        }
        if let Some(b) = rec.get("backend").and_then(Value::as_str) {
            let dev = self.devices.get(b).cloned().unwrap_or_default();
            rec.entry("device").or_insert(json!(dev));
        }
        for (k, v) in &self.host {
            rec.entry(k.clone()).or_insert(v.clone());
        }
        self.records.push(Value::Object(rec));
    }

    fn fail(&mut self, what: String) {
        eprintln!("\nmatrix: {what}");
        self.failures.push(what);
    }

    /// `shadowvol bench` of one scene on several backends in one process (the scene is built
    /// once), all given modes; records each result. When the combined call fails, each backend
    /// is retried on its own so that one failing backend does not lose the others.
    fn bench(
        &mut self,
        experiment: &str,
        scene: &str,
        backends: &[String],
        modes: &[String],
        lights: u32,
    ) {
        self.progress
            .step(&format!("{experiment}: {scene} x{lights} light(s)"));
        if let Err(e) = self.bench_call(experiment, scene, backends, modes, lights) {
            if backends.len() == 1 {
                self.fail(format!("{experiment}: {e}"));
                return;
            }
            for b in backends {
                if let Err(e) =
                    self.bench_call(experiment, scene, std::slice::from_ref(b), modes, lights)
                {
                    self.fail(format!("{experiment}: {e}"));
                }
            }
        }
    }

    fn bench_call(
        &mut self,
        experiment: &str,
        scene: &str,
        backends: &[String],
        modes: &[String],
        lights: u32,
    ) -> Result<(), String> {
        let modes_s = modes.join(",");
        let backends_s = backends.join(",");
        let frames = self.frames();
        let warmup = self.opts.warmup.to_string();
        let lights_s = lights.to_string();
        let args = [
            "bench",
            "--scene",
            scene,
            "--backend",
            &backends_s,
            "--mode",
            &modes_s,
            "--frames",
            &frames,
            "--warmup",
            &warmup,
            "--lights",
            &lights_s,
            "--format",
            "json",
        ];
        let v = self.cli.json(&args)?;
        let floor = v["floor_ms"].clone();
        for r in v["records"].as_array().cloned().unwrap_or_default() {
            let mut rec = r.as_object().cloned().unwrap_or_default();
            rec.insert("floor_ms".into(), floor.clone());
            self.push(experiment, rec);
        }
        Ok(())
    }

    /// Copies the records of one measurement under another experiment's name (the same
    /// scene, backend, mode and lights measured once serves several tables).
    fn reuse(&mut self, from: &str, scene: &str, lights: u64, to: &str) {
        let copies: Vec<Value> = self
            .records
            .iter()
            .filter(|r| {
                r["experiment"] == from
                    && r["scene"] == scene
                    && r["lights"].as_u64() == Some(lights)
            })
            .cloned()
            .map(|mut r| {
                r["experiment"] = json!(to);
                r["reused_from"] = json!(from);
                r
            })
            .collect();
        self.records.extend(copies);
    }

    fn run_plan(&mut self, plan: &Plan) {
        let modes = plan.modes.clone();
        let backends = plan.backends.clone();
        let two: Vec<String> = ["original", "robust"]
            .iter()
            .filter(|m| modes.iter().any(|x| x == *m))
            .map(|s| (*s).to_owned())
            .collect();
        // Table 1 and the accuracy table's time ratios; also the 10^6 point of Table 3 and
        // of time against triangles.
        self.bench("table1", T1_SCENE, &backends, &modes, 1);
        self.reuse("table1", T1_SCENE, 1, "table3");
        self.reuse("table1", T1_SCENE, 1, "triangles");
        // Full frame time per mode (render included).
        for b in &backends {
            for m in &modes {
                self.render("table1-frame", T1_SCENE, b, m, false, plan.render_size);
            }
        }
        for s in T2_SCENES {
            self.bench("table2", s, &backends, &two, 1);
        }
        for s in TRI_SCENES.iter().filter(|s| **s != T1_SCENE) {
            self.bench("triangles", s, &backends, &modes, 1);
        }
        for s in T3_SCENES {
            if s == T1_SCENE {
                continue;
            }
            if TRI_SCENES.contains(&s) {
                self.reuse("triangles", s, 1, "table3");
            } else {
                self.bench("table3", s, &backends, &two, 1);
            }
        }
        for &n in &plan.light_counts {
            if n == 1 && TRI_SCENES.contains(&LIGHT_SCENE) {
                self.reuse("triangles", LIGHT_SCENE, 1, "lights");
            } else {
                self.bench("lights", LIGHT_SCENE, &backends, &modes, n);
            }
        }
        // Accuracy on hard-* scenes: open vertices and sign differences against exact.
        for b in &backends {
            self.progress.step(&format!("accuracy: {b}"));
            let modes_s = modes.join(",");
            match self.cli.json(&[
                "accuracy",
                "--backend",
                b,
                "--mode",
                &modes_s,
                "--format",
                "json",
            ]) {
                Ok(v) => {
                    for r in v["records"].as_array().cloned().unwrap_or_default() {
                        self.push("accuracy", r.as_object().cloned().unwrap_or_default());
                    }
                }
                Err(e) => self.fail(format!("accuracy: {e}")),
            }
        }
        for s in &plan.render_scenes {
            for b in &backends {
                for m in &modes {
                    self.render("artifacts", s, b, m, true, plan.render_size);
                }
            }
        }
        // The seeds' CPU algorithms against our modes on cpu and simd.
        for s in &plan.toywars_scenes {
            self.progress.step(&format!("toywars: {s}"));
            let frames = self.frames();
            let warmup = self.opts.warmup.to_string();
            match self.cli.json(&[
                "baselines",
                "--scene",
                s,
                "--frames",
                &frames,
                "--warmup",
                &warmup,
                "--format",
                "json",
            ]) {
                Ok(v) => {
                    for r in v["records"].as_array().cloned().unwrap_or_default() {
                        self.push("toywars", r.as_object().cloned().unwrap_or_default());
                    }
                }
                Err(e) => self.fail(format!("toywars: {e}")),
            }
        }
    }

    fn render(
        &mut self,
        experiment: &str,
        scene: &str,
        backend: &str,
        mode: &str,
        reference: bool,
        size: &str,
    ) {
        self.progress
            .step(&format!("{experiment}: {scene} {backend} {mode}"));
        let png = self
            .opts
            .out
            .join("renders")
            .join(format!("{experiment}-{scene}-{backend}-{mode}.png"));
        let png_s = png.to_string_lossy().to_string();
        let mut args = vec![
            "render",
            scene,
            "--out",
            &png_s,
            "--size",
            size,
            "--mode",
            mode,
            "--backend",
            backend,
            "--format",
            "json",
        ];
        if reference {
            args.push("--reference");
        }
        // The hard-* presets have no ground: a backdrop receives their shadows.
        if scene.starts_with("hard-") {
            args.push("--backdrop");
        }
        match self.cli.json(&args) {
            Ok(v) => {
                let mut rec = Map::new();
                rec.insert("scene".into(), json!(scene));
                rec.insert("backend".into(), json!(backend));
                rec.insert("mode".into(), json!(mode));
                rec.insert("size".into(), json!(size));
                for k in [
                    "artifact_pixels",
                    "shadow_pixels",
                    "reference_shadow_pixels",
                    "covered_pixels",
                    "adapter",
                ] {
                    if let Some(x) = v.get(k) {
                        rec.insert(k.into(), x.clone());
                    }
                }
                if let Some(t) = v.get("timings").and_then(Value::as_object) {
                    for (k, x) in t {
                        rec.insert(format!("timing_{k}"), x.clone());
                    }
                    rec.insert("frame_ms".into(), json!(frame_ms(t)));
                }
                rec.insert("png".into(), json!(png_s));
                self.push(experiment, rec);
            }
            Err(e) => self.fail(format!("{experiment}: {e}")),
        }
    }

    // -----------------------------------------------------------------------------------------
    // Output

    fn write_outputs(
        &self,
        available: &[String],
        unavailable: &[(String, String)],
        elapsed: f64,
    ) -> Result<(), String> {
        let out = &self.opts.out;
        let results = json!({
            "host": self.host,
            "command": self.command,
            "warmup": self.opts.warmup,
            "quick": self.opts.quick,
            "frames": self.opts.frames,
            "elapsed_s": elapsed,
            "backends": available,
            "devices": self.devices,
            "unavailable": unavailable.iter().map(|(n, r)| json!({"name": n, "reason": r})).collect::<Vec<_>>(),
            "failures": self.failures,
            "records": self.records,
        });
        write(
            &out.join("results.json"),
            &serde_json::to_string_pretty(&results).map_err(|e| e.to_string())?,
        )?;
        self.write_derived(available, unavailable, elapsed)
    }

    /// Writes what is derived from the records: CSV, tables and plots.
    fn write_derived(
        &self,
        available: &[String],
        unavailable: &[(String, String)],
        elapsed: f64,
    ) -> Result<(), String> {
        let out = &self.opts.out;
        write(&out.join("results.csv"), &to_csv(&self.records))?;
        let tables = self.tables(available, unavailable, elapsed);
        write(&out.join("tables.md"), &tables)?;
        crate::plots::all(out, &self.records).map_err(|e| format!("plots: {e}"))?;
        Ok(())
    }

    fn find(
        &self,
        experiment: &str,
        scene: &str,
        backend: &str,
        mode: &str,
        lights: Option<u64>,
    ) -> Option<&Value> {
        self.records.iter().find(|r| {
            r["experiment"] == experiment
                && r["scene"] == scene
                && r["backend"] == backend
                && r["mode"] == mode
                && lights.is_none_or(|n| r["lights"].as_u64() == Some(n))
        })
    }

    fn ms(&self, experiment: &str, scene: &str, backend: &str, mode: &str) -> Option<f64> {
        self.find(experiment, scene, backend, mode, Some(1))
            .and_then(|r| r["median_ms"].as_f64())
    }

    fn tables(
        &self,
        available: &[String],
        unavailable: &[(String, String)],
        elapsed: f64,
    ) -> String {
        let mut s = String::new();
        let h = &self.host;
        let get = |k: &str| h.get(k).and_then(Value::as_str).unwrap_or("?").to_owned();
        s += "# shadowvol experiment matrix\n\n";
        s += &format!(
            "Command: `{}` ({} warm-up and {} timed frames per measurement; {elapsed:.0} s in \
             all).\n\n",
            self.command, self.opts.warmup, self.opts.frames
        );
        s += "**This machine**: ";
        s += &format!(
            "{} ({} cores), {}, {}, git {}, RUSTFLAGS=`{}`.\n\n",
            get("cpu"),
            h.get("cores").map_or("?".into(), ToString::to_string),
            get("os"),
            get("rustc"),
            get("git_rev"),
            get("rustflags")
        );
        s += "| backend | device |\n|---|---|\n";
        for b in available {
            s += &format!(
                "| {b} | {} |\n",
                self.devices.get(b).map_or("", String::as_str)
            );
        }
        for (b, r) in unavailable {
            s += &format!("| {b} | unavailable: {r} |\n");
        }
        s += &format!(
            "\nSIMD level used by `simd`: {}. Build: {}.\n",
            get("simd_level"),
            get("flags")
        );
        s +=
            "\nTimes are medians over the timed frames after warm-up, in milliseconds (p10-p90 in \
              results.json). `floor` is the time to stream the bytes the extraction must touch, \
              measured in the same run. Absolute times of GPU backends only mean something on a \
              real GPU; on lavapipe/PoCL they run on this CPU.\n\n";

        // Table 1.
        s += &format!("## Table 1: accuracy modes on `{T1_SCENE}` (silhouette and full frame)\n\n");
        s += "Ours (this machine): silhouette ms (median of `bench`) / frame ms (one `render` frame at the run's image size: silhouettes, side building and raster, without the one-off upload of the edge tables), and the silhouette time's ratio to `original`.\n\n";
        s += "| backend |";
        for m in &self.opts.modes {
            s += &format!(" {m} |");
        }
        s += " floor |\n|---|";
        for _ in &self.opts.modes {
            s += "---|";
        }
        s += "---|\n";
        for b in available {
            s += &format!("| {b} |");
            let orig = self.ms("table1", T1_SCENE, b, "original");
            for m in &self.opts.modes {
                let sil = self.ms("table1", T1_SCENE, b, m);
                let frame = self
                    .find("table1-frame", T1_SCENE, b, m, None)
                    .and_then(|r| r["frame_ms"].as_f64());
                let ratio = match (sil, orig) {
                    (Some(x), Some(o)) if o > 0.0 => format!(" ({:.2}x)", x / o),
                    _ => String::new(),
                };
                s += &format!(" {} / {}{} |", fmt_ms(sil), fmt_ms(frame), ratio);
            }
            let floor = self
                .find("table1", T1_SCENE, b, "original", Some(1))
                .and_then(|r| r["floor_ms"].as_f64());
            s += &format!(" {} |\n", fmt_ms(floor));
        }
        s += "\nThe paper (2013 hardware, FPS of the whole frame, robust / original):\n\n";
        s += PAPER_T1;

        // Table 2.
        s += "\n## Table 2: individual vs baked objects (~6.5*10^5 triangles)\n\n";
        s += &self.scene_table("table2", &T2_SCENES, available);
        s += "\nThe paper (2013 hardware, FPS, robust):\n\n";
        s += PAPER_T2;

        // Table 3.
        s += "\n## Table 3: number of triangles and of objects\n\n";
        s += &self.scene_table("table3", &T3_SCENES, available);
        s += "\nThe paper (2013 hardware, FPS, robust):\n\n";
        s += PAPER_T3;

        // Accuracy.
        s += "\n## What accuracy costs\n\n";
        s += &format!(
            "Time relative to `original` on `{T1_SCENE}`; open vertices (vertices where the \
             silhouette chain does not close) and edges whose sign differs from `exact`, summed \
             over every hard-* scene and light; artifact pixels against the ray-traced reference, \
             summed over the rendered hard scenes.\n\n"
        );
        s += "| backend | mode | time / original | open vertices | sign differs from exact | artifact pixels | uncertain (host-decided) |\n|---|---|---|---|---|---|---|\n";
        for b in available {
            let orig = self.ms("table1", T1_SCENE, b, "original");
            for m in &self.opts.modes {
                let ratio = match (self.ms("table1", T1_SCENE, b, m), orig) {
                    (Some(x), Some(o)) if o > 0.0 => format!("{:.2}", x / o),
                    _ => "n/a".into(),
                };
                let acc: Vec<&Value> = self
                    .records
                    .iter()
                    .filter(|r| {
                        r["experiment"] == "accuracy"
                            && r["backend"] == b.as_str()
                            && r["mode"] == m.as_str()
                    })
                    .collect();
                let sum = |k: &str| -> String {
                    if acc.is_empty() {
                        "n/a".into()
                    } else {
                        acc.iter()
                            .map(|r| r[k].as_u64().unwrap_or(0))
                            .sum::<u64>()
                            .to_string()
                    }
                };
                let art: Vec<u64> = self
                    .records
                    .iter()
                    .filter(|r| {
                        r["experiment"] == "artifacts"
                            && r["backend"] == b.as_str()
                            && r["mode"] == m.as_str()
                    })
                    .filter_map(|r| r["artifact_pixels"].as_u64())
                    .collect();
                let art = if art.is_empty() {
                    "n/a".into()
                } else {
                    art.iter().sum::<u64>().to_string()
                };
                s += &format!(
                    "| {b} | {m} | {ratio} | {} | {} | {art} | {} |\n",
                    sum("open_vertices"),
                    sum("sign_diff_vs_exact"),
                    sum("uncertain")
                );
            }
        }
        s += &self.artifact_table(available);

        // The thesis' scaling.
        s += &format!("\n## Scaling (the thesis): time against lights on `{LIGHT_SCENE}`\n\n");
        let counts: BTreeSet<u64> = self
            .records
            .iter()
            .filter(|r| r["experiment"] == "lights")
            .filter_map(|r| r["lights"].as_u64())
            .collect();
        s += "| backend | mode |";
        for n in &counts {
            s += &format!(" {n} |");
        }
        s += "\n|---|---|";
        for _ in &counts {
            s += "---|";
        }
        s += "\n";
        for b in available {
            for m in &self.opts.modes {
                s += &format!("| {b} | {m} |");
                for &n in &counts {
                    let v = self
                        .find("lights", LIGHT_SCENE, b, m, Some(n))
                        .and_then(|r| r["median_ms"].as_f64());
                    s += &format!(" {} |", fmt_ms(v));
                }
                s += "\n";
            }
        }
        s += "\n## Scaling (the thesis): time against triangles (one light)\n\n| backend | mode |";
        for sc in TRI_SCENES {
            s += &format!(" {sc} |");
        }
        s += "\n|---|---|";
        for _ in TRI_SCENES {
            s += "---|";
        }
        s += "\n";
        for b in available {
            for m in &self.opts.modes {
                s += &format!("| {b} | {m} |");
                for sc in TRI_SCENES {
                    s += &format!(" {} |", fmt_ms(self.ms("triangles", sc, b, m)));
                }
                s += "\n";
            }
        }

        // Toy Wars.
        s += "\n## Seed \"Toy Wars\" table: the seeds' CPU algorithms against ours\n\n";
        s += &self.toywars_table();
        s += "\nThe Toy Wars notes (PSP-era hardware, ms):\n\n";
        s += PAPER_TOYWARS;

        s += "\n## Plots\n\n![time vs triangles](time_vs_triangles.png)\n![time vs lights](time_vs_lights.png)\n![accuracy cost](accuracy_cost.png)\n![individual vs baked](individual_vs_baked.png)\n";
        if !self.failures.is_empty() {
            s += "\n## Failures\n\n";
            for f in &self.failures {
                s += &format!("- {}\n", f.replace('\n', " "));
            }
        }
        s
    }

    /// Artifact pixels per rendered scene (rows) and mode (columns): one number when every
    /// backend got the same count, else the count of each backend in `available` order.
    fn artifact_table(&self, available: &[String]) -> String {
        let recs: Vec<&Value> = self
            .records
            .iter()
            .filter(|r| r["experiment"] == "artifacts")
            .collect();
        let mut scenes: Vec<&str> = Vec::new();
        for r in &recs {
            let sc = r["scene"].as_str().unwrap_or("?");
            if !scenes.contains(&sc) {
                scenes.push(sc);
            }
        }
        let size = recs.first().and_then(|r| r["size"].as_str()).unwrap_or("?");
        let mut s = format!(
            "\nArtifact pixels per rendered scene ({size} pixels, `--backdrop` behind the hard-* \
             scenes). One number when all backends \
             agree, else one per backend ({}):\n\n| scene | reference shadow pixels |",
            available.join(" / ")
        );
        for m in &self.opts.modes {
            s += &format!(" {m} |");
        }
        s += "\n|---|---|";
        for _ in &self.opts.modes {
            s += "---|";
        }
        s += "\n";
        for sc in scenes {
            let shadow = recs
                .iter()
                .find(|r| r["scene"] == sc && r["mode"] == "exact")
                .or_else(|| recs.iter().find(|r| r["scene"] == sc))
                .map_or("?".to_owned(), |r| {
                    r["reference_shadow_pixels"]
                        .as_u64()
                        .or_else(|| r["shadow_pixels"].as_u64())
                        .map_or("?".into(), |n| n.to_string())
                });
            s += &format!("| {sc} | {shadow} |");
            for m in &self.opts.modes {
                let per: Vec<String> = available
                    .iter()
                    .map(|b| {
                        recs.iter()
                            .find(|r| {
                                r["scene"] == sc
                                    && r["backend"] == b.as_str()
                                    && r["mode"] == m.as_str()
                            })
                            .and_then(|r| r["artifact_pixels"].as_u64())
                            .map_or("n/a".to_owned(), |n| n.to_string())
                    })
                    .collect();
                let cell = if per.windows(2).all(|w| w[0] == w[1]) {
                    per.first().cloned().unwrap_or_default()
                } else {
                    per.join(" / ")
                };
                let cell = if cell != "0" && cell != "n/a" {
                    format!("**{cell}**")
                } else {
                    cell
                };
                s += &format!(" {cell} |");
            }
            s += "\n";
        }
        s
    }

    /// One row per algorithm (the seeds' and ours per backend and mode), one column group per
    /// scene: median ms (p10-p90), silhouette edges, and whether the edge set equals exact's.
    fn toywars_table(&self) -> String {
        let recs: Vec<&Value> = self
            .records
            .iter()
            .filter(|r| r["experiment"] == "toywars")
            .collect();
        let mut scenes: Vec<(String, u64)> = Vec::new();
        let mut rows: Vec<(String, String)> = Vec::new();
        for r in &recs {
            let sc = r["scene"].as_str().unwrap_or("?").to_owned();
            if !scenes.iter().any(|(x, _)| *x == sc) {
                scenes.push((sc, r["triangles"].as_u64().unwrap_or(0)));
            }
            let row = (
                r["backend"].as_str().unwrap_or("?").to_owned(),
                r["mode"].as_str().unwrap_or("-").to_owned(),
            );
            if !rows.contains(&row) {
                rows.push(row);
            }
        }
        if recs.is_empty() {
            return "No data in this run (see Failures).\n".into();
        }
        let mut s = String::from("| algorithm | mode |");
        for (sc, t) in &scenes {
            s += &format!(" {sc} ({t} tri.) ms | silhouette edges | = exact |");
        }
        s += "\n|---|---|";
        for _ in &scenes {
            s += "---|---|---|";
        }
        s += "\n";
        for (alg, mode) in &rows {
            s += &format!("| {alg} | {mode} |");
            for (sc, _) in &scenes {
                let r = recs.iter().find(|r| {
                    r["scene"] == sc.as_str()
                        && r["backend"] == alg.as_str()
                        && r["mode"].as_str().unwrap_or("-") == mode
                });
                match r {
                    Some(r) if r["median_ms"].is_number() => {
                        s += &format!(
                            " {} ({}-{}) | {} | {} |",
                            fmt_ms(r["median_ms"].as_f64()),
                            fmt_ms(r["p10_ms"].as_f64()),
                            fmt_ms(r["p90_ms"].as_f64()),
                            r["silhouette_edges"],
                            match r["agrees_with_exact"].as_bool() {
                                Some(true) => "yes",
                                Some(false) => "**no**",
                                None => "?",
                            }
                        );
                    }
                    Some(r) => {
                        s += &format!(
                            " failed: {} | | |",
                            r["error"].as_str().unwrap_or("?").replace('|', "/")
                        );
                    }
                    None => s += " n/a | | |",
                }
            }
            s += "\n";
        }
        s += "\nThe seeds' algorithms (`classic`, `fast-hash-N`, `connectivity`, `two-step`) are \
              single-threaded scalar code with an f32 facing test per triangle; `= exact` compares \
              the edge set (m != 0, every light) with the `cpu` backend's `exact` result.\n";
        s
    }

    fn scene_table(&self, experiment: &str, scenes: &[&str], available: &[String]) -> String {
        let mut s = String::from("Ours (this machine), silhouette ms:\n\n| backend | mode |");
        for sc in scenes {
            s += &format!(" {sc} |");
        }
        s += "\n|---|---|";
        for _ in scenes {
            s += "---|";
        }
        s += "\n";
        for b in available {
            for m in ["robust", "original"] {
                if !self.opts.modes.iter().any(|x| x == m) {
                    continue;
                }
                s += &format!("| {b} | {m} |");
                for sc in scenes {
                    s += &format!(" {} |", fmt_ms(self.ms(experiment, sc, b, m)));
                }
                s += "\n";
            }
        }
        s
    }
}

/// Frame time of a render from its timings: `total_ms - prepare_ms` (the one-off upload of the
/// edge tables is not part of a frame) when given, else the sum of the per-stage `*_ms` without
/// `prepare` and `reference`.
fn frame_ms(t: &Map<String, Value>) -> f64 {
    let prepare = t.get("prepare_ms").and_then(Value::as_f64).unwrap_or(0.0);
    if let Some(v) = t.get("total_ms").and_then(Value::as_f64) {
        return v - prepare;
    }
    t.iter()
        .filter(|(k, _)| {
            k.ends_with("_ms") && !k.starts_with("reference") && !k.starts_with("prepare")
        })
        .filter_map(|(_, v)| v.as_f64())
        .sum()
}

fn fmt_ms(v: Option<f64>) -> String {
    match v {
        Some(x) if x >= 100.0 => format!("{x:.0}"),
        Some(x) if x >= 10.0 => format!("{x:.1}"),
        Some(x) => format!("{x:.2}"),
        None => "n/a".into(),
    }
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Flattens records to CSV with the union of their scalar keys as columns.
fn to_csv(records: &[Value]) -> String {
    let mut keys = BTreeSet::new();
    for r in records {
        if let Some(o) = r.as_object() {
            for (k, v) in o {
                if !v.is_object() && !v.is_array() {
                    keys.insert(k.clone());
                }
            }
        }
    }
    let keys: Vec<String> = keys.into_iter().collect();
    let mut s = keys.join(",");
    s.push('\n');
    for r in records {
        let row: Vec<String> = keys
            .iter()
            .map(|k| match &r[k] {
                Value::Null => String::new(),
                Value::String(x) => csv_field(x),
                other => csv_field(&other.to_string()),
            })
            .collect();
        s += &row.join(",");
        s.push('\n');
    }
    s
}

fn csv_field(x: &str) -> String {
    if x.contains([',', '"', '\n']) {
        format!("\"{}\"", x.replace('"', "\"\""))
    } else {
        x.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_and_unions_keys() {
        let recs = vec![json!({"a": 1, "b": "x,y"}), json!({"c": true})];
        let csv = to_csv(&recs);
        assert_eq!(csv, "a,b,c\n1,\"x,y\",\n,,true\n");
    }

    #[test]
    fn args_parse() {
        let o = parse_args(&["--quick".into(), "--modes".into(), "exact".into()])
            .unwrap()
            .unwrap();
        assert!(o.quick);
        assert_eq!(o.frames, 5);
        assert_eq!(o.modes, vec!["exact"]);
        assert!(parse_args(&["--modes".into(), "fast".into()]).is_err());
        assert!(parse_args(&["--frames".into(), "0".into()]).is_err());
    }

    #[test]
    fn frame_time_prefers_total() {
        let t = json!({"silhouette_ms": 1.0, "raster_ms": 2.0});
        assert_eq!(frame_ms(t.as_object().unwrap()), 3.0);
        let t = json!({"silhouette_ms": 1.0, "total_ms": 5.0});
        assert_eq!(frame_ms(t.as_object().unwrap()), 5.0);
        let t =
            json!({"silhouette_ms": 1.0, "prepare_ms": 2.0, "total_ms": 5.0, "reference_ms": 9.0});
        assert_eq!(frame_ms(t.as_object().unwrap()), 3.0);
        let t = json!({"silhouette_ms": 1.0, "prepare_ms": 2.0, "raster_ms": 4.0});
        assert_eq!(frame_ms(t.as_object().unwrap()), 5.0);
    }
}
