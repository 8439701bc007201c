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
///
/// It may also index one [`TableRange`] of a table, numbered as the range's own table would be
/// (a part of a scene cut by [`SceneParts`](crate::SceneParts)), reading the whole table.
#[derive(Debug, Clone)]
pub struct SceneIndex {
    tables: Vec<Arc<EdgeTable>>,
    /// Per object and one past the last: first global edge.
    edges: Vec<usize>,
    /// Per object and one past the last: first global OV slot.
    slots: Vec<usize>,
    /// Per object and one past the last: first global triangle.
    tris: Vec<usize>,
    /// The range indexed, when this indexes a range of `tables[0]` rather than whole tables.
    range: Option<TableRange>,
}

/// A range of a table's triangles numbered as a table of its own: the triangles in their
/// order, the edges they have in the table's order, and each edge's opposite vertices in
/// those triangles, in ascending triangle order. That is the numbering of
/// [`EdgeTable::build`] on the range's triangles, with the vertices they use renumbered in
/// ascending order (which keeps every edge's and every triangle's vertex order).
#[derive(Debug, Clone)]
pub struct TableRange {
    /// The table.
    pub table: Arc<EdgeTable>,
    /// The range's triangles, as indices of `table.triangles`.
    pub triangles: Range<u32>,
    /// The range's edges, as ascending indices of `table.edges`: each edge that a triangle of the
    /// range has.
    pub edges: Arc<[u32]>,
    /// Per range edge and one past the last: the range's first OV slot of the edge (its OV
    /// slots are those of its references whose triangle is in the range).
    pub slots: Arc<[u32]>,
}

impl TableRange {
    /// The range of `table`'s triangles `triangles`, with its edges and OV slots found in
    /// `table` (about 8 bytes a range edge) in one pass over the table's references.
    ///
    /// # Panics
    /// If `triangles` is not a range of `table.triangles`.
    #[must_use]
    pub fn new(table: Arc<EdgeTable>, triangles: Range<u32>) -> Self {
        assert!(
            triangles.start <= triangles.end && triangles.end as usize <= table.triangles.len(),
            "a range of the table's triangles"
        );
        let tris = triangles.clone();
        let [(edges, slots)] = scan(&table, move |t| tris.contains(&t).then_some(0));
        Self {
            table,
            triangles,
            edges: edges.into(),
            slots: slots.into(),
        }
    }

    /// `table` cut into consecutive ranges of `max` triangles (at least 1; the last one may be
    /// shorter), found together in one pass over the table's references.
    #[must_use]
    pub fn cut(table: &Arc<EdgeTable>, max: usize) -> Vec<Self> {
        let (max, n) = (max.max(1), table.triangles.len());
        let mut found: Vec<(Vec<u32>, Vec<u32>)> = vec![(Vec::new(), vec![0]); n.div_ceil(max)];
        scan_into(table, &mut found, |t| Some(t as usize / max));
        found
            .into_iter()
            .enumerate()
            .map(|(k, (edges, slots))| Self {
                table: Arc::clone(table),
                triangles: (k * max) as u32..((k + 1) * max).min(n) as u32,
                edges: edges.into(),
                slots: slots.into(),
            })
            .collect()
    }

    /// Heap bytes of the range's own arrays (the table is shared).
    #[must_use]
    pub fn heap_bytes(&self) -> u64 {
        4 * (self.edges.len() + self.slots.len()) as u64
    }

    /// The references of the table's edge `e` whose triangle is in the range, in order.
    fn refs_of(&self, e: usize) -> impl Iterator<Item = u32> + '_ {
        let tris = self.triangles.clone();
        self.table
            .ov_refs_of(e)
            .iter()
            .copied()
            .filter(move |&r| tris.contains(&EdgeTable::ov_triangle(r)))
    }
}

/// [`scan_into`] for one range.
fn scan(table: &EdgeTable, range_of: impl Fn(u32) -> Option<usize>) -> [(Vec<u32>, Vec<u32>); 1] {
    let mut found = [(Vec::new(), vec![0])];
    scan_into(table, &mut found, range_of);
    found
}

/// For each range `k` (`range_of` a triangle: `Some(k)`, or `None` for none), pushes onto
/// `found[k]` (each `(Vec::new(), vec![0])` at first) the table's edges that a triangle of the
/// range has, ascending, and each one's end of OV slots in the range's numbering: one pass over
/// the edges' references, which are in ascending triangle order.
fn scan_into(
    table: &EdgeTable,
    found: &mut [(Vec<u32>, Vec<u32>)],
    range_of: impl Fn(u32) -> Option<usize>,
) {
    for e in 0..table.edges.len() {
        let mut last = None;
        for &r in table.ov_refs_of(e) {
            let Some(k) = range_of(EdgeTable::ov_triangle(r)) else {
                continue;
            };
            let (edges, ends) = &mut found[k];
            if last != Some(k) {
                edges.push(e as u32);
                ends.push(*ends.last().expect("starts at 0"));
                last = Some(k);
            }
            *ends.last_mut().expect("pushed") += 1;
        }
    }
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
            range: None,
        }
    }

    /// The index of a one-object scene whose object is `range` (with the object's transform),
    /// numbered as that scene's layouts number it: the same answers as [`SceneIndex::new`] of
    /// the scene with the range's own table, without that table.
    #[must_use]
    pub fn of_range(range: TableRange) -> Self {
        let n = range.triangles.len();
        let slots = range.slots.last().copied().unwrap_or(0) as usize;
        Self {
            tables: vec![Arc::clone(&range.table)],
            edges: vec![0, range.edges.len()],
            slots: vec![0, slots],
            tris: vec![0, n],
            range: Some(range),
        }
    }

    /// Heap bytes of the index itself (the tables, and a range's arrays, belong to the scene
    /// and its parts).
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
        match &self.range {
            Some(r) => (0, r.edges[e] as usize),
            None => {
                let o = Self::object_of(&self.edges, e);
                (o, e - self.edges[o])
            }
        }
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
        let table = &self.tables[o];
        let local = match &self.range {
            Some(r) => r.triangles.start as usize + t,
            None => t - self.tris[o],
        };
        let tri = table.triangles[local];
        let mut pairs = [(0u32, 0u32); 3];
        for (i, pair) in pairs.iter_mut().enumerate() {
            let e = table.edge_index(tri[i], tri[(i + 1) % 3])?;
            // The edge in the index's numbering, and its first slot there.
            let (edge, first) = match &self.range {
                Some(r) => {
                    let k = r.edges.binary_search(&e).ok()?;
                    (k, r.slots[k] as usize)
                }
                None => (
                    self.edges[o] + e as usize,
                    self.slots[o] + table.ov_offsets[e as usize] as usize,
                ),
            };
            let of_t = |x: u32| EdgeTable::ov_triangle(x) as usize == local;
            let j = match &self.range {
                Some(r) => r.refs_of(e as usize).position(of_t)?,
                None => table.ov_refs_of(e as usize).iter().position(|&x| of_t(x))?,
            };
            *pair = (u32::try_from(edge).ok()?, u32::try_from(first + j).ok()?);
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
        if let Some(r) = &self.range {
            return r.slots[e] as usize..r.slots[e + 1] as usize;
        }
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
        let (o, local) = self.local_edge(e);
        let t = &self.tables[o];
        let r = match &self.range {
            Some(range) => range
                .refs_of(local)
                .nth(k - range.slots[e] as usize)
                .expect("k is one of the edge's slots"),
            None => t.ov_refs[k - self.slots[o]],
        };
        t.positions[t.ov_vertex(r) as usize].to_array()
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
