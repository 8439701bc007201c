//! `shadowvol view`: a live window onto a scene, rendered with stencil shadow volumes.
//!
//! The [`Renderer`](shadowvol_renderer::Renderer) runs on the window's own wgpu device
//! ([`RenderDevice::on_device`](shadowvol_renderer::RenderDevice::on_device)) and draws each
//! frame straight into a texture that the window samples onto its surface
//! ([`Renderer::render_into`](shadowvol_renderer::Renderer::render_into)). In the GPU pipeline
//! (the default) it extracts, builds and draws the volumes on the device: nothing travels
//! through the host but the plan's counts (a few bytes per light and surface, for the overlay).
//! The host pipeline (`--pipeline host`, and while the volumes are shown, V) brings the
//! multiplicities back and uploads the volumes; its silhouette backend is started the first time
//! it is needed. An [egui](https://docs.rs/egui) overlay shows the frame's figures.
//!
//! Controls: left drag orbits, right (or middle) drag pans, the wheel zooms; the arrow keys or
//! shift + left drag move the first light around the scene's centre; 1–4 pick the accuracy
//! mode (original, ordered, robust, exact); T cycles the technique (auto, z-pass, z-fail); V
//! cycles the volumes (hidden, translucent, wire), drawn over the image so that cracks show;
//! M switches between the volumes and shadow maps ([`ViewOptions::maps`]); Esc or Q quits.
//!
//! For automation, [`ViewOptions::frames`] renders that many frames, writes the last one's
//! image to [`ViewOptions::screenshot`] and returns a [`ViewReport`].
//!
//! ```no_run
//! use shadowvol_viewer::{view, ViewOptions};
//! let scene = shadowvol_renderer::hard::edge_on_frustum()?;
//! let mut options = ViewOptions::new(640, 480);
//! options.frames = Some(10);
//! options.screenshot = Some("view.png".into());
//! // The host pipeline's backend, started only if the host pipeline is used (V).
//! let backend = Box::new(|| Ok(Box::new(shadowvol_cpu::CpuBackend::new()) as _));
//! let report = view(scene, backend, options)?;
//! println!("{:.1} fps on {}", report.fps, report.adapter);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

/// The README's code, compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

mod app;
pub mod controls;
mod gfx;
mod overlay;
pub mod shaders;

use shadowvol_renderer::{Pipeline, RenderError, RenderOptions, Scene};
use shadowvol_silhouette::{BackendError, SilhouetteBackend};
use std::path::PathBuf;

/// Starts the silhouette backend of the host pipeline (for example a registry entry's
/// `start`); the viewer calls it the first time it needs the host pipeline, so a viewer that
/// stays on the GPU pipeline starts no backend.
pub type BackendStarter = Box<dyn FnMut() -> Result<Box<dyn SilhouetteBackend>, BackendError>>;

/// What to open and how.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewOptions {
    /// The renderer's options at start: `width × height` is the window's size in physical
    /// pixels (the image follows the window when it is resized), `mode` the accuracy mode (keys
    /// 1–4 change it), `policy` the technique policy (T changes it).
    pub render: RenderOptions,
    /// Render this many frames, then close and report; `None`: until the user closes it.
    pub frames: Option<u32>,
    /// With `frames`: where to write the last frame's image (the 3D view without the overlay),
    /// as PNG.
    pub screenshot: Option<PathBuf>,
    /// With `frames`: where to write the last frame's whole window (view, volumes and
    /// overlay) as PNG.
    pub window_screenshot: Option<PathBuf>,
    /// How the volumes show at start (V cycles it).
    pub volumes: controls::VolumeView,
    /// The window title.
    pub title: String,
    /// Where volumes are built: [`Pipeline::Gpu`] (on the device, nothing read back but the
    /// image; used when the adapter supports it, else the host pipeline with a warning) or
    /// [`Pipeline::Host`]. While the volumes are shown (V) frames use the host pipeline, which
    /// keeps their geometry. [`Pipeline::Map`] starts with shadow maps (M switches to the GPU
    /// pipeline's volumes and back).
    pub pipeline: Pipeline,
    /// The shadow maps' settings, while maps are shown (M).
    pub maps: shadowvol_renderer::MapSettings,
}

