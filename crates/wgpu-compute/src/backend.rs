//! [`WgpuBackend`]: the backend type, its accessors (device, queue, layouts, device-side
//! results) and the [`SilhouetteBackend`] implementation (`prepare` uploads the static buffers,
//! `extract` runs [`crate::dispatch`]).

use crate::device::{device_error, limit_error, Health, WgpuOptions};
use crate::layout::Prepared;
use crate::pipeline::Pipelines;
use crate::NAME;
use shadowvol_gpu::shaders;
use shadowvol_gpu::{ErrorScopes, Extras, TableBuffers, TablePacking};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::{self, ExactFilter, SceneIndex, TableBuffer, TableWriter};
use shadowvol_silhouette::{
    BackendError, BackendInfo, ExtractStats, Multiplicities, PreparedBytes, PreparedId,
    PreparedScenes, SceneParts, SilhouetteBackend, TopologyScene,
};
use std::sync::Arc;

/// Device-side results of the last [`SilhouetteBackend::extract`] on a prepared scene, for a
/// renderer that works on the same [`wgpu::Device`] (see [`WgpuBackend::from_device`]).
///
/// Layouts (`E` = [`GpuResults::edge_count`], light `l` counted within
/// `first_light..first_light + light_count`):
///
/// * `multiplicities`: `array<i32>`, `m` at `l * E + edge` (global edge index);
/// * `counters`: `array<u32>`, the length of light `l`'s compact list at `l`; the entry at
///   `light_count` is the raw number of `(triangle, light)` pairs the exact filter left in the
///   dispatch (decided on the device by the resolution step, or by the host with
///   [`WgpuOptions::exact_on_device`](crate::WgpuOptions::exact_on_device) off; 0 when the
///   integer fallback ran inline);
/// * `silhouettes`: `array<vec2<u32>>`, light `l`'s compact list at `l * C .. l * C +
///   counters[l]` (`C` = [`GpuResults::list_capacity`]), entries `(edge, bitcast<u32>(m))` in
///   unspecified order, only `m != 0`;
/// * `edges`: `array<vec2<u32>>`, the ends `(a, b)` of each global edge, global vertex ids
///   (object `i`'s ids start at its first vertex in [`TableBuffer::Objects`]);
/// * `positions`: `array<f32>`, object-space `xyz` per global vertex.
///
/// In exact mode the host has already patched `multiplicities`, `silhouettes` and the list
/// lengths with its exact decisions, so they are final. When the call needed several dispatches
/// (more lights than one dispatch holds), only the last dispatch's lights are on the device.
#[derive(Debug, Clone, Copy)]
pub struct GpuResults<'a> {
    /// Per-edge multiplicities (`i32`).
    pub multiplicities: &'a wgpu::Buffer,
    /// Compact-list lengths (`u32`).
    pub counters: &'a wgpu::Buffer,
    /// Compact lists (`vec2<u32>`).
    pub silhouettes: &'a wgpu::Buffer,
    /// The scene's tables packed into one buffer of `u32` words: edge ends (two global vertex
    /// ids each) from word `tables.packing.at.edges`, positions (`f32` bits, three per vertex)
    /// from word `tables.packing.at.positions` ([`shadowvol_gpu::TablePacking`]).
    pub tables: &'a TableBuffers,
    /// Number of edges `E` (the stride between lights in `multiplicities`).
    pub edge_count: u32,
    /// Entries `C` of each light's compact list (the stride between lights in `silhouettes`):
    /// at most `E`, and at least every list's length.
    pub list_capacity: u32,
    /// Index (in the `extract` call's light list) of the first light held.
    pub first_light: usize,
    /// Number of lights held.
    pub light_count: usize,
}

/// The wgpu compute backend. See the crate documentation.
pub struct WgpuBackend {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pub(crate) adapter: wgpu::AdapterInfo,
    pub(crate) filter: ExactFilter,
    pub(crate) options: WgpuOptions,
    pub(crate) limits: wgpu::Limits,
    pub(crate) pipelines: Pipelines,
    pub(crate) health: Arc<Health>,
    pub(crate) scenes: PreparedScenes<Entry>,
}

/// A prepared scene: whole, or cut into parts whose buffers each fit the device
/// ([`SceneParts`]), extracted one after the other and added up.
pub(crate) enum Entry {
    Whole(Box<Prepared>),
    Split {
        parts: SceneParts,
        prepared: Vec<Prepared>,
    },
}

