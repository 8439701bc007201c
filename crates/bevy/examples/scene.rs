//! A window: the bundled bunny (glTF, made from `assets/bunny.obj` with obj2gltf) on a ground,
//! lit by a point light that circles it, its shadows drawn with volumes.
//!
//! `cargo run --example scene` (from `crates/bevy`; needs a display). Keys:
//! - `M`: the next accuracy mode (original, robust, ordered, exact);
//! - `V`: volumes or Bevy's own shadow maps for the same light;
//! - `Space`: stop or start the light.
//!
//! The window's title says what is on. `--screenshot OUT.png` saves the window after 120 frames
//! and exits (CI runs it under Xvfb).

use bevy::diagnostic::FrameCount;
use bevy::prelude::*;
use bevy::render::view::screenshot::{save_to_disk, Screenshot};
use bevy::window::PrimaryWindow;
use shadowvol_bevy::{Accuracy, ShadowVolumeLight, ShadowVolumes, ShadowVolumesPlugin};

/// `--screenshot PATH`: where to save the window, then exit.
#[derive(Resource)]
struct ScreenshotTo(String);

fn main() -> AppExit {
    let mut args = std::env::args().skip(1);
    let shot = match (args.next().as_deref(), args.next()) {
        (None, _) => None,
        (Some("--screenshot"), Some(path)) => Some(ScreenshotTo(path)),
        _ => {
            eprintln!("usage: scene [--screenshot OUT.png]");
            return AppExit::error();
        }
    };
    let mut app = App::new();
    if let Some(s) = shot {
        app.insert_resource(s)
            .add_systems(Update, screenshot_and_exit);
    }
    app.add_plugins(DefaultPlugins.set(AssetPlugin {
        // The repository's assets folder, two levels above this crate.
        file_path: "../../assets".into(),
        ..default()
    }))
    .add_plugins(ShadowVolumesPlugin)
    .init_resource::<Paused>()
    .add_systems(Startup, setup)
    .add_systems(Update, (keys, circle_light, title))
    .run()
}

fn screenshot_and_exit(
    mut commands: Commands,
    frames: Res<FrameCount>,
    to: Res<ScreenshotTo>,
    mut exit: MessageWriter<AppExit>,
) {
    match frames.0 {
        120 => {
            commands
                .spawn(Screenshot::primary_window())
                .observe(save_to_disk(to.0.clone()));
        }
        130 => {
            exit.write(AppExit::Success);
        }
        _ => {}
    }
}

#[derive(Resource, Default)]
struct Paused(bool);

#[derive(Component)]
struct Circling;

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    commands.spawn((
        Camera3d::default(),
        ShadowVolumes::default(),
        Transform::from_xyz(5.0, 5.0, 7.0).looking_at(Vec3::new(0.0, 1.0, 0.0), Vec3::Y),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(12.0, 12.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.8, 0.8, 0.75))),
    ));
    // Every mesh casts, the glTF scene's too (`ShadowCasters::Marked` would make it opt-in).
    commands.spawn((
        WorldAssetRoot(assets.load(GltfAssetLabel::Scene(0).from_asset("bunny.glb"))),
        Transform::from_scale(Vec3::splat(0.25)),
    ));
    commands.spawn((
        PointLight {
            intensity: 3.0e6,
            range: 40.0,
            // The light's own setting: shadow maps. Marked, it has volumes instead; the V key
            // removes the marker, which gives it its maps back.
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(3.0, 5.0, 0.0),
        ShadowVolumeLight,
        Circling,
    ));
}

fn keys(
    input: Res<ButtonInput<KeyCode>>,
    mut commands: Commands,
    mut cameras: Query<&mut ShadowVolumes>,
    mut lights: Query<(Entity, Has<ShadowVolumeLight>), With<Circling>>,
    mut paused: ResMut<Paused>,
) {
    if input.just_pressed(KeyCode::KeyM) {
        for mut s in &mut cameras {
            let i = Accuracy::ALL.iter().position(|m| *m == s.mode).unwrap_or(0);
            s.mode = Accuracy::ALL[(i + 1) % Accuracy::ALL.len()];
        }
    }
    if input.just_pressed(KeyCode::KeyV) {
        for (e, volumes) in &mut lights {
            if volumes {
                commands.entity(e).remove::<ShadowVolumeLight>();
            } else {
                commands.entity(e).insert(ShadowVolumeLight);
            }
        }
    }
    if input.just_pressed(KeyCode::Space) {
        paused.0 = !paused.0;
    }
}

fn circle_light(
    time: Res<Time>,
    paused: Res<Paused>,
    mut q: Query<&mut Transform, With<Circling>>,
) {
    if paused.0 {
        return;
    }
    let a = time.elapsed_secs() * 0.5;
    for mut t in &mut q {
        t.translation = Vec3::new(3.0 * a.cos(), 5.0, 3.0 * a.sin());
    }
}

fn title(
    cameras: Query<&ShadowVolumes>,
    lights: Query<Has<ShadowVolumeLight>, With<Circling>>,
    mut window: Query<&mut Window, With<PrimaryWindow>>,
) {
    let mode = cameras.iter().next().map_or(Accuracy::Exact, |s| s.mode);
    let volumes = lights.iter().any(|v| v);
    let shadows = if volumes {
        format!("{} shadow volumes", mode.name())
    } else {
        "Bevy shadow maps".to_owned()
    };
    let title = format!("shadowvol-bevy: {shadows} (M mode, V volumes/maps, Space light)");
    for mut w in &mut window {
        if w.title != title {
            w.title = title.clone();
        }
    }
}
