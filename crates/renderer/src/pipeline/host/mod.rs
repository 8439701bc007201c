//! The host pipeline: any [`SilhouetteBackend`] extracts the multiplicities, which come back to
//! the host; the host builds side quads and caps from them and uploads them. Silhouettes are
//! kept per (object, light) and reused while neither moved; the surfaces' vertices, laid out in
//! `prepare`, stay on the device and are written again only where a surface moved (or the eye,
//! their origin), so a frame's host work grows with the silhouettes, not with the scene.

mod frame;
mod raster;
pub mod volume;

use super::{FrameInputs, Pipeline, Recording, ShadowPipeline};
use crate::frame::UncertainUnit;
use crate::raster::{push_triangles, SurfaceVertex};
use crate::{Camera, RenderDevice, RenderError};
use glam::{Affine3A, Vec3};
use raster::{HostBuffers, HostRaster, RasterInput};
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::Scene;
use shadowvol_silhouette::{
    vec_bytes, PreparedBytes, PreparedId, SilhouetteBackend, TopologyScene,
};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// One light's silhouette of one object, as last extracted, and what the volumes take from it
/// while neither moves.
struct LightCache {
    light: Light,
    mode: Accuracy,
    /// The multiplicities without the triangles that touch the light
    /// ([`volume::remove_triangles`]): what the sides are built from.
    m: Vec<i32>,
    /// Edges with a non-zero multiplicity as extracted.
    silhouette_edges: usize,
    /// Per triangle: it touches the light ([`volume::touching_triangles`]; empty: none does).
    touching: Vec<bool>,
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
    /// The device buffers kept between frames, from `prepare`.
    buffers: Option<HostBuffers>,
    /// The surfaces as the device buffer holds them.
    surfaces: SurfaceLayout,
    keep_volumes: bool,
    /// The last frame's volume vertices (camera-relative), kept so that the next frame reuses
    /// their room.
    volumes: Vec<[f32; 4]>,
}

/// What one surface's vertices in the device buffer were written from.
#[derive(Clone)]
struct SurfaceKey {
    table: Arc<EdgeTable>,
    transform: Affine3A,
    albedo: [u32; 3],
}

impl SurfaceKey {
    fn of(s: &shadowvol_scenes::Surface<'_>) -> Self {
        Self {
            table: Arc::clone(s.table),
            transform: s.world_from_object,
            albedo: s.albedo.map(f32::to_bits),
        }
    }
}

impl PartialEq<shadowvol_scenes::Surface<'_>> for SurfaceKey {
    fn eq(&self, s: &shadowvol_scenes::Surface<'_>) -> bool {
        Arc::ptr_eq(&self.table, s.table)
            && self.transform == s.world_from_object
            && self.albedo == s.albedo.map(f32::to_bits)
    }
}

/// Where each surface's triangles lie in [`HostBuffers::surface`] and what they were written
/// from.
#[derive(Default)]
struct SurfaceLayout {
    /// Per surface: its first vertex and its vertex count (3 a triangle).
    ranges: Vec<(u32, u32)>,
    /// Per surface: what its vertices were last written from (`None`: not yet written).
    written: Vec<Option<SurfaceKey>>,
    /// The origin (the eye, as bits) the written vertices are relative to.
    origin: Option<[u32; 3]>,
}

