//! The flat, all-objects-concatenated buffer layout every GPU kernel reads (built once per
//! prepare).

use crate::{BackendError, TopologyScene};

/// The scene as the GPU kernels see it: every object's tables concatenated, with vertex ids made
/// global (object `i`'s compact ids plus `vertex_offsets[i]`).
///
/// Adding a per-object constant keeps the order of ids within an object, so the canonical
/// triangle order and its parity (robust and ordered modes) are the same as on the CPU.
///
/// | buffer | element | meaning |
/// |---|---|---|
/// | [`SceneLayout::positions`] | `f32` ×3 | object-space xyz per global vertex |
/// | [`SceneLayout::edges`] | `[u32; 4]` | `(a, b, first OV slot, object)`, plus one sentinel whose third value is the OV count |
/// | [`SceneLayout::ovs`] | `u32` | opposite vertices (global ids), CSR by edge |
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneLayout {
    /// Object-space positions, `3 * vertex_count` values.
    pub positions: Vec<f32>,
    /// Edge records `(a, b, ov_begin, object)`, `edge_count + 1` entries (the last is a sentinel
    /// `(0, 0, ov_count, 0)`, so edge `e`'s OVs are slots `edges[e][2]..edges[e + 1][2]`).
    pub edges: Vec<[u32; 4]>,
    /// Opposite vertices (global vertex ids).
    pub ovs: Vec<u32>,
    /// First global vertex id of each object; `object_count + 1` entries.
    pub vertex_offsets: Vec<u32>,
    /// First global edge of each object; `object_count + 1` entries.
    pub edge_offsets: Vec<usize>,
}

fn to_u32(backend: &'static str, what: &str, n: usize) -> Result<u32, BackendError> {
    u32::try_from(n).map_err(|_| BackendError::Limit {
        backend,
        message: format!(
            "the scene has {n} {what}; the {backend} kernel indexes them with u32 (at most {})",
            u32::MAX
        ),
    })
}

impl SceneLayout {
    /// Heap bytes of the layout's arrays (capacities).
    #[must_use]
    pub fn heap_bytes(&self) -> u64 {
        use crate::vec_bytes;
        vec_bytes(&self.positions)
            + vec_bytes(&self.edges)
            + vec_bytes(&self.ovs)
            + vec_bytes(&self.vertex_offsets)
            + vec_bytes(&self.edge_offsets)
    }

    /// Concatenates the objects of `scene` for `backend` (named in errors).
    ///
    /// # Errors
    /// [`BackendError::Limit`] naming `backend` when the scene has more than `u32::MAX` vertices,
    /// opposite vertices or objects, or more than `u32::MAX - 1` edges, in total.
    pub fn build(scene: &TopologyScene, backend: &'static str) -> Result<Self, BackendError> {
        let vertices = scene.total_vertices();
        let edges = scene.total_edges();
        let ovs = scene.total_ovs();
        to_u32(backend, "vertices", vertices)?;
        to_u32(backend, "edges", edges + 1)?;
        to_u32(backend, "opposite vertices", ovs)?;
        to_u32(backend, "objects", scene.objects.len())?;
        let mut layout = Self {
            positions: Vec::with_capacity(3 * vertices),
            edges: Vec::with_capacity(edges + 1),
            ovs: Vec::with_capacity(ovs),
            vertex_offsets: Vec::with_capacity(scene.objects.len() + 1),
            edge_offsets: scene.edge_offsets(),
        };
        let mut vbase = 0u32;
        let mut obase = 0u32;
        layout.vertex_offsets.push(0);
        for (object, o) in scene.objects.iter().enumerate() {
            let t = &o.table;
            layout
                .positions
                .extend(t.positions.iter().flat_map(|p| p.to_array()));
            for (e, &[a, b]) in t.edges.iter().enumerate() {
                layout
                    .edges
                    .push([a + vbase, b + vbase, t.ov_offsets[e] + obase, object as u32]);
            }
            layout
                .ovs
                .extend(t.ov_refs.iter().map(|&c| t.ov_vertex(c) + vbase));
            vbase += t.positions.len() as u32;
            obase += t.ov_refs.len() as u32;
            layout.vertex_offsets.push(vbase);
        }
        layout.edges.push([0, 0, obase, 0]);
        Ok(layout)
    }

    /// Number of edges (without the sentinel).
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges.len().saturating_sub(1)
    }

    /// Number of vertices (all objects).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.positions.len() / 3
    }

    /// Number of objects.
    #[must_use]
    pub fn object_count(&self) -> usize {
        self.vertex_offsets.len().saturating_sub(1)
    }

    /// The object-space position of global vertex `id`.
    ///
    /// # Panics
    /// Panics if `id` is out of range.
    #[must_use]
    pub fn position(&self, id: u32) -> [f32; 3] {
        super::xyz(&self.positions, id)
    }

    /// The vertices `(a, b)` and the object of global edge `e`.
    ///
    /// # Panics
    /// Panics if `e >= self.edge_count()`.
    #[must_use]
    pub fn edge(&self, e: usize) -> (u32, u32, u32) {
        let [a, b, _, object] = self.edges[e];
        (a, b, object)
    }

    /// The OV slots of global edge `e` (indices into [`SceneLayout::ovs`]).
    ///
    /// # Panics
    /// Panics if `e >= self.edge_count()`.
    #[must_use]
    pub fn ov_slots(&self, e: usize) -> std::ops::Range<usize> {
        self.edges[e][2] as usize..self.edges[e + 1][2] as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowvol_test_support::shapes;

    #[test]
    fn objects_are_concatenated_with_global_ids() {
        let sphere = shapes::uv_sphere_y(6, 4, 1.0);
        let one = crate::TopologyScene::single(
            shadowvol_mesh_topology::EdgeTable::build(&sphere).unwrap(),
        );
        let mut two = one.clone();
        two.objects.push(one.objects[0].clone());
        let l1 = SceneLayout::build(&one, "t").unwrap();
        let l2 = SceneLayout::build(&two, "t").unwrap();
        let (v, e, k) = (l1.vertex_count(), l1.edge_count(), l1.ovs.len());
        assert_eq!(
            (l2.vertex_count(), l2.edge_count(), l2.object_count()),
            (2 * v, 2 * e, 2)
        );
        assert_eq!(l2.vertex_offsets, vec![0, v as u32, 2 * v as u32]);
        assert_eq!(l2.edge_offsets, vec![0, e, 2 * e]);
        for i in 0..e {
            let (a, b, o) = l2.edge(i);
            let (a2, b2, o2) = l2.edge(e + i);
            assert_eq!((a2, b2, o2), (a + v as u32, b + v as u32, o + 1));
            assert_eq!(l2.position(a), l2.position(a2));
            let (s1, s2) = (l2.ov_slots(i), l2.ov_slots(e + i));
            assert_eq!((s2.start, s2.end), (s1.start + k, s1.end + k));
            for (x, y) in s1.zip(s2) {
                assert_eq!(l2.ovs[y], l2.ovs[x] + v as u32);
            }
        }
        assert_eq!(
            l2.edges.last(),
            Some(&[0, 0, 2 * k as u32, 0]),
            "the sentinel"
        );
    }
}
