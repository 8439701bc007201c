//! The device every pipeline records on: a wgpu device, its queue and adapter, and what it can
//! do (depth clamp, the depth-stencil format, whether the GPU pipeline runs).

use crate::RenderError;
use shadowvol_gpu::requirements::{self, RESIDENT};
use shadowvol_gpu::ErrorScopes;

/// A wgpu device with what the renderer needs to know about it. Open one with
/// [`RenderDevice::open`], or wrap the caller's with [`RenderDevice::on_device`] (a window's
/// device, an engine's), opened with [`RenderDevice::requirements`].
#[derive(Debug, Clone)]
pub struct RenderDevice {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter it was opened on.
    pub adapter: wgpu::Adapter,
    /// The adapter in words: name, backend, driver.
    pub description: String,
    /// The depth-stencil format of the frames (32-bit float depth where the device has it).
    pub depth_format: wgpu::TextureFormat,
    /// True when shadow volumes are drawn with `unclipped_depth` (depth clamp).
    pub depth_clamp: bool,
    /// Why the GPU pipeline cannot run on this device (a missing capability or limit, named),
    /// or `None` when it can.
    pub gpu_pipeline_unsupported: Option<String>,
    /// True when the device copies a stencil aspect to a buffer (wgpu's
    /// `DEPTH_TEXTURE_AND_BUFFER_COPIES`; OpenGL cannot). Where it cannot, a frame read back
    /// copies each light's stencil through an 8-bit colour target, one draw per bit: the same
    /// bytes, eight full-screen draws a light more.
    pub stencil_copies: bool,
}

impl RenderDevice {
    /// Opens the first adapter wgpu finds (any backend; `WGPU_BACKEND` and the other `WGPU_*`
    /// variables are honoured) with [`RenderDevice::requirements`]. No display is needed: the
    /// instance is created without a display handle.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when there is no adapter (naming the driver to install),
    /// [`RenderError::Device`] when the device cannot be opened.
    pub fn open() -> Result<Self, RenderError> {
        Self::on_adapter(Self::headless_adapter()?)
    }

    /// Opens the first adapter of `backends` (only those; the `WGPU_*` variables are not read),
    /// as [`RenderDevice::open`] does: `wgpu::Backends::GL` for OpenGL's, for example.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when none of `backends` has an adapter here,
    /// [`RenderError::Device`] when the device cannot be opened.
    pub fn open_with(backends: wgpu::Backends) -> Result<Self, RenderError> {
        let adapter = request_adapter(backends, false)
            .map_err(|e| RenderError::NoAdapter(format!("{e} (backends {backends:?})")))?;
        Self::on_adapter(adapter)
    }

    /// Opens a device on `adapter` with [`RenderDevice::requirements`].
    fn on_adapter(adapter: wgpu::Adapter) -> Result<Self, RenderError> {
        let info = adapter.get_info();
        let (features, limits) = Self::requirements(&adapter);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadowvol-renderer"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(format!("request_device on {}: {e}", info.name)))?;
        Ok(Self::on_device(adapter, device, queue))
    }

    /// The adapter a headless renderer opens: the primary backends (Vulkan, Metal, DX12) first,
    /// and only when none has an adapter, every backend (OpenGL too). Probing OpenGL's EGL on a
    /// machine without a display makes the Wayland client library print an `error:` line
    /// although nothing failed, so it is probed last. `WGPU_BACKEND` overrides both.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] naming the driver to install.
    pub fn headless_adapter() -> Result<wgpu::Adapter, RenderError> {
        request_adapter(wgpu::Backends::PRIMARY, true)
            .or_else(|_| request_adapter(wgpu::Backends::all(), true))
            .map_err(|e| {
                RenderError::NoAdapter(format!(
                    "{e}; install a Vulkan driver (for example Mesa's lavapipe, package mesa-vulkan-drivers)"
                ))
            })
    }

    /// The features and limits to open a device on `adapter` with, for every pipeline the
    /// adapter can run: depth clamp and a 32-bit float depth where it has them, and the GPU
    /// pipeline's limits and features where it has those (otherwise downlevel defaults, and
    /// only the host pipeline runs).
    #[must_use]
    pub fn requirements(adapter: &wgpu::Adapter) -> (wgpu::Features, wgpu::Limits) {
        let features = adapter.features();
        let mut required = wgpu::Features::empty();
        for f in [
            wgpu::Features::DEPTH_CLIP_CONTROL,
            wgpu::Features::DEPTH32FLOAT_STENCIL8,
        ] {
            if features.contains(f) {
                required |= f;
            }
        }
        required |= requirements::optional_features(adapter);
        let limits = RESIDENT.limits(adapter, buffer_cap()).unwrap_or_else(|_| {
            let mut l = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
            l.max_buffer_size = l.max_buffer_size.min(buffer_cap().unwrap_or(u64::MAX));
            l
        });
        (required, limits)
    }

