//! What a frame gives back: its image with the per-pixel data the reference reads, and one
//! report of the same shape whichever pipeline drew it.

use crate::{Camera, RenderError};
pub use shadowvol_report::{FrameReport, GpuTimings, Timings, UncertainUnit};

/// A frame's image and its per-pixel data.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 pixels, top row first.
    pub rgba: Vec<u8>,
    /// Per pixel `[surface + 1, triangle]` (the surface's index in
    /// [`Scene::surfaces`](shadowvol_scenes::Scene::surfaces), the triangle's in its table);
    /// `[0, _]` for background.
    pub ids: Vec<[u32; 2]>,
    /// Per light, per pixel: the stencil after the light's stencil pass (0 = lit).
    pub stencil: Vec<Vec<u8>>,
}

impl FrameImage {
    /// The image as an `image` buffer.
    ///
    /// # Panics
    /// Never for images produced by the renderer (the size matches the pixels).
    #[must_use]
    pub fn image(&self) -> image::RgbaImage {
        image::RgbaImage::from_raw(self.width, self.height, self.rgba.clone())
            .expect("size matches")
    }

    /// Writes the image as PNG.
    ///
    /// # Errors
    /// [`RenderError::Image`] when the file cannot be written.
    pub fn save_png(&self, path: impl AsRef<std::path::Path>) -> Result<(), RenderError> {
        let p = path.as_ref();
        self.image()
            .save_with_format(p, image::ImageFormat::Png)
            .map_err(|e| RenderError::Image {
                path: p.display().to_string(),
                message: e.to_string(),
            })
    }
}

/// A rendered frame: its image (when read back), its report, and the camera it was drawn from.
#[derive(Debug, Clone)]
pub struct Frame {
    /// The image and per-pixel data; `None` for a frame drawn into the caller's view
    /// ([`crate::Renderer::render_into`]).
    pub image: Option<FrameImage>,
    /// What ran and what it drew.
    pub report: FrameReport,
    /// The camera the frame was drawn from (the scene's, or the default framing).
    pub camera: Camera,
    /// With [`crate::pipeline::HostPipeline::keep_volumes`]: every shadow-volume vertex drawn,
    /// as triangles, relative to the camera's eye (`w = 0`: extruded to infinity); empty
    /// otherwise.
    pub volumes: Vec<[f32; 4]>,
}

impl Frame {
    /// The image, for a frame that was read back.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a frame drawn into the caller's view.
    pub fn read_image(&self) -> Result<&FrameImage, RenderError> {
        self.image.as_ref().ok_or_else(|| {
            RenderError::InvalidInput(
                "the frame was drawn into the caller's view; nothing was read back".to_owned(),
            )
        })
    }

    /// Writes the image as PNG.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] without an image, [`RenderError::Image`] when the file
    /// cannot be written.
    pub fn save_png(&self, path: impl AsRef<std::path::Path>) -> Result<(), RenderError> {
        self.read_image()?.save_png(path)
    }
}

/// One frame rendered without reading its image back ([`crate::Renderer::render_timed`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameTime {
    /// Wall time from the start of the call until the device finished, milliseconds.
    pub total_ms: f64,
    /// Bytes brought to the host during the frame ([`FrameReport::readback_bytes`]).
    pub readback_bytes: u64,
    /// The GPU time of each pass, where the pipeline and device have timestamp queries (read
    /// after the frame; not counted in `readback_bytes`).
    pub gpu_timings: Option<GpuTimings>,
}
