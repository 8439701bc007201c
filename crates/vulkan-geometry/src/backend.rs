//! [`VulkanBackend`]: the backend type, its accessors, deferred clean-up after a timeout, its
//! release on drop, and the [`SilhouetteBackend`] implementation over the geometry shader
//! (`prepare` creates the scene's buffers, whole or in parts when one would exceed
//! `maxStorageBufferRange`; `extract` runs [`crate::dispatch`] on each).

use crate::device::{device_err, Buffer, Context, VulkanOptions};
use crate::layout::{BufferGuard, Prepared, INITIAL_UNCERTAIN, UNCERTAIN_HEADER};
use crate::pipeline::{Pipelines, BINDINGS};
use crate::NAME;
use ash::vk;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, BackendInfo, ExtractStats, Multiplicities,
    PartsBackend, PartsEntry, PreparedBytes, PreparedId, PreparedScenes, SilhouetteBackend,
    TopologyScene, WholeScene,
};
use std::num::NonZeroUsize;
use std::time::Instant;

/// Frees device objects (see [`VulkanBackend::retire`]).
type Cleanup = Box<dyn FnOnce(&Context)>;

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
/// into batches, one pass each; the result is the same as one pass would give. A scene whose
/// static buffers (edge records: 16 bytes an edge) would exceed `maxStorageBufferRange` is
/// prepared in parts ([`SceneParts`](shadowvol_silhouette::SceneParts)), each extracted on its
/// own and added up: the same bits as the whole scene.
///
/// Every wait for the device is bounded by [`shadowvol_silhouette::gpu::wait_limit`]
/// (`SHADOWVOL_GPU_TIMEOUT`). After a timeout the late work is still pending: the backend then
/// refuses new work with [`BackendError::Device`] until that work's fence signals (each later
/// call waits for it up to the limit again and recovers when it has finished), and dropping the
/// backend leaks the device instead of destroying it under running work.
pub struct VulkanBackend {
    /// The scenes and parts of scenes with their device buffers, by their own ids.
    pub(crate) prepared: PreparedScenes<Prepared>,
    /// What the caller's ids name: one of `prepared`, or the parts of a split scene.
    entries: PreparedScenes<PartsEntry>,
    /// The largest static buffer a scene may have before it is prepared in parts:
    /// `maxStorageBufferRange` (lowered by tests).
    part_limit: u64,
    pub(crate) pipes: Pipelines,
    /// Cleanups of objects that a timed-out submission may still use; run once it has finished.
    pub(crate) retired: Vec<Cleanup>,
    pub(crate) max_lights_per_batch: Option<NonZeroUsize>,
    /// Geometry-shader passes (light batches) of the last `extract`.
    pub(crate) last_passes: usize,
    pub(crate) ctx: Context,
}

impl std::fmt::Debug for VulkanBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VulkanBackend")
            .field("device", &self.ctx.caps.device_name)
            .field("filter", &self.exact_filter())
            .field("scenes", &self.prepared.len())
            .finish()
    }
}

