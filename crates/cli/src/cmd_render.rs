//! `shadowvol render`: a headless stencil-shadow-volume render of a scene, with its plan, timings
//! and (optionally) the ray-traced reference and the artifact count.

use shadowvol::{find_backend, CliError, Format};
use shadowvol_renderer::{
    reference, Exposure, Frame, Pipeline, PlanPolicy, RenderError, RenderOptions, RenderScene,
    Renderer,
};
use shadowvol_robust_math::Accuracy;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// The long help of the subcommand.
pub const LONG_ABOUT: &str =
    "Render SCENE (a preset name from `shadowvol scenes`, a .gltf/.glb \
    file with its KHR_lights_punctual lights and camera, or a .obj/.stl/.ply mesh) with stencil \
    shadow volumes on the GPU (wgpu; headless), and write a PNG (--out, by default SCENE's file \
    stem or preset name + .png in the current directory).\n\n\
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
    with a warning. --frames N renders N further frames with every light moving on a fixed \
    orbit (1 degree per frame about the vertical axis through the scene's centre), so each \
    frame re-extracts, and reports their times; nothing but the final image is read back in the \
    GPU pipeline (frame_readback_bytes).\n\n\
    Silhouettes come from the pipeline in --mode; caps use the same per-triangle signs. For each \
    (light, object) the plan picks: culled (its shadow cannot reach the view), z-pass (the \
    near-clip volume test proves the camera is outside the shadow volume) or z-fail with caps \
    (no back cap for directional lights). --explain prints the plan.\n\n\
    --reference ray-casts every pixel's surface point to every light (BVH, all cores) and counts \
    artifact pixels: pixels whose lit/shadowed state differs from the reference and that are more \
    than one pixel from a reference shadow boundary. Lit means the light changes the 8-bit pixel \
    (albedo x intensity x cos >= 1/255); geometric_artifact_pixels counts the same with lit \
    meaning cos > 0, however dim (there even exact silhouettes leave raster z-fighting on faces \
    edge-on to the light, which is invisible in the image). --diff FILE writes the disagreement (red: \
    lit but should be shadowed, blue: shadowed but should be lit, yellow: at a boundary or \
    undecidable, not counted); it implies --reference.\n\n\
    JSON: {\"artifact_pixels\": N or null without --reference, \"shadow_pixels\": N, \"plan\": \
    [{\"light\", \"object\", \"object_name\", \"technique\", \"back_cap\", \"silhouette\", \
    \"silhouette_edges\", \"side_quads\", \"cap_triangles\", \"reason\"}], \"timings\": \
    {\"silhouette_ms\", \"side_building_ms\", \"raster_ms\", \"prepare_ms\", \"total_ms\", \
    \"reference_ms\"}, \"scene\", \"backend\", \"mode\", \"size\": [w, h], \"adapter\", \"out\", \
    \"covered_pixels\", \"reference_shadow_pixels\", \"geometric_artifact_pixels\", \"undecidable_pixels\" \
    (covered pixels the reference could not decide), \"boundary_pixels\" (raster and reference differ \
    within one pixel of a reference shadow boundary; neither is counted as an artifact), \
    \"lights\": [[x, y, z, w]] (the lights used), \"lights_source\": \"file\", \"flags\" or \
    \"default\", \"ground\": null or {\"y\", \"source\": \"scene\", \"auto\" or \"flags\"}, \
    \"exposure\": output per lux for the file's lights, null when all are unit lights, \
    \"scissor_pixels_saved\": pixels kept out of the stencil and lit passes by each light's \
    scissor, the screen rectangle of its range sphere or spot cone within the scene's bounds \
    (each plan entry's \"scissor\": [x, y, w, h] or \
    null for the whole image; --no-scissor turns it off, the image is the same), \
    \"pipeline\": \"gpu\" or \"host\", \"frame_readback_bytes\": bytes brought to the host during \
    the --frames frames besides the final image (host: the multiplicities, 4 bytes per edge and \
    light and extraction; gpu: 0), \"frames\": null or {\"count\", \"median_ms\", \"p10_ms\", \
    \"p90_ms\"}, \"gpu_timings_ms\": null or {\"extract\", \"sides\", \"caps\", \"stencil\" (sides + \
    caps), \"lighting\" (pre-pass + lit passes)}, GPU milliseconds from timestamp queries (gpu \
    pipeline on an adapter with TIMESTAMP_QUERY; the median over --frames, else the final frame), \
    \"uncertain\": exact-mode evaluations the certified filter left undecided (host: (edge, \
    opposite vertex, light) triples; gpu: (triangle, light) pairs), \"host_resolved\": those \
    decided on the host (gpu: 0)}. With the gpu pipeline \"backend\" is \"wgpu\", whose kernels it runs, \
    and timings.silhouette_ms and side_building_ms are 0: extraction and volumes are part of \
    raster_ms.\n\n\
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
    shadowvol render town --out town.png --reference --diff town-diff.png --format json";

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
    /// The scene: a preset name (see `shadowvol scenes`) or a .gltf/.glb/.obj/.stl/.ply file
    /// (`shadowvol --help` lists what each format reads).
    #[arg(value_name = "SCENE")]
    scene: String,

    /// A light as homogeneous X,Y,Z,W (w = 1 point, w = 0 directional towards (X,Y,Z)); repeat
    /// for several. Replaces the scene's own lights; without any light anywhere, a default key
    /// light is placed from the scene's bounds.
    #[arg(
        long = "light",
        value_name = "X,Y,Z,W",
        allow_hyphen_values = true,
        value_parser = parse_light
    )]
    lights: Vec<shadowvol_robust_math::Light>,

    /// The PNG to write [default: SCENE's file stem or preset name + .png, in the current
    /// directory].
    #[arg(long, value_name = "FILE.png")]
    out: Option<PathBuf>,

    /// A receiver plane under the scene: auto (under files with nothing below their casters),
    /// on or off.
    #[arg(long, value_enum, default_value_t = GroundArg::Auto)]
    ground: GroundArg,

    /// Image size in pixels.
    #[arg(long, default_value = "512x512", value_name = "WxH", value_parser = parse_size)]
    size: (u32, u32),

    /// Accuracy mode of silhouettes and caps.
    #[arg(long, value_parser = shadowvol::mode_parser(), default_value = "exact")]
    mode: Accuracy,

    /// Silhouette backend of the host pipeline (see `shadowvol backends`), or `auto`: the first
    /// backend on a hardware GPU, else `simd`, with a warning naming what was skipped. Giving it
    /// selects the host pipeline [default with --pipeline host: cpu].
    #[arg(long, value_name = "NAME")]
    backend: Option<String>,

    /// gpu: extraction, sides and caps on the renderer's device, nothing read back during a
    /// frame; host: the backend's multiplicities come to the host, which builds the volumes
    /// [default: gpu where the adapter supports it and no --backend is given, else host].
    #[arg(long, value_enum, value_name = "gpu|host")]
    pipeline: Option<PipelineArg>,

    /// After the final image, render N further frames with the lights on a fixed orbit (each
    /// re-extracts) and report their median, p10 and p90 times.
    #[arg(long, default_value_t = 0, value_name = "N")]
    frames: u32,

    /// Ray-trace the reference and count artifact pixels.
    #[arg(long)]
    reference: bool,

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

