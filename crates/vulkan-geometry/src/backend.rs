//! [`VulkanBackend`]: the `SilhouetteBackend` implementation over the geometry shader.

use crate::context::{device_err, Buffer, Context, VulkanOptions};
use crate::pipelines::{Pipelines, Push, BINDINGS};
use crate::twin::{DeviceFilter, DeviceScene};
use crate::NAME;
use ash::vk;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::{self, UncertainRecord};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, BackendInfo, ExtractStats, Multiplicities,
    PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::num::NonZeroUsize;
use std::ops::Range;
use std::time::Instant;

/// Bytes of the uncertain buffer's header (count, clamped count, two pads).
const UNCERTAIN_HEADER: usize = 16;
/// Bytes of one object's transform record (`mat4 clip_from_anchor; vec4 anchor;`).
pub(crate) const XFORM_BYTES: u64 = 80;
/// Initial capacity of the uncertain buffer, in records.
const INITIAL_UNCERTAIN: u32 = 1024;

/// Frees device objects (see [`VulkanBackend::retire`]).
type Cleanup = Box<dyn FnOnce(&Context)>;

/// One prepared scene: its device buffers and descriptor set.
pub(crate) struct Prepared {
    pub scene: TopologyScene,
    pub ds: DeviceScene,
    positions: Buffer,
    edges: Buffer,
    ovs: Buffer,
    lights: Buffer,
    pub models: Buffer,
    pub mult: Buffer,
    uncertain: Buffer,
    vertex_object: Buffer,
    corners: Buffer,
    /// Exact triangle signs for one light (z-fail caps in exact mode).
    pub tri_sign: Buffer,
    pub uncertain_capacity: u32,
    pool: vk::DescriptorPool,
    pub set: vk::DescriptorSet,
}

impl Prepared {
    fn buffers(&self) -> [&Buffer; BINDINGS as usize] {
        [
            &self.positions,
            &self.edges,
            &self.ovs,
            &self.lights,
            &self.models,
            &self.mult,
            &self.uncertain,
            &self.vertex_object,
            &self.corners,
            &self.tri_sign,
        ]
    }

    fn write_set(&self, ctx: &Context) {
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

    /// Zeroes the uncertain buffer's counters.
    pub(crate) fn uncertain_reset(&self) {
        self.uncertain.write(0, &[0u8; UNCERTAIN_HEADER]);
    }

    fn destroy(self, ctx: &Context) {
        // SAFETY: the device is idle; the pool frees the set.
        unsafe { ctx.device.destroy_descriptor_pool(self.pool, None) };
        for b in [
            self.positions,
            self.edges,
            self.ovs,
            self.lights,
            self.models,
            self.mult,
            self.uncertain,
            self.vertex_object,
            self.corners,
            self.tri_sign,
        ] {
            b.destroy(ctx);
        }
    }
}

/// The `vulkan` backend: the paper's geometry-shader path on a headless Vulkan device.
///
/// `extract` draws one point per (edge, light) (`vkCmdDraw(edges, lights)`, the instance index is
/// the light) through `shaders/silhouette_gs.geom` with rasterisation discarded; the shader writes
/// the multiplicities to a storage buffer. In exact mode the shader certifies each sign with an
/// `f64` filter (or the `f32` one on devices without `shaderFloat64`) and appends the pairs it
/// cannot certify to a buffer that the host decides with `orient_exact`. The compact silhouette
/// lists are built on the host from the multiplicities.
///
/// When the result buffer (`edges x lights` multiplicities) or the light buffer would exceed
/// `maxStorageBufferRange` (or [`VulkanOptions::max_lights_per_batch`] is set), the lights are split
/// into batches, one pass each; the result is the same as one pass would give.
///
/// Every wait for the device is bounded by [`shadowvol_silhouette::gpu::wait_limit`]
/// (`SHADOWVOL_GPU_TIMEOUT`). After a timeout the late work is still pending: the backend then
/// refuses new work with [`BackendError::Device`] until that work's fence signals (each later
/// call waits for it up to the limit again and recovers when it has finished), and dropping the
/// backend leaks the device instead of destroying it under running work.
///
/// [`VulkanBackend::render_shadow_mask`] (in `render.rs`) runs the same shader with emission on,
/// after a depth pre-pass, into a depth/stencil attachment.
pub struct VulkanBackend {
    pub(crate) prepared: PreparedScenes<Prepared>,
    pub(crate) pipes: Pipelines,
    /// Cleanups of objects that a timed-out submission may still use; run once it has finished.
    retired: Vec<Cleanup>,
    max_lights_per_batch: Option<NonZeroUsize>,
    /// Geometry-shader passes (light batches) of the last `extract`.
    last_passes: usize,
    pub(crate) ctx: Context,
}

impl std::fmt::Debug for VulkanBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VulkanBackend")
            .field("device", &self.ctx.caps.device_name)
            .field("filter", &self.filter())
            .field("scenes", &self.prepared.len())
            .finish()
    }
}

