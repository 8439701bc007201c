//! `render`'s reports: the JSON's map fields ([`shadowvol_report::RenderReport`] is the JSON) and
//! the text for people.

use super::frames::FrameStats;
use super::stage::{Ground, LightsSource, SceneArgs, ShadowsArg};
use super::Args;
use shadowvol_renderer::maps::MapKind;
use shadowvol_renderer::{Frame, UncertainUnit};
use shadowvol_report::{MapBiases, MapFields, Shadows};
use shadowvol_robust_math::Accuracy;
use std::io::Write;

/// What drew the shadows, and with `--shadows map` the maps' settings in effect (`None` for
/// volumes).
pub(super) fn map_fields(input: &SceneArgs) -> MapFields {
    if input.shadows != ShadowsArg::Map {
        return MapFields::default();
    }
    let s = input.map_settings();
    MapFields {
        shadows: Shadows::Map,
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
    match &r.ground {
        Some(g) => {
            let why = match g.source.as_str() {
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
