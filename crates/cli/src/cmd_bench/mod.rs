//! `shadowvol bench`: time silhouette extraction per backend and mode on a scene, next to the
//! measured memory floor.

mod text;

use serde::Serialize;
use shadowvol::memory::{peak_rss_bytes, table_bytes, TableBytes};
use shadowvol::{find_backend, BackendEntry, CliError, Format, MemoryFloor};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{Multiplicities, SilhouetteBackend, TopologyScene};
use std::io::Write;
use std::time::{Duration, Instant};

/// The long help of the subcommand.
pub const LONG_ABOUT: &str = "Time silhouette extraction on a scene for each backend, mode \
    and light count: warm-up frames, then --frames timed frames (one extract call for all lights \
    each); report the median, p10 and p90 frame times. By default the timed frames of one \
    backend's modes and light counts are interleaved, in turns of 5 frames of each (every turn \
    after one untimed frame of it, which brings its data back into the caches), so that a busy \
    or drifting host slows them alike and their ratios stay comparable; --schedule sequential \
    times each one's frames back to back. In the same run, floor_ms is measured for each light \
    count: the time to stream-read the bytes any extraction must touch (edge records 8 B, \
    opposite vertices 4 B, positions 12 B per vertex) and write its output (4 B per edge and \
    light), on all cores.\n\n\
    JSON: {\"floor_ms\": F, \"records\": [{\"scene\", \"backend\", \"mode\", \"triangles\", \
    \"edges\", \"objects\", \"lights\", \"median_ms\", \"p10_ms\", \"p90_ms\", ...}], \
    \"host\": {...}}. floor_ms is that of the first light count; \"floors\" lists every \
    light count's floor, and each record carries its own floor_ms and floor_ratio. Records also \
    carry upload/compute/readback medians, the uncertain count (exact mode), the backend's \
    device and details (simd_level for simd). A progress bar is drawn on stderr when it is a \
    terminal.\n\n\
    Memory: each record has \"table_bytes\" (what the prepared scene held on that backend: \
    \"table_bytes_parts\" {\"topology\", \"host\", \"device\"}) and \"peak_rss_bytes\", the \
    process's peak resident set (the kernel's VmHWM) when its backend finished; that is a \
    high-water mark over every backend run before it, so give one --backend per process to \
    attribute it. The top-level \"peak_rss_bytes\" is the whole run's.\n\n\
    --build-runs N adds \"build\": the scene's largest edge table rebuilt N times from its own \
    positions and triangles (EdgeTable::build: weld, counting sort, grouping, on rayon's \
    threads), {\"triangles\", \"vertices\", \"input_bytes\", \"runs\", \"median_ms\", \
    \"min_ms\", \"read_ms\", \"ratio\", \"threads\"}: read_ms is the median time to read \
    input_bytes on the same threads, ratio = median_ms / read_ms.";

/// Timed frames per (mode, light count) in one turn of the interleaved schedule.
const TURN_FRAMES: u32 = 5;

/// How the timed frames of one backend are ordered.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Schedule {
    /// After each one's warm-up, turns of a few timed frames of each (mode, light count), each
    /// turn preceded by one untimed frame of it.
    #[default]
    Interleaved,
    /// All frames of one (mode, light count), then the next.
    Sequential,
}

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
    #[arg(long, value_parser = shadowvol::mode_parser(), value_delimiter = ',', default_values = ["original", "robust", "ordered", "exact"])]
    mode: Vec<Accuracy>,
    /// Timed frames per (backend, mode).
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Untimed warm-up frames before the timed ones.
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Number of lights per call (default: the scene's own lights, or 1 if it has none). Extra
    /// lights beyond the scene's are point lights placed around it. Several counts,
    /// comma-separated (for example `1,4`), are all timed in the same run.
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=1024))]
    lights: Vec<u32>,
    /// Order of the timed frames of one backend: `interleaved` (turns of 5 timed frames of each
    /// mode and light count, each after one untimed frame of it) or `sequential` (all frames of
    /// one, then the next).
    #[arg(long, value_enum, default_value_t = Schedule::Interleaved)]
    schedule: Schedule,
    /// Skip backends that cannot start here (with a warning) instead of failing.
    #[arg(long)]
    skip_unavailable: bool,
    /// Also time building the scene's largest edge table from its mesh, this many times, next
    /// to reading the same bytes from memory ("build" in the JSON; 0: not timed).
    #[arg(long, default_value_t = 0)]
    build_runs: u32,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,

    #[command(flatten)]
    light_size: shadowvol::LightSizeArgs,
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
    /// The floor of this record's light count (the run's `floor_ms` for the first count).
    floor_ms: f64,
    floor_ratio: f64,
    device: String,
    details: serde_json::Map<String, serde_json::Value>,
    /// The process's peak resident set when this backend's records were made: a high-water
    /// mark, so it includes every backend run before it (run one backend per process to
    /// attribute it).
    peak_rss_bytes: Option<u64>,
    /// What the prepared scene held on this backend (edge tables, host layout, device buffers).
    table_bytes: u64,
    table_bytes_parts: TableBytes,
    /// Per original light, its radius (0 for a point light).
    light_radii: Vec<f32>,
    /// Per original light, its samples in this record's call.
    light_samples: Vec<u32>,
    /// A record of samples: the median of the same lights as point lights.
    #[serde(skip_serializing_if = "Option::is_none")]
    point_median_ms: Option<f64>,
    /// A record of samples: `median_ms / point_median_ms`.
    #[serde(skip_serializing_if = "Option::is_none")]
    samples_vs_point: Option<f64>,
    /// The record times the point lights of another record's samples.
    #[serde(skip)]
    point_reference: bool,
}

