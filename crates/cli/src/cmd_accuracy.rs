//! `shadowvol accuracy`: what each accuracy mode gets wrong, on the hard scenes.
//!
//! For each scene (default: every `hard-*` preset) and each mode, it extracts silhouettes with
//! the chosen backend and compares them with the `cpu` backend's `exact` result: open vertices
//! (where the silhouette chain does not close), edges whose sign differs from exact, and edges
//! that differ from `cpu` in the same mode. One process runs them all, so `cargo xtask matrix`
//! pays the backend start-up once.

use serde::Serialize;
use shadowvol::{find_backend, CliError, Format};
use shadowvol_cpu::CpuBackend;
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::{invariant, Multiplicities, SilhouetteBackend};
use std::io::Write;
use std::time::Instant;

/// The long help of the subcommand.
pub const LONG_ABOUT: &str = "Measure what each accuracy mode gets wrong on the hard scenes.\n\n\
For every scene and mode, extract the silhouettes of all the scene's lights with --backend and \
compare them with the cpu backend in exact mode: open_vertices (vertices where the silhouette \
chain does not close; 0 for every consistent mode), sign_diff_vs_exact (edges whose sign of m \
differs from exact), diff_vs_cpu_same_mode (edges that differ from cpu in the same mode; 0 in \
exact on every backend) and uncertain (pairs the device could not certify and the host decided).\n\n\
JSON: {\"records\": [{\"scene\", \"backend\", \"mode\", \"lights\", \"edges\", \"open_vertices\", \
\"sign_diff_vs_exact\", \"diff_vs_cpu_same_mode\", \"uncertain\", \"ms\"}]}";

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenes (presets or .gltf/.glb/.obj files with lights), comma-separated. Default: every
    /// hard-* preset.
    #[arg(long, value_delimiter = ',')]
    scenes: Vec<String>,
    /// Backend to measure (see `shadowvol backends`), or `auto`: the first backend on a hardware
    /// GPU, else `simd`, with a warning naming what was skipped.
    #[arg(long, default_value = "cpu")]
    backend: String,
    /// Accuracy modes, comma-separated.
    #[arg(long, value_parser = shadowvol::mode_parser(), value_delimiter = ',', default_values = ["original", "robust", "ordered", "exact"])]
    mode: Vec<Accuracy>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// One (scene, mode) result.
#[derive(Debug, Serialize)]
struct Record {
    scene: String,
    backend: String,
    mode: &'static str,
    lights: usize,
    edges: usize,
    open_vertices: usize,
    sign_diff_vs_exact: usize,
    diff_vs_cpu_same_mode: usize,
    uncertain: u64,
    ms: f64,
}

#[derive(Debug, Serialize)]
struct Output {
    records: Vec<Record>,
}

fn extract(
    backend: &mut dyn SilhouetteBackend,
    scene: &shadowvol_silhouette::TopologyScene,
    lights: &[shadowvol_robust_math::Light],
    mode: Accuracy,
) -> Result<(Multiplicities, u64, f64), CliError> {
    let id = backend.prepare(scene)?;
    let mut out = Multiplicities::default();
    let t = Instant::now();
    let stats = backend.extract(id, lights, mode, &mut out);
    let ms = t.elapsed().as_secs_f64() * 1e3;
    backend.release(id);
    let stats = stats?;
    Ok((out, stats.uncertain, ms))
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    let entry = find_backend(&args.backend)?;
    let mut backend = entry.start()?;
    let scenes: Vec<String> = if args.scenes.is_empty() {
        shadowvol_scenes::preset_names()
            .into_iter()
            .filter(|n| n.starts_with("hard-"))
            .collect()
    } else {
        args.scenes.clone()
    };
    let mut cpu = CpuBackend::new();
    let mut records = Vec::new();
    for name in &scenes {
        let (scene, notes) = shadowvol::load_scene(name)?;
        for n in &notes {
            eprintln!("note: {n}");
        }
        if scene.lights.is_empty() {
            return Err(CliError::Usage(format!(
                "{name}: the scene defines no lights, so there is nothing to measure"
            )));
        }
        let topo = &scene.geometry;
        let scene_lights = scene.light_positions();
        let (exact, _, _) = extract(&mut cpu, topo, &scene_lights, Accuracy::Exact)?;
        for &mode in &args.mode {
            let (got, uncertain, ms) = extract(backend.as_mut(), topo, &scene_lights, mode)?;
            let (same, _, _) = if mode == Accuracy::Exact {
                (exact.clone(), 0, 0.0)
            } else {
                extract(&mut cpu, topo, &scene_lights, mode)?
            };
            let lights = scene.lights.len();
            records.push(Record {
                scene: name.clone(),
                backend: entry.name.to_owned(),
                mode: mode.name(),
                lights,
                edges: topo.total_edges(),
                open_vertices: (0..lights)
                    .map(|l| invariant::open_vertices_scene(topo, &got, l))
                    .sum(),
                sign_diff_vs_exact: (0..lights)
                    .map(|l| invariant::differing_signs(&got, &exact, l))
                    .sum(),
                diff_vs_cpu_same_mode: (0..lights)
                    .map(|l| invariant::differing_edges(&got, &same, l))
                    .sum(),
                uncertain,
                ms,
            });
        }
    }
    match args.format {
        Format::Json => {
            serde_json::to_writer(&mut *out, &Output { records })
                .map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => {
            writeln!(
                out,
                "{:<28} {:<8} {:<9} {:>6} {:>8} {:>6} {:>9} {:>9} {:>9}",
                "scene",
                "backend",
                "mode",
                "lights",
                "edges",
                "open",
                "sign≠ex",
                "≠cpu",
                "uncertain"
            )?;
            for r in &records {
                writeln!(
                    out,
                    "{:<28} {:<8} {:<9} {:>6} {:>8} {:>6} {:>9} {:>9} {:>9}",
                    r.scene,
                    r.backend,
                    r.mode,
                    r.lights,
                    r.edges,
                    r.open_vertices,
                    r.sign_diff_vs_exact,
                    r.diff_vs_cpu_same_mode,
                    r.uncertain
                )?;
            }
        }
    }
    Ok(())
}
