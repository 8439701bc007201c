//! `shadowvol baselines`: the seeds' CPU silhouette algorithms (the "Toy Wars" table) timed next
//! to our accuracy modes on the `cpu` and `simd` backends, with the same statistics as
//! `shadowvol bench`.

use crate::cmd_bench::percentiles;
use serde::Serialize;
use shadowvol::{backends, CliError, Format};
use shadowvol_cpu::baselines::{Baseline, ClosedMesh};
use shadowvol_cpu::CpuBackend;
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::{object_lights, Multiplicities, SilhouetteBackend, TopologyScene};
use std::collections::BTreeSet;
use std::io::Write;
use std::time::Instant;

/// The long help of the subcommand.
pub const LONG_ABOUT: &str = "Time the seeds' CPU silhouette algorithms on a scene: the \
    thesis' two-step method (two-step), the Toy Wars notes' classic candidate list (classic), \
    their fast hash table with 64 and 8 columns (fast-hash-64, fast-hash-8) and their \
    connectivity table (connectivity); and, for comparison, every accuracy mode on the cpu and \
    simd backends (when they can start). Same statistics as `shadowvol bench`: --warmup untimed \
    frames, then --frames timed ones (one frame = every light of the scene on every object); \
    median, p10 and p90.\n\n\
    The seeds' algorithms need a closed, consistently oriented manifold mesh (the bunny \
    presets are); on other meshes their records carry the reason in `error`. Each record's \
    edge set (edges with m != 0, over all lights) is checked against the cpu backend's exact \
    result: `agrees_with_exact`.\n\n\
    JSON: {\"records\": [{\"scene\", \"backend\" (algorithm or backend name), \"mode\" (null \
    for the seeds' algorithms), \"kind\" (\"baseline\" or \"backend\"), \"triangles\", \
    \"edges\", \"objects\", \"lights\", \"median_ms\", \"p10_ms\", \"p90_ms\", \"frames\", \
    \"silhouette_edges\" (summed over lights), \"agrees_with_exact\", \"device\", \"details\", \
    \"error\"}]}. median_ms and the others are null when the algorithm failed.";

/// Examples shown after the help.
pub const AFTER_HELP: &str = "Examples:\n  shadowvol baselines --scene bunny\n  \
    shadowvol baselines --scene bunny-subdivided --frames 10 --format json";

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene: a preset name (see `shadowvol scenes`) or a .gltf/.glb/.obj file with lights.
    #[arg(long)]
    scene: String,
    /// Timed frames per algorithm.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Untimed warm-up frames before the timed ones.
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// One algorithm's result.
#[derive(Debug, Serialize)]
struct Record {
    scene: String,
    backend: String,
    mode: Option<&'static str>,
    kind: &'static str,
    triangles: usize,
    edges: usize,
    objects: usize,
    lights: usize,
    median_ms: Option<f64>,
    p10_ms: Option<f64>,
    p90_ms: Option<f64>,
    frames: u32,
    silhouette_edges: Option<usize>,
    agrees_with_exact: Option<bool>,
    device: String,
    details: serde_json::Map<String, serde_json::Value>,
    error: Option<String>,
}

#[derive(Debug, Serialize)]
struct Output {
    records: Vec<Record>,
}

/// The seeds' algorithms, in table order.
const BASELINES: [Baseline; 5] = [
    Baseline::Classic,
    Baseline::FastHash { columns: 64 },
    Baseline::FastHash { columns: 8 },
    Baseline::Connectivity,
    Baseline::TwoStep,
];

/// A silhouette as a set of (light, global edge index).
type EdgeSet = BTreeSet<(usize, u32)>;

fn edge_set(m: &Multiplicities) -> EdgeSet {
    (0..m.light_count())
        .flat_map(|l| m.silhouette(l).iter().map(move |&e| (l, e)))
        .collect()
}

struct Common<'a> {
    scene: &'a str,
    topo: &'a TopologyScene,
    lights: usize,
    frames: u32,
    warmup: u32,
}

