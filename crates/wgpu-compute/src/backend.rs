//! The wgpu backend: device set-up, prepare (static buffers), extract (dispatch, readback,
//! host resolution).

use crate::resolve::{expand_uncertain, finish_batch, BatchOutput, Patch, UncertainTriangle};
use crate::twin::{pack_lights, ExactFilter};
use crate::{shaders, NAME};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::gpu::{SceneLayout, TriangleLayout};
use shadowvol_silhouette::{
    check_lights, gpu, object_lights, BackendError, BackendInfo, ExtractStats, Multiplicities,
    PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::num::NonZeroUsize;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

mod dispatch;

/// The error for a wait that failed; a timeout names the limit and how to change it.
fn wait_error(what: &str, e: &wgpu::PollError, limit: Duration) -> BackendError {
    match e {
        wgpu::PollError::Timeout => device_error(format!(
            "{what}: the device did not finish within {}",
            shadowvol_silhouette::gpu::describe_wait_limit(limit)
        )),
        other => device_error(format!("{what}: {other}")),
    }
}

/// Options of [`WgpuBackend`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WgpuOptions {
    /// Use the `f32` exact-mode filter even when the adapter has `SHADER_F64` (default
    /// `false`), for testing both paths on one device.
    pub force_f32_filter: bool,
    /// Exact mode decides what the filter cannot certify on the device, with `orient_int`'s
    /// integer arithmetic (default `true`: nothing is resolved on the host and
    /// [`ExtractStats::uncertain`](shadowvol_silhouette::ExtractStats::uncertain) is 0);
    /// `false` sends those triples to the host, as the other GPU backends do.
    pub exact_on_device: bool,
    /// Read back the whole per-edge multiplicity buffer instead of rebuilding the values from the
    /// compact lists (default `false`). Same result, more bytes moved; for checking the device
    /// buffer.
    pub full_readback: bool,
    /// Most lights per batch, one dispatch each (default 64; `None`: only the buffer limits
    /// split the lights). More lights are processed in several batches with the same result;
    /// the buffer limits may lower it further.
    pub max_lights_per_batch: Option<NonZeroUsize>,
    /// Initial capacity of the uncertain-triple buffer (default 4096); it grows (and the
    /// dispatch is repeated) when a dispatch overflows it.
    pub initial_uncertain_capacity: u32,
    /// A cap, in bytes, on every buffer and storage binding, below the device's own limits (a
    /// memory budget; default `None`). Scenes whose static buffers exceed it are refused with
    /// [`BackendError::Limit`]; per-frame buffers shrink by running fewer lights per dispatch.
    pub max_buffer_bytes: Option<u64>,
    /// A cap on workgroups per dispatch dimension, below the device's limit (default `None`).
    /// Scenes with more workgroups than one dimension holds fold them into a 2-D grid; a small
    /// cap exercises that path on small scenes.
    pub max_workgroups_per_dimension: Option<u32>,
    /// Smallest number of compact-list entries per light (and of uncertain records) copied
    /// together with the list lengths right after the dispatch (default 256). Lists that fit are
    /// read in that one round trip; longer ones need a second. The prefix adapts to the last
    /// frame's sizes (1.25 x, rounded up to a power of two); 0 starts with no prefix.
    pub min_list_prefix: u32,
}

impl Default for WgpuOptions {
    fn default() -> Self {
        Self {
            force_f32_filter: false,
            full_readback: false,
            max_lights_per_batch: NonZeroUsize::new(64),
            initial_uncertain_capacity: 4096,
            max_buffer_bytes: None,
            max_workgroups_per_dimension: None,
            min_list_prefix: 256,
            exact_on_device: true,
        }
    }
}

/// Errors reported by wgpu outside an error scope, and device loss.
#[derive(Default)]
struct Health {
    errors: Mutex<Vec<String>>,
    lost: Mutex<Option<String>>,
}

fn device_error(message: impl Into<String>) -> BackendError {
    BackendError::Device {
        backend: NAME,
        message: message.into(),
    }
}

fn limit_error(message: String) -> BackendError {
    BackendError::Limit {
        backend: NAME,
        message,
    }
}

