//! Everything that lives on the window's device: the surface, the renderer, the blit of its
//! frame, the volume overlay and the egui renderer; and the window capture.

use crate::controls::VolumeView;
use crate::{ViewError, ViewOptions};
use glam::Vec3;
use shadowvol_renderer::resident::texture_2d;
use shadowvol_renderer::{Camera, Frame, RenderDevice, Renderer, ShadowPipeline};
use std::sync::Arc;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// Everything that lives on the window's device.
pub(crate) struct Gfx {
    /// The renderer, opened on the window's device: it draws straight into `frame_texture`.
    pub(crate) renderer: Renderer,
    pub(crate) window: Arc<Window>,
    pub(crate) surface: wgpu::Surface<'static>,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pub(crate) config: wgpu::SurfaceConfiguration,
    pub(crate) blit: wgpu::RenderPipeline,
    blit_layout: wgpu::BindGroupLayout,
    tri: wgpu::RenderPipeline,
    wire: wgpu::RenderPipeline,
    volume_layout: wgpu::BindGroupLayout,
    /// The frame texture (the renderer's colour target, sampled by the blit), its view and bind
    /// group, remade when the window size changes.
    pub(crate) frame_texture: Option<(wgpu::Texture, wgpu::TextureView, wgpu::BindGroup)>,
    pub(crate) egui_ctx: egui::Context,
    pub(crate) egui_state: egui_winit::State,
    pub(crate) egui: egui_wgpu::Renderer,
}

impl Gfx {
    /// The frame texture of a `w` x `h` window (the renderer's colour target, sampled by the
    /// blit), remade when the size changed.
    pub(crate) fn frame_texture(
        &mut self,
        w: u32,
        h: u32,
    ) -> &(wgpu::Texture, wgpu::TextureView, wgpu::BindGroup) {
        let stale = self
            .frame_texture
            .as_ref()
            .is_none_or(|(t, _, _)| t.width() != w || t.height() != h);
        if stale {
            let texture = texture_2d(
                &self.device,
                "frame",
                w,
                h,
                Renderer::COLOR_FORMAT,
                wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_DST
                    | wgpu::TextureUsages::RENDER_ATTACHMENT,
            );
            let view = texture.create_view(&Default::default());
            let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("frame"),
                layout: &self.blit_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
            self.frame_texture = Some((texture, view, bind_group));
        }
        self.frame_texture.as_ref().expect("made above")
    }

    /// The window's device and surface, the blit, volume and overlay pipelines, and the
    /// renderer on that device (with `options.render`) drawing with the pipeline `pipeline` makes for the device (it
    /// learns there whether the device runs the GPU pipeline).
    pub(crate) fn new(
        window: Arc<Window>,
        options: &ViewOptions,
        el: &ActiveEventLoop,
        pipeline: impl FnOnce(&RenderDevice) -> Result<Box<dyn ShadowPipeline>, ViewError>,
    ) -> Result<Self, ViewError> {
        let (surface, adapter, device, queue) = open_device(&window, el)?;
        let rd = RenderDevice::on_device(adapter.clone(), device.clone(), queue.clone());
        let first = pipeline(&rd)?;
        let renderer = Renderer::new(rd, first, options.render)?;
        let config = surface_config(&surface, &adapter, window.inner_size(), options)?;
        surface.configure(&device, &config);
        let format = config.format;
        let blit_layout = single_binding_layout(
            &device,
            "frame",
            wgpu::ShaderStages::FRAGMENT,
            wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
        );
        let volume_layout = single_binding_layout(
            &device,
            "volumes",
            wgpu::ShaderStages::VERTEX_FRAGMENT,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        );
        let blit = blit_pipeline(&device, &blit_layout, format);
        let [tri, wire] = volume_pipelines(&device, &volume_layout, format);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let egui = egui_wgpu::Renderer::new(&device, format, egui_wgpu::RendererOptions::default());
        Ok(Self {
            renderer,
            window,
            surface,
            device,
            queue,
            config,
            blit,
            blit_layout,
            tri,
            wire,
            volume_layout,
            frame_texture: None,
            egui_ctx,
            egui_state,
            egui,
        })
    }

