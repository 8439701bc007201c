//! [`OpenClBackend`]: the backend type, its accessors, its release on drop, and the
//! [`SilhouetteBackend`] implementation (`prepare` uploads the scene, whole or in parts when its
//! buffers exceed the device's largest allocation; `extract` runs the light batches of
//! [`crate::dispatch`] on each).

use crate::device::DeviceDesc;
use crate::dispatch::{Batch, Extraction, Pending};
use crate::layout::{upload, Prepared};
use crate::{wait, NAME};
use opencl3::command_queue::CommandQueue;
use opencl3::context::Context;
use opencl3::kernel::Kernel;
use opencl3::memory::CL_MEM_READ_ONLY;
use opencl3::program::Program;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::{self, ExactFilter};
use shadowvol_silhouette::{
    check_lights, object_lights, BackendError, BackendInfo, ExtractStats, Multiplicities,
    PartsBackend, PartsEntry, PreparedBytes, PreparedId, PreparedScenes, SilhouetteBackend,
    TopologyScene, WholeScene,
};
use std::mem::ManuallyDrop;
use std::num::NonZeroUsize;
use std::time::Instant;

/// The OpenCL backend. See the crate documentation.
///
/// An `extract` runs one kernel launch per batch of lights: as many lights as fit the device's
/// largest allocation (`CL_DEVICE_MAX_MEM_ALLOC_SIZE`: the silhouette list takes 8 bytes per
/// edge and light, the light buffer 16 bytes per object and light) and the kernel's 32-bit
/// indices, and at most [`OpenClOptions::max_lights_per_batch`](crate::OpenClOptions::max_lights_per_batch). Usually that is all of them;
/// the result is the same however they are split.
///
/// A scene whose buffers exceed that allocation (the edge records take 16 bytes an edge) is
/// prepared in parts ([`SceneParts`](shadowvol_silhouette::SceneParts): objects grouped, big
/// objects cut into triangle ranges), each extracted on its own and added up: the same bits as
/// the whole scene.
pub struct OpenClBackend {
    pub(crate) device: DeviceDesc,
    /// The exact filter the kernel was built with.
    pub(crate) filter: ExactFilter,
    pub(crate) kernel_origin: String,
    /// `CL_DEVICE_MAX_MEM_ALLOC_SIZE`, bytes.
    pub(crate) max_alloc: u64,
    pub(crate) max_lights_per_batch: Option<NonZeroUsize>,
    /// Light batches (kernel launches, not counting reruns after the uncertain-record buffer
    /// grew) of the last `extract`.
    pub(crate) last_batches: usize,
    /// Launch with a fixed work-group size of [`GROUP`](crate::pipeline::GROUP) × 1.
    pub(crate) fixed_group: bool,
    // Released by `Drop` (scenes, kernel, program, queue, then the context), or leaked while
    // abandoned work has not ended.
    pub(crate) kernel: ManuallyDrop<Kernel>,
    pub(crate) program: ManuallyDrop<Program>,
    pub(crate) queue: ManuallyDrop<CommandQueue>,
    pub(crate) context: ManuallyDrop<Context>,
    /// The uploaded scenes and parts of scenes, by their own ids.
    pub(crate) scenes: ManuallyDrop<PreparedScenes<Prepared>>,
    /// What the caller's ids name: one of `scenes`, or the parts of a split scene.
    pub(crate) entries: PreparedScenes<PartsEntry>,
    /// Work abandoned by a wait that gave up; the next `extract` waits for it first.
    pub(crate) pending: Option<Pending>,
}

impl Drop for OpenClBackend {
    /// Never waits for the device. When abandoned work has still not ended, everything it may
    /// use is leaked rather than released: the host memory it may read or write, and the
    /// buffers, kernel, program, queue and context (OpenCL would keep them alive until the work
    /// ends anyway, but a driver may block in a release while a kernel hangs). Otherwise they
    /// are released as usual.
    fn drop(&mut self) {
        if let Some(p) = self.pending.take() {
            if !wait::has_ended(&p.last) {
                std::mem::forget(p);
                return;
            }
        }
        // SAFETY: each field is dropped once, here, and not used afterwards.
        unsafe {
            ManuallyDrop::drop(&mut self.scenes);
            ManuallyDrop::drop(&mut self.kernel);
            ManuallyDrop::drop(&mut self.program);
            ManuallyDrop::drop(&mut self.queue);
            ManuallyDrop::drop(&mut self.context);
        }
    }
}

impl std::fmt::Debug for OpenClBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenClBackend")
            .field("device", &self.device.describe())
            .field("exact_filter", &self.filter.name())
            .field("kernel", &self.kernel_origin)
            .field("scenes", &self.scenes.len())
            .finish_non_exhaustive()
    }
}

impl OpenClBackend {
    /// The device in use.
    #[must_use]
    pub fn device(&self) -> &DeviceDesc {
        &self.device
    }

    /// The exact-mode filter the kernel was built with: `F64` when the device has
    /// `cl_khr_fp64` (and it was not disabled with
    /// [`OpenClOptions::force_f32_filter`](crate::OpenClOptions::force_f32_filter)), else `F32`.
    #[must_use]
    pub fn exact_filter(&self) -> ExactFilter {
        self.filter
    }

