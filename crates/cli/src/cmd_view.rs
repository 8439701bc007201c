//! `shadowvol view`: a live window onto a scene or mesh (see `shadowvol_viewer`).

use crate::cmd_render::{parse_size, render_error, SceneArgs, ShadowsArg, TechniqueArg};
use shadowvol::{find_backend, CliError, Format};
use shadowvol_renderer::Pipeline;
use shadowvol_viewer::controls::VolumeView;
use shadowvol_viewer::{ViewError, ViewOptions};
use std::io::Write;
use std::path::PathBuf;

/// The long help of the subcommand.
pub const LONG_ABOUT: &str = "Open a window onto SCENE (a preset, a .gltf/.glb scene or a \
    .obj/.stl/.ply mesh) rendered with stencil shadow volumes, live. Lights, camera and ground \
    as for `render`: a scene without lights gets the default key light, a file with nothing \
    below its casters a ground plane.\n\n\
    Controls: left drag orbits, right (or middle) drag pans, the wheel zooms; the arrow keys or \
    shift + left drag move the first light around the scene; 1-4 pick the accuracy mode \
    (original, ordered, robust, exact); T cycles the technique (auto, z-pass, z-fail); V cycles \
    how the volumes show (hidden, translucent, wire: cracks become visible); M switches between \
    volumes and shadow maps (--shadows and the --map-* flags as for `render`); [ and ] halve \
    and double every light's radius (from 0, ] starts at 1 % of the scene's size; soft shadows, \
    sampled as the plan decides unless --light-samples says); Esc or Q quits. \
    The overlay shows fps, frame ms, silhouette edges, the uncertain and host-resolved pairs, \
    the pipeline, each light's radius and samples, and each object's technique.\n\n\
    The renderer runs on the window's device: in the GPU pipeline it draws each frame into a \
    texture the window samples, and nothing comes back to the host but the plan's counts. The \
    host pipeline (and the volume view, V) reads each image back and uploads it; the map \
    pipeline (--shadows map, or M) draws shadow maps on the window's device like the GPU \
    pipeline.\n\n\
    For automation: --frames N renders N frames, writes the last one's 3D view to --screenshot \
    and prints {\"frames\", \"fps\", \"median_ms\", \"adapter\", \"screenshot\", \"pipeline\": \
    \"gpu\", \"host\" or \"map\"}, then exits 0. \
    Without a display (DISPLAY and WAYLAND_DISPLAY unset) it exits 1 saying so; xvfb-run \
    gives it a virtual one.";

/// Examples shown after the help.
pub const AFTER_HELP: &str = "Examples:\n  shadowvol view model.obj\n  \
    shadowvol view hard-book-3 --mode robust\n  \
    xvfb-run shadowvol view town --frames 60 --screenshot town.png --format json";

/// How the volumes show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum VolumesArg {
    /// Not drawn.
    Hidden,
    /// Translucent sides and caps.
    Translucent,
    /// Triangle edges.
    Wire,
}

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    input: SceneArgs,

    /// Window size in pixels.
    #[arg(long, default_value = "960x720", value_name = "WxH", value_parser = parse_size)]
    size: (u32, u32),

    /// Technique at start (T cycles it).
    #[arg(long, value_enum, default_value_t = TechniqueArg::Auto)]
    technique: TechniqueArg,

    /// Render this many frames, then exit and report (for automation and tests).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,

    /// With --frames: write the last frame's 3D view (no overlay) as PNG.
    #[arg(long, value_name = "FILE.png", requires = "frames")]
    screenshot: Option<PathBuf>,

    /// With --frames: write the last frame's whole window (view, volumes, overlay) as PNG.
    #[arg(long, value_name = "FILE.png", requires = "frames")]
    window_screenshot: Option<PathBuf>,

    /// How the shadow volumes show at start (V cycles it): hidden, translucent or wire.
    #[arg(long, value_enum, default_value_t = VolumesArg::Hidden)]
    volumes: VolumesArg,

    /// Output format of the --frames report.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// The `--frames` report.
#[derive(Debug, serde::Serialize)]
struct Report {
    frames: u32,
    fps: f64,
    median_ms: f64,
    adapter: String,
    screenshot: Option<String>,
    pipeline: Pipeline,
}

pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    shadowvol_viewer::check_display().map_err(|e| CliError::Other(e.to_string()))?;
    let wants_host = args.input.wants_host()?;
    let entry = find_backend(args.input.backend.as_deref().unwrap_or("cpu"))?;
    let (scene, _, _) = args.input.load()?;
    // The host pipeline's backend is started only if the viewer needs it (V, --pipeline host).
    let backend = Box::new(move || entry.start());
    let mut options = ViewOptions::new(args.size.0, args.size.1);
    options.render.mode = args.input.mode;
    options.render.policy = args.technique.into();
    options.render.light_samples = args.input.light_size.light_samples;
    options.frames = args.frames;
    options.screenshot.clone_from(&args.screenshot);
    options
        .window_screenshot
        .clone_from(&args.window_screenshot);
    options.volumes = match args.volumes {
        VolumesArg::Hidden => VolumeView::Hidden,
        VolumesArg::Translucent => VolumeView::Translucent,
        VolumesArg::Wire => VolumeView::Wire,
    };
    options.title = format!("shadowvol - {}", scene.name);
    options.maps = args.input.map_settings();
    options.pipeline = if args.input.shadows == ShadowsArg::Map {
        Pipeline::Map
    } else if wants_host == Some(true) {
        Pipeline::Host
    } else {
        Pipeline::Gpu
    };
    let report = shadowvol_viewer::view(scene, backend, options).map_err(|e| match e {
        ViewError::Render(r) => render_error(r),
        other => CliError::Other(other.to_string()),
    })?;
    if args.frames.is_none() {
        return Ok(());
    }
    let report = Report {
        frames: report.frames,
        fps: report.fps,
        median_ms: report.median_ms,
        adapter: report.adapter,
        screenshot: report.screenshot,
        pipeline: report.pipeline,
    };
    match args.format {
        Format::Json => {
            serde_json::to_writer(&mut *out, &report).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => {
            writeln!(
                out,
                "{} frames, {:.1} fps, median {:.2} ms per frame, {} pipeline, on {}",
                report.frames,
                report.fps,
                report.median_ms,
                report.pipeline.name(),
                report.adapter
            )?;
            if let Some(s) = &report.screenshot {
                writeln!(out, "screenshot {s}")?;
            }
        }
    }
    Ok(())
}
