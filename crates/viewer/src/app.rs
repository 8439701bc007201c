//! The viewer's state and its winit events: each frame sets the camera and the plan's options,
//! picks the pipeline (the host one while the volumes are shown), renders into the frame
//! texture, and draws it, the volumes and the overlay onto the window.

use crate::controls::{self, Orbit, VolumeView};
use crate::gfx::{save_capture, volume_draw, Gfx, VolumeDraw};
use crate::overlay::Stats;
use crate::{BackendStarter, ViewError, ViewOptions, ViewReport};
use glam::Vec3;
use shadowvol_renderer::resident::texture_2d;
use shadowvol_renderer::{
    Camera, Frame, GpuPipeline, HostPipeline, MapPipeline, Pipeline, PlanPolicy, RenderError,
    RenderOptions, Scene, ShadowPipeline,
};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// The state of a running viewer.
pub(crate) struct App {
    scene: Scene,
    /// Starts the silhouette backend of the host pipeline, the first time it is needed.
    backend: BackendStarter,
    /// The pipeline not in use (the host pipeline while the GPU one draws, or the other way
    /// round), kept for the next switch.
    spare: Option<Box<dyn ShadowPipeline>>,
    options: ViewOptions,
    orbit: Orbit,
    centre: Vec3,
    policy: PlanPolicy,
    volumes: VolumeView,
    /// Shadow maps instead of volumes (M switches).
    maps: bool,
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

impl App {
    /// A viewer of `scene` (which has a camera) that opens its renderer with `options.render`
    /// once the window's device exists, and starts the host pipeline's backend with `backend` when needed.
    pub(crate) fn new(
        scene: Scene,
        camera: Camera,
        backend: BackendStarter,
        options: ViewOptions,
    ) -> Self {
        let orbit = Orbit::from_camera(&camera);
        let centre = scene
            .bounds()
            .map_or(camera.target, |(lo, hi)| (lo + hi) * 0.5);
        let policy = options.render.policy;
        let volumes = options.volumes;
        let maps = options.pipeline == Pipeline::Map;
        let mut options = options;
        if maps {
            options.pipeline = Pipeline::Gpu;
        }
        Self {
            scene,
            backend,
            spare: None,
            options,
            orbit,
            centre,
            policy,
            volumes,
            maps,
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

    /// A new pipeline of `kind`: the host one over a freshly started backend, keeping its
    /// volumes for the overlay.
    fn make_pipeline(&mut self, kind: Pipeline) -> Result<Box<dyn ShadowPipeline>, ViewError> {
        Ok(match kind {
            Pipeline::Gpu => Box::new(GpuPipeline::new()),
            Pipeline::Map => Box::new(MapPipeline::new(self.options.maps)),
            Pipeline::Host => {
                let backend = (self.backend)().map_err(RenderError::Backend)?;
                Box::new(HostPipeline::new(backend).keep_volumes(true))
            }
        })
    }

    /// Draws with the `kind` pipeline from the next frame: the spare one if it is of that kind,
    /// else a new one; the current one becomes the spare.
    fn use_pipeline(&mut self, kind: Pipeline) -> Result<(), ViewError> {
        let current = self.gfx.as_ref().map(|g| g.renderer.pipeline().kind());
        if current.is_none_or(|k| k == kind) {
            return Ok(());
        }
        let next = match self.spare.take() {
            Some(p) if p.kind() == kind => p,
            other => {
                self.spare = other;
                self.make_pipeline(kind)?
            }
        };
        if let Some(gfx) = self.gfx.as_mut() {
            self.spare = Some(gfx.renderer.set_pipeline(next));
        }
        Ok(())
    }

    /// One window frame: the pipeline chosen, the scene rendered into the frame texture, then
    /// the frame, the volumes and the overlay drawn onto the window (and into the window
    /// capture on the last automated frame), and the frame time recorded.
    fn frame(&mut self, el: &ActiveEventLoop) -> Result<(), ViewError> {
        let t0 = Instant::now();
        // Only the host pipeline keeps the volume geometry the overlay draws.
        let kind = if self.maps {
            Pipeline::Map
        } else if self.volumes == VolumeView::Hidden {
            self.options.pipeline
        } else {
            Pipeline::Host
        };
        self.use_pipeline(kind)?;
        let Some(gfx) = self.gfx.as_mut() else {
            return Ok(());
        };
        let (w, h) = (gfx.config.width, gfx.config.height);
        self.scene.camera = Some(self.orbit.camera());
        let mut opts: RenderOptions = gfx.renderer.options();
        opts.width = w;
        opts.height = h;
        opts.mode = self.options.render.mode;
        opts.policy = self.policy;
        gfx.renderer.set_options(opts)?;
        let last = self
            .options
            .frames
            .is_some_and(|n| self.frame_ms.len() + 1 >= n as usize);
        let frame = render_scene(gfx, &self.scene, last && self.options.screenshot.is_some())?;
        let volumes = volume_draw(gfx, &frame, self.volumes, w, h);
        let Some(surface_texture) = acquire(gfx)? else {
            return Ok(());
        };
        let target = surface_texture.texture.create_view(&Default::default());
        let stats = Stats::of(&frame, &self.frame_ms, self.policy, self.volumes);
        let (overlay, mut textures) = run_overlay(gfx, &stats);
        let capture = self.options.window_screenshot.is_some() && last;
        let draw = WindowDraw {
            target: &target,
            volumes,
            overlay,
        };
        let (commands, readback) = record_window(gfx, &draw, capture);
        gfx.queue.submit(commands);
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
            adapter: gfx.renderer.device().description.clone(),
            screenshot,
            pipeline: gfx.renderer.pipeline().kind(),
        });
        Ok(())
    }

