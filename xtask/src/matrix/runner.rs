//! Running the plan: the release CLI as a subprocess, the host it runs on, and one record per
//! measurement.

use super::args::{Only, Options};
use super::cli::{BenchReport, RecordList, RenderReport, SceneRow};
use super::plan::{
    Plan, FRAME_GPU_KEY, FRAME_HOST_BACKEND, LIGHT_SCENE, RENDER_SCENES_EXTRA, SOFT_SCENES,
    T1_SCENE, T2_SCENES, T3_SCENES, TOYWARS_SCENES, TRI_SCENES,
};
use super::progress::Progress;
use super::records::{Baseline, Bench, Data, HostInfo, Key, ModeErrors, Record, Render, Results};
use serde::de::DeserializeOwned;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The release `shadowvol` binary, run in the workspace root.
pub(super) struct Cli {
    pub bin: PathBuf,
    pub root: PathBuf,
}

impl Cli {
    /// Runs the CLI and parses its stdout as JSON of shape `T`.
    ///
    /// # Errors
    /// When the CLI cannot start or fails (with the last lines of its stderr), or prints JSON
    /// that is invalid or of another shape (with serde's line, column and field).
    pub fn json<T: DeserializeOwned>(&self, args: &[&str]) -> Result<T, String> {
        self.json_with_env(args, &[])
    }

    /// [`Cli::json`] with the variables `env` set for the run.
    ///
    /// # Errors
    /// As [`Cli::json`].
    pub fn json_with_env<T: DeserializeOwned>(
        &self,
        args: &[&str],
        env: &[(&str, &str)],
    ) -> Result<T, String> {
        let out = Command::new(&self.bin)
            .current_dir(&self.root)
            .args(args)
            .envs(env.iter().copied())
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
        serde_json::from_slice(&out.stdout).map_err(|e| {
            format!(
                "`shadowvol {}` printed JSON the matrix cannot read: {e}",
                args.join(" ")
            )
        })
    }
}

/// The trimmed stdout of `cmd args` in `root`, or `unknown`.
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

/// Host name, OS, cores, rustc, git revision and `RUSTFLAGS` of this machine and checkout (the
/// CPU model comes from the CLI, in [`probe_build`]).
pub(super) fn host_info(root: &Path) -> HostInfo {
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
    HostInfo {
        host: Some(command_line("uname", &["-n"], root)),
        os: Some(command_line("uname", &["-sr"], root)),
        cores: Some(cores as u64),
        rustc: Some(command_line("rustc", &["-V"], root)),
        git_rev: Some(rev),
        rustflags: Some(std::env::var("RUSTFLAGS").unwrap_or_default()),
        profile: Some("release".into()),
        ..HostInfo::default()
    }
}