impl Common<'_> {
    fn record(&self, backend: String, mode: Option<&'static str>, kind: &'static str) -> Record {
        Record {
            scene: self.scene.to_owned(),
            backend,
            mode,
            kind,
            triangles: self.topo.total_triangles(),
            edges: self.topo.total_edges(),
            objects: self.topo.objects.len(),
            lights: self.lights,
            median_ms: None,
            p10_ms: None,
            p90_ms: None,
            frames: self.frames,
            silhouette_edges: None,
            agrees_with_exact: None,
            device: "host CPU, scalar, 1 thread".to_owned(),
            details: serde_json::Map::new(),
            error: None,
        }
    }

    /// Runs `frame` warm-up + timed times; fills the statistics of `rec`.
    fn time<E>(&self, rec: &mut Record, mut frame: impl FnMut() -> Result<(), E>) -> Result<(), E> {
        let mut samples = Vec::with_capacity(self.frames as usize);
        for i in 0..self.warmup + self.frames {
            let t = Instant::now();
            frame()?;
            if i >= self.warmup {
                samples.push(t.elapsed());
            }
        }
        let (m, p10, p90) = percentiles(&mut samples);
        (rec.median_ms, rec.p10_ms, rec.p90_ms) = (Some(m), Some(p10), Some(p90));
        Ok(())
    }
}

