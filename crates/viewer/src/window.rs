//! The window: winit events, a wgpu surface, the renderer on the window's device, its frame
//! sampled onto the surface, the volumes and the egui overlay on top.

use crate::controls::{self, Orbit, VolumeView};
use crate::{ViewError, ViewOptions, ViewReport};
use glam::Vec3;
use shadowvol_renderer::resident::texture_2d;
use shadowvol_renderer::{
    Camera, Frame, Pipeline, PlanPolicy, RenderOptions, RenderScene, Renderer, Technique,
};
use shadowvol_silhouette::SilhouetteBackend;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// The state of a running viewer.
pub(crate) struct App {
    scene: RenderScene,
    /// The backend and options the renderer is opened with once the window's device exists.
    pending: Option<(Box<dyn SilhouetteBackend>, RenderOptions)>,
    options: ViewOptions,
    orbit: Orbit,
    centre: Vec3,
    policy: PlanPolicy,
    volumes: VolumeView,
    gfx: Option<Gfx>,
    drag: Drag,
    frame_ms: Vec<f64>,
    started: Option<Instant>,
    last: Option<Frame>,
    pub(crate) error: Option<ViewError>,
    pub(crate) report: Option<ViewReport>,
}

#[derive(Default)]
struct Drag {
    cursor: Option<(f32, f32)>,
    left: bool,
    right: bool,
    shift: bool,
}

/// Everything that lives on the window's device.
struct Gfx {
    /// The renderer, opened on the window's device: in the GPU pipeline it draws straight into
    /// `frame_texture`.
    renderer: Renderer,
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    blit: wgpu::RenderPipeline,
    blit_layout: wgpu::BindGroupLayout,
    tri: wgpu::RenderPipeline,
    wire: wgpu::RenderPipeline,
    volume_layout: wgpu::BindGroupLayout,
    /// The frame texture (the renderer's colour target, sampled by the blit), its view and bind
    /// group, remade when the window size changes.
    frame_texture: Option<(wgpu::Texture, wgpu::TextureView, wgpu::BindGroup)>,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui: egui_wgpu::Renderer,
}

impl App {
    pub(crate) fn new(
        scene: RenderScene,
        backend: Box<dyn SilhouetteBackend>,
        render_options: RenderOptions,
        options: ViewOptions,
    ) -> Self {
        let orbit = Orbit::from_camera(&scene.camera);
        let centre = scene
            .bounds()
            .map_or(scene.camera.target, |(lo, hi)| (lo + hi) * 0.5);
        let policy = render_options.policy;
        let volumes = options.volumes;
        Self {
            scene,
            pending: Some((backend, render_options)),
            options,
            orbit,
            centre,
            policy,
            volumes,
            gfx: None,
            drag: Drag::default(),
            frame_ms: Vec::new(),
            started: None,
            last: None,
            error: None,
            report: None,
        }
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: ViewError) {
        self.error = Some(e);
        el.exit();
    }

