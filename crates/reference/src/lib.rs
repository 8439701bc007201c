//! The exact ray-cast reference and the artifact metric for shadowvol's renders.
//!
//! It reads the scene model ([`shadowvol_scenes::Scene`]) and what a raster produced per pixel
//! (a [`Shot`]: surface ids, the per-light stencil, the image), never a renderer's own types, so
//! any pipeline (host, GPU-resident, shadow maps) is measured by the same code.
//!
//! For every covered pixel, the rasterized ids name the surface and triangle the pre-pass kept.
//! The surface point is the intersection of the pixel-centre ray (from the same camera, in
//! `f64`) with that triangle's plane; that `f64` point is the reference's input. From it, a
//! shadow segment goes to each light (to a point light; towards a directional one, a ray)
//! through a BVH over all world caster triangles (the `f32` positions every pipeline draws,
//! [`shadowvol_scenes::Surface::world_positions`]), skipping the triangle itself. Every caster
//! whose box the segment reaches is decided exactly ([`occlusion`]): it blocks when the surface
//! point and the light lie strictly on opposite sides of its plane and the line through them
//! meets the closed triangle. A light in a caster's plane (edge-on) or on the caster does not
//! block it, as the volumes' sign 0 casts nothing. Run in parallel with rayon.
//!
//! Per pixel and light the state is background, unlit (the surface faces away from the light,
//! the light adds less than one 8-bit step there ([`faces_light`]), or the light is blocked) or
//! lit. [`Comparison::geometric_artifact_pixels`] repeats the count with the geometric facing
//! ([`faces_light_geometric`], any `cos θ > 0`), where rasterized volumes z-fight with faces the
//! light grazes even for exact silhouettes (see the crate README). The raster state uses the same
//! surface point and facing and the stencil (0 = lit). A pixel is an *artifact* when, for some
//! light, the raster state differs from the reference, the reference state is the same over
//! the pixel's 3×3 neighbourhood (that is, the pixel is more than one pixel away from a reference
//! shadow boundary), and no shadow boundary of that light crosses the pixel's footprint (its
//! square seen on the plane of its triangle; decided exactly, the footprint rule, see the crate
//! README); [`Comparison::boundary_pixels`] counts the differences within one pixel of a
//! boundary or with one crossing the footprint ([`Comparison::footprint_boundary_pixels`] those
//! only the footprint rule found), and [`Comparison::undecidable_pixels`] the pixels the
//! reference could not decide.
//!
//! ```
//! use shadowvol_reference::{compare, Shot};
//! use shadowvol_scenes::preset;
//!
//! // A frame whose every pixel is background: nothing to compare, nothing wrong.
//! let scene = preset("hard-tetrahedron")?;
//! let camera = scene.camera_or_default().unwrap();
//! let (w, h) = (8, 8);
//! let ids = vec![[0u32; 2]; w * h];
//! let stencil = vec![vec![0u8; w * h]; scene.lights.len()];
//! let rgba = vec![0u8; 4 * w * h];
//! let colors = vec![[0.5f32; 3]; scene.lights.len()];
//! let shot = Shot::new(&scene, camera, w as u32, h as u32, &rgba, &ids, &stencil, &colors);
//! let cmp = compare(&shot);
//! assert_eq!((cmp.artifact_pixels, cmp.covered_pixels), (0, 0));
//! # Ok::<(), shadowvol_scenes::SceneError>(())
//! ```

/// The README's code, compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

mod bvh;
mod compare;
mod footprint;
pub mod occlusion;
pub mod soft;
mod states;

pub use bvh::Bvh;
pub use compare::{
    compare, compare_with, diff_image, save_diff, shading_check, shadow_pixels, Comparison, Rule,
    ShadingCheck,
};
pub use soft::{
    compare_visibility, compare_with_reference, disk_visibility, polygon_disk_area,
    visibility_reference, visibility_reference_with, Integration, SoftCasters, SoftComparison,
    SoftReference, Visibility,
};
pub use states::{
    faces_light, faces_light_geometric, light_attenuation, raster_states, raster_states_geometric,
    reference_states, reference_states_geometric, surface_points, SurfacePoint,
};

use glam::Vec3;
use shadowvol_scenes::{Camera, Scene, Surface};
use std::sync::OnceLock;

