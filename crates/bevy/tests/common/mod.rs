//! A Bevy app driven by hand without a window, and the project's exact reference for the same
//! scene: what the headless tests and the `headless` example share.
#![allow(dead_code)]

#[path = "../../../cli/src/shot.rs"]
mod shot;

use std::sync::{Arc, Mutex};

use bevy::app::SubApps;
use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::mesh::{Indices, VertexAttributeValues};
use bevy::prelude::*;
use bevy::render::render_resource::{PollType, TextureFormat};
use bevy::render::renderer::RenderDevice;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::render::RenderPlugin;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use shadowvol_bevy::{ShadowCaster, ShadowVolumeLight, ShadowVolumes, ShadowVolumesPlugin};
use shadowvol_reference::PixelState;

/// The camera every scene here is seen from.
pub const EYE: Vec3 = Vec3::new(4.0, 5.0, 7.0);
pub const TARGET: Vec3 = Vec3::new(0.0, 0.5, 0.0);

/// A Bevy app whose frames the caller drives, rendering into an image.
pub struct Driver {
    apps: SubApps,
    target: Handle<Image>,
    pub width: u32,
    pub height: u32,
    pub camera: Entity,
    mask: MaskReadback,
}

/// A request to the render world for a layer of the mask (the image and the layer), and the
/// answer.
#[derive(Resource, Clone, Default)]
struct MaskReadback(Arc<Mutex<Exchange>>);

/// What [`MaskReadback`] holds.
#[derive(Default)]
struct Exchange {
    request: Option<MaskLayer>,
    answer: Option<Vec<f32>>,
}

/// The mask image and one of its layers.
type MaskLayer = (AssetId<Image>, u32);

/// The render world's side of [`Driver::mask_layer`]: after the frame is rendered, copies the
/// requested layer into a buffer, waits for it and converts it to `f32`.
fn read_mask(
    request: Res<MaskReadback>,
    images: Res<bevy::render::render_asset::RenderAssets<bevy::render::texture::GpuImage>>,
    device: Res<RenderDevice>,
    queue: Res<bevy::render::renderer::RenderQueue>,
) {
    let Some((id, layer)) = request.0.lock().unwrap().request else {
        return;
    };
    let Some(image) = images.get(id) else {
        return;
    };
    let texture: &wgpu::Texture = &image.texture;
    let device = device.wgpu_device();
    let queue: &wgpu::Queue = &queue;
    let (w, h) = (texture.width(), texture.height());
    let row = (w * 2).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("mask readback"),
        size: u64::from(row * h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([enc.finish()]);
    buffer
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.expect("mapped"));
    device
        .poll(PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("device poll");
    let data = buffer
        .slice(..)
        .get_mapped_range()
        .expect("the mapped mask");
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let start = (y * row) as usize;
        for x in 0..w as usize {
            let b = [data[start + 2 * x], data[start + 2 * x + 1]];
            out.push(f16_to_f32(u16::from_le_bytes(b)));
        }
    }
    *request.0.lock().unwrap() = Exchange {
        request: None,
        answer: Some(out),
    };
}

impl Driver {
    /// Bevy's default plugins without a window, `ShadowVolumesPlugin`, and a camera at
    /// [`EYE`] looking at [`TARGET`] with `ShadowVolumes` (exact), Bevy's default MSAA (4x),
    /// no tonemapping and a black background, drawing into a `width × height` sRGB image. No
    /// ambient light.
    pub fn new(width: u32, height: u32) -> Self {
        Self::build(width, height, true)
    }

    /// The same app without `ShadowVolumesPlugin` (its components, added by the helpers, do
    /// nothing there), and without Bevy's logger, which a process sets once: what a scene looks
    /// like to Bevy alone.
    pub fn without_plugin(width: u32, height: u32) -> Self {
        Self::build(width, height, false)
    }