    fn frame(&mut self, el: &ActiveEventLoop) -> Result<(), ViewError> {
        let t0 = Instant::now();
        let Some(gfx) = self.gfx.as_mut() else {
            return Ok(());
        };
        let (w, h) = (gfx.config.width, gfx.config.height);
        self.scene.camera = self.orbit.camera();
        let mut opts: RenderOptions = gfx.renderer.options();
        opts.width = w;
        opts.height = h;
        opts.mode = self.options.mode;
        opts.policy = self.policy;
        opts.keep_volumes = self.volumes != VolumeView::Hidden;
        // Only the host pipeline keeps the volume geometry the overlay draws.
        opts.pipeline = if opts.keep_volumes {
            Pipeline::Host
        } else {
            self.options.pipeline
        };
        gfx.renderer.set_options(opts);
        let last = self
            .options
            .frames
            .is_some_and(|n| self.frame_ms.len() + 1 >= n as usize);

        let stale = gfx
            .frame_texture
            .as_ref()
            .is_none_or(|(t, _, _)| t.width() != w || t.height() != h);
        if stale {
            let texture = texture_2d(
                &gfx.device,
                "frame",
                w,
                h,
                Renderer::COLOR_FORMAT,
                wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_DST
                    | wgpu::TextureUsages::RENDER_ATTACHMENT,
            );
            let view = texture.create_view(&Default::default());
            let bind_group = gfx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("frame"),
                layout: &gfx.blit_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
            gfx.frame_texture = Some((texture, view, bind_group));
        }
        let (texture, frame_view, blit_bg) = gfx.frame_texture.as_ref().expect("created above");
        // The GPU pipeline draws into the frame texture on this device; the host pipeline (and
        // the last automated frame, whose image is the screenshot) reads its image back, which
        // is then uploaded.
        let frame =
            if opts.pipeline == Pipeline::Gpu && !(last && self.options.screenshot.is_some()) {
                gfx.renderer.render_into(&self.scene, frame_view)?
            } else {
                let frame = gfx.renderer.render(&self.scene)?;
                gfx.queue.write_texture(
                    texture.as_image_copy(),
                    &frame.rgba,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * w),
                        rows_per_image: Some(h),
                    },
                    texture.size(),
                );
                frame
            };
        let volumes = volume_draw(gfx, &frame, self.volumes, w, h);

        let surface_texture = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gfx.surface.configure(&gfx.device, &gfx.config);
                return Ok(());
            }
            other => return Err(ViewError::Gpu(format!("window surface: {other:?}"))),
        };
        let target = surface_texture.texture.create_view(&Default::default());

        let raw = gfx.egui_state.take_egui_input(&gfx.window);
        let stats = Stats::of(&frame, &self.frame_ms, self.policy, self.volumes);
        let mut out = gfx.egui_ctx.run_ui(raw, |ui| stats.show(ui));
        let mut textures = std::mem::take(&mut out.textures_delta);
        gfx.egui_state
            .handle_platform_output(&gfx.window, out.platform_output);
        let jobs = gfx.egui_ctx.tessellate(out.shapes, out.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [w, h],
            pixels_per_point: out.pixels_per_point,
        };
        for (id, deltas) in textures.set.drain() {
            for delta in &deltas {
                gfx.egui.update_texture(&gfx.device, &gfx.queue, id, delta);
            }
        }
        let mut enc = gfx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view"),
            });
        let extra = gfx
            .egui
            .update_buffers(&gfx.device, &gfx.queue, &mut enc, &jobs, &screen);
        let capture = match (&self.options.window_screenshot, last) {
            (Some(_), true) => Some(texture_2d(
                &gfx.device,
                "window capture",
                w,
                h,
                gfx.config.format,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            )),
            _ => None,
        };
        let capture_view = capture.as_ref().map(|t| t.create_view(&Default::default()));
        for view in std::iter::once(&target).chain(capture_view.as_ref()) {
            let mut pass = enc
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("view"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            pass.set_pipeline(&gfx.blit);
            pass.set_bind_group(0, blit_bg, &[]);
            pass.draw(0..3, 0..1);
            if let Some((pipeline, bg, buf, n)) = &volumes {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bg, &[]);
                pass.set_vertex_buffer(0, buf.slice(..));
                pass.draw(0..*n, 0..1);
            }
            gfx.egui.render(&mut pass, &jobs, &screen);
        }
        let readback = capture.as_ref().map(|t| {
            let row = (4 * w).div_ceil(256) * 256;
            let buf = gfx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("window capture readback"),
                size: u64::from(row) * u64::from(h),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            enc.copy_texture_to_buffer(
                t.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &buf,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: Some(h),
                    },
                },
                t.size(),
            );
            (buf, row)
        });
        gfx.queue
            .submit(extra.into_iter().chain(std::iter::once(enc.finish())));
        gfx.queue.present(surface_texture);
        if let (Some((buf, row)), Some(path)) = (readback, &self.options.window_screenshot) {
            save_capture(&gfx.device, &buf, row, w, h, gfx.config.format, path)?;
        }
        for id in textures.free.drain() {
            gfx.egui.free_texture(&id);
        }

        let ms = t0.elapsed().as_secs_f64() * 1e3;
        self.frame_ms.push(ms);
        self.last = Some(frame);
        if let Some(n) = self.options.frames {
            if self.frame_ms.len() >= n as usize {
                self.finish()?;
                el.exit();
                return Ok(());
            }
        }
        gfx.window.request_redraw();
        Ok(())
    }

    /// Writes the screenshot and the report after the last automated frame.
    fn finish(&mut self) -> Result<(), ViewError> {
        let Some(gfx) = self.gfx.as_ref() else {
            return Ok(());
        };
        let total = self
            .started
            .map_or(Duration::ZERO, |t| t.elapsed())
            .as_secs_f64();
        let screenshot = match (&self.options.screenshot, &self.last) {
            (Some(path), Some(frame)) => {
                frame.save_png(path)?;
                Some(path.display().to_string())
            }
            _ => None,
        };
        let mut sorted = self.frame_ms.clone();
        sorted.sort_by(f64::total_cmp);
        let frames = sorted.len();
        self.report = Some(ViewReport {
            frames: frames as u32,
            fps: if total > 0.0 {
                frames as f64 / total
            } else {
                0.0
            },
            median_ms: sorted.get(frames / 2).copied().unwrap_or(0.0),
            adapter: gfx.renderer.adapter().to_owned(),
            screenshot,
            pipeline: gfx.renderer.options().pipeline,
        });
        Ok(())
    }

    fn key(&mut self, key: &Key, el: &ActiveEventLoop) {
        let step = 5f32.to_radians();
        let light = |app: &mut Self, yaw: f32, pitch: f32| {
            if let Some(l) = app.scene.lights.first_mut() {
                *l = controls::orbit_light(*l, app.centre, yaw, pitch);
            }
        };
        match key {
            Key::Named(NamedKey::Escape) => el.exit(),
            Key::Named(NamedKey::ArrowLeft) => light(self, -step, 0.0),
            Key::Named(NamedKey::ArrowRight) => light(self, step, 0.0),
            Key::Named(NamedKey::ArrowUp) => light(self, 0.0, step),
            Key::Named(NamedKey::ArrowDown) => light(self, 0.0, -step),
            Key::Character(c) => match c.as_str() {
                "q" | "Q" => el.exit(),
                "t" | "T" => self.policy = controls::next_policy(self.policy),
                "v" | "V" => self.volumes = self.volumes.next(),
                s => {
                    if let Some(m) = s.parse::<u8>().ok().and_then(controls::mode_of_key) {
                        self.options.mode = m;
                    }
                }
            },
            _ => {}
        }
    }
}