/// The presets of the CLI (`shadowvol scenes --format json`); fails when a scene the tables
/// need is missing, before anything is measured.
pub(super) fn scene_names(cli: &Cli) -> Result<Vec<String>, String> {
    let rows: Vec<SceneRow> = cli.json(&["scenes", "--format", "json"])?;
    let names: Vec<String> = rows.into_iter().map(|s| s.name).collect();
    let needed = std::iter::once(T1_SCENE)
        .chain(T2_SCENES)
        .chain(T3_SCENES)
        .chain(TRI_SCENES)
        .chain([LIGHT_SCENE])
        .chain(RENDER_SCENES_EXTRA)
        .chain(TOYWARS_SCENES)
        .chain(SOFT_SCENES.map(|(s, _)| s));
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

/// Asks the release CLI what it was built with (target features, profile), the CPU it runs on
/// and which SIMD level the `simd` backend picks at run time, with one tiny `bench` run; adds
/// them to `host` (the CPU is the architecture's name when the probe fails).
pub(super) fn probe_build(cli: &Cli, host: &mut HostInfo) {
    let probe: Result<BenchReport<Bench>, String> = cli.json(&[
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
    let (level, features, profile) = match probe {
        Ok(v) => {
            host.cpu = v.host.cpu;
            let level = v
                .records
                .into_iter()
                .next()
                .and_then(|r| r.details.simd_level);
            (
                level.unwrap_or_else(|| "unknown".into()),
                v.host.compile_target_features.join("+"),
                v.host.profile.unwrap_or_else(|| "release".into()),
            )
        }
        Err(e) => {
            host.cpu = Some(std::env::consts::ARCH.to_owned());
            (
                format!("unknown (simd probe failed: {e})"),
                String::new(),
                "release".to_owned(),
            )
        }
    };
    let rustflags = host.rustflags.clone().unwrap_or_default();
    host.flags = Some(format!(
        "cargo build --release; RUSTFLAGS={rustflags:?}; compile-time target features: {}",
        if features.is_empty() {
            "none beyond the target default"
        } else {
            &features
        }
    ));
    host.simd_level = Some(level);
    host.compile_target_features = Some(features);
    host.profile = Some(profile);
}

/// `render SCENE --out PNG --size SIZE --format json`, for the caller to extend.
pub(super) fn render_args<'a>(scene: &'a str, png: &'a str, size: &'a str) -> Vec<&'a str> {
    vec![
        "render", scene, "--out", png, "--size", size, "--format", "json",
    ]
}

/// One run in progress: the CLI, the options and the results so far.
pub(super) struct Matrix {
    pub cli: Cli,
    pub opts: Options,
    pub results: Results,
    pub progress: Progress,
}

impl Matrix {
    /// `--frames`, as an argument.
    pub(super) fn frames(&self) -> String {
        self.opts.frames.to_string()
    }

    /// The device of `backend`, as `shadowvol backends` named it.
    fn device(&self, backend: &str) -> String {
        self.results
            .devices
            .get(backend)
            .cloned()
            .unwrap_or_default()
    }

    /// Where a render named `name` writes its PNG: `OUT/renders/NAME.png`.
    pub(super) fn render_png(&self, name: &str) -> String {
        let png = self.opts.out.join("renders").join(format!("{name}.png"));
        png.to_string_lossy().to_string()
    }

    /// Records one measurement of `experiment`.
    pub(super) fn push(&mut self, experiment: &str, key: Key, device: String, data: Data) {
        let rec = Record {
            host: self.results.host.clone(),
            experiment: experiment.to_owned(),
            reused_from: None,
            key,
            device,
            data,
        };
        self.results.records.push(rec);
    }

    /// Records a failed measurement and says so.
    pub(super) fn fail(&mut self, what: String) {
        eprintln!("\nmatrix: {what}");
        self.results.failures.push(what);
    }

    /// Stores the CLI records of one call under `experiment`.
    fn push_all<T>(&mut self, experiment: &str, list: RecordList<T>, wrap: fn(T) -> Data) {
        for rec in list.records {
            let device = self.device(&rec.backend);
            let r = Record::from_cli(experiment, rec, wrap, &device, &self.results.host);
            self.results.records.push(r);
        }
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
        let modes = modes.join(",");
        let frames = self.frames();
        let warmup = self.opts.warmup.to_string();
        let lights = lights.to_string();
        let args = |backends: &str| {
            [
                "bench",
                "--scene",
                scene,
                "--backend",
                backends,
                "--mode",
                &modes,
                "--frames",
                &frames,
                "--warmup",
                &warmup,
                "--lights",
                &lights,
                "--format",
                "json",
            ]
            .map(str::to_owned)
        };
        if let Err(e) = self.bench_call(experiment, &args(&backends.join(","))) {
            if backends.len() == 1 {
                self.fail(format!("{experiment}: {e}"));
                return;
            }
            for b in backends {
                if let Err(e) = self.bench_call(experiment, &args(b)) {
                    self.fail(format!("{experiment}: {e}"));
                }
            }
        }
    }

    /// One `shadowvol bench` call with `args`; its records are stored under `experiment`.
    fn bench_call(&mut self, experiment: &str, args: &[String]) -> Result<(), String> {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let mut report: BenchReport<Bench> = self.cli.json(&args)?;
        // Every record of the call carries the run's floor (the first light count's).
        for r in &mut report.records {
            r.data.floor_ms = report.floor_ms;
        }
        let list = RecordList {
            records: report.records,
        };
        self.push_all(experiment, list, Data::Bench);
        Ok(())
    }

    /// Copies the records of one measurement under another experiment's name (the same
    /// scene, backend, mode and lights measured once serves several tables).
    fn reuse(&mut self, from: &str, scene: &str, lights: u64, to: &str) {
        let copies: Vec<Record> = self
            .results
            .records
            .iter()
            .filter(|r| {
                r.experiment == from
                    && r.key.scene == scene
                    && r.bench().is_some_and(|b| b.lights == Some(lights))
            })
            .cloned()
            .map(|mut r| {
                r.experiment = to.to_owned();
                r.reused_from = Some(from.to_owned());
                r
            })
            .collect();
        self.results.records.extend(copies);
    }

    /// Runs every measurement of `plan`, in table order.
    pub fn run_plan(&mut self, plan: &Plan) {
        match self.opts.only {
            Some(Only::Maps) => return self.maps_table(plan),
            Some(Only::Memory) => return self.memory_table(plan),
            Some(Only::Soft) => return self.soft_table(&plan.soft),
            None => {}
        }
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
            let args = [
                "accuracy",
                "--backend",
                b,
                "--mode",
                &modes_s,
                "--format",
                "json",
            ];
            match self.cli.json::<RecordList<ModeErrors>>(&args) {
                Ok(list) => self.push_all("accuracy", list, Data::ModeErrors),
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
        self.frame_table(plan);
        self.maps_table(plan);
        self.memory_table(plan);
        self.soft_table(&plan.soft);
        // The seeds' CPU algorithms against our modes on cpu and simd.
        for s in &plan.toywars_scenes {
            self.progress.step(&format!("toywars: {s}"));
            let frames = self.frames();
            let warmup = self.opts.warmup.to_string();
            let args = [
                "baselines",
                "--scene",
                s,
                "--frames",
                &frames,
                "--warmup",
                &warmup,
                "--format",
                "json",
            ];
            match self.cli.json::<RecordList<Baseline>>(&args) {
                Ok(list) => self.push_all("toywars", list, Data::Baseline),
                Err(e) => self.fail(format!("toywars: {e}")),
            }
        }
    }

    /// The frame table: `render SCENE --frames N` on the host pipeline (`simd`) and on the GPU
    /// pipeline, exact mode, back to back in the same run.
    fn frame_table(&mut self, plan: &Plan) {
        let frames = self.frames();
        for s in plan.frame_scenes.clone() {
            for gpu in [false, true] {
                let key = if gpu {
                    FRAME_GPU_KEY
                } else {
                    FRAME_HOST_BACKEND
                };
                self.progress.step(&format!("frames: {s} {key}"));
                let png_s = self.render_png(&format!("frames-{s}-{key}"));
                let mut args = render_args(s, &png_s, plan.render_size);
                args.extend(["--mode", "exact", "--frames", &frames]);
                if gpu {
                    args.extend(["--pipeline", "gpu"]);
                } else {
                    args.extend(["--pipeline", "host", "--backend", FRAME_HOST_BACKEND]);
                }
                match self.cli.json::<RenderReport>(&args) {
                    Ok(report) => {
                        let key = Key {
                            scene: s.to_owned(),
                            backend: key.to_owned(),
                            mode: Some("exact".to_owned()),
                        };
                        let device = report.frame.adapter.clone();
                        let render = Render::new(report, plan.render_size, png_s);
                        self.push("frames", key, device, Data::Render(render));
                    }
                    Err(e) => self.fail(format!("frames: {e}")),
                }
            }
        }
    }

    /// `shadowvol render` of one scene, backend and mode at `size`, against the ray-traced
    /// reference with `reference`; records the frame time and artifact counts.
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
        let png_s = self.render_png(&format!("{experiment}-{scene}-{backend}-{mode}"));
        let mut args = render_args(scene, &png_s, size);
        args.extend(["--mode", mode, "--backend", backend]);
        if reference {
            args.push("--reference");
        }
        // The hard-* presets have no ground: a backdrop receives their shadows.
        if scene.starts_with("hard-") {
            args.push("--backdrop");
        }
        match self.cli.json::<RenderReport>(&args) {
            Ok(report) => {
                let key = Key {
                    scene: scene.to_owned(),
                    backend: backend.to_owned(),
                    mode: Some(mode.to_owned()),
                };
                let device = self.device(backend);
                self.push(
                    experiment,
                    key,
                    device,
                    Data::Render(Render::new(report, size, png_s)),
                );
            }
            Err(e) => self.fail(format!("{experiment}: {e}")),
        }
    }
}
