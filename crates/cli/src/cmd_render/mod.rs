//! `shadowvol render`: a headless stencil-shadow-volume render of a scene, with its plan, timings
//! and (optionally) the ray-traced reference and the artifact count.

mod frames;
mod report;
mod stage;

pub(crate) use stage::{SceneArgs, ShadowsArg};

use report::TextReport;
use shadowvol::memory::{peak_rss_bytes, table_bytes};
use shadowvol::{find_backend, CliError, Format};
use shadowvol_renderer::{
    Exposure, GpuPipeline, HostPipeline, PlanPolicy, RenderDevice, RenderError, RenderOptions,
    Renderer, ShadowPipeline,
};
use shadowvol_report::{RenderReport, SceneBounds};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// The long help of the subcommand.
pub const LONG_ABOUT: &str =
    "Render SCENE (a preset name from `shadowvol scenes`, a .gltf/.glb \
    file with its KHR_lights_punctual lights and camera, or a .obj/.stl/.ply mesh) with stencil \
    shadow volumes on the GPU (wgpu; headless), and write a PNG (--out, by default SCENE's file \
    stem or preset name + .png in the current directory). The GPU: the first Vulkan, Metal or \
    DX12 adapter, else OpenGL's; WGPU_BACKEND=vulkan|gl|... chooses.\n\n\
    Any mesh renders without flags. Lights: --light (repeatable) replaces the scene's own; a \
    scene without any gets a default key light, a point light above the scene, to the camera's \
    left and slightly towards it, at 4 bounding radii from the centre, so that the shadow falls \
    to the right of the objects in view. Camera: the file's, else a framing of the bounds. \
    Ground (--ground auto, the default): a file whose casters have nothing below them (every \
    .obj/.stl/.ply, and glTF scenes without a floor object) gets a receiver plane (y up) just \
    under its lowest point; presets keep the receivers they declare. --ground on adds one to \
    any scene that has none, --ground off removes it.\n\n\
    Pipelines (--pipeline): `gpu`, the default where the adapter supports it, extracts the \
    silhouettes (in --mode), builds the side quads and caps and draws them on the renderer's \
    device with nothing read back during a frame (the `wgpu` backend's kernels; exact mode \
    decides every triangle on the device with exact integer arithmetic); `host` brings the \
    multiplicities of --backend (default cpu) to the host, which builds and uploads the volumes. \
    Giving --backend means host. Where the adapter cannot run the GPU pipeline, host is used \
    with a warning. A scene whose arrays exceed one storage binding of the device (lavapipe \
    binds 128 MiB: about 2.7 million triangles of a closed mesh, whose packed tables take 50 bytes a triangle) is uploaded in parts (\"scene_parts\" in the \
    JSON; each plan entry's counts then add up the parts', the edges where parts meet \
    included), with the same image; the host pipeline draws from several vertex buffers where \
    one would exceed the device's largest buffer. SHADOWVOL_MAX_BUFFER_BYTES caps every buffer \
    and binding the renderer asks for (a budget, and a way to see this on a small scene). The \
    GPU pipeline writes the surfaces' vertices once a frame into a buffer of 168 bytes a \
    triangle for scenes of up to 2^22 triangles and pulls them from the scene's buffers beyond \
    (less memory, slower draws; the same image): SHADOWVOL_SURFACE_VERTICES=auto|buffer|pull \
    chooses, and \"surface_vertices\" in the JSON says which ran. --frames N renders N further frames with every light moving on a fixed \
    orbit (1 degree per frame about the vertical axis through the scene's centre), so each \
    frame re-extracts, and reports their times; nothing but the final image is read back in the \
    GPU pipeline (frame_readback_bytes).\n\n\
    Silhouettes come from the pipeline in --mode; caps use the same per-triangle signs. For each \
    (light, object) the plan picks: culled (its shadow cannot reach the view), z-pass (the \
    near-clip volume test proves the camera is outside the shadow volume) or z-fail with caps \
    (no back cap for directional lights). --explain prints the plan.\n\n\
    --reference ray-casts every pixel's surface point to every light (BVH, all cores) and counts \
    artifact pixels: pixels whose lit/shadowed state differs from the reference, where the \
    reference's state is the same over the 3x3 pixels around it (more than one pixel from a \
    reference shadow boundary) and no shadow boundary of that light crosses the pixel's \
    footprint (its square seen on the plane of its triangle; decided exactly: the footprint \
    holds both some area a caster shadows and some area none does, as where a shadow wedge \
    narrower than a pixel passes between pixel centres). Lit means the light changes the 8-bit pixel \
    (albedo x intensity x cos >= 1/255); geometric_artifact_pixels counts the same with lit \
    meaning cos > 0, however dim (there even exact silhouettes leave raster z-fighting on faces \
    edge-on to the light, which is invisible in the image). --diff FILE writes the disagreement (red: \
    lit but should be shadowed, blue: shadowed but should be lit, yellow: at a boundary or \
    undecidable, not counted); it implies --reference.\n\n\
    JSON (--format json): the fields of shadowvol_report::RenderReport, described once in \
    docs/DESIGN.md (\"CLI contract\"): artifact_pixels (null without --reference), \
    shadow_pixels, the plan, timings, pipeline, backend (null for the gpu and map pipelines), \
    mode, adapter, the reference's counts (boundary_pixels, and footprint_boundary_pixels: the \
    pixels only the footprint rule kept out of artifact_pixels), the lights and where they came from, the ground, \
    exposure, uncertain and host_resolved, frames and gpu_timings_ms, the map settings, \
    peak_rss_bytes and table_bytes.\n\n\
    --shadows map draws shadow maps instead of volumes (the map pipeline, on the renderer's \
    device, nothing read back during a frame), with Bevy 0.20's defaults: a directional light \
    gets an orthographic map of 2048 texels fitted to what the view sees and to every caster, a \
    spot light a perspective map of 2048 over its cone, a point light a cube map of 1024 a face; \
    bias 0.02,0,1.8 (directional, spot) and 0.08,0,0.6 (point) as DEPTH (world units towards \
    the light), SLOPE (the map pass's slope-scaled depth bias) and NORMAL (texels along the \
    normal); PCF filtering. --map-size, --map-filter and --map-bias replace them for every \
    light; --map-cascades N splits each directional light's map into N cascades over slices of \
    the view (Bevy ships 4; the default here is 1, one map fitted to the whole view). The JSON adds \"shadows\" (\"volumes\" or \"map\"), \"map_size\", \"map_size_point\", \
    \"map_filter\", \"map_bias\" ({\"directional\", \"point\"}: {\"depth\", \"slope\", \
    \"normal\"}) and \"map_cascades\", null for volumes; --reference compares each light's map test (visibility < \
    1/2) with the reference as it compares volumes, and --explain lists each light's map.\n\n\
    glTF lights are lit as KHR_lights_punctual says: colour, intensity (candela for point and \
    spot lights, lux for directional ones) over distance squared, the range window \
    saturate(1 - (d/range)^4) and the spot cone's smooth falloff; a spot light's shadow volume \
    is a point light's. The plan culls casters that lie wholly beyond a light's range or \
    outside its cone. Lights from --light, presets and the default key light are white unit \
    lights without falloff.";