/// `t`'s ids in the canonical (ascending) vertex order every pipeline draws in.
fn canonical(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Per-pixel state for one light.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum PixelState {
    /// No surface.
    Background = 0,
    /// Surface facing away from the light or blocked.
    Unlit = 1,
    /// Surface lit.
    Lit = 2,
    /// Reference only: the answer hangs on the surface point's last `f64` bits: no caster
    /// blocks, but one touches the surface point while the shadow ray grazes its plane into it
    /// ([`occlusion::Crossing::Undecidable`]). Never counted as an artifact.
    Uncertain = 3,
}

/// One rendered frame as the reference reads it: the scene it drew (borrowed), the camera, and
/// the image with its per-pixel data. Build it with [`Shot::new`].
#[derive(Debug, Clone)]
pub struct Shot<'a> {
    /// The scene that was drawn: surfaces ([`Scene::surfaces`], whose order numbers the ids),
    /// lights with their emission, the ambient level.
    pub scene: &'a Scene,
    /// The camera the frame was drawn from.
    pub camera: Camera,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 pixels, top row first (for the shading check and the difference image).
    pub rgba: &'a [u8],
    /// Per pixel `[surface + 1, triangle within the surface's table]`; `[0, _]` is background.
    pub ids: &'a [[u32; 2]],
    /// Per light, per pixel: the stencil after the light's stencil pass (0 = lit by the
    /// volumes; for a shadow map, 0 where the map says lit).
    pub stencil: &'a [Vec<u8>],
    /// Per light: the colour times gain the lit pass multiplied by `albedo × attenuation ×
    /// cos θ` (linear RGB).
    pub light_colors: &'a [[f32; 3]],
    /// The scene's surfaces, in order.
    surfaces: Vec<Surface<'a>>,
    /// Per surface: its world triangles in canonical vertex order, built on first need (the
    /// reference's BVH); one pixel's triangle is computed alone ([`Shot::triangle`]).
    triangles: OnceLock<Vec<Vec<[Vec3; 3]>>>,
}

impl<'a> Shot<'a> {
    /// A shot of `scene` from `camera`, `width` × `height` pixels. The world triangles are
    /// computed from the scene in `f32`, as the pipelines draw them, when they are asked for.
    ///
    /// # Panics
    /// Panics if the per-pixel slices are not `width × height` long (`rgba` four times that),
    /// or `stencil` and `light_colors` do not have one entry per light of `scene`.
    #[must_use]
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        scene: &'a Scene,
        camera: Camera,
        width: u32,
        height: u32,
        rgba: &'a [u8],
        ids: &'a [[u32; 2]],
        stencil: &'a [Vec<u8>],
        light_colors: &'a [[f32; 3]],
    ) -> Self {
        let px = width as usize * height as usize;
        assert_eq!(ids.len(), px, "one id per pixel");
        assert_eq!(rgba.len(), 4 * px, "four bytes per pixel");
        assert_eq!(stencil.len(), scene.lights.len(), "one stencil per light");
        assert!(
            stencil.iter().all(|s| s.len() == px),
            "one stencil value per pixel"
        );
        assert_eq!(
            light_colors.len(),
            scene.lights.len(),
            "one colour per light"
        );
        Self {
            scene,
            camera,
            width,
            height,
            rgba,
            ids,
            stencil,
            light_colors,
            surfaces: scene.surfaces().collect(),
            triangles: OnceLock::new(),
        }
    }

    /// Per surface: its world triangles (the `f32` positions drawn), canonical vertex order.
    /// Built on the first call (36 bytes a triangle), kept for the next.
    #[must_use]
    pub fn triangles(&self) -> &[Vec<[Vec3; 3]>] {
        self.triangles.get_or_init(|| {
            self.surfaces
                .iter()
                .map(|s| {
                    let world = s.world_positions();
                    s.table
                        .triangles
                        .iter()
                        .map(|&t| canonical(t).map(|v| world[v as usize]))
                        .collect()
                })
                .collect()
        })
    }

    /// Triangle `t` of surface `surface` as [`Shot::triangles`] holds it (the same bits),
    /// computed alone; `None` past the last surface or triangle.
    #[must_use]
    pub fn triangle(&self, surface: usize, t: usize) -> Option<[Vec3; 3]> {
        let s = self.surfaces.get(surface)?;
        let tri = *s.table.triangles.get(t)?;
        Some(canonical(tri).map(|v| s.world_position(v)))
    }

    /// Triangles of each surface.
    #[must_use]
    pub fn triangle_counts(&self) -> Vec<usize> {
        self.surfaces
            .iter()
            .map(|s| s.table.triangles.len())
            .collect()
    }

    /// Light `li`'s homogeneous vector.
    #[must_use]
    pub fn light(&self, li: usize) -> [f32; 4] {
        self.scene.lights[li].light.to_array()
    }

    /// Whether surface `i` casts shadows.
    #[must_use]
    pub fn casts_shadows(&self, i: usize) -> bool {
        self.scene
            .surfaces()
            .nth(i)
            .is_some_and(|s| s.casts_shadows)
    }

    /// Surface `i`'s albedo, `None` past the last surface.
    #[must_use]
    pub fn albedo(&self, i: usize) -> Option<[f32; 3]> {
        self.surfaces.get(i).map(|s| s.albedo)
    }

    /// The ambient factor of the pre-pass, `albedo × ambient` (the scene's, clamped to `[0, 1]`).
    #[must_use]
    pub fn ambient(&self) -> f32 {
        self.scene.effects.ambient.clamp(0.0, 1.0)
    }

    /// The image as an `image` buffer.
    ///
    /// # Panics
    /// Never for a shot made by [`Shot::new`] (the size was checked there).
    #[must_use]
    pub fn image(&self) -> image::RgbaImage {
        image::RgbaImage::from_raw(self.width, self.height, self.rgba.to_vec())
            .expect("size checked in Shot::new")
    }
}