/// What the overlay shows.
struct Stats {
    fps: f64,
    frame_ms: f64,
    mode: String,
    adapter: String,
    edges: usize,
    uncertain: u64,
    host_resolved: u64,
    pipeline: Pipeline,
    policy: PlanPolicy,
    volumes: VolumeView,
    techniques: Vec<String>,
}

impl Stats {
    fn of(frame: &Frame, times: &[f64], policy: PlanPolicy, volumes: VolumeView) -> Self {
        let recent = &times[times.len().saturating_sub(30)..];
        let mean = if recent.is_empty() {
            0.0
        } else {
            recent.iter().sum::<f64>() / recent.len() as f64
        };
        Self {
            fps: if mean > 0.0 { 1e3 / mean } else { 0.0 },
            frame_ms: mean,
            mode: frame.mode.to_string(),
            adapter: frame.adapter.clone(),
            edges: frame.plan.iter().map(|e| e.silhouette_edges).sum(),
            uncertain: frame.uncertain,
            host_resolved: frame.host_resolved,
            pipeline: frame.pipeline,
            policy,
            volumes,
            techniques: frame
                .plan
                .iter()
                .filter(|e| e.reason != "receiver only: casts no shadow")
                .map(|e| {
                    let t = match e.technique {
                        Technique::Culled => "culled",
                        Technique::ZPass => "z-pass",
                        Technique::ZFail => "z-fail",
                    };
                    format!("light {} · {}: {t}", e.light, e.object_name)
                })
                .collect(),
        }
    }

    fn show(&self, ui: &mut egui::Ui) {
        egui::Window::new("shadowvol")
            .default_pos([6.0, 6.0])
            .resizable(false)
            .collapsible(true)
            .show(ui.ctx(), |ui| {
                let line = |ui: &mut egui::Ui, t: String| {
                    ui.label(egui::RichText::new(t).small());
                };
                line(
                    ui,
                    format!("{:.1} fps · {:.2} ms/frame", self.fps, self.frame_ms),
                );
                line(
                    ui,
                    format!(
                        "mode {} (1-4) · technique {} (T) · volumes {} (V)",
                        self.mode,
                        controls::policy_name(self.policy),
                        self.volumes.name()
                    ),
                );
                line(
                    ui,
                    format!(
                        "silhouette edges {} · uncertain pairs {} · host-resolved {} · {} pipeline",
                        self.edges,
                        self.uncertain,
                        self.host_resolved,
                        self.pipeline.name()
                    ),
                );
                for t in self.techniques.iter().take(6) {
                    line(ui, t.clone());
                }
                if self.techniques.len() > 6 {
                    line(ui, format!("… {} more", self.techniques.len() - 6));
                }
                line(ui, self.adapter.clone());
            });
    }
}