/// Runs one seed algorithm over every object and light; returns the global edge set.
fn run_baseline(
    meshes: &[ClosedMesh<'_>],
    offsets: &[usize],
    obj_lights: &[Vec<[f32; 4]>],
    which: Baseline,
) -> Result<EdgeSet, String> {
    let mut set = EdgeSet::new();
    for (i, (mesh, per_light)) in meshes.iter().zip(obj_lights).enumerate() {
        for (l, &light) in per_light.iter().enumerate() {
            let edges = mesh.run(which, light).map_err(|e| e.to_string())?;
            set.extend(
                edges
                    .into_iter()
                    .map(|e| (l, (offsets[i] + e as usize) as u32)),
            );
        }
    }
    Ok(set)
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    let (scene, notes) = shadowvol::load_scene(&args.scene)?;
    for n in &notes {
        eprintln!("note: {n}");
    }
    if scene.lights.is_empty() {
        return Err(CliError::Usage(format!(
            "scene {:?} defines no lights, so there is nothing to time",
            args.scene
        )));
    }
    let topo = &scene.geometry;
    let lights = &scene.light_positions();
    let common = Common {
        scene: &scene.name,
        topo,
        lights: lights.len(),
        frames: args.frames,
        warmup: args.warmup,
    };

    // The reference: the cpu backend in exact mode.
    let mut cpu = CpuBackend::new();
    let id = cpu.prepare(topo)?;
    let mut exact_m = Multiplicities::default();
    cpu.extract(id, lights, Accuracy::Exact, &mut exact_m)?;
    cpu.release(id);
    let exact = edge_set(&exact_m);

    let mut records = Vec::new();
    let obj_lights = object_lights(topo.transforms(), lights);
    let offsets = topo.edge_offsets();
    let meshes: Result<Vec<ClosedMesh<'_>>, String> = topo
        .objects
        .iter()
        .map(|o| ClosedMesh::new(&o.table).map_err(|e| format!("object {:?}: {e}", o.name)))
        .collect();
    for which in BASELINES {
        let mut rec = common.record(which.name(), None, "baseline");
        match &meshes {
            Err(e) => rec.error = Some(e.clone()),
            Ok(meshes) => {
                let mut last = EdgeSet::new();
                let timed = common.time(&mut rec, || {
                    last = run_baseline(meshes, &offsets, &obj_lights, which)?;
                    Ok::<(), String>(())
                });
                match timed {
                    Ok(()) => {
                        rec.silhouette_edges = Some(last.len());
                        rec.agrees_with_exact = Some(last == exact);
                    }
                    Err(e) => {
                        (rec.median_ms, rec.p10_ms, rec.p90_ms) = (None, None, None);
                        rec.error = Some(e);
                    }
                }
            }
        }
        records.push(rec);
    }

    // Our modes on the host backends of the registry (cpu, simd).
    for entry in backends().into_iter().filter(|e| e.host) {
        let name = entry.name;
        let mut backend = match entry.start() {
            Ok(b) => b,
            Err(e) => {
                let mut rec = common.record(name.to_owned(), None, "backend");
                rec.error = Some(e.to_string());
                records.push(rec);
                continue;
            }
        };
        let info = backend.info();
        let details: serde_json::Map<String, serde_json::Value> = info
            .details
            .iter()
            .map(|(k, v)| (k.clone(), serde_json::Value::String(v.clone())))
            .collect();
        let id = backend.prepare(topo)?;
        let mut m = Multiplicities::default();
        for mode in Accuracy::ALL {
            let mut rec = common.record(name.to_owned(), Some(mode.name()), "backend");
            rec.device.clone_from(&info.device);
            rec.details.clone_from(&details);
            let b = backend.as_mut();
            let timed = common.time(&mut rec, || b.extract(id, lights, mode, &mut m).map(|_| ()));
            match timed {
                Ok(()) => {
                    let set = edge_set(&m);
                    rec.silhouette_edges = Some(set.len());
                    rec.agrees_with_exact = Some(set == exact);
                }
                Err(e) => {
                    (rec.median_ms, rec.p10_ms, rec.p90_ms) = (None, None, None);
                    rec.error = Some(e.to_string());
                }
            }
            records.push(rec);
        }
        backend.release(id);
    }

    match args.format {
        Format::Json => {
            serde_json::to_writer(&mut *out, &Output { records })
                .map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => print_text(&records, out)?,
    }
    Ok(())
}

fn print_text(records: &[Record], out: &mut dyn Write) -> Result<(), CliError> {
    if let Some(r) = records.first() {
        writeln!(
            out,
            "scene {}: {} triangles, {} edges, {} object(s), {} light(s); {} timed frames",
            r.scene, r.triangles, r.edges, r.objects, r.lights, r.frames
        )?;
    }
    writeln!(
        out,
        "{:14} {:9} {:>10} {:>10} {:>10} {:>10}  exact?",
        "algorithm", "mode", "median_ms", "p10_ms", "p90_ms", "sil_edges"
    )?;
    let f = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |x| format!("{x:.3}"));
    for r in records {
        let agrees = match (r.agrees_with_exact, &r.error) {
            (_, Some(e)) => format!("error: {e}"),
            (Some(true), _) => "yes".to_owned(),
            (Some(false), _) => "NO".to_owned(),
            (None, None) => "-".to_owned(),
        };
        writeln!(
            out,
            "{:14} {:9} {:>10} {:>10} {:>10} {:>10}  {agrees}",
            r.backend,
            r.mode.unwrap_or("-"),
            f(r.median_ms),
            f(r.p10_ms),
            f(r.p90_ms),
            r.silhouette_edges
                .map_or_else(|| "-".to_owned(), |n| n.to_string()),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run_json(scene: &str) -> serde_json::Value {
        let args = Args {
            scene: scene.to_owned(),
            frames: 1,
            warmup: 0,
            format: Format::Json,
        };
        let mut buf = Vec::new();
        run(&args, &mut buf).unwrap();
        serde_json::from_slice(&buf).unwrap()
    }

    #[test]
    fn baselines_on_the_bunny_agree_with_exact() {
        let v = run_json("bunny");
        let recs = v["records"].as_array().unwrap();
        let names: Vec<&str> = recs
            .iter()
            .filter(|r| r["kind"] == "baseline")
            .map(|r| r["backend"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            [
                "classic",
                "fast-hash-64",
                "fast-hash-8",
                "connectivity",
                "two-step"
            ]
        );
        for r in recs {
            assert_eq!(r["triangles"], 3674);
            if r["kind"] == "baseline" {
                assert!(r["mode"].is_null());
                assert!(r["error"].is_null(), "{r}");
                assert!(r["median_ms"].as_f64().unwrap() >= 0.0);
                // The bunny's light is in general position: every seed algorithm finds
                // exactly the exact silhouette.
                assert_eq!(r["agrees_with_exact"], true, "{r}");
            } else if r["mode"] == "exact" {
                assert_eq!(r["agrees_with_exact"], true, "{r}");
            }
        }
        let exact_edges = recs
            .iter()
            .find(|r| r["backend"] == "cpu" && r["mode"] == "exact")
            .unwrap()["silhouette_edges"]
            .as_u64()
            .unwrap();
        assert!(exact_edges > 0);
    }

    #[test]
    fn non_manifold_scene_reports_why_baselines_cannot_run() {
        let v = run_json("hard-book-3");
        let recs = v["records"].as_array().unwrap();
        for r in recs.iter().filter(|r| r["kind"] == "baseline") {
            assert!(r["median_ms"].is_null());
            let e = r["error"].as_str().unwrap();
            assert!(e.contains("closed manifold"), "{e}");
        }
        // Our backends still run, and exact agrees with itself.
        let exact = recs
            .iter()
            .find(|r| r["backend"] == "cpu" && r["mode"] == "exact")
            .unwrap();
        assert_eq!(exact["agrees_with_exact"], true);
    }
}