    /// Doubles (`grow`) or halves every light's radius ([`controls::step_radius`]), from 1 %
    /// of the scene's size (0.01 rad for a directional light) at radius 0.
    fn step_radius(&mut self, grow: bool) {
        let size = self
            .scene
            .surface_bounds()
            .map_or(1.0, |(lo, hi)| (hi - lo).length());
        for l in &mut self.scene.lights {
            let directional = l.light.is_directional();
            let start = if directional { 0.01 } else { 0.01 * size };
            l.radius = controls::step_radius(l.radius, start, grow, directional);
        }
    }

    fn key(&mut self, key: &Key, el: &ActiveEventLoop) {
        let step = 5f32.to_radians();
        let light = |app: &mut Self, yaw: f32, pitch: f32| {
            if let Some(l) = app.scene.lights.first_mut() {
                l.light = controls::orbit_light(l.light, app.centre, yaw, pitch);
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
                "m" | "M" => self.maps = !self.maps,
                "[" | "]" => self.step_radius(s_is_grow(c.as_str())),
                s => {
                    if let Some(m) = s.parse::<u8>().ok().and_then(controls::mode_of_key) {
                        self.options.render.mode = m;
                    }
                }
            },
            _ => {}
        }
    }
}

/// True for the key that grows the lights' radius (`]`), false for `[`.
fn s_is_grow(key: &str) -> bool {
    key == "]"
}

/// Renders into the frame texture; `read_back` (the screenshot frame) reads it back first.
fn render_scene(gfx: &mut Gfx, scene: &Scene, read_back: bool) -> Result<Frame, ViewError> {
    let (w, h) = (gfx.config.width, gfx.config.height);
    gfx.frame_texture(w, h);
    let (texture, frame_view, _) = gfx.frame_texture.as_ref().expect("made above");
    if !read_back {
        return Ok(gfx.renderer.render_into(scene, frame_view)?);
    }
    let frame = gfx.renderer.render(scene)?;
    gfx.queue.write_texture(
        texture.as_image_copy(),
        &frame.read_image()?.rgba,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * w),
            rows_per_image: Some(h),
        },
        texture.size(),
    );
    Ok(frame)
}

/// The window's next texture, or `None` after reconfiguring an outdated or lost surface.
fn acquire(gfx: &Gfx) -> Result<Option<wgpu::SurfaceTexture>, ViewError> {
    match gfx.surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
            Ok(Some(t))
        }
        wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
            gfx.surface.configure(&gfx.device, &gfx.config);
            Ok(None)
        }
        other => Err(ViewError::Gpu(format!("window surface: {other:?}"))),
    }
}