    /// Reconfigures the surface for a `w` x `h` window (ignored while minimised).
    pub(crate) fn resize(&mut self, w: u32, h: u32) {
        if w > 0 && h > 0 {
            self.config.width = w;
            self.config.height = h;
            self.surface.configure(&self.device, &self.config);
        }
    }
}

/// A surface for `window`, an adapter that presents to it, and a device on that adapter.
fn open_device(
    window: &Arc<Window>,
    el: &ActiveEventLoop,
) -> Result<
    (
        wgpu::Surface<'static>,
        wgpu::Adapter,
        wgpu::Device,
        wgpu::Queue,
    ),
    ViewError,
> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
        Box::new(el.owned_display_handle()),
    ));
    let surface = instance
        .create_surface(Arc::clone(window))
        .map_err(|e| ViewError::Gpu(format!("cannot create a surface for the window: {e}")))?;
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        compatible_surface: Some(&surface),
        ..Default::default()
    }))
    .map_err(|e| ViewError::Gpu(format!("no GPU adapter can present to the window: {e}")))?;
    let (required_features, required_limits) = RenderDevice::requirements(&adapter);
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("shadowvol-viewer"),
        required_features,
        required_limits,
        ..Default::default()
    }))
    .map_err(|e| ViewError::Gpu(format!("device: {e}")))?;
    Ok((surface, adapter, device, queue))
}

/// The surface's configuration: its first non-sRGB format, no vsync for automated frames.
fn surface_config(
    surface: &wgpu::Surface<'_>,
    adapter: &wgpu::Adapter,
    size: winit::dpi::PhysicalSize<u32>,
    options: &ViewOptions,
) -> Result<wgpu::SurfaceConfiguration, ViewError> {
    let caps = surface.get_capabilities(adapter);
    let format = caps
        .formats
        .iter()
        .copied()
        .find(|f| !f.is_srgb())
        .or_else(|| caps.formats.first().copied())
        .ok_or_else(|| ViewError::Gpu("the window surface supports no format".into()))?;
    let present_mode = if options.frames.is_some() {
        wgpu::PresentMode::AutoNoVsync
    } else {
        wgpu::PresentMode::AutoVsync
    };
    Ok(wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        width: size.width.max(1),
        height: size.height.max(1),
        present_mode,
        desired_maximum_frame_latency: 2,
        alpha_mode: caps
            .alpha_modes
            .first()
            .copied()
            .unwrap_or(wgpu::CompositeAlphaMode::Auto),
        view_formats: vec![],
        color_space: wgpu::SurfaceColorSpace::Auto,
    })
}

/// A bind group layout with one binding, 0, of type `ty`, seen by `visibility`.
fn single_binding_layout(
    device: &wgpu::Device,
    label: &str,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BindingType,
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility,
            ty,
            count: None,
        }],
    })
}

/// A pipeline layout of the one bind group layout `bgl`.
fn pipeline_layout(device: &wgpu::Device, bgl: &wgpu::BindGroupLayout) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(bgl)],
        immediate_size: 0,
    })
}

/// The window's colour target in `format`, alpha-blended (the overlays draw over the frame).
fn window_target(format: wgpu::TextureFormat) -> [Option<wgpu::ColorTargetState>; 1] {
    [Some(wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState::ALPHA_BLENDING),
        write_mask: wgpu::ColorWrites::ALL,
    })]
}

/// The pipeline that copies the frame texture (bound through `layout`) onto the window.
fn blit_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let module = crate::shaders::blit_module(device);
    let target = window_target(format);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("blit"),
        layout: Some(&pipeline_layout(device, layout)),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_blit"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_blit"),
            compilation_options: Default::default(),
            targets: &target,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The volume overlay's pipelines, `[triangles, wires]`, over the uniforms of `layout`.
