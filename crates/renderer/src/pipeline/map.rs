//! The shadow-map pipeline: the peer the volumes are measured against. Each light gets a map
//! ([`crate::maps`]) on the renderer's device, in the frame's encoder; the pre-pass and the lit
//! pass are the volume pipelines' (same shaders, same light semantics), so that only the shadows
//! differ. Where the frame is read back, a mask pass writes each light's map test into the
//! stencil, so the reference compares maps as it compares volumes.

use super::{FrameInputs, Pipeline, Recording, ShadowPipeline};
use crate::frame::FrameReport;
use crate::maps::pass::{MapFrame, MapLight, MapScene};
use crate::maps::{light_map, FitBounds, LightMap, MapPass, MapSettings};
use crate::plan::SilhouetteSource;
use crate::GpuTimings;
use crate::{Camera, RenderDevice, RenderError};
use glam::Vec3;
use shadowvol_silhouette::PreparedBytes;

/// The shadow-map pipeline: each light gets a map ([`crate::maps`]) on the renderer's device,
/// in the frame's encoder; the pre-pass and the lit pass are the volume pipelines', so that only
/// the shadows differ. Where the frame is read back (or the attachments ask for it,
/// [`crate::raster::Attachments::with_shadow_stencil`]), a mask pass writes each light's map
/// test into the stencil, so the reference compares maps as it compares volumes.
#[derive(Debug, Default)]
pub struct MapPipeline {
    settings: MapSettings,
    pass: Option<MapPass>,
    scene: Option<MapScene>,
    maps: Vec<Option<LightMap>>,
    written: Vec<bool>,
}

impl std::fmt::Debug for MapScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MapScene").finish_non_exhaustive()
    }
}

impl MapPipeline {
    /// A shadow-map pipeline with `settings`; its passes are built on the device at the first
    /// [`ShadowPipeline::prepare`].
    #[must_use]
    pub fn new(settings: MapSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }

    /// The settings it draws with.
    #[must_use]
    pub fn settings(&self) -> MapSettings {
        self.settings
    }
}

impl ShadowPipeline for MapPipeline {
    fn kind(&self) -> Pipeline {
        Pipeline::Map
    }

    fn depth_clamp(&self, _device: &RenderDevice) -> bool {
        false
    }

    fn prepared_bytes(&self) -> PreparedBytes {
        self.scene
            .as_ref()
            .map_or_else(PreparedBytes::default, MapScene::bytes)
    }

    fn prepare(
        &mut self,
        device: &RenderDevice,
        scene: &shadowvol_scenes::Scene,
    ) -> Result<(), RenderError> {
        if self.pass.is_none() {
            self.pass = Some(MapPass::new(device)?);
        }
        let pass = self.pass.as_ref().expect("built above");
        self.scene = None;
        self.scene = Some(pass.prepare(&device.device, scene)?);
        // Frees the upload's staging memory before the first frame allocates its targets.
        crate::raster::finish_uploads(&device.device, &device.queue)
    }

    fn record(&mut self, frame: &FrameInputs<'_>, rec: Recording<'_>) -> Result<(), RenderError> {
        let (report, target, enc) = (rec.report, rec.target, rec.enc);
        let device = frame.device;
        let (Some(pass), Some(ms)) = (self.pass.as_mut(), self.scene.as_mut()) else {
            return Err(RenderError::InvalidInput(
                "the shadow-map pipeline records before prepare".to_owned(),
            ));
        };
        for (i, ((moved, s), w)) in frame
            .changes
            .moved
            .iter()
            .zip(frame.scene.surfaces())
            .zip(frame.world.surfaces())
            .enumerate()
        {
            if *moved && !frame.changes.surfaces {
                pass.update_surface(&device.queue, ms, i, &s, &w.positions);
            }
        }
        let (w, h) = frame.size;
        let aspect = (f64::from(w) / f64::from(h)) as f32;
        let bounds = fit_bounds(frame);
        let eye = frame.camera.eye;
        self.maps = frame
            .scene
            .lights
            .iter()
            .map(|l| bounds.and_then(|b| light_map(l, frame.camera, aspect, &b, &self.settings)))
            .collect();
        let lights: Vec<MapLight> = frame
            .scene
            .lights
            .iter()
            .zip(&self.maps)
            .enumerate()
            .map(|(li, (l, map))| MapLight {
                light: crate::raster::relative_light(l.light.to_array(), eye),
                color: frame.light_colors[li],
                emission: l.emission,
                map: *map,
                scissor: frame.scissors[li],
            })
            .collect();
        let map_frame = MapFrame {
            view_proj: Camera {
                eye: Vec3::ZERO,
                target: frame.camera.target - eye,
                ..*frame.camera
            }
            .view_proj(aspect),
            eye,
            ambient: frame.scene.effects.ambient.clamp(0.0, 1.0),
            filter: self.settings.filter,
            lights: &lights,
        };
        pass.update(device, ms, &map_frame)?;
        self.written = pass.record(enc, ms, &map_frame, target);
        for e in &mut report.plan {
            e.silhouette = SilhouetteSource::Skipped;
        }
        Ok(())
    }

    fn finish(
        &mut self,
        frame: &FrameInputs<'_>,
        out: &mut FrameReport,
    ) -> Result<(), RenderError> {
        let device = frame.device;
        let (Some(pass), Some(ms)) = (self.pass.as_ref(), self.scene.as_ref()) else {
            return Ok(());
        };
        out.gpu_timings = pass
            .read_timings(device, ms, &self.written)?
            .map(|t| GpuTimings {
                stencil: t.mask,
                lighting: t.lighting,
                shadow_maps: t.maps,
                ..GpuTimings::default()
            });
        Ok(())
    }

    fn maps(&self) -> &[Option<LightMap>] {
        &self.maps
    }
}

/// The boxes the maps are fitted to: the world's, and the shadow casters'; `None` without any
/// surface.
fn fit_bounds(frame: &FrameInputs<'_>) -> Option<FitBounds> {
    let scene = frame.world.bounds()?;
    let casters = frame
        .scene
        .surfaces()
        .zip(frame.world.surfaces())
        .filter(|(s, w)| s.casts_shadows && !w.positions.is_empty())
        .map(|(_, w)| (w.bounds.0.as_vec3(), w.bounds.1.as_vec3()))
        .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)));
    Some(FitBounds { scene, casters })
}
