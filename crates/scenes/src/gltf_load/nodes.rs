//! The node walk: each node's world transform, its mesh as an object, and the scene camera
//! and lights (`KHR_lights_punctual`) it carries.

use super::objects::PendingObject;
use crate::scene::{Scene, SceneLight};
use crate::Camera;
use crate::SceneError;
use glam::{Affine3A, Mat4, Vec3};
use shadowvol_robust_math::Light;
use std::collections::{HashMap, HashSet};

/// One load's walk: the file's buffers, the meshes read so far and the scene being built (its
/// objects are [`PendingObject`]s until the walk ends).
pub(super) struct Loader<'a> {
    pub(super) source_name: &'a str,
    pub(super) document: &'a gltf::Document,
    /// `KHR_draco_mesh_compression` objects of primitives, by (mesh, primitive) index.
    pub(super) draco: &'a HashMap<(usize, usize), serde_json::Value>,
    /// Buffer data by index; `None` for an `EXT_meshopt_compression` fallback buffer.
    pub(super) buffers: &'a [Option<&'a [u8]>],
    /// Decoded `EXT_meshopt_compression` views by view index.
    pub(super) decoded: &'a HashMap<usize, Vec<u8>>,
    /// Indices of the meshes read so far (instances share them).
    pub(super) read_meshes: HashSet<usize>,
    /// The nodes with a mesh, in the walk's order, whose objects are built after the walk.
    pub(super) pending: Vec<PendingObject>,
    pub(super) visited: Vec<bool>,
    /// `KHR_mesh_quantization` is in `extensionsUsed`: integer positions are allowed.
    pub(super) quantization: bool,
    pub(super) notes: Vec<String>,
    pub(super) scene: Scene,
}