    fn build(width: u32, height: u32, plugin: bool) -> Self {
        let mut app = App::new();
        let defaults = DefaultPlugins
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .disable::<WinitPlugin>();
        if plugin {
            app.add_plugins(defaults).add_plugins(ShadowVolumesPlugin);
        } else {
            app.add_plugins(defaults.disable::<bevy::log::LogPlugin>());
        }
        app.insert_resource(GlobalAmbientLight {
            brightness: 0.0,
            ..default()
        });
        let mask = MaskReadback::default();
        if let Some(render) = app.get_sub_app_mut(bevy::render::RenderApp) {
            render.insert_resource(mask.clone()).add_systems(
                bevy::render::Render,
                read_mask.in_set(bevy::render::RenderSystems::Cleanup),
            );
        }
        app.finish();
        app.cleanup();
        let mut apps = std::mem::take(app.sub_apps_mut());
        let world = apps.main.world_mut();
        let mut image =
            Image::new_target_texture(width, height, TextureFormat::Rgba8UnormSrgb, None);
        image.asset_usage = RenderAssetUsages::RENDER_WORLD;
        let target = world.resource_mut::<Assets<Image>>().add(image);
        let camera = world
            .spawn((
                Camera3d::default(),
                Camera {
                    clear_color: ClearColorConfig::Custom(Color::BLACK),
                    ..default()
                },
                RenderTarget::from(target.clone()),
                Tonemapping::None,
                ShadowVolumes::default(),
                Transform::from_translation(EYE).looking_at(TARGET, Vec3::Y),
            ))
            .id();
        Self {
            apps,
            target,
            width,
            height,
            camera,
            mask,
        }
    }

    pub fn world(&mut self) -> &mut World {
        self.apps.main.world_mut()
    }