impl VulkanBackend {
    /// Starts the backend with `options`.
    ///
    /// # Errors
    /// [`BackendError::Unavailable`] naming what is missing: the Vulkan loader, a device, Vulkan
    /// 1.1, `geometryShader`, `vertexPipelineStoresAndAtomics`, or the validation layer when it
    /// was asked for. [`BackendError::Build`] if a shader module or
    /// pipeline cannot be created.
    pub fn new(options: VulkanOptions) -> Result<Self, BackendError> {
        let ctx = Context::new(options)?;
        let pipes = Pipelines::new(&ctx)?;
        Ok(Self {
            prepared: PreparedScenes::new(NAME),
            entries: PreparedScenes::new(NAME),
            part_limit: ctx.caps.max_storage_buffer_range,
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

    /// The exact-mode filter in use: `F64` when the device has `shaderFloat64` (and it was not
    /// disabled with [`VulkanOptions::force_f32_filter`]), else `F32`.
    #[must_use]
    pub fn exact_filter(&self) -> ExactFilter {
        self.ctx.filter
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

    /// Pretends that static buffers above `bytes` exceed `maxStorageBufferRange` in the scenes
    /// prepared from now on (only the decision to cut a scene into parts changes), so that tests
    /// can reach it.
    #[doc(hidden)]
    pub fn set_part_limit_for_tests(&mut self, bytes: u64) {
        self.part_limit = bytes;
    }

    /// A descriptor pool with one set of the pipelines' layout; the pool is kept in `guard`
    /// until the caller takes it (so an error frees it), and returned with the set.
    fn allocate_set(
        &self,
        guard: &mut BufferGuard<'_>,
    ) -> Result<(vk::DescriptorPool, vk::DescriptorSet), BackendError> {
        let d = &self.ctx.device;
        let sizes = [vk::DescriptorPoolSize {
            ty: vk::DescriptorType::STORAGE_BUFFER,
            descriptor_count: BINDINGS,
        }];
        // SAFETY: valid device and infos.
        guard.pool = unsafe {
            d.create_descriptor_pool(
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
            d.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(guard.pool)
                    .set_layouts(&layouts),
            )
        }
        .map_err(|e| device_err("vkAllocateDescriptorSets", e))?[0];
        Ok((
            std::mem::replace(&mut guard.pool, vk::DescriptorPool::null()),
            set,
        ))
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
                (
                    "exact_filter".to_owned(),
                    self.exact_filter().name().to_owned(),
                ),
                ("shader_float64".to_owned(), c.float64.to_string()),
                ("validation".to_owned(), self.ctx.validation().to_string()),
                ("silhouette_list".to_owned(), "host, from m".to_owned()),
            ],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        self.prepare_parts(scene)
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        check_lights(lights)?;
        self.entries.get(id)?;
        self.settle()?;
        self.last_passes = 0;
        self.extract_parts(id, lights, mode, out)
    }

    fn prepared_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        self.parts_bytes(id)
    }

    fn release(&mut self, id: PreparedId) {
        self.release_parts(id);
    }
}

/// The scenes in parts: `maxStorageBufferRange` (or the tests' limit) bounds a part's buffers.
impl PartsBackend for VulkanBackend {
    const NAME: &'static str = NAME;

    fn entries(&self) -> &PreparedScenes<PartsEntry> {
        &self.entries
    }

    fn entries_mut(&mut self) -> &mut PreparedScenes<PartsEntry> {
        &mut self.entries
    }

    fn largest_buffer(&self) -> u64 {
        self.part_limit
    }

    /// Creates the buffers of the layout, whole, and drops the host layout; returns the
    /// scene's id among the prepared scenes.
    fn prepare_whole(&mut self, whole: WholeScene<'_>) -> Result<PreparedId, BackendError> {
        let ctx = &self.ctx;
        let (scene, layout) = (whole.scene, whole.layout);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let positions: Vec<u32> = layout.positions.iter().map(|p| p.to_bits()).collect();
        // Everything created so far is freed if a later step fails.
        let mut guard = BufferGuard {
            ctx,
            bufs: Vec::with_capacity(BINDINGS as usize),
            pool: vk::DescriptorPool::null(),
        };
        // In binding order (see `Prepared::buffers`).
        guard.bufs.push(Buffer::with_data(ctx, &positions)?);
        guard.bufs.push(Buffer::with_data(ctx, &layout.edges)?);
        guard.bufs.push(Buffer::with_data(ctx, &layout.ovs)?);
        guard.bufs.push(Buffer::new(
            ctx,
            16 * scene.objects.len().max(1) as u64,
            storage,
        )?);
        guard.bufs.push(Buffer::host_read(
            ctx,
            4 * layout.edge_count().max(1) as u64,
            storage,
        )?);
        guard.bufs.push(Buffer::host_read(
            ctx,
            UNCERTAIN_HEADER as u64 + 16 * u64::from(INITIAL_UNCERTAIN),
            storage,
        )?);
        let (pool, set) = self.allocate_set(&mut guard)?;
        let bufs = std::mem::take(&mut guard.bufs);
        let Ok::<[Buffer; BINDINGS as usize], _>([positions, edges, ovs, lights, mult, uncertain]) =
            bufs.try_into()
        else {
            // Unreachable: exactly BINDINGS buffers were pushed above.
            return Err(device_err(
                "preparing the scene's buffers",
                vk::Result::ERROR_UNKNOWN,
            ));
        };
        // The host's exact decisions read the tables through the index: the layout goes.
        drop(layout);
        let p = Prepared {
            transforms: scene.transforms().collect(),
            index: whole.index,
            positions,
            edges,
            ovs,
            lights,
            mult,
            uncertain,
            uncertain_capacity: INITIAL_UNCERTAIN,
            pool,
            set,
        };
        p.write_set(ctx);
        Ok(self.prepared.insert(p))
    }

    /// Runs the light batches (one geometry-shader pass each) on the scene or part `id`.
    fn extract_whole(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        let mut stats = ExtractStats::default();
        let t = Instant::now();
        let obj_lights = object_lights(self.scene(id)?.transforms.iter().copied(), lights);
        stats.upload += t.elapsed();
        out.reset(self.scene(id)?.index.edge_count(), lights.len());
        self.extract_batches(id, &obj_lights, mode, out, &mut stats)?;
        Ok(stats)
    }

    fn whole_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        Ok(self.prepared.get(id)?.bytes())
    }

    /// Releases the buffers of the scene or part `id`; a timed-out submission may still read
    /// them, so they are freed once it has finished.
    fn release_whole(&mut self, id: PreparedId) {
        if let Some(p) = self.prepared.remove(id) {
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
