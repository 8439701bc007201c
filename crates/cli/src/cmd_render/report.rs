//! `render`'s reports: the JSON of the CLI contract (extended) and the text for people.

use super::frames::FrameStats;
use super::stage::{Ground, LightsSource, SceneArgs, ShadowsArg};
use super::Args;
use shadowvol_renderer::maps::MapKind;
use shadowvol_renderer::{Frame, Pipeline, UncertainUnit};
use shadowvol_renderer::{MapBias, MapFilter};
use shadowvol_robust_math::Accuracy;
use std::io::Write;

/// The JSON report (the CLI contract's `render` shape, extended).
#[derive(Debug, serde::Serialize)]
pub(super) struct Report<'a> {
    pub(super) artifact_pixels: Option<usize>,
    pub(super) shadow_pixels: usize,
    pub(super) plan: &'a [shadowvol_renderer::PlanEntry],
    pub(super) timings: Timings,
    pub(super) scene: String,
    /// The silhouette backend that ran; `null` for the GPU pipeline, which runs none.
    pub(super) backend: Option<&'a str>,
    pub(super) mode: Accuracy,
    pub(super) size: [u32; 2],
    pub(super) adapter: &'a str,
    pub(super) out: String,
    pub(super) covered_pixels: Option<usize>,
    pub(super) reference_shadow_pixels: Option<usize>,
    /// `artifact_pixels` with lit meaning `cos θ > 0` (no 1/255 visibility threshold).
    pub(super) geometric_artifact_pixels: Option<usize>,
    /// Covered pixels the reference could not decide (not counted as artifacts).
    pub(super) undecidable_pixels: Option<usize>,
    /// Pixels where raster and reference differ within one pixel of a reference shadow boundary
    /// (not counted as artifacts).
    pub(super) boundary_pixels: Option<usize>,
    /// Of `boundary_pixels`, those the footprint rule kept out of `artifact_pixels`: the
    /// reference is the same over the 3×3 neighbourhood, but a shadow boundary crosses the
    /// pixel's footprint.
    pub(super) footprint_boundary_pixels: Option<usize>,
    /// The same for `geometric_artifact_pixels`.
    pub(super) geometric_footprint_boundary_pixels: Option<usize>,
    /// The lights used, homogeneous `[x, y, z, w]`.
    pub(super) lights: Vec<[f32; 4]>,
    /// Where they came from.
    pub(super) lights_source: LightsSource,
    /// The receiver plane under the scene, if any.
    pub(super) ground: Option<Ground>,
    /// Output per lux used for the file's lights, `null` when every light is a unit light.
    pub(super) exposure: Option<f32>,
    /// Pixels the per-light scissor kept out of the stencil and lit passes.
    pub(super) scissor_pixels_saved: usize,
    /// `gpu` or `host`.
    pub(super) pipeline: Pipeline,
    /// Bytes brought to the host during the `--frames` frames, besides the final image.
    pub(super) frame_readback_bytes: u64,
    /// The `--frames` frames' times, `null` without them.
    pub(super) frames: Option<FrameStats>,
    /// Per-pass GPU times from timestamp queries (the median of the `--frames` frames, else the
    /// final frame's); `null` for the host pipeline or without timestamp queries.
    pub(super) gpu_timings_ms: Option<shadowvol_renderer::resident::GpuTimings>,
    /// Parts the GPU pipeline uploaded the scene in (1, or more for a scene beyond one of the
    /// device's storage bindings; then each plan entry's counts add up the parts').
    pub(super) scene_parts: usize,
    /// Where the GPU pipeline read the surface vertices: `buffer` (written once a frame, 168
    /// bytes a triangle) or `pulled` (vertex pulling, beyond 2^22 triangles or with
    /// `SHADOWVOL_SURFACE_VERTICES=pull`); `null` for the other pipelines.
    pub(super) surface_vertices: Option<&'static str>,
    /// Exact-mode evaluations the certified filter left undecided, counted as
    /// `uncertain_unit` says.
    pub(super) uncertain: u64,
    /// What `uncertain` counts: `edge-opposite-vertex-light` triples (host pipeline) or
    /// `triangle-light` pairs (GPU pipeline).
    pub(super) uncertain_unit: shadowvol_renderer::UncertainUnit,
    /// Of those, the ones decided on the host.
    pub(super) host_resolved: u64,
    /// `shadows` and the map settings.
    #[serde(flatten)]
    pub(super) map: MapFields,
    /// The process's peak resident set (the kernel's high-water mark), `null` off Linux.
    pub(super) peak_rss_bytes: Option<u64>,
    /// What the prepared scene held: its edge tables plus the pipeline's host layout and device
    /// buffers (the image attachments not included).
    pub(super) table_bytes: u64,
    /// `table_bytes` by part.
    pub(super) table_bytes_parts: shadowvol::memory::TableBytes,
}

/// What drew the shadows, and with `--shadows map` the maps' settings in effect (`null` for
/// volumes).
#[derive(Debug, serde::Serialize)]
pub(super) struct MapFields {
    /// `volumes` or `map`.
    shadows: ShadowsArg,
    /// Side of directional and spot maps, texels.
    map_size: Option<u32>,
    /// Side of each cube face (point lights), texels.
    map_size_point: Option<u32>,
    /// `hard` or `pcf`.
    map_filter: Option<MapFilter>,
    /// The bias of directional and spot maps, and of cube maps.
    map_bias: Option<MapBiases>,
    /// Cascades of each directional light's map.
    map_cascades: Option<u32>,
}

/// The biases in effect per map kind.
#[derive(Debug, serde::Serialize)]
struct MapBiases {
    /// Directional and spot maps.
    directional: MapBias,
    /// Cube maps (point lights).
    point: MapBias,
}

