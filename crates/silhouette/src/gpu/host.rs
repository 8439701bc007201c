//! What the host reads of a scene whose flat layouts live on a device: [`HostScene`], the
//! questions the host's exact decisions ask, answered by a [`SceneLayout`] in host memory or by
//! a [`SceneIndex`], which reads the scene's own edge tables and keeps only each object's first
//! edge, OV slot and triangle in the flat numbering.

use super::SceneLayout;
use crate::TopologyScene;
use shadowvol_mesh_topology::EdgeTable;
use std::ops::Range;
use std::sync::Arc;

/// The flat scene as the host's exact decisions read it: global edges, their OV slots, and
/// object-space positions.
pub trait HostScene {
    /// Number of edges (all objects).
    fn edge_count(&self) -> usize;
    /// The OV slots of global edge `e`.
    ///
    /// # Panics
    /// If `e >= edge_count()`.
    fn ov_slots(&self, e: usize) -> Range<usize>;
    /// The object-space positions of global edge `e`'s ends `(A, B)`, and its object.
    ///
    /// # Panics
    /// If `e >= edge_count()`.
    fn edge_points(&self, e: usize) -> ([f32; 3], [f32; 3], usize);
    /// The object-space position of the opposite vertex in OV slot `k` of global edge `e`.
    ///
    /// # Panics
    /// If `k` is not one of `ov_slots(e)`.
    fn ov_point(&self, e: usize, k: usize) -> [f32; 3];
}

impl HostScene for SceneLayout {
    fn edge_count(&self) -> usize {
        SceneLayout::edge_count(self)
    }
    fn ov_slots(&self, e: usize) -> Range<usize> {
        SceneLayout::ov_slots(self, e)
    }
    fn edge_points(&self, e: usize) -> ([f32; 3], [f32; 3], usize) {
        let (a, b, object) = self.edge(e);
        (self.position(a), self.position(b), object as usize)
    }
    fn ov_point(&self, _e: usize, k: usize) -> [f32; 3] {
        self.position(self.ovs[k])
    }
}

/// A scene's objects in the flat numbering of [`SceneLayout`] and
/// [`TableLayout`](super::TableLayout), read from their edge tables: each object's first
/// global edge, OV slot and triangle (24 bytes an object) beside the tables it shares with the
/// scene. A backend that keeps this instead of the layouts holds no copy of the scene on the
/// host once the layouts are uploaded.
#[derive(Debug, Clone)]
pub struct SceneIndex {
    tables: Vec<Arc<EdgeTable>>,
    /// Per object and one past the last: first global edge.
    edges: Vec<usize>,
    /// Per object and one past the last: first global OV slot.
    slots: Vec<usize>,
    /// Per object and one past the last: first global triangle.
    tris: Vec<usize>,
}

impl SceneIndex {
    /// The index of `scene`, in the numbering [`SceneLayout::build`] and
    /// [`TableLayout::build`](super::TableLayout::build) give it.
    #[must_use]
    pub fn new(scene: &TopologyScene) -> Self {
        let prefix = |f: fn(&EdgeTable) -> usize| {
            std::iter::once(0)
                .chain(scene.objects.iter().scan(0, |sum, o| {
                    *sum += f(&o.table);
                    Some(*sum)
                }))
                .collect()
        };
        Self {
            tables: scene.objects.iter().map(|o| Arc::clone(&o.table)).collect(),
            edges: prefix(|t| t.edges.len()),
            slots: prefix(|t| t.ov_refs.len()),
            tris: prefix(|t| t.triangles.len()),
        }
    }

    /// Heap bytes of the index itself (the tables belong to the scene).
    #[must_use]
    pub fn heap_bytes(&self) -> u64 {
        crate::vec_bytes(&self.tables)
            + crate::vec_bytes(&self.edges)
            + crate::vec_bytes(&self.slots)
            + crate::vec_bytes(&self.tris)
    }