impl Entry {
    fn whole(&self) -> Option<&Prepared> {
        match self {
            Self::Whole(p) => Some(p),
            Self::Split { .. } => None,
        }
    }
}

impl std::fmt::Debug for WgpuBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WgpuBackend")
            .field("adapter", &self.adapter.name)
            .field("backend", &self.adapter.backend)
            .field("filter", &self.filter)
            .field("options", &self.options)
            .field("scenes", &self.scenes.len())
            .finish_non_exhaustive()
    }
}

impl WgpuBackend {
    /// The exact-mode filter this device runs.
    #[must_use]
    pub fn exact_filter(&self) -> ExactFilter {
        self.filter
    }

    /// The adapter in use.
    #[must_use]
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.adapter
    }

    /// The device (for sharing results with a renderer).
    #[must_use]
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue of [`WgpuBackend::device`].
    #[must_use]
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// The index of a prepared scene's objects in the flat layout it uploaded (their first
    /// global edge, OV slot and triangle, over the scene's edge tables); `None` for an unknown id
    /// or a scene prepared in parts (one too big for the device's buffers).
    #[must_use]
    pub fn index(&self, id: PreparedId) -> Option<&SceneIndex> {
        self.scenes.get(id).ok()?.whole().map(|p| &p.index)
    }

    /// The device buffers holding the results of the last `extract` on `id` (see
    /// [`GpuResults`] for their layouts), or `None` before the first extract, for an unknown id,
    /// for a scene without edges, or for a scene prepared in parts.
    #[must_use]
    pub fn gpu_results(&self, id: PreparedId) -> Option<GpuResults<'_>> {
        let p = self.scenes.get(id).ok()?.whole()?;
        let (first_light, light_count) = p.last?;
        let gpu = p.gpu.as_ref()?;
        let frame = p.frame.as_ref()?;
        Some(GpuResults {
            multiplicities: &frame.mult,
            counters: &frame.counters,
            silhouettes: &frame.silhouettes,
            tables: gpu,
            edge_count: p.index.edge_count() as u32,
            list_capacity: frame.list_capacity as u32,
            first_light,
            light_count,
        })
    }
}

impl SilhouetteBackend for WgpuBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: NAME,
            device: {
                let driver = [self.adapter.driver.trim(), self.adapter.driver_info.trim()]
                    .into_iter()
                    .filter(|s| !s.is_empty())
                    .collect::<Vec<_>>()
                    .join(" ");
                format!(
                    "{} ({:?}, {:?}; driver {})",
                    self.adapter.name, self.adapter.backend, self.adapter.device_type, driver
                )
            },
            modes: Accuracy::ALL.to_vec(),
            max_lights: None,
            details: vec![
                ("exact_filter".to_owned(), self.filter.name().to_owned()),
                (
                    "shader_f64".to_owned(),
                    self.device
                        .features()
                        .contains(wgpu::Features::SHADER_F64)
                        .to_string(),
                ),
                (
                    "workgroup_size".to_owned(),
                    shaders::WORKGROUP_SIZE.to_string(),
                ),
                (
                    "max_lights_per_batch".to_owned(),
                    self.options
                        .max_lights_per_batch
                        .map_or_else(|| "device limits".to_owned(), |n| n.to_string()),
                ),
                (
                    "max_storage_buffer_binding_size".to_owned(),
                    self.limits.max_storage_buffer_binding_size.to_string(),
                ),
                (
                    "readback".to_owned(),
                    if self.options.full_readback {
                        "full"
                    } else {
                        "compact"
                    }
                    .to_owned(),
                ),
            ],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        self.check_health()?;
        let entry = match self.part_triangles(scene) {
            None => Entry::Whole(Box::new(self.prepare_whole(scene, SceneIndex::new(scene))?)),
            Some(max) => {
                // Each part's table is built, uploaded and dropped in turn; the host's exact
                // decisions read the scene's tables through each part's index.
                let parts = SceneParts::split(scene, max);
                let prepared = parts
                    .prepare_each(|p, index| self.prepare_whole(p, index))
                    .map_err(|(e, _)| e)?;
                Entry::Split { parts, prepared }
            }
        };
        Ok(self.scenes.insert(entry))
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        self.check_health()?;
        let mut entry = self.scenes.take(id)?;
        let result = match &mut entry {
            Entry::Whole(p) => self.extract_prepared(p, lights, mode, out),
            Entry::Split { parts, prepared } => {
                self.extract_parts(parts, prepared, lights, mode, out)
            }
        };
        self.scenes.restore(id, entry);
        result
    }

    fn prepared_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        Ok(match self.scenes.get(id)? {
            Entry::Whole(p) => p.bytes(),
            Entry::Split { parts, prepared } => {
                let mut b = PreparedBytes {
                    host: parts.own_bytes(),
                    device: 0,
                };
                for p in prepared {
                    let pb = p.bytes();
                    b.host += pb.host;
                    b.device += pb.device;
                }
                b
            }
        })
    }

    fn release(&mut self, id: PreparedId) {
        if self.scenes.remove(id).is_some() {
            // Dropped buffers are freed when the device next triages its submissions: wait for
            // that here, so that the memory is back when `release` returns. A device that does
            // not answer within the wait limit (or an unreadable limit: `extract` reports that)
            // keeps its memory a while longer; nothing else depends on it.
            if let Ok(limit) = gpu::wait_limit() {
                let _ = self.device.poll(wgpu::PollType::Wait {
                    submission_index: None,
                    timeout: Some(limit),
                });
            }
        }
    }
}

