//! Starting the backend: the adapter (best first, with what to install when there is none), the
//! device and its limits, the options, and how wgpu errors and device loss become
//! [`BackendError`]s.

use crate::backend::WgpuBackend;
use crate::pipeline::create_pipelines;
use crate::NAME;
use shadowvol_gpu::requirements::SILHOUETTE;
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_silhouette::{BackendError, PreparedScenes};
use std::num::NonZeroUsize;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

/// The error for a wait that failed; a timeout names the limit and how to change it.
pub(crate) fn wait_error(what: &str, e: &wgpu::PollError, limit: Duration) -> BackendError {
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
    /// integer arithmetic, in a dispatch of its own over the undecided pairs (default `true`:
    /// nothing is resolved on the host and
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
    /// Initial capacity of the uncertain-pair list (default 4096); it grows (and the dispatch
    /// is repeated) when a dispatch overflows it. Where it cannot grow enough (the storage
    /// binding limit), exact mode on the device runs `orient_int` inline in the triangle step
    /// from then on for that scene, and the host fallback returns [`BackendError::Limit`].
    pub initial_uncertain_capacity: u32,
    /// Initial entries of each light's compact silhouette list on the device; `None` (the
    /// default) sizes it from the scene: a sixty-fourth of its edges, at least 65,536, at most
    /// the edge count. A list that overflows grows to what it needs (with room for the host's
    /// exact decisions) and the dispatch is repeated, so this only trades memory for the odd
    /// repeated dispatch.
    pub initial_list_capacity: Option<u64>,
    /// Scenes of up to this many triangles also get each OV slot's vertex id on the device (12
    /// bytes a triangle), which `original` reads in one step instead of two (through the OV's
    /// triangle); larger ones leave it out for memory. Default 2^22 (4,194,304); every mode
    /// gives the same results either way.
    pub ov_vertices_up_to: usize,
    /// A cap, in bytes, on every buffer and storage binding, below the device's own limits (a
    /// memory budget; default `None`). Scenes whose static buffers exceed it (or the device's
    /// limits) are prepared in parts that fit ([`SceneParts`](shadowvol_silhouette::SceneParts)),
    /// with the same results; per-frame buffers shrink by running fewer lights per dispatch.
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
            initial_list_capacity: None,
            ov_vertices_up_to: 1 << 22,
            max_buffer_bytes: None,
            max_workgroups_per_dimension: None,
            min_list_prefix: 256,
            exact_on_device: true,
        }
    }
}

/// Errors reported by wgpu outside an error scope, and device loss.
#[derive(Default)]
pub(crate) struct Health {
    pub(crate) errors: Mutex<Vec<String>>,
    pub(crate) lost: Mutex<Option<String>>,
}

pub(crate) fn device_error(message: impl Into<String>) -> BackendError {
    BackendError::Device {
        backend: NAME,
        message: message.into(),
    }
}

pub(crate) fn limit_error(message: String) -> BackendError {
    BackendError::Limit {
        backend: NAME,
        message,
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
        if let Err(reason) = SILHOUETTE.check_limits(&limits) {
            return Err(BackendError::Unavailable {
                backend: NAME,
                reason,
            });
        }
        let filter = ExactFilter::for_device(
            device.features().contains(wgpu::Features::SHADER_F64),
            options.force_f32_filter,
        );
        let adapter = device.adapter_info();
        let pipelines = create_pipelines(&device, filter, options.exact_on_device)?;
        let backend = Self {
            device,
            queue,
            adapter,
            filter,
            options,
            limits,
            pipelines,
            health,
            scenes: PreparedScenes::new(NAME),
        };
        backend.check_health()?;
        Ok(backend)
    }

    pub(crate) fn check_health(&self) -> Result<(), BackendError> {
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
}