/// Runs and tessellates the overlay, uploads its new textures; returns what to free.
fn run_overlay(gfx: &mut Gfx, stats: &Stats) -> (Overlay, egui::TexturesDelta) {
    let raw = gfx.egui_state.take_egui_input(&gfx.window);
    let mut out = gfx.egui_ctx.run_ui(raw, |ui| stats.show(ui));
    let mut textures = std::mem::take(&mut out.textures_delta);
    gfx.egui_state
        .handle_platform_output(&gfx.window, out.platform_output);
    let jobs = gfx.egui_ctx.tessellate(out.shapes, out.pixels_per_point);
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [gfx.config.width, gfx.config.height],
        pixels_per_point: out.pixels_per_point,
    };
    for (id, deltas) in textures.set.drain() {
        for delta in &deltas {
            gfx.egui.update_texture(&gfx.device, &gfx.queue, id, delta);
        }
    }
    (Overlay { jobs, screen }, textures)
}

/// The overlay's tessellated UI and the screen it is laid out for.
struct Overlay {
    jobs: Vec<egui::ClippedPrimitive>,
    screen: egui_wgpu::ScreenDescriptor,
}

/// What one window frame draws onto `target`: the frame, the volumes, the overlay.
struct WindowDraw<'a> {
    target: &'a wgpu::TextureView,
    volumes: Option<VolumeDraw>,
    overlay: Overlay,
}

/// Records `draw` onto the window and, with `capture`, into a capture read back later.
fn record_window(
    gfx: &mut Gfx,
    draw: &WindowDraw<'_>,
    capture: bool,
) -> (Vec<wgpu::CommandBuffer>, Option<(wgpu::Buffer, u32)>) {
    let (w, h) = (gfx.config.width, gfx.config.height);
    let mut enc = gfx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("view"),
        });
    let extra = gfx.egui.update_buffers(
        &gfx.device,
        &gfx.queue,
        &mut enc,
        &draw.overlay.jobs,
        &draw.overlay.screen,
    );
    let capture = capture.then(|| {
        texture_2d(
            &gfx.device,
            "window capture",
            w,
            h,
            gfx.config.format,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        )
    });
    let capture_view = capture.as_ref().map(|t| t.create_view(&Default::default()));
    for view in std::iter::once(draw.target).chain(capture_view.as_ref()) {
        draw_onto(gfx, &mut enc, view, draw);
    }
    let readback = capture
        .as_ref()
        .map(|t| copy_capture(&gfx.device, &mut enc, t));
    let mut commands = extra;
    commands.push(enc.finish());
    (commands, readback)
}

/// One render pass onto `view`: the frame blitted, then the volumes and the overlay.
fn draw_onto(
    gfx: &Gfx,
    enc: &mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    draw: &WindowDraw<'_>,
) {
    let (_, _, blit_bg) = gfx.frame_texture.as_ref().expect("made by render_scene");
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
    if let Some((pipeline, bg, buf, n)) = &draw.volumes {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bg, &[]);
        pass.set_vertex_buffer(0, buf.slice(..));
        pass.draw(0..*n, 0..1);
    }
    gfx.egui
        .render(&mut pass, &draw.overlay.jobs, &draw.overlay.screen);
}

/// Copies the capture into a mappable buffer, rows padded to 256 bytes; returns it, the pitch.
fn copy_capture(
    device: &wgpu::Device,
    enc: &mut wgpu::CommandEncoder,
    t: &wgpu::Texture,
) -> (wgpu::Buffer, u32) {
    let (w, h) = (t.width(), t.height());
    let row = (4 * w).div_ceil(256) * 256;
    let buf = device.create_buffer(&wgpu::BufferDescriptor {
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
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title(self.options.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(
                self.options.render.width,
                self.options.render.height,
            ));
        let window = match el.create_window(attrs) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                return self.fail(el, ViewError::Window(format!("cannot open a window: {e}")))
            }
        };
        let options = self.options.clone();
        let made = Gfx::new(window, &options, el, |rd| {
            if options.pipeline == Pipeline::Gpu {
                if let Some(why) = &rd.gpu_pipeline_unsupported {
                    eprintln!(
                        "warning: using the host pipeline: the adapter cannot run the GPU pipeline: {why}"
                    );
                    self.options.pipeline = Pipeline::Host;
                }
            }
            self.make_pipeline(if self.maps {
                Pipeline::Map
            } else {
                self.options.pipeline
            })
        });
        match made {
            Ok(g) => {
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
                            l.light = controls::orbit_light(l.light, self.centre, dx * k, -dy * k);
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
