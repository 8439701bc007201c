//! `shadowvol bench`: time silhouette extraction per backend and mode on a scene, next to the
//! measured memory floor.

use serde::Serialize;
use shadowvol::{find_backend, CliError, Format, ModeArg};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{Multiplicities, TopologyScene};
use std::io::Write;
use std::time::{Duration, Instant};

/// The long help of the subcommand.
pub const LONG_ABOUT: &str = "Time silhouette extraction on a scene for each backend and mode: \
    warm-up frames, then --frames timed frames (one extract call for all lights each); report \
    the median, p10 and p90 frame times. In the same run, floor_ms is measured: the time to \
    stream-read the bytes any extraction must touch (edge records 8 B, opposite vertices 4 B, \
    positions 12 B per vertex) and write its output (4 B per edge and light), on all cores.\n\n\
    JSON: {\"floor_ms\": F, \"records\": [{\"scene\", \"backend\", \"mode\", \"triangles\", \
    \"edges\", \"objects\", \"lights\", \"median_ms\", \"p10_ms\", \"p90_ms\", ...}], \
    \"host\": {...}}. Records also carry upload/compute/readback medians, the uncertain count \
    (exact mode), the backend's device and details (simd_level for simd). A progress bar is \
    drawn on stderr when it is a terminal.";

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene: a preset name (see `shadowvol scenes`) or a .gltf/.glb/.obj file.
    #[arg(long)]
    scene: String,
    /// Backends to time, comma-separated (names from `shadowvol backends`, or `auto`: the first
    /// backend on a hardware GPU, else `simd`, with a warning naming what was skipped).
    #[arg(long, value_delimiter = ',', default_value = "cpu,simd")]
    backend: Vec<String>,
    /// Accuracy modes to time, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [ModeArg::Original, ModeArg::Robust, ModeArg::Ordered, ModeArg::Exact])]
    mode: Vec<ModeArg>,
    /// Timed frames per (backend, mode).
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Untimed warm-up frames before the timed ones.
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Number of lights per call (default: the scene's own lights, or 1 if it has none). Extra
    /// lights beyond the scene's are point lights placed around it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    lights: Option<u32>,
    /// Skip backends that cannot start here (with a warning) instead of failing.
    #[arg(long)]
    skip_unavailable: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// Where and how the numbers were taken.
#[derive(Debug, Serialize)]
struct Host {
    cpu: String,
    cores: usize,
    os: &'static str,
    arch: &'static str,
    /// `rustc -V` of the compiler that built this binary (recorded by `build.rs`).
    rustc: String,
    /// Target features enabled at compile time (`-C target-cpu` / `-C target-feature`).
    compile_target_features: Vec<&'static str>,
    /// The `RUSTFLAGS` this binary was built with (`null` for none; recorded by `build.rs`).
    rustflags: Option<String>,
    profile: &'static str,
    /// The git revision of the checkout this binary was built from (`build.rs`; `unknown`
    /// outside a git checkout).
    git_rev: String,
}

#[derive(Debug, Serialize)]
struct Record {
    scene: String,
    backend: String,
    mode: &'static str,
    triangles: usize,
    edges: usize,
    objects: usize,
    lights: usize,
    median_ms: f64,
    p10_ms: f64,
    p90_ms: f64,
    frames: u32,
    upload_ms: f64,
    compute_ms: f64,
    readback_ms: f64,
    host_resolve_ms: f64,
    uncertain: u64,
    floor_ratio: f64,
    device: String,
    details: serde_json::Map<String, serde_json::Value>,
}

#[derive(Debug, Serialize)]
struct Report {
    floor_ms: f64,
    floor_p10_ms: f64,
    floor_p90_ms: f64,
    floor_bytes_read: usize,
    floor_bytes_written: usize,
    records: Vec<Record>,
    host: Host,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// `(median, p10, p90)` in milliseconds (nearest-rank percentiles).
fn percentiles(samples: &mut [Duration]) -> (f64, f64, f64) {
    if samples.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    samples.sort_unstable();
    let at = |q: f64| {
        let i = ((samples.len() - 1) as f64 * q).round() as usize;
        ms(samples[i])
    };
    (at(0.5), at(0.1), at(0.9))
}

fn median_ms(samples: &mut [Duration]) -> f64 {
    percentiles(samples).0
}

/// The lights of the run: the scene's own, cycled and extended with point lights on a ring
/// around the scene's bounding box when more are asked for.
fn bench_lights(scene_lights: &[Light], topo: &TopologyScene, n: Option<u32>) -> Vec<Light> {
    let n = n.map_or(scene_lights.len().max(1), |n| n as usize);
    let mut lights: Vec<Light> = scene_lights.iter().take(n).copied().collect();
    if lights.len() < n {
        let (mut lo, mut hi) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
        for o in &topo.objects {
            for p in &o.table.positions {
                let w = o.world_from_object.transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
        if lo.x > hi.x {
            (lo, hi) = (glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0));
        }
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let extra = n - lights.len();
        for k in 0..extra {
            let a = std::f32::consts::TAU * (k as f32 + 0.37) / extra as f32;
            let p = centre + radius * glam::Vec3::new(2.0 * a.cos(), 1.3, 2.0 * a.sin());
            lights.push(Light::point(p));
        }
    }
    lights
}

fn host() -> Host {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_owned())
        })
        .unwrap_or_else(|| "unknown".to_owned());
    let mut features = Vec::new();
    macro_rules! feature {
        ($($f:literal),*) => { $( if cfg!(target_feature = $f) { features.push($f); } )* };
    }
    feature!("sse2", "sse4.1", "sse4.2", "avx", "avx2", "fma", "avx512f");
    Host {
        cpu,
        cores: std::thread::available_parallelism().map_or(1, std::num::NonZero::get),
        os: std::env::consts::OS,
        arch: std::env::consts::ARCH,
        rustc: env!("SHADOWVOL_BUILD_RUSTC").to_owned(),
        compile_target_features: features,
        rustflags: Some(env!("SHADOWVOL_BUILD_RUSTFLAGS"))
            .filter(|f| !f.is_empty())
            .map(str::to_owned),
        profile: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        git_rev: env!("SHADOWVOL_BUILD_GIT_REV").to_owned(),
    }
}

