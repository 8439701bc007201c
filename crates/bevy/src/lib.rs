//! Exact, crack-free stencil shadow volumes for Bevy 0.20.
//!
//! [`ShadowVolumesPlugin`] draws shadow volumes for the lights an application marks with
//! [`ShadowVolumeLight`], cast by its meshes as Bevy's shadows would be (every `Mesh3d` unless
//! it has `NotShadowCaster`, is hidden or is on other render layers than the camera; see
//! [`ShadowCasters`] for the opt-in), seen by the camera it marks with [`ShadowVolumes`]. It
//! runs shadowvol's GPU-resident pass (`shadowvol_renderer::resident::ShadowPass`) on Bevy's own
//! device and in Bevy's own command encoder, in the `Core3d` schedule before the main pass:
//!
//! 1. a depth-stencil pre-pass of the casters and receivers, one sample per pixel, forward-Z, in
//!    its own target (Bevy's main depth is reverse-Z `Depth32Float`, which has no stencil);
//! 2. per light, the silhouette extraction and the stencil volumes (z-pass or z-fail per object,
//!    as shadowvol's plan chooses from where the camera stands) in the accuracy mode
//!    of [`ShadowVolumes::mode`] (exact by default: bit-identical signs on every device);
//! 3. per light, a resolve of the stencil into one layer of a screen-space mask (1 lit, 0 in
//!    shadow). A light with a size (soft shadows: see [`SoftShadowSamples`]) is sampled by `N`
//!    points, each with its own stencil, and its layer holds the share that sees the pixel,
//!    `k / N`. Every other 3D view clears the masks to lit before its own main pass, so a
//!    second camera is not darkened by this view's mask.
//!
//! The candidates' `StandardMaterial`s become [`ShadowVolumeMaterial`], a `StandardMaterial`
//! extended with the mask: its fragment shader (an embedded asset) runs Bevy's own PBR lighting
//! and then takes away, per volume light, the share the mask says is blocked, computed with
//! Bevy's own light functions. So the mask replaces exactly that light's shadow factor; other
//! lights, ambient, emissive and specular stay Bevy's. A surface whose geometric normal faces
//! away from a marked light takes none of it, as in shadowvol's renderer and reference (smooth
//! normals would light it, and the volumes cannot shadow it). While the volumes shadow a light,
//! its Bevy shadow maps are off; in a frame where they cannot, its maps are on (never no
//! shadow), and the reason is in [`ShadowVolumeStats::error`], logged once.
//!
//! A caster whose mesh is added, removed or changed is prepared again: the edge table of a new
//! or changed mesh is built (the others are kept per mesh), and the casters are uploaded; a
//! caster or light that only moves, or is hidden, costs a few small uploads in the next frame.
//! [`ShadowVolumeStats`] counts tables built and preparations.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use shadowvol_bevy::{ShadowVolumeLight, ShadowVolumes, ShadowVolumesPlugin};
//!
//! fn main() {
//!     App::new()
//!         .add_plugins((DefaultPlugins, ShadowVolumesPlugin))
//!         .add_systems(Startup, setup)
//!         .run();
//! }
//!
//! fn setup(
//!     mut commands: Commands,
//!     mut meshes: ResMut<Assets<Mesh>>,
//!     mut materials: ResMut<Assets<StandardMaterial>>,
//! ) {
//!     let white = materials.add(Color::WHITE);
//!     commands.spawn((Mesh3d(meshes.add(Cuboid::default())), MeshMaterial3d(white.clone()),
//!         Transform::from_xyz(0.0, 0.5, 0.0)));
//!     commands.spawn((Mesh3d(meshes.add(Plane3d::default().mesh().size(8.0, 8.0))),
//!         MeshMaterial3d(white)));
//!     commands.spawn((PointLight::default(), Transform::from_xyz(2.0, 5.0, 1.0), ShadowVolumeLight));
//!     commands.spawn((Camera3d::default(), ShadowVolumes::default(),
//!         Transform::from_xyz(4.0, 5.0, 7.0).looking_at(Vec3::ZERO, Vec3::Y)));
//! }
//! ```
//!
//! Limits, each reported (and logged once) rather than drawn wrong; a light the volumes cannot
//! shadow gets Bevy's shadow maps for that frame:
//! - one active [`ShadowVolumes`] camera (with none or several, every marked light is on its
//!   maps); a 3D camera without it sees the volume lights unshadowed, not darkened;
//! - at most [`MAX_LIGHTS`] lights with volumes, by entity order; perspective cameras only,
//!   without sub-pixel jitter (`TemporalJitter`, as TAA uses), which would misalign the mask by
//!   up to a pixel;
//! - a visible skinned or morphed caster puts every marked light on its maps (volumes would cast
//!   its bind pose; a warning once); with `NotShadowCaster` it is left out instead;
//! - a caster's mesh must be a triangle list with its positions in the main world; one that
//!   cannot be read (render-world-only, NaN) is left out and named, one still loading is
//!   skipped; the others cast as before;
//! - a surface receives volume shadows only where it is in the pre-pass (a candidate); a material
//!   other than `StandardMaterial` does not read the mask;
//! - forward rendering only (not the deferred path); clearcoat and diffuse transmission take
//!   the base layer's share.

