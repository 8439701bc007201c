//! The scene model: objects (a shared mesh and a transform), lights, a camera and the effects the
//! scene calls for.

use crate::{Emission, SceneError};
use glam::{Affine3A, DMat4, DVec3, Mat4, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_robust_math::Light;
use shadowvol_silhouette::{SceneObject, TopologyScene};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// One object: a mesh in its own frame, placed in the world by `transform`.
///
/// Several objects may share one mesh (`Arc::ptr_eq`); [`Scene::topology`] then builds its edge
/// table once.
#[derive(Debug, Clone)]
pub struct Object {
    /// A name for messages and reports (the glTF node name, or a generated one).
    pub name: String,
    /// The mesh in object space.
    pub mesh: Arc<Mesh>,
    /// World-from-object transform (`f32`, affine, expected to be invertible).
    pub transform: Affine3A,
}

/// A pinhole camera in world space (right-handed, `y` up by default) with an infinite far
/// plane (shadow volumes need it): the one camera of the workspace, which files and presets fill
/// in and the renderer, the reference and the viewer use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position (world units).
    pub eye: Vec3,
    /// A point the camera looks at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction, must not be parallel to it).
    pub up: Vec3,
    /// Vertical field of view, radians, in `(0, π)`.
    pub fov_y: f32,
    /// Near-plane distance (world units, `> 0`). There is no far plane.
    pub near: f32,
}

/// Why a camera cannot be used (what [`Camera::validate`] found), in words.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidCamera(pub String);

impl Camera {
    /// A camera at `eye` looking at `target`, `y` up, 45° vertical field of view, near plane at
    /// 1/1000 of the eye-target distance.
    #[must_use]
    pub fn look_at(eye: Vec3, target: Vec3) -> Self {
        let d = (target - eye).length().max(1e-6);
        let up = if (target - eye).normalize_or_zero().abs().y > 0.999 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        Self {
            eye,
            target,
            up,
            fov_y: 45f32.to_radians(),
            near: d * 1e-3,
        }
    }

    /// Checks that the camera is usable: finite, eye apart from target, `up` not along the
    /// view direction, `fov_y` in `(0, π)`, `near > 0`.
    ///
    /// # Errors
    /// [`InvalidCamera`] naming the bad field.
    pub fn validate(&self) -> Result<(), InvalidCamera> {
        let finite = self.eye.is_finite()
            && self.target.is_finite()
            && self.up.is_finite()
            && self.fov_y.is_finite()
            && self.near.is_finite();
        if !finite {
            return Err(InvalidCamera(format!(
                "camera has a non-finite component: {self:?}"
            )));
        }
        if self.eye == self.target {
            return Err(InvalidCamera("camera eye equals its target".into()));
        }
        if (self.target - self.eye).cross(self.up).length_squared() == 0.0 {
            return Err(InvalidCamera(
                "camera up is parallel to the view direction".into(),
            ));
        }
        if !(self.fov_y > 0.0 && self.fov_y < std::f32::consts::PI) {
            return Err(InvalidCamera(format!(
                "camera fov_y is {} rad; it must be in (0, π)",
                self.fov_y
            )));
        }
        if self.near <= 0.0 {
            return Err(InvalidCamera(format!(
                "camera near is {}; it must be > 0",
                self.near
            )));
        }
        Ok(())
    }