impl VulkanBackend {
    /// Starts the backend with `options`.
    ///
    /// # Errors
    /// [`BackendError::Unavailable`] naming what is missing: the Vulkan loader, a device, Vulkan
    /// 1.1, `geometryShader`, `vertexPipelineStoresAndAtomics`, a depth/stencil format, or the
    /// validation layer when it was asked for. [`BackendError::Build`] if a shader module or
    /// pipeline cannot be created.
    pub fn new(options: VulkanOptions) -> Result<Self, BackendError> {
        let ctx = Context::new(options)?;
        let pipes = Pipelines::new(&ctx)?;
        Ok(Self {
            prepared: PreparedScenes::new(NAME),
            pipes,
            retired: Vec::new(),
            max_lights_per_batch: options.max_lights_per_batch,
            last_passes: 0,
            ctx,
        })
    }

    /// Makes sure no timed-out submission is still running (see `Context::ensure_idle`), then
    /// frees what was retired while one was.
    pub(crate) fn settle(&mut self) -> Result<(), BackendError> {
        self.ctx.ensure_idle()?;
        for cleanup in self.retired.drain(..) {
            cleanup(&self.ctx);
        }
        Ok(())
    }

    /// Runs `cleanup` now when the device is idle, else once a timed-out submission that may
    /// still use the objects has finished (or never, if it never does: they are leaked).
    pub(crate) fn retire(&mut self, cleanup: impl FnOnce(&Context) + 'static) {
        if self.ctx.pending() {
            self.retired.push(Box::new(cleanup));
        } else {
            cleanup(&self.ctx);
        }
    }