/// Buffers uploaded once per prepared scene (cheap to clone: wgpu buffers are shared handles).
#[derive(Clone)]
struct StaticBuffers {
    positions: wgpu::Buffer,
    edges: wgpu::Buffer,
    ovs: wgpu::Buffer,
    tris: wgpu::Buffer,
    ov_tris: wgpu::Buffer,
}

/// One batch of the lights of an `extract`: what [`WgpuBackend::run_batch`] uploads and where
/// its rows of the result go.
struct LightBatch<'a> {
    /// Every light of the extraction, per object (object space).
    object_lights: &'a [Vec<[f32; 4]>],
    /// The batch's lights packed object-major, as uploaded.
    packed: Vec<[f32; 4]>,
    /// The batch's lights within the extraction.
    lights: std::ops::Range<usize>,
    /// Whether this is the extraction's last batch (its device buffers stay readable).
    last: bool,
    /// Exact mode: uncertain records are read back and resolved.
    exact: bool,
}

/// Per-frame buffers (lights in, results out), reused between frames while they are big enough.
struct Frame {
    light_capacity: usize,
    uncertain_capacity: u32,
    params: wgpu::Buffer,
    lights: wgpu::Buffer,
    mult: wgpu::Buffer,
    counters: wgpu::Buffer,
    /// Counts and list prefixes, mapped right after the dispatch.
    staging: Option<wgpu::Buffer>,
    silhouettes: wgpu::Buffer,
    uncertain: wgpu::Buffer,
    readback: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
}

struct Prepared {
    scene: TopologyScene,
    layout: SceneLayout,
    triangles: TriangleLayout,
    /// [`TriangleLayout::edge_slots`], built the first time the host decides a triangle.
    edge_slots: Option<Vec<[(u32, u32); 3]>>,
    gpu: Option<StaticBuffers>,
    frame: Option<Frame>,
    /// Lights of the last extract whose results the frame buffers hold: `(first, count)`.
    last: Option<(usize, usize)>,
    /// Compact-list entries per light copied with the counts (adapted per frame).
    list_prefix: u64,
    /// Uncertain records copied with the counts (adapted per frame).
    uncertain_prefix: u64,
}

/// Device-side results of the last [`SilhouetteBackend::extract`] on a prepared scene, for a
/// renderer that works on the same [`wgpu::Device`] (see [`WgpuBackend::from_device`]).
///
/// Layouts (`E` = [`GpuResults::edge_count`], light `l` counted within
/// `first_light..first_light + light_count`):
///
/// * `multiplicities`: `array<i32>`, `m` at `l * E + edge` (global edge index);
/// * `counters`: `array<u32>`, the length of light `l`'s compact list at `l`; the entry at
///   `light_count` is the raw number of uncertain triples of the dispatch;
/// * `silhouettes`: `array<vec2<u32>>`, light `l`'s compact list at `l * E .. l * E + counters[l]`,
///   entries `(edge, bitcast<u32>(m))` in unspecified order, only `m != 0`;
/// * `edges`: `array<vec4<u32>>`, `(a, b, first OV slot, object)` with global vertex ids
///   (object `i`'s ids start at [`SceneLayout::vertex_offsets`]`[i]`), plus a sentinel;
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
    /// Edge records (`vec4<u32>`).
    pub edges: &'a wgpu::Buffer,
    /// Positions (`f32` × 3).
    pub positions: &'a wgpu::Buffer,
    /// Number of edges `E` (the stride between lights).
    pub edge_count: u32,
    /// Index (in the `extract` call's light list) of the first light held.
    pub first_light: usize,
    /// Number of lights held.
    pub light_count: usize,
}