impl WgpuBackend {
    /// Triangles per part when `scene`'s tables, packed into one storage buffer
    /// ([`TablePacking`]), exceed one buffer or storage binding of the device (or
    /// [`WgpuOptions::max_buffer_bytes`](crate::WgpuOptions::max_buffer_bytes)); `None` when
    /// they fit whole. A part of `N` triangles has at most `3 N` vertices (a soup) and `3 N`
    /// edges, and exactly `3 N` OV slots: positions 36 bytes a triangle, edge ends 24, OV
    /// offsets 12, OV references 12, triangles 12 and the OV vertex list 12, so 108 bytes a
    /// triangle at most, besides the object bases (16 bytes an object) and a sentinel.
    fn part_triangles(&self, scene: &TopologyScene) -> Option<usize> {
        let limit = self.table_limit();
        let packed = TableWriter::new(scene, NAME)
            .map(|w| TablePacking::new(&w, self.extras(&w)).bytes())
            .unwrap_or(u64::MAX);
        let objects = 16 * (scene.objects.len() as u64 + 1);
        (packed > limit).then(|| (limit.saturating_sub(64 + objects) / 108).max(1) as usize)
    }

    /// The largest packed table buffer the device binds.
    fn table_limit(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }

    /// The optional tables the scene `writer` writes is uploaded with: the OV vertex list up
    /// to [`WgpuOptions::ov_vertices_up_to`](crate::WgpuOptions::ov_vertices_up_to) triangles.
    fn extras(&self, writer: &TableWriter<'_>) -> Extras {
        Extras {
            ov_vertices: writer.elements(TableBuffer::Triangles) <= self.options.ov_vertices_up_to,
            vertex_objects: false,
        }
    }

    /// [`SilhouetteBackend::extract`] on a scene prepared in parts: each part extracted, its
    /// multiplicities added onto the scene's edges.
    fn extract_parts(
        &self,
        parts: &SceneParts,
        prepared: &mut [Prepared],
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        parts.extract_each(lights.len(), out, |k, part| {
            self.extract_prepared(&mut prepared[k], lights, mode, part)
        })
    }

    /// Uploads `scene` whole, its [`TableBuffer`]s written in chunks straight from its edge
    /// tables (no host copy). The host's exact decisions read the tables through `index`
    /// ([`SceneIndex::new`] of `scene`, or of the range a part of a cut scene is).
    fn prepare_whole(
        &self,
        scene: &TopologyScene,
        index: SceneIndex,
    ) -> Result<Prepared, BackendError> {
        let writer = TableWriter::new(scene, NAME)?;
        let gpu = if writer.elements(TableBuffer::Edges) == 0 {
            None
        } else {
            let extras = self.extras(&writer);
            TablePacking::new(&writer, extras)
                .check("the kernels", self.table_limit())
                .map_err(limit_error)?;
            let scope = ErrorScopes::push(&self.device);
            let usage = wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::VERTEX;
            let wait = |i| self.wait(i);
            let buffers =
                TableBuffers::upload(&self.device, &self.queue, &writer, usage, extras, wait);
            if let Some(e) = scope.pop() {
                return Err(device_error(format!("uploading the scene: {e}")));
            }
            Some(buffers?)
        };
        self.check_health()?;
        Ok(Prepared {
            transforms: scene.transforms().collect(),
            index,
            gpu,
            frame: None,
            last: None,
            list_prefix: u64::from(self.options.min_list_prefix),
            uncertain_prefix: u64::from(self.options.min_list_prefix),
            inline_exact: false,
        })
    }
}