    /// Lights per geometry-shader pass for `edges` edges and `objects` objects: as many as the
    /// result buffer (`4 * edges` bytes per light) and the light buffer (`16 * objects` bytes
    /// per light) allow within `maxStorageBufferRange` and `u32` indices, at most
    /// [`VulkanOptions::max_lights_per_batch`].
    fn lights_per_batch(&self, edges: usize, objects: usize) -> Result<usize, BackendError> {
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

    /// The exact-mode filter in use: `F64` when the device has `shaderFloat64` (and it was not
    /// disabled with [`VulkanOptions::force_f32_filter`]), else `F32`.
    #[must_use]
    pub fn filter(&self) -> DeviceFilter {
        if self.ctx.use_f64 {
            DeviceFilter::F64
        } else {
            DeviceFilter::F32
        }
    }

    /// The device name, as the driver reports it.
    #[must_use]
    pub fn device_name(&self) -> &str {
        &self.ctx.caps.device_name
    }

    /// True when the Khronos validation layer is active.
    #[must_use]
    pub fn validation_enabled(&self) -> bool {
        self.ctx.validation()
    }

    /// Warnings and errors reported by the validation layer so far (empty without validation).
    #[must_use]
    pub fn validation_messages(&self) -> Vec<String> {
        self.ctx.messages()
    }

    /// How many light batches (geometry-shader passes, not counting reruns after the uncertain
    /// buffer grew) the last `extract` ran; for tests of the light splitting.
    #[doc(hidden)]
    #[must_use]
    pub fn passes_of_last_extract_for_tests(&self) -> usize {
        self.last_passes
    }

    /// Makes one deliberately invalid but harmless call (a buffer with no usage flags) so that
    /// tests can check the validation layer is really listening. Returns false without
    /// validation.
    #[doc(hidden)]
    #[must_use]
    pub fn provoke_validation_error_for_tests(&self) -> bool {
        if !self.ctx.validation() {
            return false;
        }
        let info = vk::BufferCreateInfo::default()
            .size(16)
            .usage(vk::BufferUsageFlags::empty())
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: lavapipe and other drivers accept the call; the layer flags the missing usage.
        unsafe {
            if let Ok(b) = self.ctx.device.create_buffer(&info, None) {
                self.ctx.device.destroy_buffer(b, None);
            }
        }
        true
    }

    pub(crate) fn scene(&self, id: PreparedId) -> Result<&Prepared, BackendError> {
        self.prepared.get(id)
    }

    /// Makes the light, multiplicity and uncertain buffers large enough for the lights
    /// `lights` (indices into each object's list in `obj_lights`), writes those lights and zeroes
    /// the uncertain counters. The caller keeps the batch within [`Self::lights_per_pass`].
    pub(crate) fn upload_lights(
        &mut self,
        id: PreparedId,
        obj_lights: &[Vec<[f32; 4]>],
        lights: Range<usize>,
    ) -> Result<(), BackendError> {
        let max_range = self.ctx.caps.max_storage_buffer_range;
        let ctx = &self.ctx;
        let p = self.prepared.get_mut(id)?;
        let edges = p.ds.layout.edge_count();
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

    /// Reads the uncertain buffer's header: (appended count, clamped-emission count).
    pub(crate) fn uncertain_header(p: &Prepared) -> (u32, u32) {
        let mut h = [0u8; 8];
        p.uncertain.read(0, &mut h);
        (
            u32::from_le_bytes([h[0], h[1], h[2], h[3]]),
            u32::from_le_bytes([h[4], h[5], h[6], h[7]]),
        )
    }

    /// Records the extraction draw (rasteriser discard) into `cmd`.
    fn record_extract(&self, p: &Prepared, cmd: vk::CommandBuffer, push: &Push, lights: u32) {
        let d = &self.ctx.device;
        let edges = p.ds.layout.edge_count() as u32;
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
            d.cmd_set_viewport(
                cmd,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: 1.0,
                    height: 1.0,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.cmd_set_scissor(
                cmd,
                0,
                &[vk::Rect2D {
                    offset: vk::Offset2D { x: 0, y: 0 },
                    extent: vk::Extent2D {
                        width: 1,
                        height: 1,
                    },
                }],
            );
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.pipes.layout,
                0,
                &[p.set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                self.pipes.layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::GEOMETRY,
                0,
                bytemuck::bytes_of(push),
            );
            d.cmd_draw(cmd, edges, lights, 0, 0);
            d.cmd_end_render_pass(cmd);
            host_barrier(d, cmd);
        }
    }

    /// Runs the GS over every (edge, light), in batches of at most [`Self::lights_per_pass`]
    /// lights, host-resolves uncertain pairs, and fills `out` (light-major). The stats add up
    /// over the batches.
    pub(crate) fn extract_impl(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        check_lights(lights)?;
        self.settle()?;
        self.last_passes = 0;
        let mut stats = ExtractStats::default();
        let t = Instant::now();
        let obj_lights = object_lights(&self.scene(id)?.scene, lights);
        stats.upload = t.elapsed();

        let edges = self.scene(id)?.ds.layout.edge_count();
        out.reset(edges, lights.len());
        if edges == 0 || lights.is_empty() {
            return Ok(stats);
        }
        let per_pass = self.lights_per_batch(edges, obj_lights.len())?;
        let mut first = 0;
        while first < lights.len() {
            let batch = first..(first + per_pass).min(lights.len());
            first = batch.end;
            self.extract_batch(id, &obj_lights, batch, mode, out, &mut stats)?;
            self.last_passes += 1;
        }
        // The compact silhouette lists are built on the host from m; counted as readback.
        let t = Instant::now();
        out.rebuild_silhouettes();
        stats.readback += t.elapsed();
        Ok(stats)
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

        let edges = self.scene(id)?.ds.layout.edge_count();
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
                emit: 0,
                pass: 0,
            };
            self.ctx
                .submit_and_wait(|_, cmd| self.record_extract(p, cmd, &push, light_count))?;
            (count, _) = Self::uncertain_header(p);
            if count <= p.uncertain_capacity {
                break;
            }
            // Too many uncertain pairs for the buffer: grow it and run again.
            self.grow_uncertain(id, count.next_power_of_two())?;
        }
        stats.compute += t.elapsed();

        let t = Instant::now();
        let p = self.scene(id)?;
        let rows = &mut out.all_values_mut()[batch.start * edges..batch.end * edges];
        p.mult.read(0, bytemuck::cast_slice_mut(rows));
        let mut words = vec![0u32; UncertainRecord::WORDS * count as usize];
        if count > 0 {
            p.uncertain
                .read(UNCERTAIN_HEADER, bytemuck::cast_slice_mut(&mut words));
        }
        let records = UncertainRecord::read_all(&words);
        stats.readback += t.elapsed();

        let t = Instant::now();
        stats.uncertain += u64::from(count);
        gpu::resolve_uncertain(&p.ds.layout, obj_lights, batch, &records, out, NAME)?;
        stats.host_resolve += t.elapsed();
        Ok(())
    }
}

/// Frees the buffers and descriptor pool of a half-prepared scene on an early return.
struct BufferGuard<'a> {
    ctx: &'a Context,
    bufs: Vec<Buffer>,
    pool: vk::DescriptorPool,
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