mod extract;
mod material;
mod render;

/// The README's code, compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

use std::sync::{Arc, Mutex};

use bevy::prelude::*;

pub use material::{ShadowMask, ShadowVolumeMaterial};
pub use shadowvol_robust_math::Accuracy;

/// The most lights one camera shadows with volumes: the layers of the mask.
pub const MAX_LIGHTS: usize = 8;

/// Marks a mesh entity as a caster where the plugin's [`ShadowCasters`] setting is
/// [`ShadowCasters::Marked`] (the opt-in for large scenes); with the default,
/// [`ShadowCasters::AllMeshes`], every `Mesh3d` casts and the marker changes nothing. On an entity
/// with children (a glTF `WorldAssetRoot`, say) it marks every mesh below it as well. Its mesh
/// needs its positions in the main world (`RenderAssetUsages::MAIN_WORLD`, Bevy's default for
/// meshes it builds and loads), as a triangle list.
#[derive(Component, Reflect, Debug, Default, Clone, Copy, PartialEq, Eq)]
#[reflect(Component, Default, Debug, Clone, PartialEq)]
pub struct ShadowCaster;

/// Which meshes cast shadow volumes: a resource the plugin adds with its default; insert another
/// value to change it.
///
/// In both cases a mesh casts and receives only as Bevy's shadows would have it: it is skipped
/// while its `InheritedVisibility` is false (`Visibility::Hidden`, itself or an ancestor) or its
/// `RenderLayers` do not meet the [`ShadowVolumes`] camera's, one with `NotShadowCaster`
/// receives but does not cast, and one casts for a light only where its `RenderLayers` meet the
/// light's. A mesh that is only outside the camera's frustum still casts
/// (its shadow may fall into view), as with Bevy's shadow maps.
#[derive(Resource, Reflect, Debug, Default, Clone, Copy, PartialEq, Eq)]
#[reflect(Resource, Default, Debug, Clone, PartialEq)]
pub enum ShadowCasters {
    /// Every `Mesh3d` casts (Bevy's habit: opt out with `NotShadowCaster`).
    #[default]
    AllMeshes,
    /// Only meshes marked [`ShadowCaster`] (or below a marked entity) cast and receive; the
    /// others keep `StandardMaterial` and are lit unshadowed by the marked lights. For scenes
    /// whose edge tables would cost too much to build for every mesh.
    Marked,
}

/// How many points sample a marked light with a size (soft shadows): a resource the plugin adds
/// with its default, 16; insert another value to change it.
///
/// A marked `PointLight` or `SpotLight` with `soft_shadows_enabled` and a `radius` over 0 is a
/// disk of that radius (world units), and a marked `DirectionalLight` whose `soft_shadow_size`
/// is `Some` is a cone of directions of half its `SunDisk`'s angular size (the Earth's sun
/// without a `SunDisk`): shadowvol's lights with a size. Each is sampled by this many points,
/// each casting its exact hard shadow, and its mask holds the share of them that sees the pixel,
/// `k / N`, so the penumbra has `N + 1` levels. Every sample costs one more stencil pass.
///
/// The value is rounded up to a power of two, at most [`MAX_SAMPLES`]: the mask adds `1 / N`
/// per sample in `R16Float`, which is exact for a power of two; 1 gives hard shadows.
#[derive(Resource, Reflect, Debug, Clone, Copy, PartialEq, Eq)]
#[reflect(Resource, Default, Debug, Clone, PartialEq)]
pub struct SoftShadowSamples(pub u32);

/// The most samples a light with a size gets (the renderer's plan picks at most as many).
pub const MAX_SAMPLES: u32 = 64;

impl Default for SoftShadowSamples {
    fn default() -> Self {
        Self(16)
    }
}

impl SoftShadowSamples {
    /// The samples a light with a size gets: the setting rounded up to a power of two, from 1
    /// to [`MAX_SAMPLES`].
    #[must_use]
    pub fn per_light(self) -> u32 {
        self.0.clamp(1, MAX_SAMPLES).next_power_of_two()
    }
}

/// Marks a `PointLight`, `SpotLight` or `DirectionalLight` whose shadows are drawn with
/// volumes. While the plugin shadows it, its Bevy shadow maps are off
/// (`shadow_maps_enabled = false`); in a frame where it cannot (too many lights, no usable
/// camera, a skinned caster, ...), they are on, and the reason is logged once and kept in
/// [`ShadowVolumeStats::error`]. Removing the marker gives the light back its own
/// `shadow_maps_enabled`, as it was when the marker was added.
#[derive(Component, Reflect, Debug, Default, Clone, Copy, PartialEq, Eq)]
#[reflect(Component, Default, Debug, Clone, PartialEq)]
#[component(on_remove = extract::restore_own_shadow_maps)]
pub struct ShadowVolumeLight;

