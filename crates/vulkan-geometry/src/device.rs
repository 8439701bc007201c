//! Headless Vulkan set-up: loader, instance (with optional validation), physical device, logical
//! device, one graphics queue, host-visible buffers.

use crate::NAME;
use ash::vk;
use shadowvol_silhouette::gpu::{self, describe_wait_limit, ExactFilter, TIMEOUT_ENV};
use shadowvol_silhouette::BackendError;
use std::ffi::{c_void, CStr, CString};
use std::num::NonZeroUsize;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Environment variable that turns the Khronos validation layer on (`1`).
pub const VALIDATION_ENV: &str = "SHADOWVOL_VULKAN_VALIDATION";

/// Name of the Khronos validation layer.
pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to start the Vulkan backend.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct VulkanOptions {
    /// Enable `VK_LAYER_KHRONOS_validation` and collect its messages (see
    /// [`crate::VulkanBackend::validation_messages`]). Starting fails with
    /// [`BackendError::Unavailable`] when the layer is not installed.
    pub validation: bool,
    /// Use the `f32` exact-mode filter even when the device has `shaderFloat64` (for testing the
    /// fallback path on devices that have f64).
    pub force_f32_filter: bool,
    /// Most lights per geometry-shader pass (default `None`: as many as the device's buffer
    /// limits allow). `extract` splits its lights into batches of at most this many, one pass
    /// each, and assembles one result identical to a single pass; a small value exercises the
    /// splitting on small scenes. The device limits (`maxStorageBufferRange` for the result and
    /// light buffers, `u32` result indices) lower it further.
    pub max_lights_per_batch: Option<NonZeroUsize>,
}

impl VulkanOptions {
    /// Options from the environment: `validation` is on when `SHADOWVOL_VULKAN_VALIDATION=1`.
    #[must_use]
    pub fn from_env() -> Self {
        Self {
            validation: std::env::var(VALIDATION_ENV).is_ok_and(|v| v.trim() == "1"),
            force_f32_filter: false,
            max_lights_per_batch: None,
        }
    }
}

pub(crate) fn unavailable(reason: impl Into<String>) -> BackendError {
    BackendError::Unavailable {
        backend: NAME,
        reason: reason.into(),
    }
}

pub(crate) fn device_err(what: &str, r: vk::Result) -> BackendError {
    BackendError::Device {
        backend: NAME,
        message: format!("{what} failed: {r}"),
    }
}

/// `limit` in nanoseconds for `vkWaitForFences`.
fn nanos(limit: Duration) -> u64 {
    u64::try_from(limit.as_nanos()).unwrap_or(u64::MAX)
}

/// The error for a submission that did not finish within `limit`.
fn timeout_err(limit: Duration) -> BackendError {
    BackendError::Device {
        backend: NAME,
        message: format!(
            "the device did not finish within {}; the work is still pending, so this backend \
             refuses new work until it finishes (raise {TIMEOUT_ENV} for scenes this large \
             on a slow device)",
            describe_wait_limit(limit)
        ),
    }
}

/// No submission is in flight.
const IDLE: u8 = 0;
/// A submission timed out and may still be running: nothing it uses may be touched or freed.
const PENDING: u8 = 1;
/// Dropping gave up waiting for a pending submission: the device's handles are leaked.
const ABANDONED: u8 = 2;

/// Messages collected from the validation layer (warnings and errors).
pub(crate) type MessageLog = Arc<Mutex<Vec<String>>>;

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the layer passes a valid callback-data pointer; `user` is the `Mutex` kept alive by
    // the `Context` that owns the messenger.
    let (message, log) = unsafe {
        let d = &*data;
        let message = if d.p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr(d.p_message).to_string_lossy().into_owned()
        };
        (message, &*(user as *const Mutex<Vec<String>>))
    };
    if let Ok(mut v) = log.lock() {
        v.push(format!("{severity:?}: {message}"));
    }
    vk::FALSE
}

/// What the chosen device can do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Capabilities {
    pub device_name: String,
    pub api_version: u32,
    pub driver: String,
    pub float64: bool,
    pub max_storage_buffer_range: u64,
}