/// Maps a window capture and writes it as an RGBA PNG (BGRA surfaces swizzled).
fn save_capture(
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

type VolumeDraw = (wgpu::RenderPipeline, wgpu::BindGroup, wgpu::Buffer, u32);

/// The volume overlay's pipeline, bind group, vertex buffer and vertex count, or `None`.
fn volume_draw(gfx: &Gfx, frame: &Frame, view: VolumeView, w: u32, h: u32) -> Option<VolumeDraw> {
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

impl Gfx {
    fn new(
        window: Arc<Window>,
        options: &ViewOptions,
        el: &ActiveEventLoop,
        (backend, render_options): (Box<dyn SilhouetteBackend>, RenderOptions),
    ) -> Result<Self, ViewError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(el.owned_display_handle()),
            ));
        let surface = instance
            .create_surface(Arc::clone(&window))
            .map_err(|e| ViewError::Gpu(format!("cannot create a surface for the window: {e}")))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| ViewError::Gpu(format!("no GPU adapter can present to the window: {e}")))?;
        let (required_features, required_limits) = Renderer::device_requirements(&adapter);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadowvol-viewer"),
            required_features,
            required_limits,
            ..Default::default()
        }))
        .map_err(|e| ViewError::Gpu(format!("device: {e}")))?;
        let renderer = Renderer::on_device(
            backend,
            render_options,
            adapter.clone(),
            device.clone(),
            queue.clone(),
        )?;
        let size = window.inner_size();
        let caps = surface.get_capabilities(&adapter);
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
        let config = wgpu::SurfaceConfiguration {
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
        };
        surface.configure(&device, &config);

        let blit_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let volume_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volumes"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let blit_module = crate::shaders::blit_module(&device);
        let volume_module = crate::shaders::volumes_module(&device);
        let layout = |bgl: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(bgl)],
                immediate_size: 0,
            })
        };
        let target = [Some(wgpu::ColorTargetState {
            format,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let blit_pl = layout(&blit_layout);
        let blit = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: Some(&blit_pl),
            vertex: wgpu::VertexState {
                module: &blit_module,
                entry_point: Some("vs_blit"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &blit_module,
                entry_point: Some("fs_blit"),
                compilation_options: Default::default(),
                targets: &target,
            }),
            multiview_mask: None,
            cache: None,
        });
        let volume_pl = layout(&volume_layout);
        let volume_pipeline = |topology: wgpu::PrimitiveTopology, label: &str| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&volume_pl),
                vertex: wgpu::VertexState {
                    module: &volume_module,
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
                    module: &volume_module,
                    entry_point: Some("fs_volume"),
                    compilation_options: Default::default(),
                    targets: &target,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let tri = volume_pipeline(wgpu::PrimitiveTopology::TriangleList, "volumes");
        let wire = volume_pipeline(wgpu::PrimitiveTopology::LineList, "volume wires");

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

    fn resize(&mut self, w: u32, h: u32) {
        if w > 0 && h > 0 {
            self.config.width = w;
            self.config.height = h;
            self.surface.configure(&self.device, &self.config);
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title(self.options.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(
                self.options.width,
                self.options.height,
            ));
        let window = match el.create_window(attrs) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                return self.fail(el, ViewError::Window(format!("cannot open a window: {e}")))
            }
        };
        let Some(pending) = self.pending.take() else {
            return;
        };
        match Gfx::new(window, &self.options, el, pending) {
            Ok(g) => {
                if self.options.pipeline == Pipeline::Gpu {
                    if let Some(why) = g.renderer.gpu_pipeline_unsupported() {
                        eprintln!(
                            "warning: using the host pipeline: the adapter cannot run the GPU pipeline: {why}"
                        );
                        self.options.pipeline = Pipeline::Host;
                    }
                }
                g.window.request_redraw();
                self.gfx = Some(g);
                self.started = Some(Instant::now());
            }
            Err(e) => self.fail(el, e),
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gfx) = self.gfx.as_mut() else {
            return;
        };
        let consumed = gfx.egui_state.on_window_event(&gfx.window, &event).consumed;
        let height = gfx.config.height as f32;
        match event {
            WindowEvent::CloseRequested => {
                if self.options.frames.is_some() {
                    self.error = Some(ViewError::Window(
                        "the window was closed before the last frame".into(),
                    ));
                }
                el.exit();
            }
            WindowEvent::Resized(size) => gfx.resize(size.width, size.height),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame(el) {
                    self.fail(el, e);
                }
            }
            _ if consumed => {}
            WindowEvent::ModifiersChanged(m) => self.drag.shift = m.state().shift_key(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(&event.logical_key, el);
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.drag.left = down,
                    MouseButton::Right | MouseButton::Middle => self.drag.right = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = (position.x as f32, position.y as f32);
                if let Some((x, y)) = self.drag.cursor {
                    let (dx, dy) = (p.0 - x, p.1 - y);
                    if self.drag.left && self.drag.shift {
                        let k = std::f32::consts::PI / height.max(1.0);
                        if let Some(l) = self.scene.lights.first_mut() {
                            *l = controls::orbit_light(*l, self.centre, dx * k, -dy * k);
                        }
                    } else if self.drag.left {
                        self.orbit.rotate(dx, dy, height);
                    } else if self.drag.right {
                        self.orbit.pan(dx, dy, height);
                    }
                }
                self.drag.cursor = Some(p);
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 50.0,
                };
                self.orbit.zoom(steps);
            }
            _ => {}
        }
    }
}