/// The JSON report (the CLI contract's `render` shape, extended).
#[derive(Debug, serde::Serialize)]
struct Report<'a> {
    artifact_pixels: Option<usize>,
    shadow_pixels: usize,
    plan: &'a [shadowvol_renderer::PlanEntry],
    timings: Timings,
    scene: String,
    backend: &'static str,
    mode: Accuracy,
    size: [u32; 2],
    adapter: &'a str,
    out: String,
    covered_pixels: Option<usize>,
    reference_shadow_pixels: Option<usize>,
    /// `artifact_pixels` with lit meaning `cos θ > 0` (no 1/255 visibility threshold).
    geometric_artifact_pixels: Option<usize>,
    /// Covered pixels the reference could not decide (not counted as artifacts).
    undecidable_pixels: Option<usize>,
    /// Pixels where raster and reference differ within one pixel of a reference shadow boundary
    /// (not counted as artifacts).
    boundary_pixels: Option<usize>,
    /// The lights used, homogeneous `[x, y, z, w]`.
    lights: Vec<[f32; 4]>,
    /// Where they came from.
    lights_source: LightsSource,
    /// The receiver plane under the scene, if any.
    ground: Option<Ground>,
    /// Output per lux used for the file's lights, `null` when every light is a unit light.
    exposure: Option<f32>,
    /// Pixels the per-light scissor kept out of the stencil and lit passes.
    scissor_pixels_saved: usize,
    /// `gpu` or `host`.
    pipeline: Pipeline,
    /// Bytes brought to the host during the `--frames` frames, besides the final image.
    frame_readback_bytes: u64,
    /// The `--frames` frames' times, `null` without them.
    frames: Option<FrameStats>,
    /// Per-pass GPU times from timestamp queries (the median of the `--frames` frames, else the
    /// final frame's); `null` for the host pipeline or without timestamp queries.
    gpu_timings_ms: Option<shadowvol_renderer::resident::GpuTimings>,
    /// Exact-mode evaluations the certified filter left undecided.
    uncertain: u64,
    /// Of those, the ones decided on the host.
    host_resolved: u64,
}