/// One pass over the minimum traffic (see [`LONG_ABOUT`]).
#[cfg(feature = "simd")]
struct Floor(shadowvol_simd::MemoryFloor);

#[cfg(feature = "simd")]
impl Floor {
    fn new(scene: &TopologyScene, lights: usize) -> Self {
        Self(shadowvol_simd::MemoryFloor::new(scene, lights))
    }
    fn bytes(&self) -> (usize, usize) {
        (self.0.bytes_read(), self.0.bytes_written())
    }
    fn run_once(&mut self) -> Duration {
        self.0.run_once()
    }
}

/// Without the `simd` backend compiled in: the same traffic, on all cores with std threads.
#[cfg(not(feature = "simd"))]
struct Floor {
    input: Vec<u64>,
    output: Vec<u32>,
}

#[cfg(not(feature = "simd"))]
impl Floor {
    fn new(scene: &TopologyScene, lights: usize) -> Self {
        let words: usize = scene
            .objects
            .iter()
            .map(|o| o.table.edges.len() * 2 + o.table.ovs.len() + o.table.positions.len() * 3)
            .sum();
        Self {
            input: (0..words.div_ceil(2) as u64).collect(),
            output: vec![0; scene.total_edges() * lights],
        }
    }
    fn bytes(&self) -> (usize, usize) {
        (self.input.len() * 8, self.output.len() * 4)
    }
    fn run_once(&mut self) -> Duration {
        let start = Instant::now();
        let threads = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
        let ic = self.input.len().div_ceil(threads).max(1);
        let oc = self.output.len().div_ceil(threads).max(1);
        let input = &self.input;
        let sum: u64 = std::thread::scope(|s| {
            let handles: Vec<_> = self
                .output
                .chunks_mut(oc)
                .enumerate()
                .map(|(t, out)| {
                    s.spawn(move || {
                        let part =
                            &input[(t * ic).min(input.len())..((t + 1) * ic).min(input.len())];
                        let v = part.iter().fold(0u64, |a, &b| a.wrapping_add(b));
                        out.fill(v as u32);
                        v
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap_or(0)).sum()
        });
        std::hint::black_box(sum);
        start.elapsed()
    }
}

fn floor_samples(floor: &mut Floor, warmup: u32, frames: u32, into: &mut Vec<Duration>) {
    for _ in 0..warmup {
        floor.run_once();
    }
    for _ in 0..frames {
        into.push(floor.run_once());
    }
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    // Resolve everything named on the command line before any timing.
    let entries = args
        .backend
        .iter()
        .map(|b| find_backend(b))
        .collect::<Result<Vec<_>, _>>()?;
    let modes: Vec<Accuracy> = args.mode.iter().map(|&m| m.into()).collect();
    if modes.is_empty() || entries.is_empty() {
        return Err(CliError::Usage(
            "give at least one backend and one mode".to_owned(),
        ));
    }
    let scene = shadowvol_scenes::Scene::from_name_or_path(&args.scene)
        .map_err(|e| CliError::Other(format!("scene {:?}: {e}", args.scene)))?;
    let topo = scene
        .topology()
        .map_err(|e| CliError::Other(format!("scene {:?}: {e}", args.scene)))?;
    let lights = bench_lights(&scene.lights, &topo, args.lights);

    let bar = indicatif::ProgressBar::new(
        u64::from(args.warmup + args.frames) * (entries.len() * modes.len() + 2) as u64,
    );
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );

    // The floor, before and after the backends (same run, same threads); median of both.
    let mut floor = Floor::new(&topo, lights.len());
    let mut floor_times = Vec::new();
    bar.set_message("memory floor");
    floor_samples(&mut floor, args.warmup, args.frames, &mut floor_times);
    bar.inc(u64::from(args.warmup + args.frames));

    let mut records = Vec::new();
    for entry in &entries {
        let mut backend = match entry.start() {
            Ok(b) => b,
            Err(e) if args.skip_unavailable => {
                bar.suspend(|| eprintln!("warning: skipping {}: {e}", entry.name));
                bar.inc(u64::from(args.warmup + args.frames) * modes.len() as u64);
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        let info = backend.info();
        let details: serde_json::Map<String, serde_json::Value> = info
            .details
            .iter()
            .map(|(k, v)| (k.clone(), serde_json::Value::String(v.clone())))
            .collect();
        bar.set_message(format!("{}: prepare", entry.name));
        let id = backend.prepare(&topo)?;
        let mut result = Multiplicities::default();
        for &mode in &modes {
            if !info.modes.contains(&mode) {
                return Err(CliError::Other(format!(
                    "backend {} does not support mode {mode}",
                    entry.name
                )));
            }
            bar.set_message(format!("{} {mode}", entry.name));
            let (mut frame, mut up, mut comp, mut back, mut host) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
            let mut uncertain = 0;
            for i in 0..args.warmup + args.frames {
                let t = Instant::now();
                let stats = backend.extract(id, &lights, mode, &mut result)?;
                let wall = t.elapsed();
                bar.inc(1);
                if i >= args.warmup {
                    frame.push(wall);
                    up.push(stats.upload);
                    comp.push(stats.compute);
                    back.push(stats.readback);
                    host.push(stats.host_resolve);
                    uncertain = stats.uncertain;
                }
            }
            let (median, p10, p90) = percentiles(&mut frame);
            records.push(Record {
                scene: scene.name.clone(),
                backend: entry.name.to_owned(),
                mode: mode.name(),
                triangles: topo.total_triangles(),
                edges: topo.total_edges(),
                objects: topo.objects.len(),
                lights: lights.len(),
                median_ms: median,
                p10_ms: p10,
                p90_ms: p90,
                frames: args.frames,
                upload_ms: median_ms(&mut up),
                compute_ms: median_ms(&mut comp),
                readback_ms: median_ms(&mut back),
                host_resolve_ms: median_ms(&mut host),
                uncertain,
                floor_ratio: 0.0,
                device: info.device.clone(),
                details: details.clone(),
            });
        }
        backend.release(id);
    }
    bar.set_message("memory floor");
    floor_samples(&mut floor, args.warmup, args.frames, &mut floor_times);
    bar.inc(u64::from(args.warmup + args.frames));
    bar.finish_and_clear();

    let (floor_ms, floor_p10, floor_p90) = percentiles(&mut floor_times);
    for r in &mut records {
        r.floor_ratio = if floor_ms > 0.0 {
            r.median_ms / floor_ms
        } else {
            0.0
        };
    }
    let (bytes_read, bytes_written) = floor.bytes();
    let report = Report {
        floor_ms,
        floor_p10_ms: floor_p10,
        floor_p90_ms: floor_p90,
        floor_bytes_read: bytes_read,
        floor_bytes_written: bytes_written,
        records,
        host: host(),
    };
    match args.format {
        Format::Json => {
            serde_json::to_writer(&mut *out, &report).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => print_text(&report, out)?,
    }
    Ok(())
}

fn print_text(r: &Report, out: &mut dyn Write) -> Result<(), CliError> {
    if let Some(first) = r.records.first() {
        writeln!(
            out,
            "scene {}: {} triangles, {} edges, {} object(s), {} light(s)",
            first.scene, first.triangles, first.edges, first.objects, first.lights
        )?;
    }
    writeln!(
        out,
        "floor {:.3} ms (p10 {:.3}, p90 {:.3}; reads {:.1} MB, writes {:.1} MB)",
        r.floor_ms,
        r.floor_p10_ms,
        r.floor_p90_ms,
        r.floor_bytes_read as f64 / 1e6,
        r.floor_bytes_written as f64 / 1e6
    )?;
    writeln!(
        out,
        "{:8} {:9} {:>10} {:>10} {:>10} {:>8} {:>10}  details",
        "backend", "mode", "median_ms", "p10_ms", "p90_ms", "x floor", "uncertain"
    )?;
    for rec in &r.records {
        let level = rec
            .details
            .get("simd_level")
            .and_then(|v| v.as_str())
            .map(|s| format!("simd_level={s}"))
            .unwrap_or_default();
        writeln!(
            out,
            "{:8} {:9} {:10.3} {:10.3} {:10.3} {:8.2} {:10}  {level}",
            rec.backend,
            rec.mode,
            rec.median_ms,
            rec.p10_ms,
            rec.p90_ms,
            rec.floor_ratio,
            rec.uncertain
        )?;
    }
    writeln!(
        out,
        "host: {} ({} cores), {}, {}, git {}",
        r.host.cpu, r.host.cores, r.host.rustc, r.host.profile, r.host.git_rev
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_nearest_rank() {
        let mut v: Vec<Duration> = (1..=11).rev().map(Duration::from_millis).collect();
        let (m, p10, p90) = percentiles(&mut v);
        assert_eq!((m, p10, p90), (6.0, 2.0, 10.0));
    }

    #[test]
    fn extra_lights_are_generated_around_the_scene() {
        let scene = shadowvol_scenes::preset("spheres-100x1k").unwrap();
        let topo = scene.topology().unwrap();
        let lights = bench_lights(&scene.lights, &topo, Some(4));
        assert_eq!(lights.len(), 4);
        for (i, l) in lights.iter().enumerate() {
            if i < scene.lights.len() {
                assert_eq!(*l, scene.lights[i]);
            }
        }
        // Distinct positions.
        for i in 0..4 {
            for j in 0..i {
                assert_ne!(lights[i], lights[j]);
            }
        }
    }
}
