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
