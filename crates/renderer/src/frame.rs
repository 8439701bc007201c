//! What a frame gives back: its image with the per-pixel data the reference reads, and one
//! report of the same shape whichever pipeline drew it.

use crate::plan::PlanEntry;
use crate::resident::GpuTimings;
use crate::{Accuracy, Camera, Pipeline, RenderError};
use shadowvol_scenes::Scene;

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

/// What exact mode's uncertain count counts, which differs by pipeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum UncertainUnit {
    /// (edge, opposite vertex, light) triples of the backend's extractions (host pipeline),
    /// decided by the backend's exact fallback on the host.
    EdgeOppositeVertexLight,
    /// (triangle, light) pairs, decided on the device with exact integer arithmetic (GPU
    /// pipeline).
    TriangleLight,
}

/// Wall times of one frame, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    /// The silhouette backend's `extract` calls; `None` when no backend ran (GPU pipeline:
    /// extraction is part of the device's work, see [`FrameReport::gpu_timings`]).
    pub silhouette_ms: Option<f64>,
    /// Building side quads and caps on the host; `None` when they are built on the device.
    pub side_building_ms: Option<f64>,
    /// Recording, submitting and waiting for the passes, and reading the image back.
    pub raster_ms: f64,
    /// Preparing the scene for the pipeline this frame (edge tables laid out and uploaded, the
    /// backend's `prepare`); 0 when nothing changed.
    pub prepare_ms: f64,
    /// The whole frame.
    pub total_ms: f64,
}

/// One frame's report: the same shape for every pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameReport {
    /// The pipeline that drew the frame.
    pub pipeline: Pipeline,
    /// The silhouette backend that ran (its registry name), `None` when none did (the GPU
    /// pipeline extracts on the renderer's device).
    pub backend: Option<String>,
    /// The device, in words (adapter name, backend, driver).
    pub adapter: String,
    /// The accuracy mode of silhouettes and caps.
    pub mode: Accuracy,
    /// The plan, light-major: per (light, surface) the technique, why, and what was drawn.
    pub plan: Vec<PlanEntry>,
    /// Per light: the colour times gain its lit pass multiplies by `albedo × attenuation ×
    /// cos θ`.
    pub light_colors: Vec<[f32; 3]>,
    /// Output per lux used for the lights with an emission (`None` without any).
    pub exposure: Option<f32>,
    /// Exact mode: evaluations the certified filter could not decide, counted in
    /// [`FrameReport::uncertain_unit`].
    pub uncertain: u64,
    /// What [`FrameReport::uncertain`] counts.
    pub uncertain_unit: UncertainUnit,
    /// Of the uncertain evaluations, the ones decided on the host (all of them in the host
    /// pipeline, none in the GPU pipeline).
    pub host_resolved: u64,
    /// Bytes brought to the host during the frame besides the image, the ids, the stencil and
    /// the plan's counts: the multiplicities (4 bytes per edge and light and extraction) in the
    /// host pipeline, 0 in the GPU pipeline.
    pub readback_bytes: u64,
    /// Pixels the per-light scissor kept out of the stencil and lit passes, summed over lights.
    pub scissor_pixels_saved: usize,
    /// True when the volumes were drawn with depth clamp.
    pub depth_clamp: bool,
    /// Wall times.
    pub timings: Timings,
    /// The GPU time of each pass from timestamp queries, where the pipeline and device have
    /// them (GPU pipeline).
    pub gpu_timings: Option<GpuTimings>,
    /// Parts the GPU pipeline uploaded the scene in: 1, or more for a scene beyond one storage
    /// binding of the device. With more than one, each plan entry's `silhouette_edges` and
    /// `side_quads` add up the parts', the edges where the parts meet included (their volumes
    /// cancel in the stencil).
    pub scene_parts: usize,
    /// Where the GPU pipeline read the surface vertices, `"buffer"` or `"pulled"`
    /// ([`crate::resident::SurfaceVertices`]); `None` for the other pipelines.
    pub surface_vertices: Option<&'static str>,
    /// Per light, its shadow map ([`crate::MapPipeline`]; `None`: nothing casts); empty for the
    /// volume pipelines.
    pub shadow_maps: Vec<Option<crate::maps::LightMap>>,
}

impl FrameReport {
    /// The plan as text, one line per (light, surface), after a line naming the pipeline, the
    /// backend, the mode and the device.
    #[must_use]
    pub fn explain(&self) -> String {
        let mut s = format!(
            "{} pipeline; backend {}; mode {}; adapter {}; depth clamp {}; infinite far plane\n",
            self.pipeline.name(),
            self.backend.as_deref().unwrap_or("none"),
            self.mode,
            self.adapter,
            if self.depth_clamp { "on" } else { "off" }
        );
        if self.pipeline == crate::Pipeline::Map {
            for (li, m) in self.shadow_maps.iter().enumerate() {
                s.push_str(&match m {
                    Some(m) => format!(
                        "light {li}: {:?} map {}x{}{}, texel {:.3e} {}, near {:.3e}, bias depth {} slope {} normal {} (offset {:.3e})\n",
                        m.kind,
                        m.size,
                        m.size,
                        match (m.kind, m.cascades) {
                            (crate::maps::MapKind::Cube, _) => " x 6 faces".to_owned(),
                            (_, 1) => String::new(),
                            (_, n) => format!(" x {n} cascades"),
                        },
                        m.texel,
                        if m.kind == crate::maps::MapKind::Directional { "world units" } else { "per unit of distance" },
                        m.near,
                        m.bias.depth,
                        m.bias.slope,
                        m.bias.normal,
                        m.normal_offset,
                    ),
                    None => format!("light {li}: no map (nothing casts a shadow)\n"),
                });
            }
            return s;
        }
        for e in &self.plan {
            s.push_str(&e.to_string());
            s.push('\n');
        }
        s
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

    /// The frame as the reference reads it: `scene` (the one rendered), the camera, the image
    /// and its per-pixel data, and the lights' gains.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] without an image.
    pub fn shot<'a>(
        &'a self,
        scene: &'a Scene,
    ) -> Result<shadowvol_reference::Shot<'a>, RenderError> {
        let img = self.read_image()?;
        Ok(shadowvol_reference::Shot::new(
            scene,
            self.camera,
            img.width,
            img.height,
            &img.rgba,
            &img.ids,
            &img.stencil,
            &self.report.light_colors,
        ))
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
