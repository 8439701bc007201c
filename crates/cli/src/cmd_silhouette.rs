//! `shadowvol silhouette`: silhouette edges of a mesh for one or more lights.

use shadowvol::report::{silhouette_report, SilhouetteReport};
use shadowvol::{find_backend, load_input, CliError, Format};
use shadowvol_robust_math::{Accuracy, Light};
use std::io::Write;

/// The long help of the subcommand.
pub const LONG_ABOUT: &str =
    "Compute the silhouette edges of MESH for each light, with their multiplicities \
                  m (the signed number of shadow-volume sides an edge extrudes), and count the \
                  vertices where the silhouette chain is open (0 for a closed chain).\n\n\
                  Vertices are welded when their f32 positions are exactly equal; an edge (a, b) \
                  names its vertices by their smallest 0-based input index, a < b.\n\n\
                  JSON: {\"backend\", \"mode\", \"mesh\": {\"vertices\", \"welded_vertices\", \
                  \"triangles\", \"edges\", \"boundary_edges\", \"nonmanifold_edges\", ...}, \
                  \"lights\": [{\"light\": [x,y,z,w], \"edges\": [[a,b,m], ...], \
                  \"open_vertices\": N}], \"device\", \"timings\", \"peak_rss_bytes\", \
                  \"table_bytes\", \"table_bytes_parts\"}; only m != 0 is listed, sorted by \
                  (a, b); \"notes\": [\"...\"] is added when the loader skipped something \
                  (glTF primitives that are not triangles).\n\n\
                  Memory: \"peak_rss_bytes\" is the process's peak resident set (the kernel's \
                  VmHWM, null off Linux; on lavapipe and PoCL it includes device memory); \
                  \"table_bytes\" what the prepared scene held, the sum of \
                  \"table_bytes_parts\": \"topology\" (the welded edge table), \"host\" (the \
                  backend's own layout of it) and \"device\" (its device buffers).\n\n\
                  Lights with a size: with --light-radius R > 0 (or a glTF light's own \
                  extras.radius) each light is replaced by its --light-samples N samples \
                  (default 16 here: there is no camera whose penumbra could choose), points on \
                  its disk facing the scene's bounding-box centre, all in one call; \"lights\" \
                  then lists every sample in order, and \"light_radii\" and \"light_samples\" \
                  give each original light's radius and sample count.";

/// Examples shown after the help.
pub const AFTER_HELP: &str =
    "Examples:\n  shadowvol silhouette assets/bunny.obj --light 0,10,0,1\n  \
                  shadowvol silhouette mesh.obj --light=-1,2,0.5,0 --mode robust --backend simd \
                  --format json";

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The mesh: a .obj file (v and f statements; polygons are fanned), a .gltf/.glb file (node
    /// transforms applied in f32; all objects merged into one mesh; quantized, meshopt- and
    /// Draco-compressed files too), a .stl file (ASCII or binary), a .ply file (ASCII or
    /// binary) or a scene preset name (`shadowvol scenes`). `shadowvol --help` lists what each
    /// format reads.
    #[arg(value_name = "MESH")]
    mesh: String,

    /// A light as homogeneous X,Y,Z,W: W = 1 is a point light at (X,Y,Z), W = 0 a directional
    /// light pointing from the scene towards (X,Y,Z). Repeat for several lights (one call).
    /// Without --light, the lights of the glTF file or preset are used.
    #[arg(
        long = "light",
        value_name = "X,Y,Z,W",
        allow_hyphen_values = true,
        value_parser = parse_light
    )]
    lights: Vec<Light>,

    /// Accuracy mode.
    #[arg(long, value_parser = shadowvol::mode_parser(), default_value = "exact")]
    mode: Accuracy,

    /// Backend to run on (see `shadowvol backends`), or `auto`: the first backend on a hardware
    /// GPU, else `simd`, with a warning naming what was skipped.
    #[arg(long, default_value = "cpu", value_name = "NAME")]
    backend: String,

    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,

    /// Text format only: list at most this many edges per light (0 = all).
    #[arg(long, default_value_t = 40, value_name = "N")]
    max_edges: usize,

    #[command(flatten)]
    light_size: shadowvol::LightSizeArgs,
}

