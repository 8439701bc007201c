//! Headless stencil shadow volumes (wgpu) from silhouette multiplicities, with a per-frame plan
//! and a ray-traced reference.
//!
//! * [`Renderer`]: a stateful renderer. Each [`Renderer::render`] call does a depth pre-pass with
//!   ambient light, then per light a stencil pass (two-sided, wrapping increment/decrement,
//!   volumes extruded to infinity with `w = 0` under an infinite far plane, depth clamp where the
//!   device has it) and an additive Lambert pass where the stencil is 0.
//! * [`plan`]: per (light, object) the cheapest correct technique: culled, z-pass (when the
//!   near-clip volume test proves the camera is outside the object's shadow volume) or z-fail
//!   with caps (no back cap for directional lights). Silhouettes are reused from the previous
//!   frame when neither the light nor the object moved.
//! * [`volume`]: shadow-volume geometry. Sides are `|m|` quads per silhouette edge oriented by
//!   the sign of `m`; caps use the same per-triangle sign as the accuracy mode
//!   ([`shadowvol_robust_math::triangle_sign`] on the canonical triangle), so caps and sides
//!   always meet in the consistent modes.
//! * [`reference`](mod@reference): a CPU ray caster with a BVH (rayon-parallel) that decides, from each
//!   pixel's surface point, whether each light is visible, and the artifact metric.
//!
//! ```no_run
//! use shadowvol_renderer::{Camera, RenderObject, RenderOptions, RenderScene, Renderer, reference};
//! use shadowvol_mesh_topology::Mesh;
//! use shadowvol_robust_math::Light;
//! use glam::{Affine3A, Vec3};
//! use std::sync::Arc;
//!
//! // A floor and a tetrahedron above it, lit from above.
//! let floor = Mesh::new(
//!     vec![Vec3::new(-4., 0., -4.), Vec3::new(4., 0., -4.), Vec3::new(4., 0., 4.), Vec3::new(-4., 0., 4.)],
//!     vec![[0, 2, 1], [0, 3, 2]],
//! ).unwrap();
//! let tet = Mesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::Y],
//!     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! ).unwrap();
//! let scene = RenderScene {
//!     objects: vec![
//!         RenderObject::new("floor", Arc::new(floor), Affine3A::IDENTITY),
//!         RenderObject::new("tet", Arc::new(tet), Affine3A::from_translation(Vec3::Y)),
//!     ],
//!     lights: vec![Light::point(Vec3::new(0.5, 6.0, 0.5))],
//!     emission: Vec::new(),
//!     camera: Camera::look_at(Vec3::new(3., 5., 6.), Vec3::ZERO),
//!     ambient: 0.15,
//! };
//! let backend = Box::new(shadowvol_cpu::CpuBackend::new());
//! let mut renderer = Renderer::new(backend, RenderOptions::new(128, 128)).unwrap();
//! let frame = renderer.render(&scene).unwrap();
//! frame.save_png("out.png").unwrap();
//! let cmp = reference::compare(&frame);
//! println!("artifact pixels: {}", cmp.artifact_pixels);
//! ```

/// The README's code, compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

mod gpu;
pub mod hard;
pub mod lighting;
pub mod occlusion;
pub mod plan;
pub mod reference;
mod renderer;
pub mod resident;
pub mod volume;

pub use lighting::Exposure;
pub use plan::{PlanEntry, PlanPolicy, SilhouetteSource, Technique};
pub use renderer::{Frame, FrameTime, Pipeline, RenderOptions, Renderer, Timings};
pub use shadowvol_robust_math::{Accuracy, Light};
/// The one camera type of the workspace (defined in `shadowvol-scenes`, which files and presets
/// fill in).
pub use shadowvol_scenes::{Camera, InvalidCamera};

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::{Mesh, MeshError};
use shadowvol_silhouette::BackendError;
use std::sync::Arc;

/// One object to render: a mesh (object space), where it is, and its colour.
#[derive(Debug, Clone)]
pub struct RenderObject {
    /// Name for the plan and messages.
    pub name: String,
    /// Triangles in object space. The renderer welds it and builds its edge table once per
    /// distinct `Arc` (pointer identity), and caches silhouettes for it.
    pub mesh: Arc<Mesh>,
    /// World-from-object transform (must be invertible).
    pub world_from_object: Affine3A,
    /// Diffuse colour, linear RGB in `[0, 1]`.
    pub albedo: [f32; 3],
    /// False for a receiver only (a ground plane): drawn and lit, but it casts no shadow, has no
    /// silhouette and is not in the reference's occluders.
    pub casts_shadows: bool,
}

impl RenderObject {
    /// An object with a light grey albedo.
    #[must_use]
    pub fn new(name: impl Into<String>, mesh: Arc<Mesh>, world_from_object: Affine3A) -> Self {
        Self {
            name: name.into(),
            mesh,
            world_from_object,
            albedo: [0.8, 0.8, 0.8],
            casts_shadows: true,
        }
    }