impl ViewOptions {
    /// A `width × height` window with [`RenderOptions::new`]'s defaults (exact mode, the
    /// automatic technique), the GPU pipeline, until closed.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            render: RenderOptions::new(width, height),
            frames: None,
            screenshot: None,
            window_screenshot: None,
            volumes: controls::VolumeView::Hidden,
            title: "shadowvol".into(),
            pipeline: Pipeline::Gpu,
            maps: shadowvol_renderer::MapSettings::default(),
        }
    }
}

/// What an automated run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewReport {
    /// Frames rendered and shown.
    pub frames: u32,
    /// Frames per second over the whole run (wall time from the first frame's start).
    pub fps: f64,
    /// Median wall time of one frame (render, overlay, present; in the host pipeline also the
    /// image's copy to the window), ms.
    pub median_ms: f64,
    /// The renderer's GPU adapter.
    pub adapter: String,
    /// The screenshot written, if any.
    pub screenshot: Option<String>,
    /// The pipeline of the last frame.
    pub pipeline: Pipeline,
}

/// Why the viewer could not run.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// No display to open a window on.
    #[error(
        "no display: neither DISPLAY (X11) nor WAYLAND_DISPLAY (Wayland) is set; run it in a \
         desktop session, or under a virtual X server (for example `xvfb-run shadowvol view ...`)"
    )]
    NoDisplay,
    /// The window or its event loop failed.
    #[error("window: {0}")]
    Window(String),
    /// The window's GPU device or surface failed.
    #[error("GPU: {0}")]
    Gpu(String),
    /// Rendering a frame failed.
    #[error("render: {0}")]
    Render(#[from] RenderError),
    /// Bad options.
    #[error("invalid options: {0}")]
    Options(String),
}

/// Whether a display is there to open a window on: `DISPLAY` or `WAYLAND_DISPLAY` set and not
/// empty (on Linux and the BSDs; elsewhere always).
///
/// # Errors
/// [`ViewError::NoDisplay`] naming both variables.
pub fn check_display() -> Result<(), ViewError> {
    if cfg!(all(
        unix,
        not(target_os = "macos"),
        not(target_os = "android")
    )) {
        let set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
            return Err(ViewError::NoDisplay);
        }
    }
    Ok(())
}

/// Opens a window onto `scene`, with the host pipeline's silhouettes from the backend `backend`
/// starts, and runs until the user closes it or, with [`ViewOptions::frames`], until that many
/// frames are shown.
///
/// # Errors
/// [`ViewError::NoDisplay`] without a display (checked before anything opens),
/// [`ViewError::Options`] for a zero size, `frames = Some(0)` or a scene without vertices,
/// [`ViewError::Window`] when the event loop or window cannot be created, [`ViewError::Gpu`]
/// when no adapter can present to it, [`ViewError::Render`] when the renderer or the backend
/// fails to start or to render a frame.
pub fn view(
    scene: Scene,
    backend: BackendStarter,
    options: ViewOptions,
) -> Result<ViewReport, ViewError> {
    let (width, height) = (options.render.width, options.render.height);
    if width == 0 || height == 0 {
        return Err(ViewError::Options(format!(
            "window size {width}x{height}: both must be > 0"
        )));
    }
    if options.frames == Some(0) {
        return Err(ViewError::Options("frames must be at least 1".into()));
    }
    let camera = scene
        .camera_or_default()
        .ok_or_else(|| ViewError::Options(format!("scene {:?} has nothing to show", scene.name)))?;
    check_display()?;
    let event_loop = winit::event_loop::EventLoop::new()
        .map_err(|e| ViewError::Window(format!("cannot connect to the display: {e}")))?;
    let pipeline = options.pipeline;
    let mut app = app::App::new(scene, camera, backend, options);
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewError::Window(format!("event loop: {e}")))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    Ok(app.report.take().unwrap_or(ViewReport {
        frames: 0,
        fps: 0.0,
        median_ms: 0.0,
        adapter: String::new(),
        screenshot: None,
        pipeline,
    }))
}