    /// Wraps a device the caller opened on `adapter` (for example the device of a window, whose
    /// surface then shows frames drawn by [`crate::Renderer::render_into`] without a copy
    /// through the host). Open it with [`RenderDevice::requirements`] to get every pipeline the
    /// adapter can run; depth clamp and the 32-bit float depth are used when the device has
    /// them, and the GPU pipeline runs when the device's limits allow it.
    #[must_use]
    pub fn on_device(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let info = adapter.get_info();
        let features = device.features();
        let depth_clamp = features.contains(wgpu::Features::DEPTH_CLIP_CONTROL);
        let depth_format = if features.contains(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
            wgpu::TextureFormat::Depth32FloatStencil8
        } else {
            wgpu::TextureFormat::Depth24PlusStencil8
        };
        let stencil_copies = adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
        let unsupported = RESIDENT.limits(&adapter, buffer_cap()).and_then(|l| {
            if l.check_limits(&device.limits()) {
                Ok(())
            } else {
                Err(
                    "the device was opened with lower limits than the GPU pipeline needs \
                     (open it with RenderDevice::requirements)"
                        .to_owned(),
                )
            }
        });
        Self {
            description: format!("{} ({:?}, {})", info.name, info.backend, info.driver_info),
            device,
            queue,
            adapter,
            depth_format,
            depth_clamp,
            gpu_pipeline_unsupported: unsupported.err(),
            stencil_copies,
        }
    }

    /// [`RenderError::InvalidInput`] unless both sides of a `w` x `h` image are in
    /// `1..=max_texture_dimension_2d`.
    ///
    /// # Errors
    /// As above, naming the size and the limit.
    pub fn check_size(&self, w: u32, h: u32) -> Result<(), RenderError> {
        let max = self.device.limits().max_texture_dimension_2d;
        if w == 0 || h == 0 || w > max || h > max {
            return Err(RenderError::InvalidInput(format!(
                "image size {w}x{h}: each side must be in 1..={max}"
            )));
        }
        Ok(())
    }

    /// Runs `record` on a new encoder, submits it, and turns validation, internal and
    /// out-of-memory errors raised meanwhile into [`RenderError::Device`].
    ///
    /// # Errors
    /// `record`'s own error, or [`RenderError::Device`] naming the device error.
    pub fn submit(
        &self,
        label: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<(), RenderError>,
    ) -> Result<(), RenderError> {
        let scope = ErrorScopes::push(&self.device);
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        let recorded = record(&mut enc);
        self.queue.submit([enc.finish()]);
        let errors = scope.pop();
        recorded?;
        match errors {
            Some(e) => Err(RenderError::Device(e)),
            None => Ok(()),
        }
    }
}

/// The first adapter of `backends` (high performance preferred), on an instance without a
/// display handle; with `env`, the `WGPU_*` variables may override `backends`.
fn request_adapter(
    backends: wgpu::Backends,
    env: bool,
) -> Result<wgpu::Adapter, wgpu::RequestAdapterError> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    let instance = wgpu::Instance::new(if env { desc.with_env() } else { desc });
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: None,
        apply_limit_buckets: false,
    }))
}

/// Environment variable that caps, in bytes, every buffer and storage binding the renderer asks
/// a device for ([`RenderDevice::requirements`]): a memory budget, and the way to see on a
/// small scene what a device with smaller limits does with a large one (the GPU pipeline
/// refuses a scene beyond one binding with [`RenderError::TooLarge`]; the host pipeline draws
/// from several buffers).
pub const BUFFER_CAP_ENV: &str = "SHADOWVOL_MAX_BUFFER_BYTES";

/// The cap of [`BUFFER_CAP_ENV`], if it is set to a number of bytes.
#[must_use]
pub fn buffer_cap() -> Option<u64> {
    std::env::var(BUFFER_CAP_ENV).ok()?.trim().parse().ok()
}
