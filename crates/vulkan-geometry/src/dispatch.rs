//! One `extract` on the device: the light batches, each uploaded, drawn through the geometry
//! shader with rasterisation discarded, waited for within the limit and read back, with the
//! uncertain pairs decided on the host ([`crate::resolve`]).

use crate::backend::VulkanBackend;
use crate::device::Buffer;
use crate::layout::{Prepared, UNCERTAIN_HEADER};
use crate::pipeline::{Push, STAGES};
use crate::resolve::{finish_batch, read_pass};
use crate::NAME;
use ash::vk;
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::gpu;
use shadowvol_silhouette::{BackendError, ExtractStats, Multiplicities, PreparedId};
use std::ops::Range;
use std::time::Instant;

impl VulkanBackend {
    /// Makes the light, multiplicity and uncertain buffers large enough for the lights
    /// `lights` (indices into each object's list in `obj_lights`), writes those lights and zeroes
    /// the uncertain counters. The caller keeps the batch within [`Self::lights_per_batch`].
    fn upload_lights(
        &mut self,
        id: PreparedId,
        obj_lights: &[Vec<[f32; 4]>],
        lights: Range<usize>,
    ) -> Result<(), BackendError> {
        let max_range = self.ctx.caps.max_storage_buffer_range;
        let ctx = &self.ctx;
        let p = self.prepared.get_mut(id)?;
        let edges = p.index.edge_count();
        let light_count = lights.len();
        let slots = edges
            .checked_mul(light_count)
            .filter(|&s| u32::try_from(s).is_ok() && (s as u64) * 4 <= max_range)
            .ok_or_else(|| BackendError::Limit {
                backend: NAME,
                message: format!(
                    "{edges} edges x {light_count} lights do not fit one result buffer (at most \
                     {} multiplicities, maxStorageBufferRange {max_range} bytes)",
                    (max_range / 4).min(u64::from(u32::MAX))
                ),
            })?;
        let mut bits: Vec<[u32; 4]> = Vec::with_capacity(obj_lights.len() * light_count);
        for per_object in obj_lights {
            let batch = per_object.get(lights.clone()).ok_or_else(|| {
                BackendError::InvalidInput(format!(
                    "lights {lights:?} are out of range: an object has {} lights",
                    per_object.len()
                ))
            })?;
            bits.extend(batch.iter().map(|l| l.map(f32::to_bits)));
        }
        let light_bytes: &[u8] = bytemuck::cast_slice(&bits);
        if light_bytes.len() as u64 > max_range {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "{light_count} lights for {} objects need {} bytes, more than one light \
                     buffer holds (maxStorageBufferRange {max_range} bytes)",
                    obj_lights.len(),
                    light_bytes.len()
                ),
            });
        }
        let mut changed = false;
        if (light_bytes.len() as u64) > p.lights.size {
            let new = Buffer::new(
                ctx,
                light_bytes.len() as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?;
            std::mem::replace(&mut p.lights, new).destroy(ctx);
            changed = true;
        }
        p.lights.write(0, light_bytes);
        if (slots as u64) * 4 > p.mult.size {
            let new =
                Buffer::host_read(ctx, slots as u64 * 4, vk::BufferUsageFlags::STORAGE_BUFFER)?;
            std::mem::replace(&mut p.mult, new).destroy(ctx);
            changed = true;
        }
        if changed {
            p.write_set(ctx);
        }
        p.uncertain.write(0, &[0u8; UNCERTAIN_HEADER]);
        Ok(())
    }

    /// Grows the uncertain buffer to hold `records` records (contents are discarded).
    fn grow_uncertain(&mut self, id: PreparedId, records: u32) -> Result<(), BackendError> {
        let ctx = &self.ctx;
        let p = self.prepared.get_mut(id)?;
        let bytes = UNCERTAIN_HEADER as u64 + 16 * u64::from(records);
        if bytes > ctx.caps.max_storage_buffer_range {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "{records} uncertain pairs do not fit one storage buffer \
                     (maxStorageBufferRange {} bytes)",
                    ctx.caps.max_storage_buffer_range
                ),
            });
        }
        let new = Buffer::host_read(ctx, bytes, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        std::mem::replace(&mut p.uncertain, new).destroy(ctx);
        p.uncertain_capacity = records;
        p.write_set(ctx);
        p.uncertain.write(0, &[0u8; UNCERTAIN_HEADER]);
        Ok(())
    }

    /// Reads the uncertain buffer's count of appended records (possibly more than it holds).
    fn uncertain_count(p: &Prepared) -> u32 {
        let mut h = [0u8; 4];
        p.uncertain.read(0, &mut h);
        u32::from_le_bytes(h)
    }

    /// Records the extraction draw (rasteriser discard) into `cmd`.
    fn record_extract(&self, p: &Prepared, cmd: vk::CommandBuffer, push: &Push, lights: u32) {
        let d = &self.ctx.device;
        let edges = p.index.edge_count() as u32;
        // SAFETY: all handles are live; the command buffer is recording.
        unsafe {
            d.cmd_begin_render_pass(
                cmd,
                &vk::RenderPassBeginInfo::default()
                    .render_pass(self.pipes.extract_pass)
                    .framebuffer(self.pipes.extract_fb)
                    .render_area(vk::Rect2D {
                        offset: vk::Offset2D { x: 0, y: 0 },
                        extent: vk::Extent2D {
                            width: 1,
                            height: 1,
                        },
                    }),
                vk::SubpassContents::INLINE,
            );
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipes.extract);
            begin_draws(d, cmd, self.pipes.layout, p.set);
            d.cmd_push_constants(cmd, self.pipes.layout, STAGES, 0, bytemuck::bytes_of(push));
            d.cmd_draw(cmd, edges, lights, 0, 0);
            d.cmd_end_render_pass(cmd);
            host_barrier(d, cmd);
        }
    }

    /// Runs the GS over every (edge, light) of the object-space lights `obj_lights` into `out`
    /// (reset by the caller to the scene's edges and the lights), in batches of at most
    /// [`Self::lights_per_batch`] lights, host-resolves the uncertain pairs and builds the
    /// compact silhouette lists; the times of every batch add to `stats`.
    pub(crate) fn extract_batches(
        &mut self,
        id: PreparedId,
        obj_lights: &[Vec<[f32; 4]>],
        mode: Accuracy,
        out: &mut Multiplicities,
        stats: &mut ExtractStats,
    ) -> Result<(), BackendError> {
        let (edges, lights) = (out.edge_count(), out.light_count());
        if edges == 0 || lights == 0 {
            return Ok(());
        }
        let per_pass = self.lights_per_batch(edges, obj_lights.len())?;
        let mut first = 0;
        while first < lights {
            let batch = first..(first + per_pass).min(lights);
            first = batch.end;
            self.extract_batch(id, obj_lights, batch, mode, out, stats)?;
            self.last_passes += 1;
        }
        // The compact silhouette lists are built on the host from m; counted as readback.
        let t = Instant::now();
        out.rebuild_silhouettes();
        stats.readback += t.elapsed();
        Ok(())
    }

    /// One pass over the lights `batch`: uploads them, draws, reads the multiplicities into
    /// their rows of `out` and resolves their uncertain pairs, adding the times to `stats`.
    fn extract_batch(
        &mut self,
        id: PreparedId,
        obj_lights: &[Vec<[f32; 4]>],
        batch: Range<usize>,
        mode: Accuracy,
        out: &mut Multiplicities,
        stats: &mut ExtractStats,
    ) -> Result<(), BackendError> {
        let t = Instant::now();
        self.upload_lights(id, obj_lights, batch.clone())?;
        stats.upload += t.elapsed();

        let edges = self.scene(id)?.index.edge_count();
        let light_count = batch.len() as u32;
        let t = Instant::now();
        let mut count;
        loop {
            let p = self.scene(id)?;
            let push = Push {
                mode: gpu::mode_code(mode),
                edge_count: edges as u32,
                light_count,
                uncertain_capacity: p.uncertain_capacity,
            };
            self.ctx
                .submit_and_wait(|_, cmd| self.record_extract(p, cmd, &push, light_count))?;
            count = Self::uncertain_count(p);
            if count <= p.uncertain_capacity {
                break;
            }
            // Too many uncertain pairs for the buffer: grow it and run again.
            self.grow_uncertain(id, count.next_power_of_two())?;
        }
        stats.compute += t.elapsed();

        let t = Instant::now();
        let p = self.scene(id)?;
        let records = read_pass(p, batch.clone(), count, out);
        stats.readback += t.elapsed();

        let t = Instant::now();
        stats.uncertain += u64::from(count);
        finish_batch(&p.index, obj_lights, batch, &records, out)?;
        stats.host_resolve += t.elapsed();
        Ok(())
    }
}