/// Times of the `--frames` frames.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct FrameStats {
    count: usize,
    median_ms: f64,
    p10_ms: f64,
    p90_ms: f64,
}

impl FrameStats {
    /// Median, p10 and p90 (nearest rank) of `ms`; `None` when empty.
    fn of(ms: &mut [f64]) -> Option<Self> {
        if ms.is_empty() {
            return None;
        }
        ms.sort_by(f64::total_cmp);
        let at = |q: f64| ms[((ms.len() - 1) as f64 * q).round() as usize];
        Some(Self {
            count: ms.len(),
            median_ms: at(0.5),
            p10_ms: at(0.1),
            p90_ms: at(0.9),
        })
    }
}

/// The lights of orbit frame `k`: each turned by `k` degrees about the vertical axis through
/// `centre` (point lights move, directional lights turn).
fn orbit_lights(
    lights: &[shadowvol_robust_math::Light],
    centre: glam::Vec3,
    k: u32,
) -> Vec<shadowvol_robust_math::Light> {
    let rot = glam::Quat::from_rotation_y((k as f32).to_radians());
    lights
        .iter()
        .map(|l| {
            if l.is_directional() {
                shadowvol_robust_math::Light::directional(rot * l.to_vec4().truncate())
            } else {
                shadowvol_robust_math::Light::point(
                    centre + rot * (l.to_vec4().truncate() - centre),
                )
            }
        })
        .collect()
}

/// Where the lights of a render came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum LightsSource {
    /// The scene file or preset.
    File,
    /// `--light`.
    Flags,
    /// The default key light ([`shadowvol_scenes::Scene::key_light`]).
    Default,
}

/// The receiver plane `y = ground_y` and why it is there.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct Ground {
    y: f32,
    /// `scene` (the preset declares it), `auto` (nothing lay below the casters) or `flags`
    /// (`--ground on`).
    source: &'static str,
}

#[derive(Debug, serde::Serialize)]
struct Timings {
    silhouette_ms: f64,
    side_building_ms: f64,
    raster_ms: f64,
    prepare_ms: f64,
    total_ms: f64,
    reference_ms: Option<f64>,
}