/// The wgpu compute backend. See the crate documentation.
pub struct WgpuBackend {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: wgpu::AdapterInfo,
    filter: ExactFilter,
    options: WgpuOptions,
    limits: wgpu::Limits,
    bind_group_layout: wgpu::BindGroupLayout,
    /// The edge step, per mode ([`shaders::mode_value`]).
    pipelines: Vec<wgpu::ComputePipeline>,
    /// The triangle step, per mode; `None` for `original`, which has none.
    triangle_pipelines: Vec<Option<wgpu::ComputePipeline>>,
    health: Arc<Health>,
    scenes: PreparedScenes<Prepared>,
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

fn device_type_rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

const INSTALL_HINT: &str = "install a Vulkan driver (on Debian/Ubuntu: `apt install mesa-vulkan-drivers libvulkan1` \
     for the lavapipe CPU implementation, or your GPU vendor's driver); WGPU_BACKEND=vulkan|gl selects the API";

impl WgpuBackend {
    /// Finds the best adapter (discrete, integrated, virtual, then CPU; Vulkan first), opens a
    /// device with the adapter's limits and, when available and allowed, `SHADER_F64`, and builds
    /// the pipelines. `WGPU_BACKEND` and the other wgpu environment variables are honoured.
    ///
    /// # Errors
    /// [`BackendError::Unavailable`] when no adapter with compute shaders exists (naming what to
    /// install) or the device cannot be opened; [`BackendError::Build`] if a shader fails to
    /// compile on the device.
    pub fn new(options: WgpuOptions) -> Result<Self, BackendError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let mut seen = Vec::new();
        let mut usable: Vec<wgpu::Adapter> = Vec::new();
        for a in adapters {
            let info = a.get_info();
            let compute = a
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS);
            seen.push(format!(
                "{} ({:?}{})",
                info.name,
                info.backend,
                if compute { "" } else { ", no compute shaders" }
            ));
            if compute {
                usable.push(a);
            }
        }
        usable.sort_by_key(|a| {
            let info = a.get_info();
            (
                device_type_rank(info.device_type),
                u8::from(info.backend != wgpu::Backend::Vulkan),
            )
        });
        let Some(adapter) = usable.into_iter().next() else {
            let reason = if seen.is_empty() {
                format!("no GPU adapter found; {INSTALL_HINT}")
            } else {
                format!(
                    "no adapter with compute shaders (found: {}); {INSTALL_HINT}",
                    seen.join(", ")
                )
            };
            return Err(BackendError::Unavailable {
                backend: NAME,
                reason,
            });
        };
        let mut features = wgpu::Features::empty();
        if !options.force_f32_filter && adapter.features().contains(wgpu::Features::SHADER_F64) {
            features |= wgpu::Features::SHADER_F64;
        }
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadowvol-wgpu-compute"),
            required_features: features,
            required_limits: adapter.limits(),
            experimental_features: wgpu::ExperimentalFeatures::default(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| BackendError::Unavailable {
            backend: NAME,
            reason: format!(
                "cannot open a device on {} ({:?}): {e}",
                info.name, info.backend
            ),
        })?;
        Self::from_device(device, queue, options)
    }

    /// Builds the backend on an existing device (for example the renderer's), so that
    /// [`WgpuBackend::gpu_results`] can be used by other pipelines on that device. Exact mode uses
    /// the `f64` filter when the device was opened with `SHADER_F64` and not `options.force_f32_filter`.
    ///
    /// This installs an uncaptured-error handler and a device-lost callback on `device`: wgpu
    /// errors become [`BackendError::Device`] instead of panics.
    ///
    /// # Errors
    /// [`BackendError::Build`] if a shader fails to compile, [`BackendError::Unavailable`] if the
    /// device's limits cannot hold the kernel's bindings.
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        options: WgpuOptions,
    ) -> Result<Self, BackendError> {
        let health = Arc::new(Health::default());
        {
            let h = Arc::clone(&health);
            device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                h.errors
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .push(e.to_string());
            }));
            let h = Arc::clone(&health);
            device.set_device_lost_callback(move |reason, message| {
                *h.lost.lock().unwrap_or_else(PoisonError::into_inner) =
                    Some(format!("device lost ({reason:?}): {message}"));
            });
        }
        let mut limits = device.limits();
        if let Some(cap) = options.max_buffer_bytes {
            limits.max_buffer_size = limits.max_buffer_size.min(cap);
            limits.max_storage_buffer_binding_size =
                limits.max_storage_buffer_binding_size.min(cap);
        }
        if let Some(cap) = options.max_workgroups_per_dimension {
            limits.max_compute_workgroups_per_dimension =
                limits.max_compute_workgroups_per_dimension.min(cap.max(1));
        }
        if limits.max_storage_buffers_per_shader_stage < STORAGE_BUFFERS
            || limits.max_compute_invocations_per_workgroup < shaders::WORKGROUP_SIZE
            || limits.max_compute_workgroup_size_x < shaders::WORKGROUP_SIZE
        {
            return Err(BackendError::Unavailable {
                backend: NAME,
                reason: format!(
                    "the device allows {} storage buffers per stage and {} invocations per workgroup; the kernels need {STORAGE_BUFFERS} and {}",
                    limits.max_storage_buffers_per_shader_stage,
                    limits.max_compute_invocations_per_workgroup,
                    shaders::WORKGROUP_SIZE
                ),
            });
        }
        let filter = if !options.force_f32_filter
            && device.features().contains(wgpu::Features::SHADER_F64)
        {
            ExactFilter::F64
        } else {
            ExactFilter::F32
        };
        let adapter = device.adapter_info();
        let source = shaders::module_source_with(filter, options.exact_on_device);
        let scope = ErrorScopes::push(&device);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shaders/silhouette.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("silhouette bindings"),
            entries: &bind_group_layout_entries(),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("silhouette"),
            bind_group_layouts: &[Some(&bind_group_layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str, mode: Accuracy| {
            let constants = [(shaders::MODE_CONSTANT, f64::from(shaders::mode_value(mode)))];
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(mode.name()),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            })
        };
        let pipelines = Accuracy::ALL
            .iter()
            .map(|&mode| pipeline(shaders::ENTRY_POINT, mode))
            .collect();
        let triangle_pipelines = Accuracy::ALL
            .iter()
            .map(|&mode| {
                (mode != Accuracy::Original).then(|| pipeline(shaders::TRIANGLE_ENTRY_POINT, mode))
            })
            .collect();
        if let Some(e) = scope.pop() {
            return Err(BackendError::Build {
                backend: NAME,
                what: format!("shaders/silhouette.wgsl ({} exact filter)", filter.name()),
                log: e,
            });
        }
        let backend = Self {
            device,
            queue,
            adapter,
            filter,
            options,
            limits,
            bind_group_layout,
            pipelines,
            triangle_pipelines,
            health,
            scenes: PreparedScenes::new(NAME),
        };
        backend.check_health()?;
        Ok(backend)
    }

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

    /// The flat layout of a prepared scene (global vertex ids, edge records), as uploaded.
    #[must_use]
    pub fn layout(&self, id: PreparedId) -> Option<&SceneLayout> {
        self.scenes.get(id).ok().map(|p| &p.layout)
    }

    /// The device buffers holding the results of the last `extract` on `id` (see
    /// [`GpuResults`] for their layouts), or `None` before the first extract, for an unknown id,
    /// or for a scene without edges.
    #[must_use]
    pub fn gpu_results(&self, id: PreparedId) -> Option<GpuResults<'_>> {
        let p = self.scenes.get(id).ok()?;
        let (first_light, light_count) = p.last?;
        let gpu = p.gpu.as_ref()?;
        let frame = p.frame.as_ref()?;
        Some(GpuResults {
            multiplicities: &frame.mult,
            counters: &frame.counters,
            silhouettes: &frame.silhouettes,
            edges: &gpu.edges,
            positions: &gpu.positions,
            edge_count: p.layout.edge_count() as u32,
            first_light,
            light_count,
        })
    }

    fn check_health(&self) -> Result<(), BackendError> {
        if let Some(lost) = self
            .health
            .lost
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
        {
            return Err(device_error(lost));
        }
        let mut errors = self
            .health
            .errors
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if errors.is_empty() {
            Ok(())
        } else {
            let message = errors.join("; ");
            errors.clear();
            Err(device_error(message))
        }
    }

    fn wait(&self, index: wgpu::SubmissionIndex) -> Result<(), BackendError> {
        let limit = gpu::wait_limit()?;
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: Some(limit),
            })
            .map_err(|e| wait_error("waiting for the device", &e, limit))?;
        self.check_health()
    }

    /// Maps `buffer[0..size]` for reading and hands the bytes to `f`.
    fn read_mapped<T>(
        &self,
        buffer: &wgpu::Buffer,
        size: u64,
        f: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, BackendError> {
        let slot = Arc::new(Mutex::new(None));
        let s = Arc::clone(&slot);
        buffer.map_async(wgpu::MapMode::Read, 0..size, move |r| {
            *s.lock().unwrap_or_else(PoisonError::into_inner) = Some(r);
        });
        let limit = gpu::wait_limit()?;
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(limit),
            })
            .map_err(|e| wait_error("waiting for a buffer mapping", &e, limit))?;
        self.check_health()?;
        let state = slot.lock().unwrap_or_else(PoisonError::into_inner).take();
        match state {
            Some(Ok(())) => {}
            Some(Err(e)) => return Err(device_error(format!("mapping a readback buffer: {e}"))),
            None => return Err(device_error("a readback mapping did not complete")),
        }
        let result = {
            let view = buffer
                .get_mapped_range(0..size)
                .map_err(|e| device_error(format!("reading a mapped buffer: {e}")))?;
            f(&view)
        };
        buffer.unmap();
        Ok(result)
    }

    fn check_buffer(&self, what: &str, bytes: u64, binding: bool) -> Result<(), BackendError> {
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
    fn lights_per_batch(
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

    fn create_frame(
        &self,
        gpu: &StaticBuffers,
        edges: u64,
        tris: u64,
        objects: u64,
        light_capacity: usize,
        uncertain_capacity: u32,
    ) -> Result<Frame, BackendError> {
        let lc = light_capacity as u64;
        // As many records as the limits allow, at most the capacity asked for.
        let max_records = (self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
            / 16)
            .min(u64::from(u32::MAX)) as u32;
        let uncertain_capacity = uncertain_capacity.min(max_records).max(1);
        let uncertain_bytes = u64::from(uncertain_capacity) * 16;
        self.check_buffer("the uncertain-triple buffer", uncertain_bytes, true)?;
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
            size: 16,
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
        // The triangle step's signs, `[light * tri_count + triangle]` (kept alive by the bind
        // group).
        let signs = storage(
            "triangle signs",
            (tris * lc * 4).max(4),
            wgpu::BufferUsages::empty(),
        );
        let silhouettes = storage("silhouettes", edges * lc * 8, wgpu::BufferUsages::VERTEX);
        let uncertain = storage("uncertain", uncertain_bytes, wgpu::BufferUsages::empty());
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("silhouette"),
            layout: &self.bind_group_layout,
            entries: &[
                entry(0, &params),
                entry(1, &gpu.positions),
                entry(2, &gpu.edges),
                entry(3, &gpu.ovs),
                entry(4, &lights),
                entry(5, &mult),
                entry(6, &counters),
                entry(7, &silhouettes),
                entry(8, &uncertain),
                entry(9, &gpu.tris),
                entry(10, &gpu.ov_tris),
                entry(11, &signs),
            ],
        });
        Ok(Frame {
            light_capacity,
            uncertain_capacity,
            params,
            lights,
            mult,
            counters,
            staging: None,
            silhouettes,
            uncertain,
            readback: None,
            bind_group,
        })
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// Storage buffers the kernels bind in one stage.
const STORAGE_BUFFERS: u32 = 11;

fn bind_group_layout_entries() -> [wgpu::BindGroupLayoutEntry; 12] {
    let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    [
        wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(16),
            },
            count: None,
        },
        storage(1, true),
        storage(2, true),
        storage(3, true),
        storage(4, true),
        storage(5, false),
        storage(6, false),
        storage(7, false),
        storage(8, false),
        storage(9, true),
        storage(10, true),
        storage(11, false),
    ]
}