/// Triangles written to the device per queue write when surfaces are (re)written: bounds the
/// host memory a frame that writes surfaces allocates (1 MiB of vertices).
const SURFACE_BLOCK: usize = (1 << 20) / (3 * std::mem::size_of::<SurfaceVertex>());

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
            buffers: None,
            surfaces: SurfaceLayout::default(),
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

    /// Lays the surfaces of `scene` out in a new device buffer (with the uniforms' and the
    /// volumes') unless the kept one holds exactly their vertex counts; a new layout is written
    /// in full by the next frame.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] before the raster exists, [`RenderError::TooLarge`] for
    /// surfaces of more than `u32::MAX` vertices in all or a triangle beyond one buffer.
    fn lay_out(&mut self, device: &RenderDevice, scene: &Scene) -> Result<(), RenderError> {
        let raster = self.raster.as_ref().ok_or_else(|| {
            RenderError::InvalidInput("the host pipeline records before prepare".to_owned())
        })?;
        let layout = &mut self.surfaces;
        let same = self.buffers.is_some()
            && layout.ranges.len() == scene.surfaces().len()
            && layout
                .ranges
                .iter()
                .zip(scene.surfaces())
                .all(|(&(_, n), s)| n as usize == 3 * s.table.triangles.len());
        if same {
            return Ok(());
        }
        let mut ranges = Vec::with_capacity(scene.surfaces().len());
        let mut first = 0u32;
        for s in scene.surfaces() {
            let n = u32::try_from(3 * s.table.triangles.len())
                .ok()
                .filter(|&n| first.checked_add(n).is_some())
                .ok_or_else(|| {
                    RenderError::TooLarge(format!(
                        "the surfaces up to {:?} have more than {} vertices",
                        s.name,
                        u32::MAX
                    ))
                })?;
            ranges.push((first, n));
            first += n;
        }
        self.buffers = Some(raster.buffers(&device.device, first, scene.lights.len())?);
        layout.written = vec![None; ranges.len()];
        layout.ranges = ranges;
        layout.origin = None;
        Ok(())
    }

    /// Writes into the device buffer the vertices of every surface that moved (the world's
    /// change list), whose table, transform or albedo differ from those it was written from, or
    /// all of them when the eye (their origin) moved. A still scene writes nothing.
    fn write_surfaces(&mut self, device: &RenderDevice, frame: &FrameInputs<'_>) {
        let Some(buffers) = &self.buffers else {
            return;
        };
        let layout = &mut self.surfaces;
        let origin = frame.camera.eye;
        let origin_bits = origin.to_array().map(f32::to_bits);
        if layout.origin != Some(origin_bits) {
            layout.written.fill(None);
            layout.origin = Some(origin_bits);
        }
        let mut scratch: Vec<SurfaceVertex> = Vec::new();
        let surfaces = frame.scene.surfaces().zip(frame.world.surfaces());
        for (i, (s, w)) in surfaces.enumerate() {
            let moved = frame.changes.moved.get(i).copied().unwrap_or(true);
            if !moved && layout.written[i].as_ref().is_some_and(|k| *k == s) {
                continue;
            }
            let first = layout.ranges[i].0;
            let n = s.table.triangles.len();
            for lo in (0..n).step_by(SURFACE_BLOCK) {
                let hi = n.min(lo + SURFACE_BLOCK);
                scratch.clear();
                push_triangles(
                    &mut scratch,
                    i,
                    s.table,
                    lo..hi,
                    &w.positions,
                    s.albedo,
                    origin,
                );
                let at = first + 3 * lo as u32;
                buffers.surface.write(&device.queue, at, &scratch);
            }
            layout.written[i] = Some(SurfaceKey::of(&s));
        }
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
        // The backend's preparations (each object on its own, and the whole geometry), the
        // device buffers kept between frames (surfaces, volumes, uniforms), and the host's
        // volume vertices kept for the next frame.
        let ids = self
            .objects
            .iter()
            .map(|c| c.prepared)
            .chain(self.whole.as_ref().map(|(id, _)| *id));
        let mut bytes = PreparedBytes {
            host: vec_bytes(&self.volumes),
            device: self.buffers.as_ref().map_or(0, HostBuffers::device_bytes),
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
        self.sync_objects(scene)?;
        self.lay_out(device, scene)
    }

    fn record(&mut self, frame: &FrameInputs<'_>, rec: Recording<'_>) -> Result<(), RenderError> {
        let (report, target, enc) = (rec.report, rec.target, rec.enc);
        let device = frame.device;
        let plan = &mut report.plan;
        self.lay_out(device, frame.scene)?;
        self.sync_objects(frame.scene)?;
        let extracted = self.extract_silhouettes(frame, plan)?;

        let t_build = Instant::now();
        let mut volumes = std::mem::take(&mut self.volumes);
        volumes.clear();
        let built = self.build_volumes(frame, plan, &mut volumes);
        self.volumes = volumes;
        let mut draws = built?;
        // Camera-relative coordinates for the GPU: every finite vertex (surface and volume) is
        // shifted by the same f32 subtraction, so shared vertices stay bit-identical and depth
        // precision no longer suffers from large world coordinates (the 1e4-offset scenes).
        // Extrusion directions (w = 0) do not depend on the origin.
        let origin = frame.camera.eye;
        for v in &mut self.volumes {
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

        self.write_surfaces(device, frame);
        let (w, h) = frame.size;
        let aspect = (f64::from(w) / f64::from(h)) as f32;
        let (Some(raster), Some(buffers)) = (&self.raster, &mut self.buffers) else {
            return Err(RenderError::InvalidInput(
                "the host pipeline records before prepare".to_owned(),
            ));
        };
        let surface_vertices = self.surfaces.ranges.last().map_or(0, |&(f, n)| f + n);
        raster.record(
            device,
            buffers,
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
                surface_vertices: surface_vertices as usize,
                volumes: &self.volumes,
                lights: &draws,
                passes: frame.passes,
            },
        )?;
        report.timings.silhouette_ms = Some(ms(extracted.time));
        report.timings.side_building_ms = Some(ms(build_time));
        report.uncertain = extracted.uncertain;
        report.host_resolved = extracted.uncertain;
        report.readback_bytes = extracted.readback_bytes;
        Ok(())
    }

    fn volumes(&self) -> &[[f32; 4]] {
        if self.keep_volumes {
            &self.volumes
        } else {
            &[]
        }
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