    /// One frame, waited for on the device.
    pub fn update(&mut self) {
        self.apps.update();
        self.apps
            .main
            .world()
            .resource::<RenderDevice>()
            .wgpu_device()
            .poll(PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .expect("device poll");
    }

    /// The next frame's image, RGBA8 sRGB, row-major from the top.
    pub fn capture(&mut self) -> Vec<u8> {
        let target = self.target.clone();
        self.capture_of(&target)
    }

    /// The next frame's image of another target (a second camera's), as [`Driver::capture`].
    pub fn capture_of(&mut self, target: &Handle<Image>) -> Vec<u8> {
        let slot: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
        let s = slot.clone();
        let target = target.clone();
        self.world()
            .spawn(Screenshot::image(target))
            .observe(move |ev: On<ScreenshotCaptured>| {
                *s.lock().unwrap() = ev.image.data.clone();
            });
        for _ in 0..20 {
            self.update();
            if let Some(data) = slot.lock().unwrap().take() {
                return data;
            }
        }
        panic!("no screenshot after 20 frames");
    }

    /// Adds a mesh entity with a white `StandardMaterial`, marked as a caster.
    pub fn spawn_caster(&mut self, mesh: Mesh, transform: Transform) -> Entity {
        let e = self.spawn_mesh(mesh, transform);
        self.world().entity_mut(e).insert(ShadowCaster);
        e
    }

    /// Adds a mesh entity with a white `StandardMaterial`, unmarked (as a Bevy user writes it:
    /// with the plugin's default, every mesh casts).
    pub fn spawn_mesh(&mut self, mesh: Mesh, transform: Transform) -> Entity {
        let mesh = self.world().resource_mut::<Assets<Mesh>>().add(mesh);
        self.spawn_handle(mesh, transform)
    }

    /// Adds an unmarked entity with this mesh handle (loaded or not) and a white
    /// `StandardMaterial`.
    pub fn spawn_handle(&mut self, mesh: Handle<Mesh>, transform: Transform) -> Entity {
        let world = self.world();
        let material = world
            .resource_mut::<Assets<StandardMaterial>>()
            .add(StandardMaterial {
                base_color: Color::WHITE,
                perceptual_roughness: 1.0,
                reflectance: 0.0,
                ..default()
            });
        world
            .spawn((Mesh3d(mesh), MeshMaterial3d(material), transform))
            .id()
    }

    /// Adds a second 3D camera without `ShadowVolumes` at `eye` looking at [`TARGET`], drawn
    /// after the first into its own `width × height` image (as a minimap or a render-to-texture
    /// view), with the first camera's settings otherwise. Returns the camera and its image.
    pub fn spawn_plain_camera(
        &mut self,
        eye: Vec3,
        width: u32,
        height: u32,
    ) -> (Entity, Handle<Image>) {
        let mut image =
            Image::new_target_texture(width, height, TextureFormat::Rgba8UnormSrgb, None);
        image.asset_usage = RenderAssetUsages::RENDER_WORLD;
        let world = self.world();
        let target = world.resource_mut::<Assets<Image>>().add(image);
        let camera = world
            .spawn((
                Camera3d::default(),
                Camera {
                    clear_color: ClearColorConfig::Custom(Color::BLACK),
                    order: 1,
                    ..default()
                },
                RenderTarget::from(target.clone()),
                Tonemapping::None,
                Transform::from_translation(eye).looking_at(TARGET, Vec3::Y),
            ))
            .id();
        (camera, target)
    }

    /// Adds a marked point light of this colour.
    pub fn spawn_light(&mut self, position: Vec3, color: Color) -> Entity {
        self.world()
            .spawn((
                PointLight {
                    color,
                    intensity: 2.0e6,
                    range: 40.0,
                    ..default()
                },
                Transform::from_translation(position),
                ShadowVolumeLight,
            ))
            .id()
    }

    /// Adds a marked directional light shining from `towards` (a direction, not a point) to
    /// the origin, with this illuminance in lux.
    pub fn spawn_directional(&mut self, towards: Vec3, color: Color, lux: f32) -> Entity {
        self.world()
            .spawn((
                DirectionalLight {
                    color,
                    illuminance: lux,
                    ..default()
                },
                Transform::from_translation(towards).looking_at(Vec3::ZERO, Vec3::Y),
                ShadowVolumeLight,
            ))
            .id()
    }

    /// Adds a marked spot light at `position` aimed at `target`, its cone `outer` radians wide
    /// on each side.
    pub fn spawn_spot(&mut self, position: Vec3, target: Vec3, color: Color, outer: f32) -> Entity {
        self.world()
            .spawn((
                SpotLight {
                    color,
                    intensity: 2.0e6,
                    range: 40.0,
                    outer_angle: outer,
                    inner_angle: outer * 0.8,
                    ..default()
                },
                Transform::from_translation(position).looking_at(target, Vec3::Y),
                ShadowVolumeLight,
            ))
            .id()
    }

    /// Draws into a new `width × height` target from now on, as when a window is resized.
    pub fn resize(&mut self, width: u32, height: u32) {
        let mut image =
            Image::new_target_texture(width, height, TextureFormat::Rgba8UnormSrgb, None);
        image.asset_usage = RenderAssetUsages::RENDER_WORLD;
        let target = self.world().resource_mut::<Assets<Image>>().add(image);
        let camera = self.camera;
        self.world()
            .entity_mut(camera)
            .insert(RenderTarget::from(target.clone()));
        (self.target, self.width, self.height) = (target, width, height);
    }

    /// Moves the camera to `eye`, looking at `target`.
    pub fn look(&mut self, eye: Vec3, target: Vec3) {
        let camera = self.camera;
        self.world()
            .entity_mut(camera)
            .insert(Transform::from_translation(eye).looking_at(target, Vec3::Y));
    }

    /// Layer `layer` of the plugin's mask as a coming frame leaves it (the [`ShadowVolumes`]
    /// camera's, when it is the only 3D view): row-major from the top, one value per pixel of
    /// the camera's viewport, copied on the device by a system of the render world after the
    /// frame is rendered (it runs on its own thread), and read back.
    pub fn mask_layer(&mut self, layer: u32) -> Vec<f32> {
        let mask = self
            .world()
            .resource::<Assets<shadowvol_bevy::ShadowVolumeMaterial>>()
            .iter()
            .next()
            .map(|(_, m)| m.extension.mask.id())
            .expect("a caster's material");
        *self.mask.0.lock().unwrap() = Exchange {
            request: Some((mask, layer)),
            answer: None,
        };
        for _ in 0..20 {
            self.update();
            if let Some(data) = self.mask.0.lock().unwrap().answer.take() {
                return data;
            }
        }
        panic!("no mask read back after 20 frames");
    }

    /// The plugin's statistics.
    pub fn stats(&mut self) -> shadowvol_bevy::ShadowVolumeStats {
        self.world()
            .resource::<shadowvol_bevy::ShadowVolumeStats>()
            .clone()
    }
}

/// The floor: an 8 × 8 plane at y = 0.
pub fn floor() -> Mesh {
    Plane3d::default().mesh().size(8.0, 8.0).build()
}

/// A unit box.
pub fn unit_box() -> Mesh {
    Cuboid::new(1.0, 1.0, 1.0).into()
}

/// A Bevy mesh's positions and triangles for the reference (read here, not by the plugin).
pub fn topology(mesh: &Mesh) -> shadowvol_mesh_topology::Mesh {
    let Some(VertexAttributeValues::Float32x3(p)) = mesh.attribute(Mesh::ATTRIBUTE_POSITION) else {
        panic!("positions");
    };
    let idx: Vec<u32> = match mesh.indices() {
        Some(Indices::U16(i)) => i.iter().map(|&i| u32::from(i)).collect(),
        Some(Indices::U32(i)) => i.clone(),
        None => (0..p.len() as u32).collect(),
    };
    shadowvol_mesh_topology::Mesh::new(
        p.iter().map(|&v| glam::Vec3::from(v)).collect(),
        idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    )
    .expect("mesh")
}

/// The exact reference's per-light, per-pixel states for these meshes (with their transforms)
/// and homogeneous lights (`w = 1` a point, `w = 0` a direction towards the light), seen from
/// [`EYE`] at `width × height`: the project's renderer gives each pixel's surface, and the
/// reference ray-casts every light from it.
pub fn reference(
    meshes: &[(&Mesh, Transform)],
    lights: &[Vec4],
    width: u32,
    height: u32,
) -> Vec<Vec<PixelState>> {
    reference_from(EYE, TARGET, meshes, lights, width, height)
}

/// [`reference`] seen from `eye` looking at `target`.
pub fn reference_from(
    eye: Vec3,
    target: Vec3,
    meshes: &[(&Mesh, Transform)],
    lights: &[Vec4],
    width: u32,
    height: u32,
) -> Vec<Vec<PixelState>> {
    use shadowvol_renderer::{Camera, RenderOptions, Renderer, Scene};
    let mut scene = Scene::new("bevy test");
    for (i, (m, t)) in meshes.iter().enumerate() {
        let table = scene
            .add_mesh(&format!("m{i}"), &topology(m))
            .expect("table");
        scene.add_object(format!("m{i}"), table, affine(t));
    }
    scene.add_unit_lights(
        lights
            .iter()
            .map(|l| shadowvol_robust_math::Light::new(l.x, l.y, l.z, l.w).expect("light")),
    );
    scene.camera = Some(Camera::look_at(
        glam::Vec3::from(eye.to_array()),
        glam::Vec3::from(target.to_array()),
    ));
    let mut renderer = Renderer::gpu(RenderOptions::new(width, height)).expect("renderer");
    let frame = renderer.render(&scene).expect("render");
    let shot = shot::shot(&frame, &scene).expect("a frame read back");
    let points = shadowvol_reference::surface_points(&shot);
    shadowvol_reference::reference_states(&shot, &points)
}

/// Bevy's transform (glam 0.33) as shadowvol's (glam 0.34).
fn affine(t: &Transform) -> glam::Affine3A {
    let m = t.to_matrix().to_cols_array();
    glam::Affine3A::from_mat4(glam::Mat4::from_cols_array(&m))
}

/// How one light's shadows in Bevy's image agree with the reference.
#[derive(Debug, Default, Clone, Copy)]
pub struct Agreement {
    /// Pixels where both say something and they differ.
    pub artifacts: usize,
    /// Pixels compared.
    pub compared: usize,
    /// Of those, pixels the reference has in shadow.
    pub shadowed: usize,
}

/// Compares light `li`'s shadows, read from colour channel `channel` of `shadowed` against the
/// same frame drawn without volume shadows (`unshadowed`), with the reference's states.
/// A pixel is compared where the light brightens it visibly without shadows (at least `8/255`)
/// and the reference decides it (lit or unlit): Bevy has it lit when it keeps more than half
/// of its unshadowed value.
pub fn agreement(
    shadowed: &[u8],
    unshadowed: &[u8],
    states: &[PixelState],
    channel: usize,
) -> Agreement {
    let mut a = Agreement::default();
    for (px, state) in states.iter().enumerate() {
        let u = unshadowed[px * 4 + channel];
        let s = shadowed[px * 4 + channel];
        if u < 8 || !matches!(state, PixelState::Lit | PixelState::Unlit) {
            continue;
        }
        a.compared += 1;
        let reference_lit = *state == PixelState::Lit;
        if !reference_lit {
            a.shadowed += 1;
        }
        if (2 * u32::from(s) > u32::from(u)) != reference_lit {
            a.artifacts += 1;
        }
    }
    a
}

/// The repository's `assets/bunny.obj`, read by the project's OBJ loader, as a Bevy mesh with
/// smooth normals.
pub fn bunny() -> Mesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/bunny.obj");
    let m = shadowvol_scenes::obj::load_obj(path).expect("assets/bunny.obj");
    let positions: Vec<[f32; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
    let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    Mesh::new(
        bevy::mesh::PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
    .with_inserted_indices(Indices::U32(indices))
    .with_computed_smooth_normals()
}

/// A transform that scales `mesh` to `height` and stands it on the floor at the origin.
pub fn stand_on_floor(mesh: &Mesh, height: f32) -> Transform {
    let Some(VertexAttributeValues::Float32x3(p)) = mesh.attribute(Mesh::ATTRIBUTE_POSITION) else {
        panic!("positions");
    };
    let (lo, hi) = p.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
        (lo.min(Vec3::from(v)), hi.max(Vec3::from(v)))
    });
    let s = height / (hi.y - lo.y);
    let centre = (lo + hi) * 0.5;
    Transform::from_xyz(-centre.x * s, -lo.y * s, -centre.z * s).with_scale(Vec3::splat(s))
}