/// A started Vulkan device with one queue.
pub(crate) struct Context {
    /// Keeps the loaded Vulkan library alive as long as the handles made from it.
    entry: ash::Entry,
    pub instance: ash::Instance,
    debug: Option<Messenger>,
    pub messages: MessageLog,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    pub fence: vk::Fence,
    pub memory: vk::PhysicalDeviceMemoryProperties,
    pub caps: Capabilities,
    /// The exact filter the geometry shader runs (its SPIR-V variant).
    pub filter: ExactFilter,
    /// [`IDLE`], [`PENDING`] or [`ABANDONED`].
    state: AtomicU8,
}

fn device_type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// The debug messenger of the validation layer and its loader.
type Messenger = (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT);

/// Loads the Vulkan loader library and checks that it supports Vulkan 1.1.
fn load_entry() -> Result<ash::Entry, BackendError> {
    // SAFETY: loading the system Vulkan loader; its initialisers are trusted like any driver.
    let entry = unsafe { ash::Entry::load() }.map_err(|e| {
        unavailable(format!(
            "no Vulkan loader: {e} (install the Vulkan loader and a driver, for example \
             Debian/Ubuntu: apt-get install libvulkan1 mesa-vulkan-drivers)"
        ))
    })?;
    // SAFETY: plain query on a loaded entry.
    let version = unsafe { entry.try_enumerate_instance_version() }
        .map_err(|e| device_err("vkEnumerateInstanceVersion", e))?
        .unwrap_or(vk::API_VERSION_1_0);
    if version < vk::API_VERSION_1_1 {
        return Err(unavailable(format!(
            "the Vulkan loader supports only Vulkan {}.{}; Vulkan 1.1 or newer is needed",
            vk::api_version_major(version),
            vk::api_version_minor(version)
        )));
    }
    Ok(entry)
}

/// Creates the instance, with the validation layer and `VK_EXT_debug_utils` when `validation`
/// (an error naming the package to install when the layer is missing).
fn create_instance(entry: &ash::Entry, validation: bool) -> Result<ash::Instance, BackendError> {
    let mut layers: Vec<*const i8> = Vec::new();
    let mut extensions: Vec<*const i8> = Vec::new();
    if validation {
        // SAFETY: plain query.
        let available = unsafe { entry.enumerate_instance_layer_properties() }
            .map_err(|e| device_err("vkEnumerateInstanceLayerProperties", e))?;
        let found = available
            .iter()
            .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
        if !found {
            return Err(unavailable(format!(
                "validation was requested ({VALIDATION_ENV}=1) but the layer \
                 VK_LAYER_KHRONOS_validation is not installed (Debian/Ubuntu: apt-get install \
                 vulkan-validationlayers)"
            )));
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let app_name = CString::new("shadowvol").unwrap_or_default();
    let app = vk::ApplicationInfo::default()
        .application_name(&app_name)
        .engine_name(&app_name)
        .api_version(vk::API_VERSION_1_1);
    let create = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    // SAFETY: the create info and everything it points to outlive the call.
    unsafe { entry.create_instance(&create, None) }.map_err(|e| match e {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER | vk::Result::ERROR_INITIALIZATION_FAILED => {
            unavailable(format!(
                "no Vulkan device: the loader found no usable driver ({e}); install one, for \
                 example Mesa's lavapipe: apt-get install mesa-vulkan-drivers"
            ))
        }
        vk::Result::ERROR_LAYER_NOT_PRESENT | vk::Result::ERROR_EXTENSION_NOT_PRESENT => {
            unavailable(format!(
                "the Vulkan instance lacks a requested layer or extension ({e}); validation \
                 needs VK_LAYER_KHRONOS_validation and VK_EXT_debug_utils"
            ))
        }
        e => device_err("vkCreateInstance", e),
    })
}

/// The validation layer's messenger, collecting warnings and errors into `messages`. On failure
/// the instance is destroyed (nothing else was created from it yet).
fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    messages: &MessageLog,
) -> Result<Messenger, BackendError> {
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(Arc::as_ptr(messages) as *mut c_void);
    // SAFETY: `messages` lives as long as the Context, which destroys the messenger first.
    match unsafe { loader.create_debug_utils_messenger(&info, None) } {
        Ok(m) => Ok((loader, m)),
        Err(e) => {
            // SAFETY: nothing else was created from this instance yet.
            unsafe { instance.destroy_instance(None) };
            Err(device_err("vkCreateDebugUtilsMessengerEXT", e))
        }
    }
}

/// The logical device with one queue of `family`, the features the geometry-shader path needs
/// (and `shaderFloat64` for the `f64` filter), and its command pool, command buffer and fence.
/// On failure after the device exists, the device is destroyed.
fn create_device(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    family: u32,
    filter: ExactFilter,
) -> Result<DeviceParts, BackendError> {
    let features = vk::PhysicalDeviceFeatures::default()
        .geometry_shader(true)
        .vertex_pipeline_stores_and_atomics(true)
        .shader_float64(filter == ExactFilter::F64);
    let priorities = [1.0f32];
    let queue_info = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&priorities)];
    let dev_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_info)
        .enabled_features(&features);
    // SAFETY: the physical device comes from this instance; infos outlive the call.
    let device = unsafe { instance.create_device(physical, &dev_info, None) }
        .map_err(|e| device_err("vkCreateDevice", e))?;
    // SAFETY: queue 0 of the family we created.
    let queue = unsafe { device.get_device_queue(family, 0) };
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(family)
        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
    let created = (|| {
        // SAFETY: valid device and infos.
        unsafe {
            let pool = device
                .create_command_pool(&pool_info, None)
                .map_err(|e| device_err("vkCreateCommandPool", e))?;
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let cmd = device
                .allocate_command_buffers(&alloc)
                .map_err(|e| device_err("vkAllocateCommandBuffers", e))?[0];
            let fence = device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .map_err(|e| device_err("vkCreateFence", e))?;
            Ok::<_, BackendError>((pool, cmd, fence))
        }
    })();
    match created {
        Ok((pool, cmd, fence)) => Ok(DeviceParts {
            device,
            queue,
            pool,
            cmd,
            fence,
        }),
        Err(e) => {
            // SAFETY: nothing from the device is in use.
            unsafe { device.destroy_device(None) };
            Err(e)
        }
    }
}