/// Sets the dynamic viewport (depth 0 to 1) and scissor of `cmd` to the extraction's 1 × 1
/// framebuffer and binds the scene's descriptor set `set` (set 0 of `layout`) for the draw that
/// follows.
///
/// # Safety
/// `cmd` must be recording; `layout` and `set` must be live.
unsafe fn begin_draws(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    layout: vk::PipelineLayout,
    set: vk::DescriptorSet,
) {
    let extent = vk::Extent2D {
        width: 1,
        height: 1,
    };
    let viewport = vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: extent.width as f32,
        height: extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    let scissor = vk::Rect2D {
        offset: vk::Offset2D { x: 0, y: 0 },
        extent,
    };
    // SAFETY: guaranteed by the caller.
    unsafe {
        d.cmd_set_viewport(cmd, 0, &[viewport]);
        d.cmd_set_scissor(cmd, 0, &[scissor]);
        d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, layout, 0, &[set], &[]);
    }
}

/// Makes shader and transfer writes visible to the host.
///
/// # Safety
/// `cmd` must be recording, outside a render pass.
unsafe fn host_barrier(d: &ash::Device, cmd: vk::CommandBuffer) {
    let barrier = vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(vk::AccessFlags::HOST_READ);
    // SAFETY: guaranteed by the caller.
    unsafe {
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::GEOMETRY_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::HOST,
            vk::DependencyFlags::empty(),
            &[barrier],
            &[],
            &[],
        );
    }
}