    /// View matrix (world → camera), `f32`.
    #[must_use]
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up)
    }

    /// Projection with an infinite far plane and depth range `[0, 1]` (points with `w = 0` map
    /// to depth exactly 1), `f32`.
    #[must_use]
    pub fn projection(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective_infinite(self.fov_y, aspect, self.near)
    }

    /// `projection * view`, the matrix every pass uses.
    #[must_use]
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// The same matrices in `f64` (for the reference and the plan).
    #[must_use]
    pub fn view_proj_f64(&self, aspect: f64) -> DMat4 {
        let v = glam::dcamera::rh::view::look_at_mat4(
            self.eye.as_dvec3(),
            self.target.as_dvec3(),
            self.up.as_dvec3(),
        );
        glam::dcamera::rh::proj::directx::perspective_infinite(
            f64::from(self.fov_y),
            aspect,
            f64::from(self.near),
        ) * v
    }

    /// The four corners of the near-plane rectangle in world space (`f64`), counter-clockwise
    /// as seen from the eye: bottom-left, bottom-right, top-right, top-left.
    #[must_use]
    pub fn near_corners(&self, aspect: f64) -> [DVec3; 4] {
        let eye = self.eye.as_dvec3();
        let f = (self.target.as_dvec3() - eye).normalize();
        let r = f.cross(self.up.as_dvec3()).normalize();
        let u = r.cross(f);
        let n = f64::from(self.near);
        let h = n * (f64::from(self.fov_y) * 0.5).tan();
        let w = h * aspect;
        let c = eye + f * n;
        [
            c - r * w - u * h,
            c + r * w - u * h,
            c + r * w + u * h,
            c - r * w + u * h,
        ]
    }

    /// A camera that sees the axis-aligned box `[min, max]` whole, from the direction `from`
    /// (pointing from the box centre towards the eye), with a 45° vertical field of view.
    #[must_use]
    pub fn framing(min: Vec3, max: Vec3, from: Vec3) -> Self {
        let (centre, radius) = box_centre_radius(min, max);
        let radius = radius.max(1e-3);
        let fov_y = 45f32.to_radians();
        let distance = radius / (fov_y * 0.5).sin() * 1.05;
        let dir = from
            .try_normalize()
            .unwrap_or(Vec3::new(0.3, 0.5, 1.0).normalize());
        let up = if dir.cross(Vec3::Y).length_squared() < 1e-6 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        Self {
            eye: centre + dir * distance,
            target: centre,
            up,
            fov_y,
            near: (distance - radius).max(distance * 1e-3) * 0.5,
        }
    }
}

/// The effects a scene calls for; the renderer plans its passes from these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effects {
    /// Cast stencil shadow volumes from every light (false: lighting only).
    pub shadows: bool,
    /// Ambient light level in `[0, 1]` that shadowed pixels keep.
    pub ambient: f32,
    /// The objects never move: silhouettes can be cached while the lights stand still.
    pub static_geometry: bool,
    /// Height of a horizontal receiver plane (`y = ground_y`, facing `+Y`) the renderer should
    /// draw under the objects so shadows have somewhere to fall. It is not an object: it casts
    /// nothing and is not part of silhouette extraction. `None`: no receiver plane.
    pub ground_y: Option<f32>,
}

impl Default for Effects {
    fn default() -> Self {
        Self {
            shadows: true,
            ambient: 0.2,
            static_geometry: true,
            ground_y: None,
        }
    }
}

/// A scene: objects, lights, an optional camera and the effects it calls for.
///
/// Load one from a file with [`Scene::load`], build a preset with [`crate::preset`], or either
/// with [`Scene::from_name_or_path`].
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// A name for reports (the preset name or the file name).
    pub name: String,
    /// The objects, in order (glTF: depth-first node order).
    pub objects: Vec<Object>,
    /// Lights in world space (homogeneous: `w = 1` point, `w = 0` directional towards the light).
    pub lights: Vec<Light>,
    /// What each light emits (glTF `KHR_lights_punctual` colour, intensity, range, cone): empty,
    /// or one per light in the order of `lights`. Empty means the renderer's unit lights (white,
    /// no falloff; presets and `--light`).
    pub emission: Vec<Emission>,
    /// The camera, if the scene has one.
    pub camera: Option<Camera>,
    /// What the renderer should simulate.
    pub effects: Effects,
}