    /// A receiver-only square (two triangles) centred at `centre` with unit normal-ish `normal`
    /// and half-size `half`: it is drawn and lit but casts no shadow.
    #[must_use]
    pub fn receiver_plane(name: impl Into<String>, centre: Vec3, normal: Vec3, half: f32) -> Self {
        let n = normal.normalize_or(Vec3::Y);
        let helper = if n.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
        let u = n.cross(helper).normalize() * half;
        let v = n.cross(u);
        let positions = vec![
            centre - u - v,
            centre + u - v,
            centre + u + v,
            centre - u + v,
        ];
        let mesh = Mesh {
            positions,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        Self {
            name: name.into(),
            mesh: Arc::new(mesh),
            world_from_object: Affine3A::IDENTITY,
            albedo: [0.75, 0.72, 0.65],
            casts_shadows: false,
        }
    }
}

/// Everything one frame needs.
#[derive(Debug, Clone)]
pub struct RenderScene {
    /// Objects; each is a shadow caster and a receiver.
    pub objects: Vec<RenderObject>,
    /// Lights in world space (point `w = 1`, directional `w = 0`).
    pub lights: Vec<Light>,
    /// What each light emits: empty (every light a unit light, see [`lighting`]) or one per
    /// light, in the order of `lights`.
    pub emission: Vec<shadowvol_scenes::Emission>,
    /// The camera.
    pub camera: Camera,
    /// Ambient factor in `[0, 1]` applied to the albedo in the pre-pass.
    pub ambient: f32,
}

impl RenderScene {
    /// Converts a [`shadowvol_scenes::Scene`]: its objects, lights, camera (or a framing
    /// default), ambient, and its ground plane (`effects.ground_y`) as a receiver-only object.
    /// With `effects.shadows == false` every object becomes receiver-only.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a scene without objects.
    pub fn from_scene(scene: &shadowvol_scenes::Scene) -> Result<Self, RenderError> {
        let cam = scene.camera_or_default().ok_or_else(|| {
            RenderError::InvalidInput(format!("scene {:?} has no objects to render", scene.name))
        })?;
        let mut objects: Vec<RenderObject> = scene
            .objects
            .iter()
            .map(|o| {
                let mut r = RenderObject::new(o.name.clone(), o.mesh.clone(), o.transform);
                r.casts_shadows = scene.effects.shadows;
                r
            })
            .collect();
        let mut out = Self {
            objects: Vec::new(),
            lights: scene.lights.clone(),
            emission: scene.emission.clone(),
            camera: cam,
            ambient: scene.effects.ambient.clamp(0.0, 1.0),
        };
        out.objects.append(&mut objects);
        if let (Some(y), Some((lo, hi))) = (scene.effects.ground_y, out.bounds()) {
            let (c, r) = shadowvol_scenes::box_centre_radius(lo, hi);
            let half = (2.0 * r).max(1e-3) * 3.0;
            out.objects.push(RenderObject::receiver_plane(
                "ground",
                Vec3::new(c.x, y, c.z),
                Vec3::Y,
                half,
            ));
        }
        Ok(out)
    }

    /// Adds a receiver-only backdrop behind the scene as seen from the first light, so that
    /// shadows have somewhere to fall (used for the `hard-*` scenes, which have no ground).
    /// Does nothing without lights or objects.
    pub fn add_backdrop(&mut self) {
        let (Some(light), Some((lo, hi))) = (self.lights.first(), self.bounds()) else {
            return;
        };
        let (c, r) = shadowvol_scenes::box_centre_radius(lo, hi);
        let r = r.max(1e-3);
        let l = light.to_array();
        let away = if l[3] == 0.0 {
            -Vec3::new(l[0], l[1], l[2])
        } else {
            c - Vec3::new(l[0], l[1], l[2]) / l[3]
        };
        let away = away.normalize_or(Vec3::NEG_Y);
        self.objects.push(RenderObject::receiver_plane(
            "backdrop",
            c + away * (r * 1.5),
            -away,
            r * 6.0,
        ));
    }

    /// World-space bounding box of all objects (`f32` transform of every vertex), or `None`
    /// for an empty scene.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut any = false;
        for o in &self.objects {
            for p in &o.mesh.positions {
                let w = o.world_from_object.transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
                any = true;
            }
        }
        any.then_some((lo, hi))
    }
}

/// Errors from rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No usable GPU adapter (install a Vulkan driver, for example Mesa lavapipe).
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
    /// The device failed (out of memory, validation, lost).
    #[error("GPU device error: {0}")]
    Device(String),
    /// The silhouette backend failed.
    #[error("silhouette backend: {0}")]
    Backend(#[from] BackendError),
    /// An object's mesh is invalid.
    #[error("object {object:?}: {source}")]
    Mesh {
        /// Object name.
        object: String,
        /// What is wrong.
        source: MeshError,
    },
    /// The device lacks a feature, capability or limit the GPU pipeline needs (named).
    #[error("unsupported device: {0}")]
    Unsupported(String),
    /// Bad parameters (size, camera, light).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// Writing an image failed.
    #[error("image {path}: {message}")]
    Image {
        /// The file.
        path: String,
        /// What failed.
        message: String,
    },
}

impl From<InvalidCamera> for RenderError {
    fn from(e: InvalidCamera) -> Self {
        RenderError::InvalidInput(e.0)
    }
}