impl MapFields {
    pub(super) fn new(input: &SceneArgs) -> Self {
        if input.shadows != ShadowsArg::Map {
            return Self {
                shadows: input.shadows,
                map_size: None,
                map_size_point: None,
                map_filter: None,
                map_bias: None,
                map_cascades: None,
            };
        }
        let s = input.map_settings();
        Self {
            shadows: input.shadows,
            map_size: Some(s.size_for(MapKind::Directional)),
            map_size_point: Some(s.size_for(MapKind::Cube)),
            map_filter: Some(s.filter),
            map_bias: Some(MapBiases {
                directional: s.bias_for(MapKind::Directional),
                point: s.bias_for(MapKind::Cube),
            }),
            map_cascades: Some(s.cascades),
        }
    }
}

#[derive(Debug, serde::Serialize)]
pub(super) struct Timings {
    /// `null` when no backend ran (GPU pipeline).
    pub(super) silhouette_ms: Option<f64>,
    /// `null` when the volumes are built on the device (GPU pipeline).
    pub(super) side_building_ms: Option<f64>,
    pub(super) raster_ms: f64,
    pub(super) prepare_ms: f64,
    pub(super) total_ms: f64,
    pub(super) reference_ms: Option<f64>,
}

/// What the text output shows.
pub(super) struct TextReport<'a> {
    pub(super) args: &'a Args,
    pub(super) out_path: &'a std::path::Path,
    pub(super) scene: &'a shadowvol_scenes::Scene,
    pub(super) lights_source: LightsSource,
    pub(super) ground: Option<Ground>,
    pub(super) backend: Option<&'a str>,
    pub(super) frame: &'a Frame,
    pub(super) shadow_pixels: usize,
    pub(super) cmp: Option<&'a shadowvol_reference::Comparison>,
    pub(super) reference_ms: Option<f64>,
    pub(super) frames: Option<FrameStats>,
    pub(super) frame_readback_bytes: u64,
}

/// The text report of `render`.
pub(super) fn write_text(out: &mut dyn Write, r: &TextReport<'_>) -> std::io::Result<()> {
    let (args, report) = (r.args, &r.frame.report);
    let (width, height) = args.size;
    writeln!(
        out,
        "rendered {} ({width}x{height}, mode {}, {} pipeline, backend {}) on {} -> {}",
        r.scene.name,
        report.mode,
        report.pipeline.name(),
        r.backend.unwrap_or("none"),
        report.adapter,
        r.out_path.display()
    )?;
    let from = match r.lights_source {
        LightsSource::File => "from the scene",
        LightsSource::Flags => "from --light",
        LightsSource::Default => "default key light: the scene has none",
    };
    let list: Vec<String> = r
        .scene
        .lights
        .iter()
        .map(|l| {
            let [x, y, z, w] = l.light.to_array();
            format!("({x}, {y}, {z}, {w})")
        })
        .collect();
    writeln!(out, "lights          {} ({from})", list.join(", "))?;
    match r.ground {
        Some(g) => {
            let why = match g.source {
                "auto" => "added: nothing lies below the casters",
                "flags" => "added by --ground on",
                _ => "the scene's own",
            };
            writeln!(out, "ground          y = {} ({why})", g.y)?;
        }
        None => writeln!(out, "ground          none")?,
    }
    if let Some(x) = report.exposure {
        writeln!(
            out,
            "exposure        {x:e} per lux (the file's lights; --exposure)"
        )?;
    }
    writeln!(out, "shadow pixels   {}", r.shadow_pixels)?;
    if let Some(c) = r.cmp {
        let total = (width * height) as usize;
        writeln!(
            out,
            "artifact pixels {} ({:.3}% of the image; {} differ at boundaries ({} of them where a shadow boundary crosses the pixel's footprint), {} undecidable: {:.1}% of covered pixels checked; reference shadow pixels {}; geometric, with no 1/255 threshold: {})",
            c.artifact_pixels,
            100.0 * c.artifact_fraction(total),
            c.boundary_pixels,
            c.footprint_boundary_pixels,
            c.undecidable_pixels,
            100.0 * c.checked_fraction(),
            c.reference_shadow_pixels,
            c.geometric_artifact_pixels
        )?;
    }
    let t = report.timings;
    let on_host =
        |ms: Option<f64>| ms.map_or_else(|| "on the device".to_owned(), |ms| format!("{ms:.2} ms"));
    write!(
        out,
        "timings         silhouette {}, side building {}, raster {:.2} ms, prepare {:.2} ms, total {:.2} ms",
        on_host(t.silhouette_ms),
        on_host(t.side_building_ms),
        t.raster_ms,
        t.prepare_ms,
        t.total_ms
    )?;
    if let Some(ms) = r.reference_ms {
        write!(out, ", reference {ms:.2} ms")?;
    }
    writeln!(out)?;
    if let Some(f) = r.frames {
        writeln!(
            out,
            "frames          {} on the light orbit: median {:.2} ms (p10 {:.2}, p90 {:.2}); {} bytes read back",
            f.count, f.median_ms, f.p10_ms, f.p90_ms, r.frame_readback_bytes
        )?;
    }
    if report.mode == Accuracy::Exact {
        let unit = match report.uncertain_unit {
            UncertainUnit::EdgeOppositeVertexLight => "(edge, opposite vertex, light) triples",
            UncertainUnit::TriangleLight => "(triangle, light) pairs",
        };
        writeln!(
            out,
            "exact           {} uncertain {unit}, {} decided on the host",
            report.uncertain, report.host_resolved
        )?;
    }
    if let Some(p) = &args.diff {
        writeln!(out, "diff            {}", p.display())?;
    }
    if args.explain {
        writeln!(out, "\nplan:")?;
        write!(out, "{}", report.explain())?;
    }
    Ok(())
}
