//! What a prepared scene keeps on the device: the static buffers uploaded once, the per-frame
//! buffers (lights in, results out) and their bind group, and how many lights fit one dispatch
//! within the device's buffer limits.

use crate::backend::WgpuBackend;
use crate::device::{device_error, limit_error};
use shadowvol_gpu::tables::entry;
use shadowvol_gpu::TableBuffers;
use shadowvol_silhouette::gpu::{self, SceneIndex};
use shadowvol_silhouette::{vec_bytes, BackendError, PreparedBytes};

/// Object-space lights packed object-major for lights `first..first + count`, as uploaded:
/// `packed[object * count + light - first]`.
pub(crate) fn pack_lights(
    obj_lights: &[Vec<[f32; 4]>],
    first: usize,
    count: usize,
) -> Vec<[f32; 4]> {
    obj_lights
        .iter()
        .flat_map(|per_object| per_object[first..first + count].iter().copied())
        .collect()
}

/// Per-frame buffers (lights in, results out), reused between frames while they are big enough.
pub(crate) struct Frame {
    pub(crate) light_capacity: usize,
    pub(crate) uncertain_capacity: u32,
    /// Entries of each light's compact list (at most the edge count).
    pub(crate) list_capacity: u64,
    pub(crate) params: wgpu::Buffer,
    pub(crate) lights: wgpu::Buffer,
    pub(crate) mult: wgpu::Buffer,
    pub(crate) counters: wgpu::Buffer,
    /// Counts and list prefixes, mapped right after the dispatch.
    pub(crate) staging: Option<wgpu::Buffer>,
    pub(crate) silhouettes: wgpu::Buffer,
    pub(crate) uncertain: wgpu::Buffer,
    /// The triangle step's signs, `[light * tri_count + triangle]`.
    pub(crate) signs: wgpu::Buffer,
    pub(crate) readback: Option<wgpu::Buffer>,
    pub(crate) bind_group: wgpu::BindGroup,
}

pub(crate) struct Prepared {
    /// Per object: world from object (the device buffers hold everything else the kernels
    /// read).
    pub(crate) transforms: Vec<glam::Affine3A>,
    /// The objects in the uploaded layout's numbering, over the scene's edge tables: what the
    /// host's exact decisions read.
    pub(crate) index: SceneIndex,
    pub(crate) gpu: Option<TableBuffers>,
    pub(crate) frame: Option<Frame>,
    /// Lights of the last extract whose results the frame buffers hold: `(first, count)`.
    pub(crate) last: Option<(usize, usize)>,
    /// Compact-list entries per light copied with the counts (adapted per frame).
    pub(crate) list_prefix: u64,
    /// Uncertain records copied with the counts (adapted per frame).
    pub(crate) uncertain_prefix: u64,
    /// Exact mode on the device runs the triangle step with the integer fallback inline, since a
    /// batch's undecided pairs did not fit the largest uncertain list the device binds.
    pub(crate) inline_exact: bool,
}

impl Prepared {
    /// What the scene holds beyond its edge tables: its index and transforms on the host, and
    /// every device buffer (the scene's and the last frame's).
    pub(crate) fn bytes(&self) -> PreparedBytes {
        let host = self.index.heap_bytes() + vec_bytes(&self.transforms);
        let mut device = 0;
        if let Some(g) = &self.gpu {
            for b in g.all() {
                device += b.size();
            }
        }
        if let Some(f) = &self.frame {
            for b in [
                &f.params,
                &f.lights,
                &f.mult,
                &f.counters,
                &f.silhouettes,
                &f.uncertain,
                &f.signs,
            ] {
                device += b.size();
            }
            for b in [&f.staging, &f.readback].into_iter().flatten() {
                device += b.size();
            }
        }
        PreparedBytes { host, device }
    }
}

impl WgpuBackend {
    pub(crate) fn check_buffer(
        &self,
        what: &str,
        bytes: u64,
        binding: bool,
    ) -> Result<(), BackendError> {
        let max_binding = self.limits.max_storage_buffer_binding_size;
        let max_buffer = self.limits.max_buffer_size;
        if bytes > max_buffer || (binding && bytes > max_binding) {
            return Err(limit_error(format!(
                "{what} needs {bytes} bytes, but the device allows buffers of {max_buffer} bytes and storage bindings of {max_binding} bytes"
            )));
        }
        Ok(())
    }