/// Examples shown after the help.
pub const AFTER_HELP: &str = "Examples:\n  shadowvol render model.obj\n  \
    shadowvol render sphere-1m --frames 10 --pipeline gpu --format json\n  \
    shadowvol render hard-book-3 --out book.png --reference --backdrop\n  \
    shadowvol render scene.glb --out scene.png --size 640x480 --mode robust --backend simd --explain\n  \
    shadowvol render town --out town.png --reference --diff town-diff.png --format json\n  \
    shadowvol render bunny --shadows map --map-size 4096 --map-filter hard --reference";

/// How the plan may choose between z-pass and z-fail.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum TechniqueArg {
    /// Z-pass where the near-clip volume test proves it safe, else z-fail.
    #[default]
    Auto,
    /// Always z-fail with caps (after culling).
    ZFail,
    /// Always z-pass (after culling); wrong when the camera is inside a shadow volume.
    ZPass,
}

impl From<TechniqueArg> for PlanPolicy {
    fn from(t: TechniqueArg) -> Self {
        match t {
            TechniqueArg::Auto => PlanPolicy::Auto,
            TechniqueArg::ZFail => PlanPolicy::AlwaysZFail,
            TechniqueArg::ZPass => PlanPolicy::AlwaysZPass,
        }
    }
}