/// On a `Camera3d`: draw shadow volumes for this view, in this accuracy mode.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq, Eq)]
#[reflect(Component, Default, Debug, Clone, PartialEq)]
pub struct ShadowVolumes {
    /// How silhouette signs are decided (`Accuracy::Exact` by default: exact signs, closed
    /// volumes, however degenerate the mesh). `Original` is the naive float test whose cracks
    /// the paper measures. Not reflected (`Accuracy` is shadowvol's type, which has no
    /// `Reflect`): a reflected or deserialized `ShadowVolumes` is exact.
    #[reflect(ignore)]
    pub mode: Accuracy,
}

impl Default for ShadowVolumes {
    fn default() -> Self {
        Self {
            mode: Accuracy::Exact,
        }
    }
}

/// What the plugin has done so far, shared by the main and the render world: read it from the
/// main world to watch preparations, frames and errors.
#[derive(Resource, Debug, Clone, Default)]
pub struct ShadowVolumeStats(Arc<Mutex<StatsInner>>);

#[derive(Debug, Default)]
struct StatsInner {
    prepares: u64,
    tables_built: u64,
    tables: usize,
    frames: u64,
    /// Per side (`[main world, render world]`): its current error.
    errors: [Option<String>; 2],
}

/// Which world reports an error: each side sets and clears its own.
#[derive(Debug, Clone, Copy)]
enum Side {
    Main = 0,
    Render = 1,
}

impl ShadowVolumeStats {
    fn with<R>(&self, f: impl FnOnce(&mut StatsInner) -> R) -> R {
        f(&mut self
            .0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner))
    }

    /// How many times the casters were prepared: uploaded to the GPU, all of them (the edge
    /// tables built for that are counted by [`ShadowVolumeStats::tables_built`]). Moving a
    /// caster or a light does not prepare again; adding, removing or changing a caster's mesh
    /// does.
    #[must_use]
    pub fn prepares(&self) -> u64 {
        self.with(|s| s.prepares)
    }

    /// How many edge tables (the welded edges of one mesh, what casting needs) were built on
    /// the CPU so far. One is built per distinct mesh when a caster with that mesh arrives or
    /// the mesh changes; adding or removing a caster builds no other mesh's table.
    #[must_use]
    pub fn tables_built(&self) -> u64 {
        self.with(|s| s.tables_built)
    }

    /// How many edge tables are kept now: one per distinct mesh among the casters (a table is
    /// dropped when no caster uses its mesh any more).
    #[must_use]
    pub fn tables(&self) -> usize {
        self.with(|s| s.tables)
    }

    /// How many frames drew their masks.
    #[must_use]
    pub fn frames(&self) -> u64 {
        self.with(|s| s.frames)
    }

    /// The last error: a mesh that could not be read, a device that lacks what the pass needs,
    /// a camera or light beyond the limits. `None` while all is well. Each error is also logged
    /// once, with `error!`.
    #[must_use]
    pub fn error(&self) -> Option<String> {
        self.with(|s| {
            let e: Vec<&str> = s.errors.iter().flatten().map(String::as_str).collect();
            (!e.is_empty()).then(|| e.join("; "))
        })
    }

    /// Records `message` as `side`'s current error, logging it when it is new.
    fn fail(&self, side: Side, message: String) {
        self.with(|s| {
            let slot = &mut s.errors[side as usize];
            if slot.as_deref() != Some(message.as_str()) {
                error!("shadowvol: {message}");
                *slot = Some(message);
            }
        });
    }

    /// The render world's current error: the pass failed on the device or refused the view.
    fn render_error(&self) -> Option<String> {
        self.with(|s| s.errors[Side::Render as usize].clone())
    }

    /// `side` is well again.
    fn clear(&self, side: Side) {
        self.with(|s| s.errors[side as usize] = None);
    }
}

/// The plugin: adds [`ShadowVolumeMaterial`], the systems that turn marked entities into
/// shadowvol's scene model, and the pass in the `Core3d` schedule. Add it after
/// `DefaultPlugins` (it needs `RenderPlugin` and `PbrPlugin`).
#[derive(Debug, Default, Clone, Copy)]
pub struct ShadowVolumesPlugin;

impl Plugin for ShadowVolumesPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<ShadowCaster>()
            .register_type::<ShadowVolumeLight>()
            .register_type::<ShadowVolumes>()
            .register_type::<ShadowCasters>()
            .register_type::<SoftShadowSamples>()
            .init_resource::<ShadowCasters>()
            .init_resource::<SoftShadowSamples>();
        material::build(app);
        extract::build(app);
        render::build(app);
    }
}