/// What [`create_device`] makes.
struct DeviceParts {
    device: ash::Device,
    queue: vk::Queue,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Context {
    /// Loads the Vulkan library and starts the best device that has what the GS path needs.
    pub fn new(options: VulkanOptions) -> Result<Self, BackendError> {
        let entry = load_entry()?;
        let messages: MessageLog = Arc::new(Mutex::new(Vec::new()));
        let instance = create_instance(&entry, options.validation)?;
        let debug = if options.validation {
            Some(create_messenger(&entry, &instance, &messages)?)
        } else {
            None
        };
        // Destroys the instance (and messenger) on every early return below.
        let mut ctx_partial = Partial {
            instance: Some(instance.clone()),
            debug,
        };
        let (physical, family, caps) = pick_device(&instance)?;
        let filter = ExactFilter::for_device(caps.float64, options.force_f32_filter);
        let parts = create_device(&instance, physical, family, filter)?;
        // SAFETY: plain query.
        let memory = unsafe { instance.get_physical_device_memory_properties(physical) };
        let debug = ctx_partial.debug.take();
        ctx_partial.instance = None;
        Ok(Self {
            entry,
            instance,
            debug,
            messages,
            device: parts.device,
            queue: parts.queue,
            pool: parts.pool,
            cmd: parts.cmd,
            fence: parts.fence,
            memory,
            caps,
            filter,
            state: AtomicU8::new(IDLE),
        })
    }

    /// Index of a memory type allowed by `type_bits` with all of `flags`.
    pub fn memory_type(&self, type_bits: u32, flags: vk::MemoryPropertyFlags) -> Option<u32> {
        (0..self.memory.memory_type_count).find(|&i| {
            type_bits & (1 << i) != 0
                && self.memory.memory_types[i as usize]
                    .property_flags
                    .contains(flags)
        })
    }

    /// True while a submission that timed out may still be running on the device. Nothing it
    /// uses (buffers, images, descriptor sets, the command buffer) may be written or destroyed
    /// then.
    pub fn pending(&self) -> bool {
        self.state.load(Ordering::Acquire) != IDLE
    }

    /// Makes sure no earlier submission is still running. After a timeout the context is
    /// poisoned: this waits for the late submission up to [`wait_limit`](gpu::wait_limit) once more; if its
    /// fence has signalled by then the context recovers (everything the late work touched is
    /// rewritten before the next submission reads it), otherwise this fails.
    ///
    /// Call it before touching any device memory that a submission uses.
    pub fn ensure_idle(&self) -> Result<(), BackendError> {
        if !self.pending() {
            return Ok(());
        }
        let limit = gpu::wait_limit()?;
        // SAFETY: the fence is ours and was submitted (the state says so).
        match unsafe {
            self.device
                .wait_for_fences(&[self.fence], true, nanos(limit))
        } {
            Ok(()) => {
                self.state.store(IDLE, Ordering::Release);
                Ok(())
            }
            Err(vk::Result::TIMEOUT) => Err(BackendError::Device {
                backend: NAME,
                message: format!(
                    "an earlier submission that timed out is still running on the device (it \
                     has not finished within another {}); this backend cannot run anything until \
                     it does: retry later, or drop the backend and start a new one",
                    describe_wait_limit(limit)
                ),
            }),
            Err(e) => Err(device_err(
                "vkWaitForFences (for an earlier submission that timed out)",
                e,
            )),
        }
    }

    /// Records with `record`, submits, and waits for completion, at most [`wait_limit`](gpu::wait_limit).
    ///
    /// On a timeout the context becomes pending (see [`Context::ensure_idle`]) and the error is
    /// a [`BackendError::Device`] naming the limit and `SHADOWVOL_GPU_TIMEOUT`.
    pub fn submit_and_wait(
        &self,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<(), BackendError> {
        self.ensure_idle()?;
        let limit = gpu::wait_limit()?;
        let d = &self.device;
        // SAFETY: the command buffer is idle (`ensure_idle` saw its last submission finish), from
        // our pool.
        unsafe {
            d.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
                .map_err(|e| device_err("vkResetCommandBuffer", e))?;
            d.begin_command_buffer(
                self.cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .map_err(|e| device_err("vkBeginCommandBuffer", e))?;
            record(d, self.cmd);
            d.end_command_buffer(self.cmd)
                .map_err(|e| device_err("vkEndCommandBuffer", e))?;
            let cmds = [self.cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            d.reset_fences(&[self.fence])
                .map_err(|e| device_err("vkResetFences", e))?;
            d.queue_submit(self.queue, &submit, self.fence)
                .map_err(|e| device_err("vkQueueSubmit", e))?;
            self.state.store(PENDING, Ordering::Release);
            match d.wait_for_fences(&[self.fence], true, nanos(limit)) {
                Ok(()) => self.state.store(IDLE, Ordering::Release),
                Err(vk::Result::TIMEOUT) => return Err(timeout_err(limit)),
                // Device lost or out of memory: the state stays pending, so nothing the
                // submission used is freed while the driver may still hold it.
                Err(e) => return Err(device_err("vkWaitForFences", e)),
            }
        }
        Ok(())
    }

    /// Before destroying anything: true when no submission is running, waiting for a pending
    /// one at most [`wait_limit`](gpu::wait_limit) (the default limit when `SHADOWVOL_GPU_TIMEOUT` is
    /// invalid). False when the work is still running; the context is then abandoned (its
    /// handles will be leaked) and later calls return false at once.
    pub fn idle_for_destruction(&self) -> bool {
        match self.state.load(Ordering::Acquire) {
            IDLE => return true,
            ABANDONED => return false,
            _ => {}
        }
        let limit = gpu::wait_limit().unwrap_or(gpu::DEFAULT_TIMEOUT);
        // SAFETY: the fence is ours and was submitted.
        if unsafe {
            self.device
                .wait_for_fences(&[self.fence], true, nanos(limit))
        }
        .is_ok()
        {
            self.state.store(IDLE, Ordering::Release);
            true
        } else {
            self.state.store(ABANDONED, Ordering::Release);
            eprintln!(
                "shadowvol vulkan backend: a submission is still running on the device after \
                 {} s ({TIMEOUT_ENV}); leaking the device instead of destroying it under \
                 the running work",
                limit.as_secs_f64()
            );
            false
        }
    }

    /// Validation messages collected so far.
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|v| v.clone()).unwrap_or_default()
    }

    /// True when the validation layer is active.
    pub fn validation(&self) -> bool {
        self.debug.is_some()
    }
}

/// Cleans up a half-built instance on early return.
struct Partial {
    instance: Option<ash::Instance>,
    debug: Option<Messenger>,
}

impl Drop for Partial {
    fn drop(&mut self) {
        if let Some(instance) = self.instance.take() {
            // SAFETY: nothing created from it survives (the device, if any, was destroyed).
            unsafe {
                if let Some((loader, m)) = self.debug.take() {
                    loader.destroy_debug_utils_messenger(m, None);
                }
                instance.destroy_instance(None);
            }
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        if !self.idle_for_destruction() {
            // A submission is still running (it outlived the wait limit twice, or the device was
            // lost). Destroying the fence, pool, device or instance under it is undefined
            // behaviour (drivers free memory the work still writes to), and waiting longer is a
            // hang, so every handle is leaked instead: the instance, device and debug messenger
            // stay alive, and so do the loader library (the driver's threads run its code) and
            // the message log (the messenger's callback points at it).
            std::mem::forget(self.entry.clone());
            std::mem::forget(Arc::clone(&self.messages));
            return;
        }
        // SAFETY: we own every handle; every submission has finished (all go through our one
        // fence and `idle_for_destruction` saw it signalled or none was pending).
        unsafe {
            self.device.destroy_fence(self.fence, None);
            self.device.destroy_command_pool(self.pool, None);
            self.device.destroy_device(None);
            if let Some((loader, m)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// Chooses the device: Vulkan 1.1+, a graphics queue, geometryShader and
/// vertexPipelineStoresAndAtomics; discrete before integrated before CPU.
fn pick_device(
    instance: &ash::Instance,
) -> Result<(vk::PhysicalDevice, u32, Capabilities), BackendError> {
    // SAFETY: plain queries on a valid instance.
    let devices = unsafe { instance.enumerate_physical_devices() }
        .map_err(|e| device_err("vkEnumeratePhysicalDevices", e))?;
    if devices.is_empty() {
        return Err(unavailable(
            "no Vulkan device: the loader found no driver (install one, for example Mesa's \
             lavapipe: apt-get install mesa-vulkan-drivers)",
        ));
    }
    let mut rejected = Vec::new();
    let mut best: Option<(u32, vk::PhysicalDevice, u32, Capabilities)> = None;
    for pd in devices {
        // SAFETY: `pd` comes from this instance.
        let (props, features, families) = unsafe {
            (
                instance.get_physical_device_properties(pd),
                instance.get_physical_device_features(pd),
                instance.get_physical_device_queue_family_properties(pd),
            )
        };
        let name = props
            .device_name_as_c_str()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|_| "unnamed device".to_owned());
        let mut missing = Vec::new();
        if props.api_version < vk::API_VERSION_1_1 {
            missing.push("Vulkan 1.1".to_owned());
        }
        if features.geometry_shader == vk::FALSE {
            missing.push("the geometryShader feature".to_owned());
        }
        if features.vertex_pipeline_stores_and_atomics == vk::FALSE {
            missing.push("the vertexPipelineStoresAndAtomics feature".to_owned());
        }
        let family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS));
        if family.is_none() {
            missing.push("a graphics queue".to_owned());
        }
        if !missing.is_empty() {
            rejected.push(format!("{name}: no {}", missing.join(", no ")));
            continue;
        }
        let rank = device_type_rank(props.device_type);
        let caps = Capabilities {
            driver: format!(
                "Vulkan {}.{}.{}, driver version {:#x}",
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version),
                vk::api_version_patch(props.api_version),
                props.driver_version
            ),
            device_name: name,
            api_version: props.api_version,
            float64: features.shader_float64 == vk::TRUE,
            max_storage_buffer_range: u64::from(props.limits.max_storage_buffer_range),
        };
        let family = family.unwrap_or(0) as u32;
        if best.as_ref().is_none_or(|b| rank < b.0) {
            best = Some((rank, pd, family, caps));
        }
    }
    best.map(|(_, pd, f, c)| (pd, f, c)).ok_or_else(|| {
        unavailable(format!(
            "no Vulkan device has what the geometry-shader path needs: {}",
            rejected.join("; ")
        ))
    })
}

/// A host-visible, persistently mapped storage buffer.
pub(crate) struct Buffer {
    pub buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    ptr: *mut u8,
    /// Size in bytes.
    pub size: u64,
}

impl Buffer {
    /// Creates a buffer of at least `size` bytes (16 at least) that the device reads and the host
    /// writes: device-local host-visible memory where there is some (resizable BAR), else any
    /// host-visible coherent memory.
    pub fn new(
        ctx: &Context,
        size: u64,
        usage: vk::BufferUsageFlags,
    ) -> Result<Self, BackendError> {
        Self::create(ctx, size, usage, false)
    }

    /// Creates a buffer the host reads back: host-cached coherent memory where there is some
    /// (reading device-local memory through the BAR is uncached and very slow), else any
    /// host-visible coherent memory.
    pub fn host_read(
        ctx: &Context,
        size: u64,
        usage: vk::BufferUsageFlags,
    ) -> Result<Self, BackendError> {
        Self::create(ctx, size, usage, true)
    }

    fn create(
        ctx: &Context,
        size: u64,
        usage: vk::BufferUsageFlags,
        host_read: bool,
    ) -> Result<Self, BackendError> {
        let size = size.max(16).next_multiple_of(16);
        let d = &ctx.device;
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info; every object is destroyed on the error paths.
        unsafe {
            let buffer = d
                .create_buffer(&info, None)
                .map_err(|e| device_err("vkCreateBuffer", e))?;
            let req = d.get_buffer_memory_requirements(buffer);
            let host =
                vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let preferred = if host_read {
                host | vk::MemoryPropertyFlags::HOST_CACHED
            } else {
                host | vk::MemoryPropertyFlags::DEVICE_LOCAL
            };
            let Some(ty) = ctx
                .memory_type(req.memory_type_bits, preferred)
                .or_else(|| ctx.memory_type(req.memory_type_bits, host))
            else {
                d.destroy_buffer(buffer, None);
                return Err(unavailable(
                    "the device has no host-visible, host-coherent memory type for storage buffers",
                ));
            };
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(ty);
            let memory = match d.allocate_memory(&alloc, None) {
                Ok(m) => m,
                Err(e) => {
                    d.destroy_buffer(buffer, None);
                    return Err(BackendError::Limit {
                        backend: NAME,
                        message: format!("cannot allocate a buffer of {size} bytes: {e}"),
                    });
                }
            };
            let bound = d.bind_buffer_memory(buffer, memory, 0);
            let mapped = bound.and_then(|()| {
                d.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())
            });
            match mapped {
                Ok(ptr) => Ok(Self {
                    buffer,
                    memory,
                    ptr: ptr.cast(),
                    size,
                }),
                Err(e) => {
                    d.destroy_buffer(buffer, None);
                    d.free_memory(memory, None);
                    Err(device_err("binding or mapping buffer memory", e))
                }
            }
        }
    }

    /// A storage buffer holding `data`.
    pub fn with_data<T: bytemuck::Pod>(ctx: &Context, data: &[T]) -> Result<Self, BackendError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let b = Self::new(
            ctx,
            bytes.len() as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        b.write(0, bytes);
        Ok(b)
    }

    /// Copies `bytes` into the buffer at `offset`.
    ///
    /// # Panics
    /// If the range exceeds the buffer.
    pub fn write(&self, offset: usize, bytes: &[u8]) {
        assert!(
            offset + bytes.len() <= self.size as usize,
            "buffer write out of range"
        );
        // SAFETY: the mapping covers `size` bytes; the range was checked; the device is idle
        // whenever the host touches a buffer (we wait for every submission).
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), self.ptr.add(offset), bytes.len());
        }
    }

    /// Copies bytes out of the buffer from `offset` into `out`.
    ///
    /// # Panics
    /// If the range exceeds the buffer.
    pub fn read(&self, offset: usize, out: &mut [u8]) {
        assert!(
            offset + out.len() <= self.size as usize,
            "buffer read out of range"
        );
        // SAFETY: as in `write`.
        unsafe {
            std::ptr::copy_nonoverlapping(self.ptr.add(offset), out.as_mut_ptr(), out.len());
        }
    }

    /// Destroys the buffer and frees its memory.
    pub fn destroy(self, ctx: &Context) {
        // SAFETY: the device is idle whenever buffers are destroyed (we wait for every submit).
        unsafe {
            ctx.device.unmap_memory(self.memory);
            ctx.device.destroy_buffer(self.buffer, None);
            ctx.device.free_memory(self.memory, None);
        }
    }
}
