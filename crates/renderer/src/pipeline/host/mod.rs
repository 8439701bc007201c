//! The host pipeline: any [`SilhouetteBackend`] extracts the multiplicities, which come back to
//! the host; the host builds side quads and caps from them and uploads them with the surfaces.
//! Silhouettes are kept per (object, light) and reused while neither moved.

mod frame;
mod raster;
pub mod volume;

use super::{FrameInputs, Pipeline, ShadowPipeline};
use crate::frame::{FrameReport, UncertainUnit};
use crate::raster::{push_surface, Attachments};
use crate::{Camera, RenderDevice, RenderError};
use glam::{Affine3A, Vec3};
use raster::{HostRaster, RasterInput};
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::Scene;
use shadowvol_silhouette::{
    vec_bytes, PreparedBytes, PreparedId, SilhouetteBackend, TopologyScene,
};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// One light's silhouette of one object, as last extracted.
struct LightCache {
    light: Light,
    mode: Accuracy,
    m: Vec<i32>,
}

/// One caster as the backend knows it: its table prepared on its own (object space, identity
/// transform: a moved object keeps it) and its silhouettes.
struct ObjectCache {
    table: Arc<EdgeTable>,
    prepared: PreparedId,
    transform: Affine3A,
    lights: Vec<Option<LightCache>>,
}

/// What the whole geometry was prepared for: each object's table and transform.
type PreparedKey = Vec<(Arc<EdgeTable>, Affine3A)>;

/// The host pipeline: any [`SilhouetteBackend`] extracts the multiplicities, which come back to
/// the host; the host builds side quads and caps from them and uploads them with the surfaces.
/// Silhouettes are kept per (object, light) and reused while neither moved.
pub struct HostPipeline {
    backend: Box<dyn SilhouetteBackend>,
    name: String,
    objects: Vec<ObjectCache>,
    /// The whole geometry prepared at once (real transforms), with the (table, transform) of
    /// each object it was prepared for: one `extract` serves every still object.
    whole: Option<(PreparedId, PreparedKey)>,
    raster: Option<HostRaster>,
    keep_volumes: bool,
    volumes: Vec<[f32; 4]>,
}

impl std::fmt::Debug for HostPipeline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HostPipeline")
            .field("backend", &self.name)
            .field("objects", &self.objects.len())
            .finish_non_exhaustive()
    }
}

impl HostPipeline {
    /// The host pipeline over `backend`.
    #[must_use]
    pub fn new(backend: Box<dyn SilhouetteBackend>) -> Self {
        let name = backend.info().name.to_string();
        Self {
            backend,
            name,
            objects: Vec::new(),
            whole: None,
            raster: None,
            keep_volumes: false,
            volumes: Vec::new(),
        }
    }

    /// Keeps each frame's shadow-volume vertices for [`ShadowPipeline::volumes`] (for viewers
    /// that draw the volumes themselves).
    #[must_use]
    pub fn keep_volumes(mut self, keep: bool) -> Self {
        self.keep_volumes = keep;
        self
    }

    /// Prepares every caster of `scene` that is new or has another table on its own, and
    /// forgets the silhouettes of moved ones.
    fn sync_objects(&mut self, scene: &Scene) -> Result<(), RenderError> {
        let objects = &scene.geometry.objects;
        while self.objects.len() > objects.len() {
            let c = self.objects.pop().expect("non-empty");
            self.backend.release(c.prepared);
        }
        for (oi, o) in objects.iter().enumerate() {
            if !self
                .objects
                .get(oi)
                .is_some_and(|c| Arc::ptr_eq(&c.table, &o.table))
            {
                let prepared = self
                    .backend
                    .prepare(&TopologyScene::one(&o.name, Arc::clone(&o.table)))?;
                let entry = ObjectCache {
                    table: Arc::clone(&o.table),
                    prepared,
                    transform: o.world_from_object,
                    lights: Vec::new(),
                };
                if oi < self.objects.len() {
                    let old = std::mem::replace(&mut self.objects[oi], entry);
                    self.backend.release(old.prepared);
                } else {
                    self.objects.push(entry);
                }
            }
            let c = &mut self.objects[oi];
            if c.transform != o.world_from_object {
                c.transform = o.world_from_object;
                c.lights.clear();
            }
            c.lights.resize_with(scene.lights.len(), || None);
        }
        Ok(())
    }