/// Makes shader and transfer writes visible to the host.
///
/// # Safety
/// `cmd` must be recording, outside a render pass.
pub(crate) unsafe fn host_barrier(d: &ash::Device, cmd: vk::CommandBuffer) {
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

impl SilhouetteBackend for VulkanBackend {
    fn info(&self) -> BackendInfo {
        let c = &self.ctx.caps;
        BackendInfo {
            name: NAME,
            device: format!("{} ({}), geometry shader", c.device_name, c.driver),
            modes: Accuracy::ALL.to_vec(),
            max_lights: None,
            details: vec![
                ("exact_filter".to_owned(), self.filter().name().to_owned()),
                ("shader_float64".to_owned(), c.float64.to_string()),
                ("depth_clamp".to_owned(), c.depth_clamp.to_string()),
                ("validation".to_owned(), self.ctx.validation().to_string()),
                (
                    "stencil".to_owned(),
                    "z-pass or z-fail with caps, two-sided, wrapping".to_owned(),
                ),
                ("silhouette_list".to_owned(), "host, from m".to_owned()),
            ],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        let ds = DeviceScene::build(scene)?;
        let ctx = &self.ctx;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let positions: Vec<u32> = ds.layout.positions.iter().map(|p| p.to_bits()).collect();
        // Everything created so far is freed if a later step fails.
        let mut guard = BufferGuard {
            ctx,
            bufs: Vec::with_capacity(BINDINGS as usize),
            pool: vk::DescriptorPool::null(),
        };
        guard.bufs.push(Buffer::with_data(ctx, &positions)?);
        guard.bufs.push(Buffer::with_data(ctx, &ds.layout.edges)?);
        guard.bufs.push(Buffer::with_data(ctx, &ds.layout.ovs)?);
        guard.bufs.push(Buffer::new(
            ctx,
            16 * scene.objects.len().max(1) as u64,
            storage,
        )?);
        // Per-object clip transforms (written by the render path), 80 bytes each.
        guard.bufs.push(Buffer::new(
            ctx,
            XFORM_BYTES * ds.models.len().max(1) as u64,
            storage,
        )?);
        guard.bufs.push(Buffer::host_read(
            ctx,
            4 * ds.layout.edge_count().max(1) as u64,
            storage,
        )?);
        guard.bufs.push(Buffer::host_read(
            ctx,
            UNCERTAIN_HEADER as u64 + 16 * u64::from(INITIAL_UNCERTAIN),
            storage,
        )?);
        guard.bufs.push(Buffer::with_data(ctx, &ds.vertex_object)?);
        guard.bufs.push(Buffer::with_data(ctx, &ds.corners)?);
        guard.bufs.push(Buffer::new(
            ctx,
            4 * (ds.corners.len() / 3) as u64,
            storage,
        )?);
        let sizes = [vk::DescriptorPoolSize {
            ty: vk::DescriptorType::STORAGE_BUFFER,
            descriptor_count: BINDINGS,
        }];
        // SAFETY: valid device and infos.
        guard.pool = unsafe {
            ctx.device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(1)
                    .pool_sizes(&sizes),
                None,
            )
        }
        .map_err(|e| device_err("vkCreateDescriptorPool", e))?;
        let layouts = [self.pipes.set_layout];
        // SAFETY: the pool has room for one set of this layout.
        let set = unsafe {
            ctx.device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(guard.pool)
                    .set_layouts(&layouts),
            )
        }
        .map_err(|e| device_err("vkAllocateDescriptorSets", e))?[0];
        let pool = std::mem::replace(&mut guard.pool, vk::DescriptorPool::null());
        let bufs = std::mem::take(&mut guard.bufs);
        let Ok::<[Buffer; BINDINGS as usize], _>(
            [positions, edges, ovs, lights, models, mult, uncertain, vertex_object, corners, tri_sign],
        ) = bufs.try_into()
        else {
            // Unreachable: exactly BINDINGS buffers were pushed above.
            return Err(device_err(
                "preparing the scene's buffers",
                vk::Result::ERROR_UNKNOWN,
            ));
        };
        let p = Prepared {
            scene: scene.clone(),
            ds,
            positions,
            edges,
            ovs,
            lights,
            models,
            mult,
            uncertain,
            vertex_object,
            corners,
            tri_sign,
            uncertain_capacity: INITIAL_UNCERTAIN,
            pool,
            set,
        };
        p.write_set(ctx);
        Ok(self.prepared.insert(p))
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        self.extract_impl(id, lights, mode, out)
    }

    fn release(&mut self, id: PreparedId) {
        if let Some(p) = self.prepared.remove(id) {
            // A timed-out submission may still read this scene's buffers: free them later.
            self.retire(move |ctx| p.destroy(ctx));
        }
    }
}

impl Drop for VulkanBackend {
    fn drop(&mut self) {
        // Waits for a timed-out submission at most `wait_limit`. If it is still running,
        // its buffers, descriptor sets and pipelines are leaked rather than destroyed under it
        // (and the context leaks the device; see `Drop for Context`).
        if !self.ctx.idle_for_destruction() {
            return;
        }
        for cleanup in self.retired.drain(..) {
            cleanup(&self.ctx);
        }
        for (_, p) in self.prepared.drain() {
            p.destroy(&self.ctx);
        }
        self.pipes.destroy(&self.ctx);
    }
}