    /// Lights per batch for a scene of `edges` edges, `tris` triangles and `objects` objects.
    pub(crate) fn lights_per_batch(
        &self,
        edges: u64,
        tris: u64,
        objects: u64,
        lights: usize,
    ) -> Result<usize, BackendError> {
        let max_binding = self.limits.max_storage_buffer_binding_size;
        let max_buffer = self.limits.max_buffer_size;
        let list = edges * 8;
        let readback = list
            + if self.options.full_readback {
                edges * 4
            } else {
                0
            };
        let storage = max_binding.min(max_buffer);
        let n = gpu::lights_per_batch(
            &[
                (storage, list),
                (storage, tris * 4),
                (max_buffer, readback),
                (storage, objects * 16),
            ],
            self.options.max_lights_per_batch,
        )
        .min(lights);
        if n == 0 {
            return Err(limit_error(format!(
                "one light needs a {list}-byte compact list for {edges} edges, {} bytes of triangle signs for {tris} triangles and {} bytes of object-space lights for {objects} objects, but the device allows storage bindings of {max_binding} bytes and buffers of {max_buffer} bytes",
                tris * 4,
                objects * 16
            )));
        }
        Ok(n)
    }

    /// The most uncertain-pair records (16 bytes each) one storage binding can hold.
    pub(crate) fn max_uncertain_records(&self) -> u32 {
        (self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
            / 16)
            .min(u64::from(u32::MAX)) as u32
    }

    /// Entries of each compact list in a scene's first frame:
    /// [`WgpuOptions::initial_list_capacity`](crate::WgpuOptions::initial_list_capacity), or a
    /// sixty-fourth of its `edges` (a silhouette is usually far smaller), at least 65,536, at
    /// most `edges`.
    pub(crate) fn initial_list_capacity(&self, edges: u64) -> u64 {
        self.options
            .initial_list_capacity
            .unwrap_or((edges / 64).max(1 << 16))
            .clamp(1, edges.max(1))
    }

    /// Replaces the scene's frame buffers by ones with room for `uncertain` records and `lists`
    /// entries per compact list (the current frame's where `None`), keeping its staging buffer.
    pub(crate) fn replace_frame(
        &self,
        p: &mut Prepared,
        gpu: &TableBuffers,
        uncertain: Option<u32>,
        lists: Option<u64>,
    ) -> Result<(), BackendError> {
        let sizes = (
            p.index.edge_count() as u64,
            p.index.tri_count() as u64,
            p.index.object_count() as u64,
        );
        let frame = p
            .frame
            .as_mut()
            .ok_or_else(|| device_error("no frame buffers"))?;
        let uncertain = uncertain.unwrap_or(frame.uncertain_capacity);
        let lists = lists.unwrap_or(frame.list_capacity);
        let light_capacity = frame.light_capacity;
        let staging = frame.staging.take();
        let mut frame = self.create_frame(gpu, sizes, light_capacity, uncertain, lists)?;
        frame.staging = staging;
        p.frame = Some(frame);
        Ok(())
    }

    /// The frame buffers of a scene of `edges` edges, `tris` triangles and `objects` objects,
    /// for `light_capacity` lights, `uncertain_capacity` uncertain records and compact lists of
    /// `list_capacity` entries per light.
    pub(crate) fn create_frame(
        &self,
        gpu: &TableBuffers,
        (edges, tris, objects): (u64, u64, u64),
        light_capacity: usize,
        uncertain_capacity: u32,
        list_capacity: u64,
    ) -> Result<Frame, BackendError> {
        let lc = light_capacity as u64;
        let list_capacity = list_capacity.clamp(1, edges.max(1));
        // As many records as the limits allow, at most the capacity asked for.
        let uncertain_capacity = uncertain_capacity.min(self.max_uncertain_records()).max(1);
        let uncertain_bytes = u64::from(uncertain_capacity) * 16;
        self.check_buffer("the uncertain-pair list", uncertain_bytes, true)?;
        let storage = |label: &str, size: u64, extra: wgpu::BufferUsages| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC
                    | extra,
                mapped_at_creation: false,
            })
        };
        let params = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let lights = storage(
            "object lights",
            objects * lc * 16,
            wgpu::BufferUsages::empty(),
        );
        let mult = storage("multiplicities", edges * lc * 4, wgpu::BufferUsages::VERTEX);
        let counters_bytes = (lc + 1) * 4;
        let counters = storage("counters", counters_bytes, wgpu::BufferUsages::empty());
        let signs = storage(
            "triangle signs",
            (tris * lc * 4).max(4),
            wgpu::BufferUsages::empty(),
        );
        let silhouettes = storage(
            "silhouettes",
            list_capacity * lc * 8,
            wgpu::BufferUsages::VERTEX,
        );
        let uncertain = storage("uncertain", uncertain_bytes, wgpu::BufferUsages::empty());
        let mut entries = vec![
            entry(0, &params),
            entry(4, &lights),
            entry(5, &mult),
            entry(6, &counters),
            entry(7, &silhouettes),
            entry(8, &uncertain),
            entry(11, &signs),
        ];
        entries.extend(gpu.entries());
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("silhouette"),
            layout: &self.pipelines.bind_group_layout,
            entries: &entries,
        });
        Ok(Frame {
            light_capacity,
            uncertain_capacity,
            list_capacity,
            params,
            lights,
            mult,
            counters,
            staging: None,
            silhouettes,
            uncertain,
            signs,
            readback: None,
            bind_group,
        })
    }
}