/// Where silhouettes and volumes are built (see [`Pipeline`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PipelineArg {
    /// On the renderer's device, nothing read back during a frame.
    Gpu,
    /// On the host, from --backend's multiplicities.
    Host,
}

/// Whether to add a receiver plane under the scene.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum GroundArg {
    /// A plane under files whose casters have nothing below them; presets keep their own.
    #[default]
    Auto,
    /// A plane under any scene that has no ground of its own.
    On,
    /// No added plane, and none of the scene's own.
    Off,
}

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    input: SceneArgs,

    /// The PNG to write [default: SCENE's file stem or preset name + .png, in the current
    /// directory].
    #[arg(long, value_name = "FILE.png")]
    out: Option<PathBuf>,

    /// Image size in pixels.
    #[arg(long, default_value = "512x512", value_name = "WxH", value_parser = parse_size)]
    size: (u32, u32),

    /// After the final image, render N further frames with the lights on a fixed orbit (each
    /// re-extracts) and report their median, p10 and p90 times.
    #[arg(long, default_value_t = 0, value_name = "N")]
    frames: u32,

    /// Ray-trace the reference and count artifact pixels. With lights of several samples it
    /// checks each sample's hard shadow (JSON "sample_artifact_pixels") and measures each
    /// light's visibility against the true visibility of its disk ("visibility_error").
    #[arg(long)]
    reference: bool,

    /// Write the first light's visibility as an 8-bit grey PNG (255 fully lit, 0 fully
    /// shadowed; the share k/N of its samples that see each pixel, the stencil's lit or
    /// shadowed for a point light), and one file per further light with -1, -2, ... before the
    /// extension.
    #[arg(long, value_name = "FILE.png")]
    visibility: Option<PathBuf>,

    /// Print the plan (technique per light and object, and why).
    #[arg(long)]
    explain: bool,

    /// Write the disagreement with the reference as a PNG (implies --reference).
    #[arg(long, value_name = "FILE.png")]
    diff: Option<PathBuf>,

    /// Restrict the plan's choice between z-pass and z-fail.
    #[arg(long, value_enum, default_value_t = TechniqueArg::Auto)]
    technique: TechniqueArg,

    /// Add a receiver-only backdrop behind the scene as seen from its first light (for scenes
    /// without a ground, such as the hard-* presets).
    #[arg(long)]
    backdrop: bool,

    /// How the glTF lights' intensities (candela, lux) map to the image: `auto` (the brightest
    /// light's nominal illuminance at the scene's centre gives 0.6 of a unit light's brightness)
    /// or output per lux (1 = one lux on a white surface is full white). Lights from --light,
    /// presets and the default key light are unit lights and ignore it.
    #[arg(long, default_value = "auto", value_name = "auto|X", value_parser = parse_exposure)]
    exposure: Exposure,

    /// Draw every light's stencil and lit passes over the whole image instead of the screen
    /// rectangle of its range sphere or spot cone (for comparisons: the image is the same).
    #[arg(long)]
    no_scissor: bool,

    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

