//! The ways a frame can be shadowed, behind one trait.
//!
//! A [`ShadowPipeline`] prepares a scene once ([`ShadowPipeline::prepare`]: upload, lay out),
//! and per frame records the depth pre-pass, each light's shadow pass and its lit pass into the
//! caller's command encoder and attachments ([`ShadowPipeline::record`]), filling its part of
//! the frame's [`FrameReport`] (one shape for every pipeline), which [`ShadowPipeline::finish`]
//! completes once the frame was submitted and has finished on the device. Below the pipelines, and shared by all of them:
//! the plan ([`crate::plan`]), the world positions ([`crate::world`]) and the raster states
//! ([`crate::raster`]). No pipeline imports another.
//!
//! * [`HostPipeline`] wraps any [`SilhouetteBackend`](shadowvol_silhouette::SilhouetteBackend):
//!   the multiplicities come back to the host, which builds the volumes and uploads them.
//! * [`GpuPipeline`] wraps the resident pass ([`crate::resident::ShadowPass`]): extraction,
//!   sides and caps on the device, nothing read back; it starts no silhouette backend.
//! * [`MapPipeline`] draws shadow maps instead of volumes ([`crate::maps`]): the peer the
//!   volumes are measured against, with the same pre-pass, lit pass and report.

mod gpu;
mod host;
mod map;

pub use gpu::GpuPipeline;
pub use host::{volume, HostPipeline};
pub use map::MapPipeline;

use crate::frame::{FrameReport, UncertainUnit};
use crate::plan::Scissor;
use crate::raster::Attachments;
pub use crate::soft::LightPass;
use crate::world::{World, WorldChanges};
use crate::{Accuracy, Camera, RenderDevice, RenderError};
pub use shadowvol_report::Pipeline;
use shadowvol_scenes::Scene;
pub use shadowvol_silhouette::PreparedBytes;

/// One frame's inputs: the scene (borrowed, never converted), where its surfaces are, and the
/// small per-frame values the renderer computed from it.
#[derive(Debug, Clone, Copy)]
pub struct FrameInputs<'a> {
    /// The device the scene was prepared on.
    pub device: &'a RenderDevice,
    /// The scene: surfaces, transforms, lights with their emission, ambient.
    pub scene: &'a Scene,
    /// The surfaces' world positions and boxes.
    pub world: &'a World,
    /// What moved since the last frame.
    pub changes: &'a WorldChanges,
    /// The camera.
    pub camera: &'a Camera,
    /// The attachments' size, `(width, height)`.
    pub size: (u32, u32),
    /// The accuracy mode of signs and multiplicities.
    pub mode: Accuracy,
    /// Per light: its scissor.
    pub scissors: &'a [Scissor],
    /// Per light: the colour times gain of its lit pass.
    pub light_colors: &'a [[f32; 3]],
    /// Fill the plan's counts (silhouette edges, side quads, cap triangles). The GPU pipeline
    /// pays for them with atomics and a read after the frame, so timed frames leave it off.
    pub count: bool,
    /// Per light of [`FrameInputs::scene`]: what it draws after its stencil pass
    /// ([`LightPass`]); empty: every light is [`LightPass::Hard`]. The renderer fills it when
    /// the scene's lights have a size ([`crate::soft::expand`]); a pipeline that draws no
    /// stencil shadows (the map pipeline) gets an empty slice.
    pub passes: &'a [LightPass],
}

impl FrameInputs<'_> {
    /// What light `li` draws after its stencil pass.
    #[must_use]
    pub fn pass(&self, li: usize) -> LightPass {
        self.passes.get(li).copied().unwrap_or(LightPass::Hard)
    }

    /// The group of light `li` for extraction: lights of one group are the samples of one
    /// light with a size, which a backend can extract together sharing the signs of triangles
    /// whose plane misses their box.
    #[must_use]
    pub fn group(&self, li: usize) -> usize {
        match self.pass(li) {
            LightPass::Sample { light, .. } => light,
            // A light of its own: a group no sample shares.
            LightPass::Hard | LightPass::Composite { .. } => usize::MAX - li,
        }
    }

    /// The runs of consecutive lights that sample one light with a size (the lights of one
    /// [`FrameInputs::group`] of several lights), in light order.
    #[must_use]
    pub fn sample_groups(&self) -> Vec<std::ops::Range<usize>> {
        let mut out: Vec<std::ops::Range<usize>> = Vec::new();
        for li in 0..self.passes.len() {
            if !matches!(self.pass(li), LightPass::Sample { .. }) {
                continue;
            }
            match out.last_mut() {
                Some(r) if r.end == li && self.group(r.start) == self.group(li) => r.end += 1,
                _ => out.push(li..li + 1),
            }
        }
        out.retain(|r| r.len() > 1);
        out
    }
}