/// Out-of-memory, validation and internal error scopes around a block of wgpu calls.
struct ErrorScopes {
    scopes: Vec<wgpu::ErrorScopeGuard>,
}

impl ErrorScopes {
    fn push(device: &wgpu::Device) -> Self {
        Self {
            scopes: vec![
                device.push_error_scope(wgpu::ErrorFilter::OutOfMemory),
                device.push_error_scope(wgpu::ErrorFilter::Validation),
                device.push_error_scope(wgpu::ErrorFilter::Internal),
            ],
        }
    }

    /// Pops the scopes (innermost first) and returns the captured errors, if any.
    fn pop(mut self) -> Option<String> {
        let mut errors = Vec::new();
        while let Some(scope) = self.scopes.pop() {
            if let Some(e) = pollster::block_on(scope.pop()) {
                errors.push(match &e {
                    wgpu::Error::OutOfMemory { .. } => "out of device memory".to_owned(),
                    other => other.to_string(),
                });
            }
        }
        (!errors.is_empty()).then(|| errors.join("; "))
    }
}

/// Compact-list entries `(edge, m)` from little-endian `u32` pairs.
fn read_pairs(bytes: &[u8]) -> Vec<(u32, i32)> {
    let words: Vec<u32> = read_u32s(bytes).collect();
    words.chunks_exact(2).map(|w| (w[0], w[1] as i32)).collect()
}