/// An IEEE half (the mask's `R16Float`) as `f32`, exactly.
fn f16_to_f32(h: u16) -> f32 {
    let sign = if h >> 15 == 1 { -1.0 } else { 1.0 };
    let e = u32::from((h >> 10) & 0x1f);
    let m = u32::from(h & 0x3ff);
    let v = match e {
        0 => m as f32 * 2f32.powi(-24),
        31 if m == 0 => f32::INFINITY,
        31 => f32::NAN,
        _ => f32::from_bits(((e + 112) << 23) | (m << 13)),
    };
    sign * v
}

/// One pixel of a [`SoftCheck`].
#[derive(Debug, Clone, Copy)]
pub struct Worst {
    /// Where: `(x, y)` from the top left.
    pub at: (usize, usize),
    /// The renderer's `[surface + 1, triangle]` there (the reference's surface point).
    pub id: [u32; 2],
    /// The true visibility and its bound.
    pub truth: (f64, f64),
    /// The plugin's mask there.
    pub mask: f32,
    /// The renderer's `k / N` there.
    pub renderer: f32,
}

/// A soft light's visibility in the plugin's mask against the project's exact soft reference
/// and against the renderer's own visibility for the same scene, camera and light.
pub struct SoftCheck {
    /// The mask against the reference ([`shadowvol_reference::soft::compare_visibility`]).
    pub reference: shadowvol_reference::soft::SoftComparison,
    /// Covered pixels where the mask differs from the renderer's `k / N`.
    pub differ_from_renderer: usize,
    /// Of those, pixels on an edge of the renderer's triangles (a 3×3 neighbour shows another
    /// triangle or the background), where the two pre-passes may pick different triangles.
    pub differ_on_edges: usize,
    /// The largest `|mask − renderer|` off the renderer's triangle edges: a multiple of `1 / N`,
    /// where a sample's hard shadow boundary passes between the two surface points of a pixel
    /// (the two cameras round differently).
    pub largest_off_edges: f32,
    /// Covered pixels.
    pub covered: usize,
    /// The penumbra pixel where the mask is farthest from the truth.
    pub worst: Option<Worst>,
}

