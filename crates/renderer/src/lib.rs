//! Stencil shadow volumes on wgpu, behind one pipeline trait, with a per-frame plan.
//!
//! * [`Renderer`]: a device, one [`ShadowPipeline`], and the shared steps of every frame: world
//!   positions ([`world`]), light gains ([`lighting`]), the plan ([`plan`]), the attachments and
//!   their readback ([`raster`]). [`Renderer::render`] draws a [`Scene`] (borrowed, never
//!   converted) and returns a [`Frame`]: its image with the per-pixel surface ids and stencil
//!   the reference reads ([`Frame::read_image`]), and a [`FrameReport`] of one shape for every
//!   pipeline.
//! * [`pipeline`]: [`HostPipeline`] wraps any silhouette backend (multiplicities come back to
//!   the host, which builds the volumes); [`GpuPipeline`] wraps the resident pass
//!   ([`resident::ShadowPass`]: extraction, sides and caps on the device, nothing read back),
//!   which applications can also embed on their own device and encoder.
//! * [`MapPipeline`] draws shadow maps instead ([`maps`]: directional, spot and cube maps with
//!   Bevy 0.20's defaults), the peer the volumes are measured against.
//! * [`plan`]: per (light, surface) the cheapest correct technique: culled, z-pass (when the
//!   near-clip volume test proves the camera is outside the surface's shadow volume) or z-fail
//!   with caps (no back cap for directional lights).
//! * Each light's stencil pass is two-sided with wrapping increment/decrement, volumes extruded
//!   to infinity with `w = 0` under an infinite far plane, depth clamp where the device has it;
//!   its lit pass is additive Lambert where the stencil is 0.
//!
//! ```no_run
//! use shadowvol_renderer::{RenderOptions, Renderer};
//! use shadowvol_scenes::preset;
//!
//! let scene = preset("hard-book-3")?;
//! let mut renderer = Renderer::gpu(RenderOptions::new(128, 128))?;
//! let frame = renderer.render(&scene)?;
//! frame.save_png("book.png")?;
//! print!("{}", frame.report.explain());
//! let img = frame.read_image()?;
//! let shot = shadowvol_reference::Shot::new(&scene, frame.camera, img.width, img.height,
//!     &img.rgba, &img.ids, &img.stencil, &frame.report.light_colors);
//! println!("artifact pixels: {}", shadowvol_reference::compare(&shot).artifact_pixels);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

/// The README's code, compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

mod device;
mod error;
mod frame;
pub mod hard;
pub mod lighting;
pub mod maps;
mod nearest;
pub mod pipeline;
pub mod plan;
pub mod raster;
mod renderer;
pub mod resident;
pub mod soft;
pub mod world;

pub use device::{buffer_cap, RenderDevice, BUFFER_CAP_ENV};
pub use error::RenderError;
pub use frame::{Frame, FrameImage, FrameReport, FrameTime, GpuTimings, Timings, UncertainUnit};
pub use lighting::Exposure;
pub use maps::{MapBias, MapFilter, MapSettings};
pub use pipeline::volume;
pub use pipeline::{GpuPipeline, HostPipeline, MapPipeline, Pipeline, ShadowPipeline};
pub use plan::{PlanEntry, PlanPolicy, SilhouetteSource, Technique};
pub use renderer::{RenderOptions, Renderer};
pub use shadowvol_robust_math::{Accuracy, Light};
/// The one camera type of the workspace (defined in `shadowvol-scenes`, which files and presets
/// fill in).
pub use shadowvol_scenes::{Camera, InvalidCamera, Scene};