pub(crate) fn parse_light(s: &str) -> Result<shadowvol_robust_math::Light, String> {
    s.parse::<shadowvol_robust_math::Light>()
        .map_err(|e| e.to_string())
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    if args.pipeline == Some(PipelineArg::Gpu) {
        if let Some(b) = &args.backend {
            return Err(CliError::Other(format!(
                "--backend {b} selects the host pipeline; it cannot be combined with --pipeline gpu \
                 (the GPU pipeline runs the wgpu kernels on the renderer's device)"
            )));
        }
    }
    let entry = find_backend(args.backend.as_deref().unwrap_or("cpu"))?;
    let (mut scene, notes) = shadowvol::load_scene(&args.scene)?;
    for n in &notes {
        eprintln!("note: {n}");
    }
    let (lights_source, ground) = stage(&mut scene, &args.scene, &args.lights, args.ground)?;
    let out_path = out_path(args);
    let mut rscene = RenderScene::from_scene(&scene).map_err(render_error)?;
    if args.backdrop {
        rscene.add_backdrop();
    }
    let backend = entry.start()?;
    let mut options = RenderOptions::new(args.size.0, args.size.1);
    options.mode = args.mode;
    options.exposure = args.exposure;
    options.scissor = !args.no_scissor;
    options.policy = args.technique.into();
    let mut renderer = Renderer::new(backend, options).map_err(render_error)?;
    let pipeline = match (args.pipeline, &args.backend) {
        (Some(PipelineArg::Host), _) | (None, Some(_)) => Pipeline::Host,
        (Some(PipelineArg::Gpu), _) => {
            if let Some(why) = renderer.gpu_pipeline_unsupported() {
                return Err(CliError::Other(format!(
                    "--pipeline gpu: the adapter cannot run the GPU pipeline: {why}"
                )));
            }
            Pipeline::Gpu
        }
        (None, None) => match renderer.gpu_pipeline_unsupported() {
            Some(why) => {
                eprintln!("warning: using the host pipeline: the adapter cannot run the GPU pipeline: {why}");
                Pipeline::Host
            }
            None => Pipeline::Gpu,
        },
    };
    options.pipeline = pipeline;
    renderer.set_options(options);
    let backend_name = match pipeline {
        Pipeline::Gpu => "wgpu",
        Pipeline::Host => entry.name,
    };
    let frame = renderer.render(&rscene).map_err(render_error)?;
    frame.save_png(&out_path).map_err(render_error)?;
    let timed = timed_frames(&mut renderer, &rscene, &scene, args.frames)?;
    let (frames, frame_readback_bytes) = (timed.stats, timed.readback_bytes);

    let want_reference = args.reference || args.diff.is_some();
    let (cmp, reference_ms) = if want_reference {
        let t = Instant::now();
        let cmp = reference::compare(&frame);
        (Some(cmp), Some(t.elapsed().as_secs_f64() * 1e3))
    } else {
        (None, None)
    };
    if let (Some(path), Some(cmp)) = (&args.diff, &cmp) {
        reference::save_diff(&frame, cmp, path).map_err(render_error)?;
    }
    let shadow_pixels = cmp
        .as_ref()
        .map_or_else(|| reference::shadow_pixels(&frame), |c| c.shadow_pixels);
    match args.format {
        Format::Json => {
            let t = frame.timings;
            let report = Report {
                artifact_pixels: cmp.as_ref().map(|c| c.artifact_pixels),
                shadow_pixels,
                plan: &frame.plan,
                timings: Timings {
                    silhouette_ms: t.silhouette_ms,
                    side_building_ms: t.side_building_ms,
                    raster_ms: t.raster_ms,
                    prepare_ms: t.prepare_ms,
                    total_ms: t.total_ms,
                    reference_ms,
                },
                scene: scene.name.clone(),
                backend: backend_name,
                mode: frame.mode,
                size: [frame.width, frame.height],
                adapter: &frame.adapter,
                out: out_path.display().to_string(),
                covered_pixels: cmp.as_ref().map(|c| c.covered_pixels),
                reference_shadow_pixels: cmp.as_ref().map(|c| c.reference_shadow_pixels),
                geometric_artifact_pixels: cmp.as_ref().map(|c| c.geometric_artifact_pixels),
                undecidable_pixels: cmp.as_ref().map(|c| c.undecidable_pixels),
                boundary_pixels: cmp.as_ref().map(|c| c.boundary_pixels),
                lights: scene.lights.iter().map(|l| l.to_array()).collect(),
                lights_source,
                ground,
                exposure: frame.exposure,
                scissor_pixels_saved: frame.scissor_pixels_saved,
                pipeline,
                frame_readback_bytes,
                frames,
                gpu_timings_ms: timed.gpu_timings.or(frame.gpu_timings),
                uncertain: frame.uncertain,
                host_resolved: frame.host_resolved,
            };
            serde_json::to_writer(&mut *out, &report).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => write_text(
            out,
            &TextReport {
                args,
                out_path: &out_path,
                scene: &scene,
                lights_source,
                ground,
                backend: backend_name,
                frame: &frame,
                shadow_pixels,
                cmp: cmp.as_ref(),
                reference_ms,
                frames,
                frame_readback_bytes,
            },
        )?,
    }
    Ok(())
}

/// Chooses the lights and the ground of `scene` from the flags: `--light` replaces the scene's
/// lights, a scene without any gets [`shadowvol_scenes::Scene::key_light`] seen from its camera
/// (or the default framing); `--ground` sets `effects.ground_y`.
pub(crate) fn stage(
    scene: &mut shadowvol_scenes::Scene,
    scene_arg: &str,
    lights: &[shadowvol_robust_math::Light],
    ground: GroundArg,
) -> Result<(LightsSource, Option<Ground>), CliError> {
    let camera = scene.camera_or_default().ok_or_else(|| {
        CliError::Other(format!(
            "{scene_arg}: no vertices, nothing to render or light"
        ))
    })?;
    let too_large = |what: &str| {
        let (lo, hi) = scene.bounds().unwrap_or_default();
        shadowvol::bounds_too_large(scene_arg, lo, hi, what, "scale the model down")
    };
    if camera.validate().is_err() {
        return Err(too_large("a camera that frames them"));
    }
    let lights_source = if !lights.is_empty() {
        scene.lights = lights.to_vec();
        scene.emission.clear();
        LightsSource::Flags
    } else if !scene.lights.is_empty() {
        LightsSource::File
    } else {
        let key = scene
            .key_light(&camera)
            .ok_or_else(|| too_large("the default key light (give --light)"))?;
        scene.lights.push(key);
        scene.emission.clear();
        LightsSource::Default
    };
    let own = scene
        .effects
        .ground_y
        .map(|y| Ground { y, source: "scene" });
    let ground = match ground {
        GroundArg::Off => None,
        GroundArg::On => own.or_else(|| {
            scene
                .ground_y_below()
                .map(|y| Ground { y, source: "flags" })
        }),
        GroundArg::Auto if shadowvol_scenes::is_preset(scene_arg) => own,
        GroundArg::Auto => {
            own.or_else(|| scene.auto_ground_y().map(|y| Ground { y, source: "auto" }))
        }
    };
    scene.effects.ground_y = ground.map(|g| g.y);
    Ok((lights_source, ground))
}

/// `--out`, or SCENE's file stem (a preset's name) + `.png` in the current directory.
fn out_path(args: &Args) -> PathBuf {
    args.out.clone().unwrap_or_else(|| {
        let stem = std::path::Path::new(&args.scene)
            .file_stem()
            .map_or_else(|| "render".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{stem}.png"))
    })
}

/// What the text output shows.
struct TextReport<'a> {
    args: &'a Args,
    out_path: &'a std::path::Path,
    scene: &'a shadowvol_scenes::Scene,
    lights_source: LightsSource,
    ground: Option<Ground>,
    backend: &'a str,
    frame: &'a Frame,
    shadow_pixels: usize,
    cmp: Option<&'a reference::Comparison>,
    reference_ms: Option<f64>,
    frames: Option<FrameStats>,
    frame_readback_bytes: u64,
}

/// What the `--frames` frames measured.
#[derive(Debug, Default)]
struct Timed {
    stats: Option<FrameStats>,
    readback_bytes: u64,
    /// The median of each pass's GPU time, where timestamps were read.
    gpu_timings: Option<shadowvol_renderer::resident::GpuTimings>,
}

/// The median of each field over `all` (`None` when empty).
fn median_timings(
    all: &[shadowvol_renderer::resident::GpuTimings],
) -> Option<shadowvol_renderer::resident::GpuTimings> {
    if all.is_empty() {
        return None;
    }
    let med = |f: fn(&shadowvol_renderer::resident::GpuTimings) -> f64| {
        let mut v: Vec<f64> = all.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    Some(shadowvol_renderer::resident::GpuTimings {
        extract: med(|t| t.extract),
        sides: med(|t| t.sides),
        caps: med(|t| t.caps),
        stencil: med(|t| t.stencil),
        lighting: med(|t| t.lighting),
    })
}

/// `--frames`: `n` frames with the lights on the orbit, timed without reading images back.
fn timed_frames(
    renderer: &mut Renderer,
    rscene: &RenderScene,
    scene: &shadowvol_scenes::Scene,
    n: u32,
) -> Result<Timed, CliError> {
    if n == 0 {
        return Ok(Timed::default());
    }
    let centre = scene
        .bounds()
        .map_or(glam::Vec3::ZERO, |(lo, hi)| (lo + hi) * 0.5);
    let mut moving = rscene.clone();
    let bar = indicatif::ProgressBar::new(u64::from(n));
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} frames",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut ms = Vec::with_capacity(n as usize);
    let mut bytes = 0u64;
    let mut gpu = Vec::new();
    for k in 1..=n {
        moving.lights = orbit_lights(&rscene.lights, centre, k);
        let t = renderer.render_timed(&moving).map_err(render_error)?;
        ms.push(t.total_ms);
        bytes += t.readback_bytes;
        gpu.extend(t.gpu_timings);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(Timed {
        stats: FrameStats::of(&mut ms),
        readback_bytes: bytes,
        gpu_timings: median_timings(&gpu),
    })
}

fn write_text(out: &mut dyn Write, r: &TextReport<'_>) -> std::io::Result<()> {
    let (args, frame, backend) = (r.args, r.frame, r.backend);
    writeln!(
        out,
        "rendered {} ({}x{}, mode {}, {} pipeline, backend {backend}) on {} -> {}",
        r.scene.name,
        frame.width,
        frame.height,
        frame.mode,
        frame.pipeline.name(),
        frame.adapter,
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
            let [x, y, z, w] = l.to_array();
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
    if let Some(x) = frame.exposure {
        writeln!(
            out,
            "exposure        {x:e} per lux (the file's lights; --exposure)"
        )?;
    }
    writeln!(out, "shadow pixels   {}", r.shadow_pixels)?;
    if let Some(c) = r.cmp {
        let total = (frame.width * frame.height) as usize;
        writeln!(
            out,
            "artifact pixels {} ({:.3}% of the image; {} differ at boundaries, {} undecidable: {:.1}% of covered pixels checked; reference shadow pixels {}; geometric, with no 1/255 threshold: {})",
            c.artifact_pixels,
            100.0 * c.artifact_fraction(total),
            c.boundary_pixels,
            c.undecidable_pixels,
            100.0 * c.checked_fraction(),
            c.reference_shadow_pixels,
            c.geometric_artifact_pixels
        )?;
    }
    let t = frame.timings;
    write!(
        out,
        "timings         silhouette {:.2} ms, side building {:.2} ms, raster {:.2} ms, prepare {:.2} ms, total {:.2} ms",
        t.silhouette_ms, t.side_building_ms, t.raster_ms, t.prepare_ms, t.total_ms
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
    if frame.mode == Accuracy::Exact {
        writeln!(
            out,
            "exact           {} uncertain, {} decided on the host",
            frame.uncertain, frame.host_resolved
        )?;
    }
    if let Some(p) = &args.diff {
        writeln!(out, "diff            {}", p.display())?;
    }
    if args.explain {
        writeln!(out, "\nplan:")?;
        write!(out, "{}", frame.explain())?;
    }
    Ok(())
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
