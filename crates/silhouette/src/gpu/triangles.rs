//! The triangle side of the flattened scene: what a two-step kernel (one sign per triangle, then
//! one sum per edge) reads besides the [`SceneLayout`].

use super::SceneLayout;
use crate::{BackendError, TopologyScene};
use shadowvol_mesh_topology::EdgeTable;

/// Set on a [`TriangleLayout::ov_tris`] entry when the edge's `(a, b, o)` is an odd permutation
/// of the triangle's canonical (ascending) order, that is when `a < o < b`.
pub const NEGATIVE: u32 = 0x8000_0000;

/// Every triangle of a scene once, and the triangle behind each opposite-vertex slot, so that a
/// kernel can evaluate one sign per (triangle, light) and let each edge sum its triangles' signs.
///
/// Ids are global, as in the [`SceneLayout`] it is built against:
///
/// | buffer | element | meaning |
/// |---|---|---|
/// | [`TriangleLayout::tris`] | `[u32; 4]` | canonical (ascending) global vertex ids and the object |
/// | [`TriangleLayout::ov_tris`] | `u32` | per OV slot: its global triangle, [`NEGATIVE`] set for an odd permutation |
///
/// Edge `(a, b)` with opposite vertex `o` of triangle `t` has `orient(a, b, L, o) = ±
/// orient(canonical t)`, minus exactly when the slot's [`NEGATIVE`] bit is set; the exact sign
/// obeys this for every input, and the `robust` and `ordered` modes define theirs by it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TriangleLayout {
    /// Per global triangle: its vertex ids in ascending order and its object.
    pub tris: Vec<[u32; 4]>,
    /// Per opposite-vertex slot of [`SceneLayout::ovs`]: the global triangle, with [`NEGATIVE`]
    /// set for an odd permutation.
    pub ov_tris: Vec<u32>,
    /// First global triangle of each object; `object_count + 1` entries.
    pub tri_offsets: Vec<u32>,
}

impl TriangleLayout {
    /// Heap bytes of the layout's arrays (capacities).
    #[must_use]
    pub fn heap_bytes(&self) -> u64 {
        use crate::vec_bytes;
        vec_bytes(&self.tris) + vec_bytes(&self.ov_tris) + vec_bytes(&self.tri_offsets)
    }

    /// The triangles of `scene`, against `layout` (built from the same scene), for `backend`
    /// (named in errors).
    ///
    /// # Errors
    /// [`BackendError::Limit`] when the scene has 2^31 triangles or more (the top bit of an
    /// [`TriangleLayout::ov_tris`] entry is the parity).
    ///
    /// # Panics
    /// Panics if `layout` was not built from `scene`.
    pub fn build(
        scene: &TopologyScene,
        layout: &SceneLayout,
        backend: &'static str,
    ) -> Result<Self, BackendError> {
        let total: usize = scene.objects.iter().map(|o| o.table.triangles.len()).sum();
        if total >= NEGATIVE as usize {
            return Err(BackendError::Limit {
                backend,
                message: format!(
                    "the scene has {total} triangles; the {backend} kernel names them with 31 bits (at most {})",
                    NEGATIVE - 1
                ),
            });
        }
        let mut tris = Vec::with_capacity(total);
        let mut ov_tris = vec![0u32; layout.ovs.len()];
        let mut tri_offsets = Vec::with_capacity(scene.objects.len() + 1);
        tri_offsets.push(0u32);
        let mut obase = 0usize;
        for (oi, o) in scene.objects.iter().enumerate() {
            let t = &o.table;
            let vbase = layout.vertex_offsets[oi];
            let tbase = tris.len() as u32;
            tris.extend(t.triangles.iter().map(|tri| {
                let mut c = *tri;
                c.sort_unstable();
                [c[0] + vbase, c[1] + vbase, c[2] + vbase, oi as u32]
            }));
            // The table's OV references name each (edge, OV) pair's triangle and parity; the
            // layout keeps the table's OV order, so slot `obase + k` is the table's entry `k`.
            for (k, &r) in t.ov_refs.iter().enumerate() {
                let odd = EdgeTable::ov_odd(r);
                ov_tris[obase + k] =
                    (tbase + EdgeTable::ov_triangle(r)) | if odd { NEGATIVE } else { 0 };
            }
            obase += t.ov_refs.len();
            tri_offsets.push(tris.len() as u32);
        }
        Ok(Self {
            tris,
            ov_tris,
            tri_offsets,
        })
    }

    /// Number of triangles (all objects).
    #[must_use]
    pub fn tri_count(&self) -> usize {
        self.tris.len()
    }

    /// The inverse of [`TriangleLayout::ov_tris`]: per global triangle, its three `(edge, OV
    /// slot)` pairs, in slot order. The host uses it to turn an undecided triangle into the
    /// `(edge, OV slot)` triples it contributes to.
    ///
    /// # Panics
    /// Panics if `layout` is not the layout this was built against.
    #[must_use]
    pub fn edge_slots(&self, layout: &SceneLayout) -> Vec<[(u32, u32); 3]> {
        let mut out = vec![[(0u32, 0u32); 3]; self.tris.len()];
        let mut filled = vec![0u8; self.tris.len()];
        for e in 0..layout.edge_count() {
            for k in layout.ov_slots(e) {
                let t = (self.ov_tris[k] & !NEGATIVE) as usize;
                out[t][usize::from(filled[t])] = (e as u32, k as u32);
                filled[t] += 1;
            }
        }
        debug_assert!(filled.iter().all(|&n| n == 3));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowvol_test_support::shapes;

    #[test]
    fn every_slot_names_its_triangle_and_parity() {
        let sphere = shapes::uv_sphere_y(7, 5, 1.0);
        let one =
            TopologyScene::single(shadowvol_mesh_topology::EdgeTable::build(&sphere).unwrap());
        let mut two = one.clone();
        two.objects.push(one.objects[0].clone());
        let layout = SceneLayout::build(&two, "t").unwrap();
        let tl = TriangleLayout::build(&two, &layout, "t").unwrap();
        assert_eq!(tl.tri_count(), 2 * one.objects[0].table.triangles.len());
        assert_eq!(
            tl.tri_offsets,
            vec![0, tl.tri_count() as u32 / 2, tl.tri_count() as u32]
        );
        for e in 0..layout.edge_count() {
            let (a, b, object) = layout.edge(e);
            for k in layout.ov_slots(e) {
                let o = layout.ovs[k];
                let t = tl.tris[(tl.ov_tris[k] & !NEGATIVE) as usize];
                assert_eq!(t[3], object);
                let mut ids = [a, b, o];
                ids.sort_unstable();
                assert_eq!(&t[..3], &ids);
                assert_eq!(tl.ov_tris[k] & NEGATIVE != 0, a < o && o < b);
            }
        }
        let slots = tl.edge_slots(&layout);
        for (t, s) in slots.iter().enumerate() {
            for &(e, k) in s {
                assert!(layout.ov_slots(e as usize).contains(&(k as usize)));
                assert_eq!((tl.ov_tris[k as usize] & !NEGATIVE) as usize, t);
            }
        }
    }
}