    /// How many light batches (kernel launches, not counting reruns after the uncertain-record
    /// buffer grew) the last `extract` ran; for tests of the light splitting.
    #[doc(hidden)]
    #[must_use]
    pub fn batches_of_last_extract_for_tests(&self) -> usize {
        self.last_batches
    }

    /// Pretends the device's largest allocation is `bytes` from now on (checks and batch sizes
    /// only; nothing is allocated differently), so that tests can reach the device limits.
    #[doc(hidden)]
    pub fn set_max_alloc_for_tests(&mut self, bytes: u64) {
        self.max_alloc = bytes;
    }
}

/// The scenes in parts: the device's largest allocation bounds a part's buffers.
impl PartsBackend for OpenClBackend {
    const NAME: &'static str = NAME;

    fn largest_buffer(&self) -> u64 {
        self.max_alloc
    }

    fn entries(&self) -> &PreparedScenes<PartsEntry> {
        &self.entries
    }

    fn entries_mut(&mut self) -> &mut PreparedScenes<PartsEntry> {
        &mut self.entries
    }

    /// Uploads the layout's buffers, then drops the host layout; returns the scene's id among
    /// the uploaded scenes.
    fn prepare_whole(&mut self, whole: WholeScene<'_>) -> Result<PreparedId, BackendError> {
        let WholeScene {
            scene,
            layout,
            index,
        } = whole;
        let edge_words = layout.edges.as_flattened();
        let hint = "; split the scene";
        self.check_alloc("the position buffer", layout.positions.len() * 4, hint)?;
        self.check_alloc("the edge buffer", edge_words.len() * 4, hint)?;
        self.check_alloc("the OV buffer", layout.ovs.len() * 4, hint)?;
        let ro = CL_MEM_READ_ONLY;
        let at_least_one = |n: usize| (n.max(1) * 4) as u64;
        let static_bytes = at_least_one(layout.positions.len())
            + at_least_one(edge_words.len())
            + at_least_one(layout.ovs.len());
        let prepared = Prepared {
            pos: upload(&self.context, ro, &layout.positions, "positions")?,
            edges: upload(&self.context, ro, edge_words, "edges")?,
            ovs: upload(&self.context, ro, &layout.ovs, "opposite vertices")?,
            transforms: scene.transforms().collect(),
            index,
            static_bytes,
            lights: None,
            counts: None,
            sil: None,
            unc: None,
            unc_records: 0,
        };
        Ok(self.scenes.insert(prepared))
    }

    /// [`SilhouetteBackend::extract`] on the uploaded scene or part `id`, counting its light
    /// batches (`batches_of_last_extract_for_tests`).
    fn extract_whole(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        let limit = gpu::wait_limit()?;
        self.settle(limit)?;
        let p = self.scenes.get(id)?;
        let num_lights = lights.len();
        let edges = p.index.edge_count();
        if edges == 0 {
            out.reset(0, num_lights);
            return Ok(ExtractStats::default());
        }
        let mut per_launch =
            self.lights_per_batch(edges, p.index.object_count(), p.index.slot_count())?;
        // Per-frame host preparation (object-space lights) counts as upload.
        let prep_start = Instant::now();
        let obj_lights = object_lights(p.transforms.iter().copied(), lights);
        out.reset(edges, num_lights);
        let mut stats = ExtractStats {
            upload: prep_start.elapsed(),
            ..ExtractStats::default()
        };
        let job = Extraction {
            id,
            obj_lights: &obj_lights,
            mode,
            limit,
        };
        let mut first = 0;
        while first < num_lights {
            let batch = first..(first + per_launch).min(num_lights);
            match self.extract_batch(&job, batch.clone(), out, &mut stats)? {
                Batch::Done => {
                    first = batch.end;
                    self.last_batches += 1;
                }
                // Only returned for batches of two or more lights.
                Batch::TooManyUncertain => per_launch = batch.len() / 2,
            }
        }
        Ok(stats)
    }

    fn whole_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        Ok(self.scenes.get(id)?.bytes())
    }

    fn release_whole(&mut self, id: PreparedId) {
        self.scenes.remove(id);
    }
}

impl SilhouetteBackend for OpenClBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: NAME,
            device: self.device.describe(),
            modes: Accuracy::ALL.to_vec(),
            max_lights: None,
            details: vec![
                ("platform".to_owned(), self.device.platform_name.clone()),
                (
                    "platform_version".to_owned(),
                    self.device.platform_version.clone(),
                ),
                ("device_type".to_owned(), self.device.device_type.to_owned()),
                ("driver".to_owned(), self.device.driver_version.clone()),
                (
                    "exact_filter".to_owned(),
                    match self.filter {
                        ExactFilter::F64 => "f64 (cl_khr_fp64)",
                        ExactFilter::F32 => "f32",
                    }
                    .to_owned(),
                ),
                ("kernel".to_owned(), self.kernel_origin.clone()),
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
        self.entries.get(id)?;
        check_lights(lights)?;
        self.last_batches = 0;
        self.extract_parts(id, lights, mode, out)
    }

    fn prepared_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        self.parts_bytes(id)
    }

    fn release(&mut self, id: PreparedId) {
        self.release_parts(id);
    }
}
