//! The host's copy of where every surface is: world positions (`f32`, as drawn) and world boxes,
//! computed when a surface's table or transform changes and kept otherwise. The plan reads it
//! every frame; the host pipeline builds its volumes from it.

use crate::RenderError;
use glam::{Affine3A, DVec3, Vec3};
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_scenes::Scene;
use std::sync::Arc;

/// One surface's world data.
#[derive(Debug, Clone)]
pub struct WorldSurface {
    table: Arc<EdgeTable>,
    transform: Affine3A,
    /// The table's positions in world space ([`shadowvol_scenes::Surface::world_positions`]).
    pub positions: Vec<Vec3>,
    /// The box `(lo, hi)` of `positions`, in `f64`.
    pub bounds: (DVec3, DVec3),
}

impl WorldSurface {
    /// The surface's triangles (ids into [`WorldSurface::positions`]).
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.table.triangles
    }
}

/// What changed in the last [`World::sync`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct WorldChanges {
    /// True when the surfaces are not those of the previous sync (added, removed, or another
    /// table): the pipelines prepare the scene again.
    pub surfaces: bool,
    /// Per surface: its world positions changed (new table or new transform).
    pub moved: Vec<bool>,
}

impl WorldChanges {
    /// True when something moved or the surfaces changed.
    #[must_use]
    pub fn any(&self) -> bool {
        self.surfaces || self.moved.iter().any(|&m| m)
    }
}

/// World positions and boxes of every surface of a scene ([`Scene::surfaces`] order).
#[derive(Debug, Clone, Default)]
pub struct World {
    surfaces: Vec<WorldSurface>,
    bounds: Option<(Vec3, Vec3)>,
}

impl World {
    /// The surfaces' world data.
    #[must_use]
    pub fn surfaces(&self) -> &[WorldSurface] {
        &self.surfaces
    }

    /// The box `(lo, hi)` of every surface's world positions, `None` without any.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.bounds
    }

    /// Brings the world data in line with `scene`: surfaces whose table (`Arc::ptr_eq`) or
    /// transform changed get new positions; the others keep theirs.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] naming the object whose transform is not finite and
    /// invertible.
    pub fn sync(&mut self, scene: &Scene) -> Result<WorldChanges, RenderError> {
        let n = scene.surfaces().len();
        let mut changes = WorldChanges {
            surfaces: self.surfaces.len() != n,
            moved: vec![false; n],
        };
        self.surfaces.truncate(n);
        for (i, s) in scene.surfaces().enumerate() {
            let t = s.world_from_object;
            if !t.is_finite() || t.matrix3.determinant() == 0.0 {
                return Err(RenderError::InvalidInput(format!(
                    "object {:?}: transform is not finite and invertible",
                    s.name
                )));
            }
            let same_table = self
                .surfaces
                .get(i)
                .is_some_and(|w| Arc::ptr_eq(&w.table, s.table));
            if same_table && self.surfaces[i].transform == t {
                continue;
            }
            changes.surfaces |= !same_table;
            changes.moved[i] = true;
            let positions = s.world_positions();
            let bounds = positions
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p.as_dvec3()), hi.max(p.as_dvec3()))
                });
            let w = WorldSurface {
                table: Arc::clone(s.table),
                transform: t,
                positions,
                bounds,
            };
            if i < self.surfaces.len() {
                self.surfaces[i] = w;
            } else {
                self.surfaces.push(w);
            }
        }
        if changes.any() {
            // The f64 boxes hold f32 values exactly, so this is the f32 box.
            self.bounds = self
                .surfaces
                .iter()
                .filter(|w| !w.positions.is_empty())
                .map(|w| (w.bounds.0.as_vec3(), w.bounds.1.as_vec3()))
                .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)));
        }
        Ok(changes)
    }
}