impl Scene {
    /// Total number of input triangles over all objects (instances counted each time).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangles.len()).sum()
    }

    /// Total number of input vertices over all objects (instances counted each time).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.positions.len()).sum()
    }

    /// The topology scene backends prepare: one [`SceneObject`] per object, with the object's
    /// transform. Objects that share a mesh (`Arc::ptr_eq`) share one `Arc<EdgeTable>`.
    ///
    /// # Errors
    /// [`SceneError::Mesh`] naming the object if its mesh is invalid (non-finite position,
    /// index out of range, too large).
    pub fn topology(&self) -> Result<TopologyScene, SceneError> {
        let mut tables: HashMap<*const Mesh, Arc<EdgeTable>> = HashMap::new();
        let mut objects = Vec::with_capacity(self.objects.len());
        for (i, o) in self.objects.iter().enumerate() {
            let key = Arc::as_ptr(&o.mesh);
            let table = match tables.get(&key) {
                Some(t) => Arc::clone(t),
                None => {
                    let t =
                        Arc::new(
                            EdgeTable::build(&o.mesh).map_err(|source| SceneError::Mesh {
                                what: format!("object {i} '{}'", o.name),
                                source,
                            })?,
                        );
                    tables.insert(key, Arc::clone(&t));
                    t
                }
            };
            objects.push(SceneObject {
                name: o.name.clone(),
                table,
                world_from_object: o.transform,
            });
        }
        Ok(TopologyScene { objects })
    }

    /// All objects merged into one world-space mesh: each object's transform is applied to its
    /// positions in `f32` on the host (with [`apply_f32`]), and the objects are concatenated in
    /// order, so vertex `i` of object `k` gets index `(vertices of objects before k) + i`.
    ///
    /// # Errors
    /// [`SceneError::Mesh`] if the result is too large for `u32` indexing or a mesh is invalid.
    pub fn baked_mesh(&self) -> Result<Mesh, SceneError> {
        let mut out = Mesh {
            positions: Vec::with_capacity(self.vertex_count()),
            triangles: Vec::with_capacity(self.triangle_count()),
        };
        for (i, o) in self.objects.iter().enumerate() {
            let moved = transformed(&o.mesh, &o.transform);
            out.append(&moved).map_err(|source| SceneError::Mesh {
                what: format!("baking object {i} '{}'", o.name),
                source,
            })?;
        }
        out.validate().map_err(|source| SceneError::Mesh {
            what: format!("baked mesh of scene '{}'", self.name),
            source,
        })?;
        Ok(out)
    }

    /// This scene with all objects baked into one object (identity transform), keeping lights,
    /// camera and effects.
    ///
    /// # Errors
    /// As [`Scene::baked_mesh`].
    pub fn baked(&self) -> Result<Self, SceneError> {
        Ok(Self {
            name: self.name.clone(),
            objects: vec![Object {
                name: format!("{} (baked)", self.name),
                mesh: Arc::new(self.baked_mesh()?),
                transform: Affine3A::IDENTITY,
            }],
            lights: self.lights.clone(),
            emission: self.emission.clone(),
            camera: self.camera,
            effects: self.effects,
        })
    }

    /// World-space axis-aligned bounds `(min, max)` of all objects' vertices (each object's
    /// corners transformed), or `None` for a scene without vertices.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        (0..self.objects.len())
            .filter_map(|i| self.object_bounds(i))
            .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)))
    }

    /// The scene's camera, or one framing its bounds (from `+x+y+z`-ish) when it has none.
    /// `None` only for a scene without vertices and without camera.
    #[must_use]
    pub fn camera_or_default(&self) -> Option<Camera> {
        self.camera.or_else(|| {
            self.bounds()
                .map(|(lo, hi)| Camera::framing(lo, hi, Vec3::new(0.6, 0.5, 1.0)))
        })
    }
}

/// Applies a world-from-object transform to one point in `f32`: the one definition used by
/// [`Scene::baked_mesh`] and the glTF loader, so baked positions are reproducible bit for bit.
#[inline]
#[must_use]
pub fn apply_f32(t: &Affine3A, p: Vec3) -> Vec3 {
    t.transform_point3(p)
}

/// `mesh` with `t` applied to every position in `f32` (triangles unchanged). The identity leaves
/// positions bit-identical.
#[must_use]
pub fn transformed(mesh: &Mesh, t: &Affine3A) -> Mesh {
    if *t == Affine3A::IDENTITY {
        return mesh.clone();
    }
    Mesh {
        positions: mesh.positions.iter().map(|&p| apply_f32(t, p)).collect(),
        triangles: mesh.triangles.clone(),
    }
}

/// Axis-aligned bounds of a mesh's positions, `None` when it has none.
#[must_use]
pub fn mesh_bounds(mesh: &Mesh) -> Option<(Vec3, Vec3)> {
    let first = *mesh.positions.first()?;
    Some(
        mesh.positions
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    )
}

/// The centre and half the diagonal of the box `[lo, hi]`, computed so that neither overflows
/// while the result fits in `f32`: the centre as `lo / 2 + hi / 2` and the half diagonal in
/// `f64` (an `f32` [`Vec3::length`] overflows for extents beyond about 1.8e19). The half
/// diagonal is infinite only when it exceeds `f32::MAX`.
///
/// ```
/// use glam::Vec3;
/// // The extent, 6e38, is beyond f32::MAX: `hi - lo` would be infinite.
/// let (c, r) = shadowvol_scenes::box_centre_radius(Vec3::new(-3e38, 0.0, 0.0), Vec3::new(3e38, 0.0, 0.0));
/// assert_eq!(c, Vec3::ZERO);
/// assert_eq!(r, 3e38);
/// ```
#[must_use]
pub fn box_centre_radius(lo: Vec3, hi: Vec3) -> (Vec3, f32) {
    let centre = lo * 0.5 + hi * 0.5;
    let radius = (hi.as_dvec3() - lo.as_dvec3()).length() * 0.5;
    (centre, radius as f32)
}

pub(crate) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}