/// How messages name a node: its index, and its name where it has one.
fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) => format!("node {} '{n}'", node.index()),
        None => format!("node {}", node.index()),
    }
}
impl Loader<'_> {
    /// A [`SceneError::Gltf`] of the file being loaded at `context`.
    pub(super) fn err(&self, context: String, message: impl Into<String>) -> SceneError {
        SceneError::Gltf {
            file: self.source_name.to_owned(),
            context,
            message: message.into(),
        }
    }

    /// Visits the nodes under `roots` depth-first, pre-order, with a stack (no recursion).
    pub(super) fn walk(&mut self, roots: Vec<gltf::Node>) -> Result<(), SceneError> {
        let mut stack: Vec<(gltf::Node, Affine3A)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Affine3A::IDENTITY))
            .collect();
        while let Some((node, parent)) = stack.pop() {
            let world = self.visit(&node, parent)?;
            let children: Vec<gltf::Node> = node.children().collect();
            for c in children.into_iter().rev() {
                stack.push((c, world));
            }
        }
        Ok(())
    }

    /// Handles one node; returns its world transform.
    fn visit(&mut self, node: &gltf::Node, parent: Affine3A) -> Result<Affine3A, SceneError> {
        let label = node_label(node);
        if std::mem::replace(&mut self.visited[node.index()], true) {
            return Err(self.err(
                label,
                "is reached twice from the scene (the node hierarchy must be a forest: no \
                 cycles, no node with two parents)",
            ));
        }
        let world = self.world_transform(&label, node, parent)?;
        if let Some(mesh) = node.mesh() {
            self.add_object(&label, node, &mesh, world)?;
        }
        if let Some(light) = node.light() {
            self.add_light(&label, &light, world)?;
        }
        if let (Some(cam), None) = (node.camera(), self.scene.camera) {
            self.set_camera(&label, node, &cam, world)?;
        }
        Ok(world)
    }

    /// The node's world transform `parent * local`, checked finite and affine.
    fn world_transform(
        &self,
        label: &str,
        node: &gltf::Node,
        parent: Affine3A,
    ) -> Result<Affine3A, SceneError> {
        let m = Mat4::from_cols_array_2d(&node.transform().matrix());
        if !m.is_finite() {
            return Err(self.err(label.to_owned(), "transform has a NaN or infinite entry"));
        }
        let row3 = m.row(3);
        if row3 != glam::Vec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(self.err(
                label.to_owned(),
                format!("matrix is not affine: its last row is {row3}, expected (0, 0, 0, 1)"),
            ));
        }
        let local = Affine3A::from_mat4(m);
        let world = parent * local;
        if !world.is_finite() {
            return Err(self.err(label.to_owned(), "world transform overflows f32"));
        }
        Ok(world)
    }

    /// Records the node's mesh as an object at `world`, reading the mesh on its first use.
    fn add_object(
        &mut self,
        label: &str,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Affine3A,
    ) -> Result<(), SceneError> {
        let det = world.matrix3.determinant();
        if !det.is_normal() {
            return Err(self.err(
                label.to_owned(),
                format!(
                    "world transform of the mesh is singular or degenerate (determinant \
                     {det:e}): a zero scale flattens the object, and lights cannot be \
                     brought into its frame"
                ),
            ));
        }
        // The first node that uses a mesh reads it; the table is built after the walk.
        let read = if self.read_meshes.insert(mesh.index()) {
            Some(self.read_mesh(label, mesh)?)
        } else {
            None
        };
        let name = node
            .name()
            .or(mesh.name())
            .map_or_else(|| format!("node{}", node.index()), str::to_owned);
        self.pending.push(PendingObject {
            label: label.to_owned(),
            name,
            mesh: mesh.index(),
            read,
            world,
            note_at: self.notes.len(),
        });
        Ok(())
    }

    /// Adds the node's punctual light at `world`, with its emission.
    fn add_light(
        &mut self,
        label: &str,
        light: &gltf::khr_lights_punctual::Light,
        world: Affine3A,
    ) -> Result<(), SceneError> {
        let l = match light.kind() {
            gltf::khr_lights_punctual::Kind::Directional => {
                let z = world.matrix3.z_axis;
                Light::new(z.x, z.y, z.z, 0.0)
            }
            gltf::khr_lights_punctual::Kind::Point
            | gltf::khr_lights_punctual::Kind::Spot { .. } => {
                let t = world.translation;
                Light::new(t.x, t.y, t.z, 1.0)
            }
        }
        .map_err(|e| {
            self.err(
                format!("{label}, light {}", light.index()),
                format!("invalid light: {e}"),
            )
        })?;
        let emission = crate::emission::from_gltf(light, &world)
            .map_err(|m| self.err(format!("{label}, light {}", light.index()), m))?;
        // KHR_lights_punctual has no size: `extras.radius` on the light (or its node) gives one.
        let radius = extras_f32(light.extras(), "radius").unwrap_or(0.0);
        crate::disk::check_radius(l, radius).map_err(|m| {
            self.err(
                format!("{label}, light {}", light.index()),
                format!("extras.radius: {m}"),
            )
        })?;
        self.scene.lights.push(SceneLight {
            light: l,
            emission: Some(emission),
            radius,
        });
        Ok(())
    }

    /// Makes a perspective camera the scene's: eye at the node, looking down `-Z`.
    fn set_camera(
        &mut self,
        label: &str,
        node: &gltf::Node,
        cam: &gltf::Camera,
        world: Affine3A,
    ) -> Result<(), SceneError> {
        let gltf::camera::Projection::Perspective(p) = cam.projection() else {
            return Ok(());
        };
        let eye = Vec3::from(world.translation);
        let forward = -Vec3::from(world.matrix3.z_axis);
        let up = Vec3::from(world.matrix3.y_axis);
        let target =
            extras_vec3(node.extras(), "target").unwrap_or(eye + forward.normalize_or(Vec3::NEG_Z));
        let camera = Camera {
            eye,
            target,
            up: up.normalize_or(Vec3::Y),
            fov_y: p.yfov(),
            near: p.znear(),
        };
        let ok = camera.eye.is_finite()
            && camera.target.is_finite()
            && camera.fov_y.is_finite()
            && camera.fov_y > 0.0
            && camera.near.is_finite()
            && camera.near > 0.0
            && camera.target != camera.eye;
        if !ok {
            return Err(self.err(
                format!("{label}, camera {}", cam.index()),
                "camera is degenerate (needs finite eye and target apart, yfov > 0, znear > 0)",
            ));
        }
        self.scene.camera = Some(camera);
        Ok(())
    }
}

/// The walk's roots: the `scene`'s nodes, else the first scene's, else all root nodes.
pub(super) fn root_nodes(document: &gltf::Document) -> Vec<gltf::Node<'_>> {
    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(s) => s.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            for n in document.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    }
}

/// Reads `extras[key]` as a number (`None` when absent or not a number).
fn extras_f32(extras: &gltf::json::Extras, key: &str) -> Option<f32> {
    let raw = extras.as_ref()?;
    let v: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    v.get(key)?.as_f64().map(|x| x as f32)
}

/// Reads `extras[key]` as a finite `[x, y, z]`.
fn extras_vec3(extras: &gltf::json::Extras, key: &str) -> Option<Vec3> {
    let raw = extras.as_ref()?;
    let v: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    let a = v.get(key)?.as_array()?;
    if a.len() != 3 {
        return None;
    }
    let f = |i: usize| a[i].as_f64().map(|x| x as f32);
    let p = Vec3::new(f(0)?, f(1)?, f(2)?);
    p.is_finite().then_some(p)
}