/// Records what a light of pass `pass` draws after its stencil pass and the stencil's copy, around its lit
/// pass `lit` (which draws the light's Lambert term where the stencil is 0 into the view it is
/// given): a hard light's lit pass into the colour; a sample's count into the visibility; a
/// light with a size's lit pass into the light target with the stencil cleared, then its
/// composite into the colour. The one place the volume pipelines share this.
///
/// # Errors
/// [`RenderError::InvalidInput`] for a light with a size on attachments without the
/// renderer's soft targets (an embedder's own [`Attachments`]).
pub(crate) fn light_output(
    pass: LightPass,
    target: &Attachments<'_>,
    enc: &mut wgpu::CommandEncoder,
    mut lit: impl FnMut(&mut wgpu::CommandEncoder, &wgpu::TextureView),
) -> Result<(), RenderError> {
    if pass == LightPass::Hard {
        lit(enc, target.color);
        return Ok(());
    }
    let soft = target.soft.ok_or_else(|| {
        RenderError::InvalidInput(
            "a light with a size needs the renderer's visibility targets; render it through \
             Renderer, or give the light radius 0"
                .to_owned(),
        )
    })?;
    match pass {
        LightPass::Hard => {}
        LightPass::Sample { index, .. } => soft.count(enc, target.depth_stencil, index == 0),
        LightPass::Composite { samples, slot, .. } => {
            soft.clear_for_light(enc, target.depth_stencil);
            lit(enc, soft.light_view());
            soft.composite(enc, target.color, target.depth_stencil, samples, slot);
        }
    }
    Ok(())
}

/// Where a frame is recorded: the caller's attachments and command encoder, and the frame's
/// report, which the pipeline fills.
#[derive(Debug)]
pub struct Recording<'a> {
    /// The frame's report: the plan (each entry's silhouette source and, with
    /// [`FrameInputs::count`], its counts) and the pipeline's own fields (see [`FrameReport`]).
    pub report: &'a mut FrameReport,
    /// The attachments: colour, ids, depth and stencil.
    pub target: &'a Attachments<'a>,
    /// The encoder the passes are recorded into.
    pub enc: &'a mut wgpu::CommandEncoder,
}

/// A way to shadow a frame. See the [module documentation](self).
pub trait ShadowPipeline {
    /// Which pipeline this is.
    fn kind(&self) -> Pipeline;

    /// The registry name of the silhouette backend it runs, `None` (the default) when it runs
    /// none.
    fn backend(&self) -> Option<&str> {
        None
    }

    /// What [`FrameReport::uncertain`] counts in this pipeline (by default (triangle, light)
    /// pairs, as a pipeline that decides signs on the device counts them).
    fn uncertain_unit(&self) -> UncertainUnit {
        UncertainUnit::TriangleLight
    }

    /// True when its volumes are drawn with depth clamp on `device`.
    fn depth_clamp(&self, device: &RenderDevice) -> bool {
        device.depth_clamp
    }

    /// Prepares `scene` (uploads and lays out its surfaces) on `device`. Called before the
    /// first frame and whenever the surfaces change ([`WorldChanges::surfaces`]); a moved
    /// surface only changes the per-frame inputs.
    ///
    /// # Errors
    /// [`RenderError::Backend`] when the backend's `prepare` fails, [`RenderError::InvalidInput`]
    /// or [`RenderError::Unsupported`] when the scene does not fit the device.
    fn prepare(&mut self, device: &RenderDevice, scene: &Scene) -> Result<(), RenderError>;

    /// Records one frame into `rec`'s encoder: the pre-pass (colour = ambient × albedo, ids,
    /// depth), then per light its shadow pass into the stencil of `rec`'s target,
    /// [`Attachments::after_stencil`], and its lit pass (stencil == 0). Fills each of the report's
    /// plan entries' silhouette source and, with [`FrameInputs::count`], the counts it knows now,
    /// and its own fields of the report (see [`FrameReport`]).
    ///
    /// # Errors
    /// [`RenderError::Backend`] when extraction fails, [`RenderError::InvalidInput`] for a
    /// light that is not finite in an object's space.
    fn record(&mut self, frame: &FrameInputs<'_>, rec: Recording<'_>) -> Result<(), RenderError>;

    /// After the frame's submission finished: fills what only the device knows into `out` (the
    /// GPU pipeline's counts, when the frame counted them, and its timestamps).
    ///
    /// # Errors
    /// [`RenderError::Device`] when reading them back fails.
    fn finish(
        &mut self,
        frame: &FrameInputs<'_>,
        out: &mut FrameReport,
    ) -> Result<(), RenderError> {
        let _ = (frame, out);
        Ok(())
    }

    /// What the prepared scene holds beyond the scene's edge tables: the pipeline's (and its
    /// backend's) host layout and its device buffers, in bytes ([`PreparedBytes`]); zero before
    /// [`ShadowPipeline::prepare`]. The attachments the frame renders into are the caller's and
    /// not counted.
    fn prepared_bytes(&self) -> PreparedBytes;

    /// The shadow-volume vertices of the last frame, camera-relative, as triangles (`w = 0`:
    /// at infinity), for viewers that draw the volumes; empty unless the pipeline keeps them.
    fn volumes(&self) -> &[[f32; 4]] {
        &[]
    }

    /// Per light, the shadow map of the last frame (`None`: the light has none, nothing casts);
    /// empty for the volume pipelines.
    fn maps(&self) -> &[Option<crate::maps::LightMap>] {
        &[]
    }
}