fn parse_exposure(s: &str) -> Result<Exposure, String> {
    if s.eq_ignore_ascii_case("auto") {
        return Ok(Exposure::Auto);
    }
    let x: f32 = s
        .parse()
        .map_err(|e| format!("exposure {s:?}: expected auto or a number > 0: {e}"))?;
    if x.is_finite() && x > 0.0 {
        Ok(Exposure::Fixed(x))
    } else {
        Err(format!("exposure {s:?}: must be finite and > 0"))
    }
}

pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size {s:?}: expected WxH, for example 640x480"))?;
    let parse = |v: &str, what: &str| -> Result<u32, String> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|e| format!("size {s:?}: {what} {v:?}: {e}"))?;
        if n == 0 || n > 16384 {
            return Err(format!("size {s:?}: {what} must be in 1..=16384"));
        }
        Ok(n)
    };
    Ok((parse(w, "width")?, parse(h, "height")?))
}

pub(crate) fn render_error(e: RenderError) -> CliError {
    match e {
        RenderError::Backend(b) => CliError::Backend(b),
        other => CliError::Other(format!("render: {other}")),
    }
}

pub(crate) fn parse_light(s: &str) -> Result<shadowvol_robust_math::Light, String> {
    s.parse::<shadowvol_robust_math::Light>()
        .map_err(|e| e.to_string())
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    args.input.wants_host()?;
    let (mut scene, lights_source, ground) = args.input.load()?;
    if args.backdrop {
        scene.add_backdrop();
    }
    let out_path = stage::out_path(args);
    let mut options = RenderOptions::new(args.size.0, args.size.1);
    options.mode = args.input.mode;
    options.exposure = args.exposure;
    options.scissor = !args.no_scissor;
    options.policy = args.technique.into();
    options.light_samples = args.input.light_size.light_samples;
    let device = RenderDevice::open().map_err(render_error)?;
    let pipeline = args.input.pipeline(&device)?;
    let mut renderer = Renderer::new(device, pipeline, options).map_err(render_error)?;
    let frame = renderer.render(&scene).map_err(render_error)?;
    frame.save_png(&out_path).map_err(render_error)?;
    let timed = frames::timed_frames(&mut renderer, &mut scene, args.frames)?;
    let table = table_bytes(scene.table_bytes(), renderer.pipeline().prepared_bytes());

    let visibility_files = write_visibility(&frame, args.visibility.as_deref())?;
    let hard = crate::shot::hard_lights(&frame);
    let shot = match &hard {
        Some(h) => crate::shot::hard_shot(&frame, h),
        None => crate::shot::shot(&frame, &scene),
    }
    .map_err(render_error)?;
    let want_reference = args.reference || args.diff.is_some();
    let (cmp, reference_ms) = if want_reference {
        let t = Instant::now();
        let cmp = shadowvol_reference::compare(&shot);
        (Some(cmp), Some(t.elapsed().as_secs_f64() * 1e3))
    } else {
        (None, None)
    };
    let sample_artifact_pixels = cmp
        .as_ref()
        .map(|c| sample_artifacts(c, hard.as_ref(), scene.lights.len()));
    let visibility_error = if args.reference {
        Some(soft_errors(&frame, &scene)?)
    } else {
        None
    };
    if let (Some(path), Some(cmp)) = (&args.diff, &cmp) {
        shadowvol_reference::save_diff(&shot, cmp, path)
            .map_err(|e| CliError::Other(format!("{}: {e}", path.display())))?;
    }
    let shadow_pixels = cmp.as_ref().map_or_else(
        || shadowvol_reference::shadow_pixels(&shot),
        |c| c.shadow_pixels,
    );
    match args.format {
        Format::Json => {
            let mut report = frame.report.clone();
            report.timings.reference_ms = reference_ms;
            report.gpu_timings = timed.gpu_timings.or(report.gpu_timings);
            let report = RenderReport {
                frame: report,
                scene: scene.name.clone(),
                size: [args.size.0, args.size.1],
                out: out_path.display().to_string(),
                shadow_pixels,
                artifact_pixels: cmp.as_ref().map(|c| c.artifact_pixels),
                covered_pixels: cmp.as_ref().map(|c| c.covered_pixels),
                reference_shadow_pixels: cmp.as_ref().map(|c| c.reference_shadow_pixels),
                geometric_artifact_pixels: cmp.as_ref().map(|c| c.geometric_artifact_pixels),
                undecidable_pixels: cmp.as_ref().map(|c| c.undecidable_pixels),
                boundary_pixels: cmp.as_ref().map(|c| c.boundary_pixels),
                footprint_boundary_pixels: cmp.as_ref().map(|c| c.footprint_boundary_pixels),
                geometric_footprint_boundary_pixels: cmp
                    .as_ref()
                    .map(|c| c.geometric_footprint_boundary_pixels),
                lights: scene.lights.iter().map(|l| l.light.to_array()).collect(),
                lights_source,
                ground,
                frame_readback_bytes: timed.readback_bytes,
                frames: timed.stats,
                map: report::map_fields(&args.input),
                peak_rss_bytes: peak_rss_bytes(),
                table_bytes: table.total(),
                table_bytes_parts: table,
                sample_artifact_pixels,
                visibility_error,
                visibility_files,
                scene_bounds: scene.bounds().map(|(lo, hi)| SceneBounds {
                    min: lo.to_array(),
                    max: hi.to_array(),
                }),
            };
            serde_json::to_writer(&mut *out, &report).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => report::write_text(
            out,
            &TextReport {
                args,
                out_path: &out_path,
                scene: &scene,
                lights_source,
                ground,
                backend: frame.report.backend.as_deref(),
                frame: &frame,
                shadow_pixels,
                cmp: cmp.as_ref(),
                reference_ms,
                frames: timed.stats,
                frame_readback_bytes: timed.readback_bytes,
            },
        )?,
    }
    Ok(())
}

/// Per scene light, the artifact pixels of each of its samples' hard shadows in `cmp` (made
/// with `hard`'s lights when the frame had lights of several samples, else with the scene's:
/// one entry per light).
fn sample_artifacts(
    cmp: &shadowvol_reference::Comparison,
    hard: Option<&crate::shot::HardLights>,
    lights: usize,
) -> Vec<Vec<usize>> {
    let mut per: Vec<Vec<usize>> = vec![Vec::new(); lights];
    match hard {
        Some(h) => {
            for (&(light, _), &n) in h.owner.iter().zip(&cmp.artifact_pixels_per_light) {
                per[light].push(n);
            }
        }
        None => {
            for (li, &n) in cmp.artifact_pixels_per_light.iter().enumerate() {
                per[li].push(n);
            }
        }
    }
    per
}

/// Writes each light's visibility ([`shadowvol_renderer::FrameImage::visibility_image`]) to
/// `path` (the first light) and `path` with `-1`, `-2`, ... before the extension (the others);
/// returns the files written.
///
/// # Errors
/// [`CliError::Other`] naming the file that cannot be written.
fn write_visibility(
    frame: &shadowvol_renderer::Frame,
    path: Option<&std::path::Path>,
) -> Result<Vec<String>, CliError> {
    let Some(path) = path else {
        return Ok(Vec::new());
    };
    let img = frame.read_image().map_err(render_error)?;
    let mut files = Vec::new();
    for li in 0..img.visibility.len() {
        let file = if li == 0 {
            path.to_path_buf()
        } else {
            let stem = path.file_stem().map_or_else(
                || "visibility".to_owned(),
                |s| s.to_string_lossy().into_owned(),
            );
            let ext = path
                .extension()
                .map_or_else(String::new, |e| format!(".{}", e.to_string_lossy()));
            path.with_file_name(format!("{stem}-{li}{ext}"))
        };
        img.save_visibility_png(li, &file).map_err(render_error)?;
        files.push(file.display().to_string());
    }
    Ok(files)
}

/// Per light of `scene`, its visibility in `frame` (`k / N` of its samples) against the
/// reference's true visibility of its disk over the penumbra; `None` for a light of radius 0.
///
/// # Errors
/// [`CliError::Other`] for a frame without an image.
fn soft_errors(
    frame: &shadowvol_renderer::Frame,
    scene: &shadowvol_scenes::Scene,
) -> Result<Vec<Option<shadowvol_report::VisibilityError>>, CliError> {
    let img = frame.read_image().map_err(render_error)?;
    if scene.lights.iter().all(|l| l.radius == 0.0) {
        return Ok(vec![None; scene.lights.len()]);
    }
    // The reference reads the scene's surfaces, the camera and the pixels' ids; the stencils
    // (one per scene light, from the visibility) only complete the shot.
    let stencils: Vec<Vec<u8>> = img
        .visibility
        .iter()
        .map(|v| v.iter().map(|&x| u8::from(x < 1.0)).collect())
        .collect();
    let shot = crate::shot::shot_with(frame, scene, &stencils, &frame.report.light_colors)
        .map_err(render_error)?;
    let casters = shadowvol_reference::soft::SoftCasters::new(&shot);
    let aim = scene.light_aim();
    Ok(scene
        .lights
        .iter()
        .enumerate()
        .map(|(li, l)| {
            let disk = l.disk(aim)?;
            let reference = shadowvol_reference::soft::visibility_reference_with(
                &shot,
                &casters,
                li,
                &disk,
                shadowvol_reference::soft::Integration::Auto,
            );
            let c =
                shadowvol_reference::soft::compare_with_reference(&reference, &img.visibility[li]);
            Some(shadowvol_report::VisibilityError {
                penumbra_pixels: c.penumbra_pixels,
                mean: c.penumbra_mean_error,
                p99: c.penumbra_p99_error,
                max: c.penumbra_max_error,
                lit_umbra_mismatches: c.lit_mismatched + c.umbra_mismatched,
                border_mismatches: c.border_mismatched,
                reference_bound: c.reference_bound,
            })
        })
        .collect())
}

/// The pipeline the flags ask for on `device`: host with `--backend` or `--pipeline host` (its
/// backend started here, `cpu` by default), else gpu, which starts no backend; without
/// `--pipeline`, host with a warning where the device cannot run the GPU pipeline.
///
/// # Errors
/// [`CliError::Other`] for `--pipeline gpu` on a device that cannot run it, naming why; the
/// backend's start error for the host pipeline.
pub(crate) fn pipeline(
    wants_host: Option<bool>,
    backend: Option<&str>,
    device: &RenderDevice,
) -> Result<Box<dyn ShadowPipeline>, CliError> {
    let unsupported = device.gpu_pipeline_unsupported.as_ref();
    let host = match (wants_host, unsupported) {
        (Some(host), None) | (Some(host @ true), _) => host,
        (Some(false), Some(why)) => {
            return Err(CliError::Other(format!(
                "--pipeline gpu: the adapter cannot run the GPU pipeline: {why}"
            )));
        }
        (None, Some(why)) => {
            eprintln!(
                "warning: using the host pipeline: the adapter cannot run the GPU pipeline: {why}"
            );
            true
        }
        (None, None) => false,
    };
    if host {
        let entry = find_backend(backend.unwrap_or("cpu"))?;
        Ok(Box::new(HostPipeline::new(entry.start()?)))
    } else {
        Ok(Box::new(GpuPipeline::new()))
    }
}

#[cfg(test)]
mod tests {
    use super::parse_size;

    #[test]
    fn size_parsing() {
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert_eq!(parse_size("16X9"), Ok((16, 9)));
        for bad in ["640", "0x10", "10x0", "axb", "-1x5", "20000x10", ""] {
            let e = parse_size(bad).unwrap_err();
            assert!(e.contains("size"), "{bad}: {e}");
        }
    }
}
