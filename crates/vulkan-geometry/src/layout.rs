//! The device buffers of a prepared scene (the scene's layout, lights, results and uncertain
//! records, bound as one descriptor set) and how many lights fit one pass within
//! `maxStorageBufferRange`.

use crate::backend::VulkanBackend;
use crate::device::{Buffer, Context};
use crate::pipeline::BINDINGS;
use crate::NAME;
use ash::vk;
use shadowvol_silhouette::gpu::SceneIndex;
use shadowvol_silhouette::{BackendError, PreparedBytes};

/// Bytes of the uncertain buffer's header (the count and three pads).
pub(crate) const UNCERTAIN_HEADER: usize = 16;
/// Initial capacity of the uncertain buffer, in records.
pub(crate) const INITIAL_UNCERTAIN: u32 = 1024;

/// One prepared scene: its device buffers and descriptor set.
pub(crate) struct Prepared {
    /// Each object's transform, world from object.
    pub(crate) transforms: Vec<glam::Affine3A>,
    /// The objects in the numbering of the uploaded layout (positions, edge records `(a, b,
    /// first OV slot, object)` plus the sentinel, opposite vertices, with global vertex ids),
    /// over the scene's edge tables: what the host's exact decisions read.
    pub(crate) index: SceneIndex,
    pub(crate) positions: Buffer,
    pub(crate) edges: Buffer,
    pub(crate) ovs: Buffer,
    pub(crate) lights: Buffer,
    pub(crate) mult: Buffer,
    pub(crate) uncertain: Buffer,
    pub(crate) uncertain_capacity: u32,
    pub(crate) pool: vk::DescriptorPool,
    pub(crate) set: vk::DescriptorSet,
}

impl Prepared {
    /// What the scene holds beyond its edge tables: the index and the device buffers.
    pub(crate) fn bytes(&self) -> PreparedBytes {
        PreparedBytes {
            host: self.index.heap_bytes() + shadowvol_silhouette::vec_bytes(&self.transforms),
            device: self.buffers().iter().map(|b| b.size).sum(),
        }
    }

    /// The buffers in binding order (see `shaders/silhouette_gs.geom`).
    fn buffers(&self) -> [&Buffer; BINDINGS as usize] {
        [
            &self.positions,
            &self.edges,
            &self.ovs,
            &self.lights,
            &self.mult,
            &self.uncertain,
        ]
    }

    pub(crate) fn write_set(&self, ctx: &Context) {
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = self
            .buffers()
            .iter()
            .map(|b| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(b.buffer)
                    .offset(0)
                    .range(vk::WHOLE_SIZE)]
            })
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set is not in use (the device is idle between calls).
        unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
    }

    pub(crate) fn destroy(self, ctx: &Context) {
        // SAFETY: the device is idle; the pool frees the set.
        unsafe { ctx.device.destroy_descriptor_pool(self.pool, None) };
        for b in [
            self.positions,
            self.edges,
            self.ovs,
            self.lights,
            self.mult,
            self.uncertain,
        ] {
            b.destroy(ctx);
        }
    }
}

/// Frees the buffers and descriptor pool of a half-prepared scene on an early return.
pub(crate) struct BufferGuard<'a> {
    pub(crate) ctx: &'a Context,
    pub(crate) bufs: Vec<Buffer>,
    pub(crate) pool: vk::DescriptorPool,
}

impl Drop for BufferGuard<'_> {
    fn drop(&mut self) {
        for b in self.bufs.drain(..) {
            b.destroy(self.ctx);
        }
        // SAFETY: the pool (null when none was made or it was handed over) is unused.
        unsafe { self.ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}

impl VulkanBackend {
    /// Lights per geometry-shader pass for `edges` edges and `objects` objects: as many as the
    /// result buffer (`4 * edges` bytes per light) and the light buffer (`16 * objects` bytes
    /// per light) allow within `maxStorageBufferRange` and `u32` indices, at most
    /// [`VulkanOptions::max_lights_per_batch`](crate::VulkanOptions::max_lights_per_batch).
    pub(crate) fn lights_per_batch(
        &self,
        edges: usize,
        objects: usize,
    ) -> Result<usize, BackendError> {
        let max_range = self.ctx.caps.max_storage_buffer_range;
        let mult = 4 * edges as u64;
        let light = 16 * objects as u64;
        let n = shadowvol_silhouette::gpu::lights_per_batch(
            &[
                (max_range, mult),
                (max_range, light),
                (u64::from(u32::MAX), edges as u64),
            ],
            self.max_lights_per_batch,
        );
        if n == 0 {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "one light alone does not fit the device's buffers: it needs {mult} bytes of \
                     multiplicities for {edges} edges and {light} bytes of object-space lights \
                     for {objects} objects, but maxStorageBufferRange is {max_range} bytes (and \
                     at most {} multiplicities per pass); split the scene",
                    u32::MAX
                ),
            });
        }
        Ok(n)
    }
}