    /// Number of edges (all objects).
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges.last().copied().unwrap_or(0)
    }

    /// Number of OV slots (all objects): the length of
    /// [`SceneLayout::ovs`](super::SceneLayout::ovs).
    #[must_use]
    pub fn slot_count(&self) -> usize {
        self.slots.last().copied().unwrap_or(0)
    }

    /// Number of objects.
    #[must_use]
    pub fn object_count(&self) -> usize {
        self.tables.len()
    }

    /// Number of triangles (all objects).
    #[must_use]
    pub fn tri_count(&self) -> usize {
        self.tris.last().copied().unwrap_or(0)
    }

    /// The object that global index `g` falls in, given the per-object starts `starts`.
    fn object_of(starts: &[usize], g: usize) -> usize {
        starts.partition_point(|&s| s <= g) - 1
    }

    /// The object of global edge `e` and the edge's index in that object's table.
    fn local_edge(&self, e: usize) -> (usize, usize) {
        let o = Self::object_of(&self.edges, e);
        (o, e - self.edges[o])
    }

    /// The three `(global edge, global OV slot)` pairs of global triangle `t`, in slot order,
    /// found in its table: the edge by binary search, the slot among the edge's
    /// references. `None` when `t` is out of range or the table lacks one of them (a table not
    /// made by [`EdgeTable::build`]).
    #[must_use]
    pub fn edge_slots(&self, t: usize) -> Option<[(u32, u32); 3]> {
        if t >= self.tri_count() {
            return None;
        }
        let o = Self::object_of(&self.tris, t);
        let (table, local) = (&self.tables[o], t - self.tris[o]);
        let tri = table.triangles[local];
        let mut pairs = [(0u32, 0u32); 3];
        for (i, pair) in pairs.iter_mut().enumerate() {
            let e = table.edge_index(tri[i], tri[(i + 1) % 3])? as usize;
            let r = table.ov_offsets[e] as usize;
            let j = table
                .ov_refs_of(e)
                .iter()
                .position(|&x| EdgeTable::ov_triangle(x) as usize == local)?;
            *pair = (
                u32::try_from(self.edges[o] + e).ok()?,
                u32::try_from(self.slots[o] + r + j).ok()?,
            );
        }
        pairs.sort_unstable_by_key(|p| p.1);
        Some(pairs)
    }
}

impl HostScene for SceneIndex {
    fn edge_count(&self) -> usize {
        SceneIndex::edge_count(self)
    }
    fn ov_slots(&self, e: usize) -> Range<usize> {
        let (o, local) = self.local_edge(e);
        let t = &self.tables[o];
        let base = self.slots[o];
        base + t.ov_offsets[local] as usize..base + t.ov_offsets[local + 1] as usize
    }
    fn edge_points(&self, e: usize) -> ([f32; 3], [f32; 3], usize) {
        let (o, local) = self.local_edge(e);
        let t = &self.tables[o];
        let [a, b] = t.edges[local];
        (
            t.positions[a as usize].to_array(),
            t.positions[b as usize].to_array(),
            o,
        )
    }
    fn ov_point(&self, e: usize, k: usize) -> [f32; 3] {
        let (o, _) = self.local_edge(e);
        let t = &self.tables[o];
        let v = t.ov_vertex(t.ov_refs[k - self.slots[o]]);
        t.positions[v as usize].to_array()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::TableLayout;
    use glam::{Affine3A, Vec3};
    use shadowvol_test_support::shapes;

    /// Two objects sharing a table and a third of its own, placed apart.
    fn scene() -> TopologyScene {
        let a = Arc::new(EdgeTable::build(&shapes::uv_sphere_y(6, 5, 1.0)).unwrap());
        let b = Arc::new(EdgeTable::build(&shapes::tetrahedron(1.0)).unwrap());
        let mut s = TopologyScene::single(EdgeTable::clone(&a));
        s.objects[0].table = Arc::clone(&a);
        for (i, t) in [a, b].into_iter().enumerate() {
            let mut o = s.objects[0].clone();
            o.table = t;
            o.world_from_object = Affine3A::from_translation(Vec3::X * (3.0 + i as f32));
            s.objects.push(o);
        }
        s
    }

    #[test]
    fn the_index_answers_as_the_layout_does() {
        let scene = scene();
        let layout = SceneLayout::build(&scene, "t").unwrap();
        let tables = TableLayout::build(&scene, "t").unwrap();
        let index = SceneIndex::new(&scene);
        assert_eq!(HostScene::edge_count(&index), layout.edge_count());
        assert_eq!(index.object_count(), layout.object_count());
        assert_eq!(index.slot_count(), layout.ovs.len());
        assert_eq!(index.tri_count(), tables.tri_count());
        for e in 0..layout.edge_count() {
            assert_eq!(index.ov_slots(e), layout.ov_slots(e), "edge {e}");
            assert_eq!(index.edge_points(e), layout.edge_points(e), "edge {e}");
            for k in layout.ov_slots(e) {
                assert_eq!(
                    index.ov_point(e, k),
                    layout.ov_point(e, k),
                    "edge {e} slot {k}"
                );
            }
        }
        // Each slot's triangle, from the references the kernels read, in slot order.
        let mut slots = vec![Vec::new(); tables.tri_count()];
        for e in 0..tables.edge_count() {
            for k in tables.ov_slots(e) {
                let t = EdgeTable::ov_triangle(tables.ov_refs[k]) as usize;
                slots[t].push((e as u32, k as u32));
            }
        }
        for (t, want) in slots.iter().enumerate() {
            assert_eq!(
                index.edge_slots(t).map(Vec::from),
                Some(want.clone()),
                "triangle {t}"
            );
        }
        assert_eq!(index.edge_slots(tables.tri_count()), None);
    }
}
