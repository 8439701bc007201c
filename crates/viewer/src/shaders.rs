//! The viewer's WGSL sources, from the workspace's `shaders/` folder. Each file is a module of
//! its own (nothing is appended to it).

/// `shaders/viewer_blit.wgsl`: the rendered frame copied onto the window's surface.
pub const BLIT_WGSL: &str = include_str!("../../../shaders/viewer_blit.wgsl");

/// `shaders/viewer_volumes.wgsl`: the shadow volumes drawn over the frame for inspection.
pub const VOLUMES_WGSL: &str = include_str!("../../../shaders/viewer_volumes.wgsl");

/// The shader module of [`BLIT_WGSL`].
pub(crate) fn blit_module(device: &wgpu::Device) -> wgpu::ShaderModule {
    module(device, "shaders/viewer_blit.wgsl", BLIT_WGSL)
}

/// The shader module of [`VOLUMES_WGSL`].
pub(crate) fn volumes_module(device: &wgpu::Device) -> wgpu::ShaderModule {
    module(device, "shaders/viewer_volumes.wgsl", VOLUMES_WGSL)
}

fn module(device: &wgpu::Device, label: &str, source: &'static str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