/// Undecided `(triangle, light)` records (4 little-endian `u32` words each).
fn read_records(bytes: &[u8]) -> Vec<UncertainTriangle> {
    let words: Vec<u32> = read_u32s(bytes).collect();
    words
        .chunks_exact(4)
        .map(|w| UncertainTriangle {
            triangle: w[0],
            light: w[1],
        })
        .collect()
}

fn read_u32s(bytes: &[u8]) -> impl Iterator<Item = u32> + '_ {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
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
        let layout = SceneLayout::build(scene, NAME)?;
        let triangles = TriangleLayout::build(scene, &layout, NAME)?;
        let gpu = if layout.edge_count() == 0 {
            None
        } else {
            let positions = bytemuck::cast_slice::<f32, u8>(&layout.positions);
            let edges = bytemuck::cast_slice::<[u32; 4], u8>(&layout.edges);
            let ovs = bytemuck::cast_slice::<u32, u8>(&layout.ovs);
            self.check_buffer("the positions", positions.len() as u64, true)?;
            self.check_buffer("the edge records", edges.len() as u64, true)?;
            self.check_buffer("the opposite vertices", ovs.len() as u64, true)?;
            let tris = bytemuck::cast_slice::<[u32; 4], u8>(&triangles.tris);
            let ov_tris = bytemuck::cast_slice::<u32, u8>(&triangles.ov_tris);
            self.check_buffer("the triangles", tris.len() as u64, true)?;
            self.check_buffer("the opposite-vertex triangles", ov_tris.len() as u64, true)?;
            let scope = ErrorScopes::push(&self.device);
            let init = |label: &str, contents: &[u8]| {
                self.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents,
                        usage: wgpu::BufferUsages::STORAGE
                            | wgpu::BufferUsages::COPY_SRC
                            | wgpu::BufferUsages::VERTEX,
                    })
            };
            let buffers = StaticBuffers {
                positions: init("positions", positions),
                edges: init("edges", edges),
                ovs: init("opposite vertices", ovs),
                tris: init("triangles", tris),
                ov_tris: init("opposite-vertex triangles", ov_tris),
            };
            if let Some(e) = scope.pop() {
                return Err(device_error(format!("uploading the scene: {e}")));
            }
            Some(buffers)
        };
        self.check_health()?;
        let id = self.scenes.insert(Prepared {
            scene: scene.clone(),
            layout,
            triangles,
            edge_slots: None,
            gpu,
            frame: None,
            last: None,
            list_prefix: u64::from(self.options.min_list_prefix),
            uncertain_prefix: u64::from(self.options.min_list_prefix),
        });
        Ok(id)
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        self.check_health()?;
        let mut prepared = self.scenes.take(id)?;
        let result = self.extract_prepared(&mut prepared, lights, mode, out);
        self.scenes.restore(id, prepared);
        result
    }

    fn release(&mut self, id: PreparedId) {
        self.scenes.remove(id);
    }
}