fn parse_light(s: &str) -> Result<Light, String> {
    s.parse::<Light>().map_err(|e| e.to_string())
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    // Check the arguments before doing any work.
    let entry = find_backend(&args.backend)?;
    let input = load_input(&args.mesh)?;
    let lights = if args.lights.is_empty() {
        input.lights.clone()
    } else {
        args.lights.clone()
    };
    if lights.is_empty() {
        return Err(CliError::Usage(format!(
            "no light given for {}: add --light X,Y,Z,W (w = 1 point, w = 0 directional)",
            input.name
        )));
    }
    // The file's own radii belong to its own lights only.
    let own_radii: &[f32] = if args.lights.is_empty() {
        &input.light_radii
    } else {
        &[]
    };
    let sampled = args.light_size.sampled(
        &lights,
        own_radii,
        input.light_aim,
        shadowvol::light_size::DEFAULT_SAMPLES,
    )?;
    let mut backend = entry.start()?;
    let mode = args.mode;
    let report = silhouette_report(backend.as_mut(), &input.table, &sampled.lights, mode)?;
    match args.format {
        Format::Json => {
            let mut json = serde_json::to_value(&report).map_err(|e| CliError::Output(e.into()))?;
            if !input.notes.is_empty() {
                json["notes"] = serde_json::Value::from(input.notes.clone());
            }
            json["light_radii"] = serde_json::Value::from(sampled.radii.clone());
            json["light_samples"] = serde_json::Value::from(sampled.samples.clone());
            // The peak once the whole report, the JSON value included, is built.
            json["peak_rss_bytes"] = serde_json::Value::from(shadowvol::memory::peak_rss_bytes());
            serde_json::to_writer(&mut *out, &json).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => {
            for n in &input.notes {
                writeln!(out, "note     {n}")?;
            }
            if sampled.is_sampled() {
                for (i, (r, n)) in sampled.radii.iter().zip(&sampled.samples).enumerate() {
                    writeln!(
                        out,
                        "size     light {i}: radius {r}, {n} sample(s), listed below in order"
                    )?;
                }
            }
            write_text(out, &input.name, &report, args.max_edges)?;
        }
    }
    Ok(())
}

fn write_text(
    out: &mut dyn Write,
    name: &str,
    r: &SilhouetteReport,
    max_edges: usize,
) -> std::io::Result<()> {
    let m = &r.mesh;
    writeln!(
        out,
        "mesh     {name}: {} vertices ({} welded), {} triangles ({} degenerate dropped)",
        m.vertices, m.welded_vertices, m.triangles, m.degenerate_triangles
    )?;
    writeln!(
        out,
        "edges    {}: {} boundary, {} manifold, {} non-manifold",
        m.edges, m.boundary_edges, m.manifold_edges, m.nonmanifold_edges
    )?;
    writeln!(out, "backend  {} ({})", r.backend, r.device)?;
    let t = &r.timings;
    if r.mode == Accuracy::Exact {
        writeln!(
            out,
            "mode     exact: compute {:.3} ms, {} uncertain (edge, vertex, light) decided exactly \
             on the host",
            t.compute_ms, t.uncertain
        )?;
    } else {
        writeln!(out, "mode     {}: compute {:.3} ms", r.mode, t.compute_ms)?;
    }
    writeln!(out, "{}", memory_line(r))?;
    for (i, l) in r.lights.iter().enumerate() {
        let [x, y, z, w] = l.light.to_array();
        let kind = if w == 0.0 { "directional" } else { "point" };
        let sum: i64 = l.edges.iter().map(|e| i64::from(e.2.unsigned_abs())).sum();
        writeln!(
            out,
            "\nlight {i}  ({x}, {y}, {z}, {w}) {kind}: {} silhouette edges, {sum} sides (sum of |m|), \
             open vertices: {}{}",
            l.edges.len(),
            l.open_vertices,
            if l.open_vertices == 0 {
                " (closed)"
            } else {
                " (the chain is open)"
            }
        )?;
        if l.edges.is_empty() {
            continue;
        }
        writeln!(out, "  {:>10} {:>10} {:>4}", "a", "b", "m")?;
        let shown = if max_edges == 0 {
            l.edges.len()
        } else {
            max_edges.min(l.edges.len())
        };
        for &(a, b, mult) in &l.edges[..shown] {
            writeln!(out, "  {a:>10} {b:>10} {mult:>4}")?;
        }
        if shown < l.edges.len() {
            writeln!(
                out,
                "  ... {} more (use --max-edges 0 or --format json to list all)",
                l.edges.len() - shown
            )?;
        }
    }
    Ok(())
}

/// `memory   peak RSS ..., table ...`: both in MB and in bytes per input triangle.
fn memory_line(r: &SilhouetteReport) -> String {
    let per_tri = |b: u64| b as f64 / r.mesh.triangles.max(1) as f64;
    let p = &r.table_bytes_parts;
    let peak = r.peak_rss_bytes.map_or_else(
        || "peak RSS unknown (no /proc/self/status)".to_owned(),
        |b| {
            format!(
                "peak RSS {:.1} MB ({:.0} B/triangle)",
                b as f64 / 1e6,
                per_tri(b)
            )
        },
    );
    format!(
        "memory   {peak}, table {:.1} MB ({:.0} B/triangle: topology {:.1} MB, backend host {:.1} \
         MB, device {:.1} MB)",
        r.table_bytes as f64 / 1e6,
        per_tri(r.table_bytes),
        p.topology as f64 / 1e6,
        p.host as f64 / 1e6,
        p.device as f64 / 1e6
    )
}