/// Checks `mask` (one light's visibility from the plugin, `width × height`) for these meshes
/// and `light` (a light with a size, sampled by `samples` points), seen from `eye` looking at
/// `target`: the renderer draws the same scene with the same samples (its
/// `FrameImage::visibility`), and the exact reference integrates each pixel's true share of the
/// light's disk (aimed at `Scene::light_aim`, as the plugin aims it).
#[allow(clippy::too_many_arguments)]
pub fn soft_check(
    (eye, target): (Vec3, Vec3),
    meshes: &[(&Mesh, Transform)],
    light: shadowvol_scenes::SceneLight,
    samples: u32,
    (width, height): (u32, u32),
    mask: &[f32],
) -> SoftCheck {
    use shadowvol_renderer::{Camera, RenderOptions, Renderer, Scene};
    let mut scene = Scene::new("bevy soft test");
    for (i, (m, t)) in meshes.iter().enumerate() {
        let table = scene
            .add_mesh(&format!("m{i}"), &topology(m))
            .expect("table");
        scene.add_object(format!("m{i}"), table, affine(t));
    }
    scene.lights.push(light);
    scene.camera = Some(Camera::look_at(
        glam::Vec3::from(eye.to_array()),
        glam::Vec3::from(target.to_array()),
    ));
    let mut options = RenderOptions::new(width, height);
    options.light_samples = Some(samples);
    let mut renderer = Renderer::gpu(options).expect("renderer");
    let frame = renderer.render(&scene).expect("render");
    let img = frame.read_image().expect("a frame read back");
    let stencils: Vec<Vec<u8>> = img
        .visibility
        .iter()
        .map(|v| v.iter().map(|&x| u8::from(x < 1.0)).collect())
        .collect();
    let shot =
        shot::shot_with(&frame, &scene, &stencils, &frame.report.light_colors).expect("a shot");
    let disk = scene.lights[0]
        .disk(scene.light_aim())
        .expect("a light with a size");
    let truth = shadowvol_reference::soft::visibility_reference(&shot, 0, &disk);
    let reference = shadowvol_reference::soft::compare_with_reference(&truth, mask);
    let ours = &img.visibility[0];
    let worst = truth
        .pixels
        .iter()
        .enumerate()
        .filter_map(|(i, v)| v.filter(|v| v.is_penumbra()).map(|v| (i, v)))
        .max_by(|a, b| {
            let e = |(i, v): &(usize, shadowvol_reference::soft::Visibility)| {
                (f64::from(mask[*i]) - v.value).abs()
            };
            e(a).total_cmp(&e(b))
        })
        .map(|(i, v)| Worst {
            at: (i % width as usize, i / width as usize),
            id: img.ids[i],
            truth: (v.value, v.bound),
            mask: mask[i],
            renderer: ours[i],
        });
    let covered: Vec<usize> = (0..mask.len())
        .filter(|&i| img.ids.get(i).is_some_and(|id| id[0] != 0))
        .collect();
    let w = width as usize;
    let on_edge = |i: usize| {
        let (x, y) = (i % w, i / w);
        (y.saturating_sub(1)..=(y + 1).min(height as usize - 1)).any(|ny| {
            (x.saturating_sub(1)..=(x + 1).min(w - 1)).any(|nx| img.ids[ny * w + nx] != img.ids[i])
        })
    };
    let differ: Vec<usize> = covered
        .iter()
        .copied()
        .filter(|&i| ours[i] != mask[i])
        .collect();
    SoftCheck {
        reference,
        differ_from_renderer: differ.len(),
        differ_on_edges: differ.iter().filter(|&&i| on_edge(i)).count(),
        largest_off_edges: differ
            .iter()
            .filter(|&&i| !on_edge(i))
            .map(|&i| (ours[i] - mask[i]).abs())
            .fold(0.0, f32::max),
        covered: covered.len(),
        worst,
    }
}
