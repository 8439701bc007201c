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
    /// Per light the pipeline drew, per pixel: the stencil after the light's stencil pass
    /// (0 = lit). With lights of several samples these are the lights of
    /// [`Frame::samples`]' scene: each sample's own hard shadow.
    pub stencil: Vec<Vec<u8>>,
    /// Per scene light, per pixel: the share of its samples that see the pixel, `k / N` in
    /// `[0, 1]` (1 = lit): counted on the device for a light of several samples, the stencil's
    /// 0 or 1 for a light of one.
    pub visibility: Vec<Vec<f32>>,
}

impl FrameImage {
    /// Light `light`'s visibility ([`FrameImage::visibility`]) as 8-bit grey, `round(255 v)`:
    /// 255 fully lit, 0 fully shadowed.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when the frame has no light `light`.
    pub fn visibility_image(&self, light: usize) -> Result<image::GrayImage, RenderError> {
        let v = self.visibility.get(light).ok_or_else(|| {
            RenderError::InvalidInput(format!(
                "the frame has {} lights; there is no light {light}",
                self.visibility.len()
            ))
        })?;
        let bytes = v
            .iter()
            .map(|&x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect();
        image::GrayImage::from_raw(self.width, self.height, bytes).ok_or_else(|| {
            RenderError::InvalidInput("the visibility does not match the image size".to_owned())
        })
    }
}

impl FrameImage {
    /// Writes light `light`'s visibility ([`FrameImage::visibility_image`]) as an 8-bit grey
    /// PNG.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] without that light, [`RenderError::Image`] when the file
    /// cannot be written.
    pub fn save_visibility_png(
        &self,
        light: usize,
        path: impl AsRef<std::path::Path>,
    ) -> Result<(), RenderError> {
        let p = path.as_ref();
        self.visibility_image(light)?
            .save_with_format(p, image::ImageFormat::Png)
            .map_err(|e| RenderError::Image {
                path: p.display().to_string(),
                message: e.to_string(),
            })
    }
}

/// Per scene light, the visibility of `image`: the device's counts `counts` (one image per
/// light with several samples, in their order) divided by the samples, and for a light of one
/// sample its stencil's lit state.
pub(crate) fn visibilities(
    image: &FrameImage,
    expanded: Option<&crate::soft::Expanded>,
    counts: &[Vec<f32>],
) -> Vec<Vec<f32>> {
    let lit = |stencil: &Vec<u8>| -> Vec<f32> {
        stencil
            .iter()
            .map(|&s| if s == 0 { 1.0 } else { 0.0 })
            .collect()
    };
    let Some(e) = expanded else {
        return image.stencil.iter().map(lit).collect();
    };
    let mut out = Vec::new();
    for (li, pass) in e.passes.iter().enumerate() {
        match *pass {
            crate::soft::LightPass::Hard => {
                out.push(image.stencil.get(li).map(lit).unwrap_or_default());
            }
            crate::soft::LightPass::Composite { samples, slot, .. } => {
                let n = samples.max(1) as f32;
                let k = counts.get(slot).cloned().unwrap_or_default();
                out.push(k.into_iter().map(|k| k / n).collect());
            }
            crate::soft::LightPass::Sample { .. } => {}
        }
    }
    out
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
    /// When a light had several samples: the lights the pipeline drew (each sample as a point
    /// light, then the light itself) and what each drew; [`FrameImage::stencil`] follows its
    /// scene's lights.
    pub samples: Option<crate::soft::Expanded>,
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