/// The floor of one light count.
#[derive(Debug, Serialize)]
struct FloorRecord {
    lights: usize,
    floor_ms: f64,
    floor_p10_ms: f64,
    floor_p90_ms: f64,
    floor_bytes_read: usize,
    floor_bytes_written: usize,
}

#[derive(Debug, Serialize)]
struct Report {
    floor_ms: f64,
    floor_p10_ms: f64,
    floor_p90_ms: f64,
    floor_bytes_read: usize,
    floor_bytes_written: usize,
    /// Every light count's floor, in the order of `--lights`.
    floors: Vec<FloorRecord>,
    schedule: &'static str,
    records: Vec<Record>,
    host: Host,
    /// The process's peak resident set over the whole run.
    peak_rss_bytes: Option<u64>,
    /// The edge-table build against its memory floor (`--build-runs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    build: Option<crate::build_time::BuildTiming>,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// `(median, p10, p90)` in milliseconds (nearest-rank percentiles).
pub(crate) fn percentiles(samples: &mut [Duration]) -> (f64, f64, f64) {
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
///
/// # Errors
/// [`CliError::Other`] when a ring light's position is beyond the `f32` range (a scene whose
/// coordinates come within a few bounding radii of `f32::MAX`).
fn bench_lights(
    scene_arg: &str,
    scene_lights: &[Light],
    topo: &TopologyScene,
    n: Option<u32>,
) -> Result<Vec<Light>, CliError> {
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
        let (centre, radius) = shadowvol_scenes::box_centre_radius(lo, hi);
        let radius = radius.max(1e-3);
        let extra = n - lights.len();
        for k in 0..extra {
            let a = std::f32::consts::TAU * (k as f32 + 0.37) / extra as f32;
            let p = centre + radius * glam::Vec3::new(2.0 * a.cos(), 1.3, 2.0 * a.sin());
            lights.push(Light::new(p.x, p.y, p.z, 1.0).map_err(|e| {
                shadowvol::bounds_too_large(
                    scene_arg,
                    lo,
                    hi,
                    "the ring of generated lights",
                    &format!("{e}; give the scene its own lights"),
                )
            })?);
        }
    }
    Ok(lights)
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

fn floor_samples(floor: &mut MemoryFloor, warmup: u32, frames: u32, into: &mut Vec<Duration>) {
    for _ in 0..warmup {
        floor.run_once();
    }
    for _ in 0..frames {
        into.push(floor.run_once());
    }
}

/// Samples of one (mode, light count) of a backend.
#[derive(Default)]
struct Samples {
    frame: Vec<Duration>,
    upload: Vec<Duration>,
    compute: Vec<Duration>,
    readback: Vec<Duration>,
    host: Vec<Duration>,
    uncertain: u64,
}

/// The lights of one call, and where they came from.
struct LightSet {
    lights: Vec<Light>,
    /// Per original light, its radius.
    radii: Vec<f32>,
    /// Per original light, how many of `lights` are its samples.
    samples: Vec<u32>,
    /// For samples: the index of the set of the same lights as point lights.
    point_set: Option<usize>,
    /// The set holds the point lights of another set's samples.
    point_reference: bool,
}

/// What the command line names, resolved and loaded before any timing.
struct Setup {
    entries: Vec<BackendEntry>,
    scene_name: String,
    topo: TopologyScene,
    light_sets: Vec<LightSet>,
    /// (mode, index into `light_sets`) in the order of the records.
    combos: Vec<(Accuracy, usize)>,
}

impl Setup {
    /// Resolves the backends, modes and light counts of `args` and loads the scene.
    ///
    /// # Errors
    /// [`CliError::Usage`] for an unknown backend, no backend or mode, or a light count given
    /// twice; the scene's load errors.
    fn new(args: &Args) -> Result<Self, CliError> {
        let entries = args
            .backend
            .iter()
            .map(|b| find_backend(b))
            .collect::<Result<Vec<_>, _>>()?;
        let modes = &args.mode;
        if modes.is_empty() || entries.is_empty() {
            return Err(CliError::Usage(
                "give at least one backend and one mode".to_owned(),
            ));
        }
        if let Some(n) = args
            .lights
            .iter()
            .enumerate()
            .find_map(|(i, n)| args.lights[..i].contains(n).then_some(n))
        {
            return Err(CliError::Usage(format!("--lights lists {n} twice")));
        }
        let (scene, notes) = shadowvol::load_scene(&args.scene)?;
        for n in &notes {
            eprintln!("note: {n}");
        }
        let scene_lights = scene.light_positions();
        let own_radii: Vec<f32> = scene.lights.iter().map(|l| l.radius).collect();
        let aim = scene.light_aim();
        let topo = scene.geometry;
        let counts: Vec<Option<u32>> = if args.lights.is_empty() {
            vec![None]
        } else {
            args.lights.iter().map(|&n| Some(n)).collect()
        };
        let mut light_sets = Vec::new();
        for &n in &counts {
            let base = bench_lights(&args.scene, &scene_lights, &topo, n)?;
            let sampled = args.light_size.sampled(
                &base,
                &own_radii,
                aim,
                shadowvol::light_size::DEFAULT_SAMPLES,
            )?;
            if sampled.is_sampled() {
                light_sets.push(LightSet {
                    lights: sampled.lights,
                    radii: sampled.radii,
                    samples: sampled.samples,
                    point_set: Some(light_sets.len() + 1),
                    point_reference: false,
                });
                light_sets.push(LightSet {
                    radii: vec![0.0; base.len()],
                    samples: vec![1; base.len()],
                    lights: base,
                    point_set: None,
                    point_reference: true,
                });
            } else {
                light_sets.push(LightSet {
                    lights: sampled.lights,
                    radii: sampled.radii,
                    samples: sampled.samples,
                    point_set: None,
                    point_reference: false,
                });
            }
        }
        let combos = modes
            .iter()
            .flat_map(|&m| (0..light_sets.len()).map(move |k| (m, k)))
            .collect();
        Ok(Self {
            entries,
            scene_name: scene.name,
            topo,
            light_sets,
            combos,
        })
    }
}

/// The progress bar of a run: `total` frames.
fn progress_bar(total: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    // Resolve everything named on the command line before any timing.
    let setup = Setup::new(args)?;
    // Frames per floor, and per (backend, mode, light count): the interleaved schedule adds one
    // untimed frame per turn.
    let per = u64::from(args.warmup + args.frames);
    let per_combo = per
        + match args.schedule {
            Schedule::Interleaved => u64::from(args.frames.div_ceil(TURN_FRAMES)),
            Schedule::Sequential => 0,
        };
    let bar = progress_bar(
        per_combo * (setup.entries.len() * setup.combos.len()) as u64
            + per * 2 * setup.light_sets.len() as u64,
    );

    // The floors, before and after the backends (same run, same threads); median of both.
    let mut floors: Vec<(MemoryFloor, Vec<Duration>)> = setup
        .light_sets
        .iter()
        .map(|l| (MemoryFloor::new(&setup.topo, l.lights.len()), Vec::new()))
        .collect();
    let run_floors = |floors: &mut Vec<(MemoryFloor, Vec<Duration>)>| {
        for (floor, times) in floors.iter_mut() {
            bar.set_message("memory floor");
            floor_samples(floor, args.warmup, args.frames, times);
            bar.inc(per);
        }
    };
    run_floors(&mut floors);

    let mut records = Vec::new();
    for entry in &setup.entries {
        let mut backend = match entry.start() {
            Ok(b) => b,
            Err(e) if args.skip_unavailable => {
                bar.suspend(|| eprintln!("warning: skipping {}: {e}", entry.name));
                bar.inc(per_combo * setup.combos.len() as u64);
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        records.extend(bench_backend(args, &setup, entry, backend.as_mut(), &bar)?);
    }
    run_floors(&mut floors);
    let build = if args.build_runs > 0 {
        bar.set_message("edge-table build");
        let largest = setup
            .topo
            .objects
            .iter()
            .max_by_key(|o| o.table.triangles.len())
            .ok_or_else(|| CliError::Other("the scene has no object to build".to_owned()))?;
        Some(crate::build_time::time_build(
            &largest.table,
            args.build_runs,
        )?)
    } else {
        None
    };
    bar.finish_and_clear();

    let mut report = report(args, floors, &setup.light_sets, records);
    report.build = build;
    match args.format {
        Format::Json => {
            serde_json::to_writer(&mut *out, &report).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => text::print_text(&report, out)?,
    }
    Ok(())
}

/// Times every (mode, light count) of `setup` on the started `backend` of `entry`, in the order
/// of `args.schedule`; one record per (mode, light count), its floor still to be filled in.
///
/// # Errors
/// A mode the backend does not support, or the backend's own error from `prepare` or `extract`.
fn bench_backend(
    args: &Args,
    setup: &Setup,
    entry: &BackendEntry,
    backend: &mut dyn SilhouetteBackend,
    bar: &indicatif::ProgressBar,
) -> Result<Vec<Record>, CliError> {
    let (combos, light_sets, topo) = (&setup.combos, &setup.light_sets, &setup.topo);
    let info = backend.info();
    if let Some((mode, _)) = combos.iter().find(|(m, _)| !info.modes.contains(m)) {
        return Err(CliError::Other(format!(
            "backend {} does not support mode {mode}",
            entry.name
        )));
    }
    bar.set_message(format!("{}: prepare", entry.name));
    let id = backend.prepare(topo)?;
    // After the preparation, which some backends report on (the layout `simd` chose).
    let details: serde_json::Map<String, serde_json::Value> = backend
        .info()
        .details
        .iter()
        .map(|(k, v)| (k.clone(), serde_json::Value::String(v.clone())))
        .collect();
    // One output per light set, so that interleaving never resizes it inside a timed frame.
    let mut results: Vec<Multiplicities> = light_sets
        .iter()
        .map(|_| Multiplicities::default())
        .collect();
    let mut samples: Vec<Samples> = combos.iter().map(|_| Samples::default()).collect();
    let mut frame = |c: usize, timed: bool| -> Result<(), CliError> {
        let (mode, k) = combos[c];
        let t = Instant::now();
        let stats = backend.extract(id, &light_sets[k].lights, mode, &mut results[k])?;
        let wall = t.elapsed();
        bar.inc(1);
        if timed {
            let s = &mut samples[c];
            s.frame.push(wall);
            s.upload.push(stats.upload);
            s.compute.push(stats.compute);
            s.readback.push(stats.readback);
            s.host.push(stats.host_resolve);
            s.uncertain = stats.uncertain;
        }
        Ok(())
    };
    run_schedule(args, entry.name, combos, bar, &mut frame)?;
    let table = table_bytes(topo.table_bytes(), backend.prepared_bytes(id)?);
    let peak = peak_rss_bytes();
    let mut records: Vec<Record> = combos
        .iter()
        .zip(&mut samples)
        .map(|(&(mode, k), s)| {
            let (median, p10, p90) = percentiles(&mut s.frame);
            Record {
                scene: setup.scene_name.clone(),
                backend: entry.name.to_owned(),
                mode: mode.name(),
                triangles: topo.total_triangles(),
                edges: topo.total_edges(),
                objects: topo.objects.len(),
                lights: light_sets[k].lights.len(),
                median_ms: median,
                p10_ms: p10,
                p90_ms: p90,
                frames: args.frames,
                upload_ms: median_ms(&mut s.upload),
                compute_ms: median_ms(&mut s.compute),
                readback_ms: median_ms(&mut s.readback),
                host_resolve_ms: median_ms(&mut s.host),
                uncertain: s.uncertain,
                floor_ms: 0.0,
                floor_ratio: 0.0,
                device: info.device.clone(),
                details: details.clone(),
                peak_rss_bytes: peak,
                table_bytes: table.total(),
                table_bytes_parts: table,
                light_radii: light_sets[k].radii.clone(),
                light_samples: light_sets[k].samples.clone(),
                point_median_ms: None,
                samples_vs_point: None,
                point_reference: light_sets[k].point_reference,
            }
        })
        .collect();
    // Each record of samples against its point lights, same mode.
    for (c, &(mode, k)) in combos.iter().enumerate() {
        let Some(j) = light_sets[k].point_set else {
            continue;
        };
        if let Some(p) = combos.iter().position(|&x| x == (mode, j)) {
            let point = records[p].median_ms;
            records[c].point_median_ms = Some(point);
            records[c].samples_vs_point = (point > 0.0).then(|| records[c].median_ms / point);
        }
    }
    backend.release(id);
    Ok(records)
}

/// Runs the warm-up and timed frames of every combination of one backend: `frame(c, timed)`
/// runs one frame of combination `c`.
///
/// # Errors
/// The first error of `frame`.
fn run_schedule(
    args: &Args,
    backend: &str,
    combos: &[(Accuracy, usize)],
    bar: &indicatif::ProgressBar,
    frame: &mut dyn FnMut(usize, bool) -> Result<(), CliError>,
) -> Result<(), CliError> {
    match args.schedule {
        Schedule::Sequential => {
            for (c, (mode, _)) in combos.iter().enumerate() {
                bar.set_message(format!("{backend} {mode}"));
                for i in 0..args.warmup + args.frames {
                    frame(c, i >= args.warmup)?;
                }
            }
        }
        Schedule::Interleaved => {
            for (c, (mode, _)) in combos.iter().enumerate() {
                bar.set_message(format!("{backend} {mode}: warm-up"));
                for _ in 0..args.warmup {
                    frame(c, false)?;
                }
            }
            bar.set_message(format!("{backend}: interleaved frames"));
            // Turns of TURN_FRAMES timed frames per combination, each turn after one untimed
            // frame that brings its data back into the caches (as a sequential run keeps them),
            // so the turns compare the same steady state.
            let mut done = 0;
            while done < args.frames {
                let n = TURN_FRAMES.min(args.frames - done);
                for c in 0..combos.len() {
                    frame(c, false)?;
                    for _ in 0..n {
                        frame(c, true)?;
                    }
                }
                done += n;
            }
        }
    }
    Ok(())
}

/// The report: each light count's floor from its samples, each record's floor and ratio, and
/// the host.
fn report(
    args: &Args,
    mut floors: Vec<(MemoryFloor, Vec<Duration>)>,
    light_sets: &[LightSet],
    mut records: Vec<Record>,
) -> Report {
    let floor_records: Vec<FloorRecord> = floors
        .iter_mut()
        .zip(light_sets)
        .map(|((floor, times), lights)| {
            let (floor_ms, p10, p90) = percentiles(times);
            FloorRecord {
                lights: lights.lights.len(),
                floor_ms,
                floor_p10_ms: p10,
                floor_p90_ms: p90,
                floor_bytes_read: floor.bytes_read(),
                floor_bytes_written: floor.bytes_written(),
            }
        })
        .collect();
    for r in &mut records {
        let f = floor_records
            .iter()
            .find(|f| f.lights == r.lights)
            .map_or(0.0, |f| f.floor_ms);
        r.floor_ms = f;
        r.floor_ratio = if f > 0.0 { r.median_ms / f } else { 0.0 };
    }
    let first = &floor_records[0];
    Report {
        floor_ms: first.floor_ms,
        floor_p10_ms: first.floor_p10_ms,
        floor_p90_ms: first.floor_p90_ms,
        floor_bytes_read: first.floor_bytes_read,
        floor_bytes_written: first.floor_bytes_written,
        schedule: match args.schedule {
            Schedule::Interleaved => "interleaved",
            Schedule::Sequential => "sequential",
        },
        floors: floor_records,
        records,
        host: host(),
        peak_rss_bytes: peak_rss_bytes(),
        build: None,
    }
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
        let scene_lights = scene.light_positions();
        let lights = bench_lights("test", &scene_lights, &scene.geometry, Some(4)).unwrap();
        assert_eq!(lights.len(), 4);
        for (i, l) in lights.iter().enumerate() {
            if i < scene_lights.len() {
                assert_eq!(*l, scene_lights[i]);
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