fn volume_pipelines(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    format: wgpu::TextureFormat,
) -> [wgpu::RenderPipeline; 2] {
    let module = crate::shaders::volumes_module(device);
    let target = window_target(format);
    let pipeline_layout = pipeline_layout(device, layout);
    let volume_pipeline = |topology: wgpu::PrimitiveTopology, label: &str| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_volume"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 16,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x4],
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_volume"),
                compilation_options: Default::default(),
                targets: &target,
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    [
        volume_pipeline(wgpu::PrimitiveTopology::TriangleList, "volumes"),
        volume_pipeline(wgpu::PrimitiveTopology::LineList, "volume wires"),
    ]
}

/// A volume overlay draw: pipeline, bind group, vertex buffer, vertex count.
pub(crate) type VolumeDraw = (wgpu::RenderPipeline, wgpu::BindGroup, wgpu::Buffer, u32);

/// The volume overlay's pipeline, bind group, vertex buffer and vertex count, or `None`.
pub(crate) fn volume_draw(
    gfx: &Gfx,
    frame: &Frame,
    view: VolumeView,
    w: u32,
    h: u32,
) -> Option<VolumeDraw> {
    use wgpu::util::DeviceExt;
    if view == VolumeView::Hidden || frame.volumes.is_empty() {
        return None;
    }
    let verts: Vec<[f32; 4]> = match view {
        VolumeView::Wire => frame
            .volumes
            .chunks_exact(3)
            .flat_map(|t| [t[0], t[1], t[1], t[2], t[2], t[0]])
            .collect(),
        _ => frame.volumes.clone(),
    };
    let cam = Camera {
        eye: Vec3::ZERO,
        target: frame.camera.target - frame.camera.eye,
        ..frame.camera
    };
    let mut u = [0f32; 20];
    u[..16].copy_from_slice(&cam.view_proj(w as f32 / h as f32).to_cols_array());
    u[16..].copy_from_slice(&match view {
        VolumeView::Wire => [1.0, 0.85, 0.2, 0.9],
        _ => [1.0, 0.35, 0.1, 0.18],
    });
    let ubuf = gfx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("volume uniforms"),
            contents: bytemuck::cast_slice(&u),
            usage: wgpu::BufferUsages::UNIFORM,
        });
    let bg = gfx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("volumes"),
        layout: &gfx.volume_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: ubuf.as_entire_binding(),
        }],
    });
    let vbuf = gfx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("volume vertices"),
            contents: bytemuck::cast_slice(&verts),
            usage: wgpu::BufferUsages::VERTEX,
        });
    let pipeline = if view == VolumeView::Wire {
        gfx.wire.clone()
    } else {
        gfx.tri.clone()
    };
    Some((pipeline, bg, vbuf, verts.len() as u32))
}

/// Maps a window capture and writes it as an RGBA PNG (BGRA surfaces swizzled).
pub(crate) fn save_capture(
    device: &wgpu::Device,
    buf: &wgpu::Buffer,
    row: u32,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    path: &std::path::Path,
) -> Result<(), ViewError> {
    let slice = buf.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    // Bounded like every GPU wait (SHADOWVOL_GPU_TIMEOUT): a hung device is an error.
    let limit =
        shadowvol_silhouette::gpu::wait_limit().map_err(|e| ViewError::Gpu(e.to_string()))?;
    device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(limit),
        })
        .map_err(|e| ViewError::Gpu(format!("window capture: {e}")))?;
    rx.recv()
        .map_err(|e| ViewError::Gpu(format!("window capture: {e}")))?
        .map_err(|e| ViewError::Gpu(format!("window capture: {e}")))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| ViewError::Gpu(format!("window capture: {e:?}")))?;
    let bgra = matches!(
        format,
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let mut rgba = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h as usize {
        let line = &data[y * row as usize..y * row as usize + 4 * w as usize];
        for p in line.chunks_exact(4) {
            if bgra {
                rgba.extend_from_slice(&[p[2], p[1], p[0], 255]);
            } else {
                rgba.extend_from_slice(&[p[0], p[1], p[2], 255]);
            }
        }
    }
    drop(data);
    buf.unmap();
    image::RgbaImage::from_raw(w, h, rgba)
        .ok_or_else(|| ViewError::Gpu("window capture: size mismatch".into()))?
        .save(path)
        .map_err(|e| ViewError::Options(format!("{}: {e}", path.display())))
}