    /// The whole geometry prepared on the backend, prepared again only when an object's table
    /// or transform differs from the last preparation.
    fn whole_scene(&mut self, scene: &Scene) -> Result<PreparedId, RenderError> {
        let objects = &scene.geometry.objects;
        if let Some((id, key)) = &self.whole {
            let current = key.len() == objects.len()
                && key
                    .iter()
                    .zip(objects)
                    .all(|((t, x), o)| Arc::ptr_eq(t, &o.table) && *x == o.world_from_object);
            if current {
                return Ok(*id);
            }
        }
        if let Some((id, _)) = self.whole.take() {
            self.backend.release(id);
        }
        let id = self.backend.prepare(&scene.geometry)?;
        let key = objects
            .iter()
            .map(|o| (Arc::clone(&o.table), o.world_from_object))
            .collect();
        self.whole = Some((id, key));
        Ok(id)
    }
}

impl ShadowPipeline for HostPipeline {
    fn kind(&self) -> Pipeline {
        Pipeline::Host
    }

    fn backend(&self) -> Option<&str> {
        Some(&self.name)
    }

    fn uncertain_unit(&self) -> UncertainUnit {
        UncertainUnit::EdgeOppositeVertexLight
    }

    fn prepared_bytes(&self) -> PreparedBytes {
        // The backend's preparations (each object on its own, and the whole geometry), plus the
        // volume vertices kept for viewers. A frame's vertex buffers live for that frame only.
        let ids = self
            .objects
            .iter()
            .map(|c| c.prepared)
            .chain(self.whole.as_ref().map(|(id, _)| *id));
        let mut bytes = PreparedBytes {
            host: vec_bytes(&self.volumes),
            device: 0,
        };
        for id in ids {
            if let Ok(b) = self.backend.prepared_bytes(id) {
                bytes.host += b.host;
                bytes.device += b.device;
            }
        }
        bytes
    }

    fn prepare(&mut self, device: &RenderDevice, scene: &Scene) -> Result<(), RenderError> {
        if self.raster.is_none() {
            self.raster = Some(HostRaster::new(device)?);
        }
        self.sync_objects(scene)
    }

    fn record(
        &mut self,
        device: &RenderDevice,
        frame: &FrameInputs<'_>,
        report: &mut FrameReport,
        target: &Attachments<'_>,
        enc: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        let plan = &mut report.plan;
        self.sync_objects(frame.scene)?;
        let extracted = self.extract_silhouettes(frame, plan)?;

        let t_build = Instant::now();
        let (mut volumes, mut draws) = self.build_volumes(frame, plan)?;
        // Camera-relative coordinates for the GPU: every finite vertex (surface and volume) is
        // shifted by the same f32 subtraction, so shared vertices stay bit-identical and depth
        // precision no longer suffers from large world coordinates (the 1e4-offset scenes).
        // Extrusion directions (w = 0) do not depend on the origin.
        let origin = frame.camera.eye;
        for v in &mut volumes {
            if v[3] != 0.0 {
                v[0] -= origin.x;
                v[1] -= origin.y;
                v[2] -= origin.z;
            }
        }
        for d in &mut draws {
            d.light = crate::raster::relative_light(d.light, origin);
        }
        let build_time = t_build.elapsed();

        let mut surface = Vec::new();
        for (oi, (s, w)) in frame
            .scene
            .surfaces()
            .zip(frame.world.surfaces())
            .enumerate()
        {
            push_surface(&mut surface, oi, s.table, &w.positions, s.albedo, origin);
        }
        let (w, h) = frame.size;
        let aspect = (f64::from(w) / f64::from(h)) as f32;
        let raster = self.raster.as_ref().ok_or_else(|| {
            RenderError::InvalidInput("the host pipeline records before prepare".to_owned())
        })?;
        raster.record(
            &device.device,
            enc,
            target,
            &RasterInput {
                view_proj: Camera {
                    eye: Vec3::ZERO,
                    target: frame.camera.target - origin,
                    ..*frame.camera
                }
                .view_proj(aspect)
                .to_cols_array(),
                eye: [0.0; 3],
                ambient: frame.scene.effects.ambient.clamp(0.0, 1.0),
                surface: &surface,
                volumes: &volumes,
                lights: &draws,
            },
        )?;
        self.volumes = if self.keep_volumes {
            volumes
        } else {
            Vec::new()
        };
        report.timings.silhouette_ms = Some(ms(extracted.time));
        report.timings.side_building_ms = Some(ms(build_time));
        report.uncertain = extracted.uncertain;
        report.host_resolved = extracted.uncertain;
        report.readback_bytes = extracted.readback_bytes;
        Ok(())
    }

    fn volumes(&self) -> &[[f32; 4]] {
        &self.volumes
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
