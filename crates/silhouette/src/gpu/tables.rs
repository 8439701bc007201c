//! The scene as the two-step kernels read it (`wgpu` and the renderer's GPU-resident pass): the
//! objects' edge tables concatenated in their own form, with global ids.
//!
//! A [`TableWriter`] writes any range of any of these buffers straight from the scene's tables,
//! so a backend can upload them in chunks without a host copy; [`TableLayout`] holds them all
//! on the host, for the CPU twins and for callers that upload a whole layout.

use crate::{BackendError, TopologyScene};
use shadowvol_mesh_topology::EdgeTable;

/// One buffer of the flattened tables. Every element is a run of `u32` words
/// ([`TableBuffer::words`]); all ids are global (object `i`'s ids plus its base in
/// [`TableBuffer::Objects`]).
///
/// | buffer | words | meaning |
/// |---|---|---|
/// | [`Positions`](TableBuffer::Positions) | 3 | object-space xyz (`f32` bits) per global vertex |
/// | [`Edges`](TableBuffer::Edges) | 2 | the edge's ends `(a, b)`, `a < b` |
/// | [`OvOffsets`](TableBuffer::OvOffsets) | 1 | first OV slot of each edge, plus a sentinel: the OV count |
/// | [`OvRefs`](TableBuffer::OvRefs) | 1 | per OV slot, `4 t + r`: global triangle `t` and the rank `r` of the OV among its ids |
/// | [`Triangles`](TableBuffer::Triangles) | 3 | the triangle's ids in ascending (canonical) order |
/// | [`Objects`](TableBuffer::Objects) | 4 | per object `(first edge, first triangle, first vertex, first OV slot)`, plus a sentinel of the totals |
/// | [`OvVertices`](TableBuffer::OvVertices) | 1 | optional: per OV slot, the OV's global vertex id (what a reference names, read in one step) |
///
/// The OV of slot `k` is `Triangles[t][r]`; the pair's sign is `+` or `-` the sign of the
/// canonical triangle `t`, minus exactly for `r == 1` (the OV between the edge's ends: an odd
/// permutation), as [`EdgeTable::ov_odd`] says. An edge's or triangle's object is the last
/// object whose first edge (triangle) is at most its id: [`object_of`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TableBuffer {
    /// Object-space positions.
    Positions,
    /// Edge ends.
    Edges,
    /// CSR offsets of the OV slots, with a sentinel.
    OvOffsets,
    /// OV references `4 t + r`.
    OvRefs,
    /// Canonical triangles.
    Triangles,
    /// Object bases, with a sentinel.
    Objects,
    /// The OV of each slot, as a vertex id: not in [`TableBuffer::ALL`]. It spares `original`
    /// (the one mode that reads an OV's position) a step per OV, for 12 bytes a triangle.
    OvVertices,
}

impl TableBuffer {
    /// Every buffer the kernels need, in upload order ([`TableBuffer::OvVertices`], optional,
    /// is not among them).
    pub const ALL: [TableBuffer; 6] = [
        TableBuffer::Positions,
        TableBuffer::Edges,
        TableBuffer::OvOffsets,
        TableBuffer::OvRefs,
        TableBuffer::Triangles,
        TableBuffer::Objects,
    ];

    /// `u32` words per element.
    #[must_use]
    pub fn words(self) -> usize {
        match self {
            TableBuffer::Positions | TableBuffer::Triangles => 3,
            TableBuffer::Edges => 2,
            TableBuffer::OvOffsets | TableBuffer::OvRefs | TableBuffer::OvVertices => 1,
            TableBuffer::Objects => 4,
        }
    }

    /// The buffer's name in labels and errors.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            TableBuffer::Positions => "positions",
            TableBuffer::Edges => "edge ends",
            TableBuffer::OvOffsets => "opposite-vertex offsets",
            TableBuffer::OvRefs => "opposite-vertex references",
            TableBuffer::Triangles => "triangles",
            TableBuffer::Objects => "object bases",
            TableBuffer::OvVertices => "opposite vertices",
        }
    }
}

/// Object field of [`TableBuffer::Objects`]: the first global edge.
pub const FIRST_EDGE: usize = 0;
/// Object field of [`TableBuffer::Objects`]: the first global triangle.
pub const FIRST_TRIANGLE: usize = 1;
/// Object field of [`TableBuffer::Objects`]: the first global vertex.
pub const FIRST_VERTEX: usize = 2;
/// Object field of [`TableBuffer::Objects`]: the first global OV slot.
pub const FIRST_SLOT: usize = 3;

/// The object of global id `id` (an edge for `field` [`FIRST_EDGE`], a triangle for
/// [`FIRST_TRIANGLE`], ...): the last object whose base is at most `id`, by binary search over
/// `objects` (with its sentinel), as the kernels' `object_of` does. Empty objects before a
/// non-empty one share its base and are passed over.
///
/// # Panics
/// Panics if `objects` has no object.
#[must_use]
pub fn object_of(objects: &[[u32; 4]], field: usize, id: u32) -> usize {
    let (mut lo, mut hi) = (0usize, objects.len() - 1);
    assert!(hi > 0, "object_of needs at least one object");
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if objects[mid][field] <= id {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Writes the flattened tables of a scene, any range of any buffer, from the scene's own edge
/// tables.
#[derive(Debug, Clone)]
pub struct TableWriter<'a> {
    scene: &'a TopologyScene,
    objects: Vec<[u32; 4]>,
}

impl<'a> TableWriter<'a> {
    /// The writer of `scene` for `backend` (named in errors).
    ///
    /// # Errors
    /// [`BackendError::Limit`] naming `backend` when a global id or word index does not fit a
    /// `u32`: `4 T` (the OV references), `3 V` and `3 T` words, `2 E` words, the OV count, or the
    /// objects.
    pub fn new(scene: &'a TopologyScene, backend: &'static str) -> Result<Self, BackendError> {
        let limit = |what: &str, n: usize| {
            if n > u32::MAX as usize {
                Err(BackendError::Limit {
                    backend,
                    message: format!(
                        "the scene needs {n} {what}; the {backend} kernels index them with u32 (at most {})",
                        u32::MAX
                    ),
                })
            } else {
                Ok(())
            }
        };
        limit(
            "opposite-vertex references (4 x triangles)",
            4 * scene.total_triangles(),
        )?;
        limit("position words (3 x vertices)", 3 * scene.total_vertices())?;
        limit(
            "triangle words (3 x triangles)",
            3 * scene.total_triangles(),
        )?;
        limit("edge words (2 x edges)", 2 * scene.total_edges() + 2)?;
        limit("opposite vertices", scene.total_ovs())?;
        limit("objects", 4 * (scene.objects.len() + 1))?;
        let mut objects = Vec::with_capacity(scene.objects.len() + 1);
        let mut base = [0u32; 4];
        for o in &scene.objects {
            objects.push(base);
            let t = &o.table;
            base[FIRST_EDGE] += t.edges.len() as u32;
            base[FIRST_TRIANGLE] += t.triangles.len() as u32;
            base[FIRST_VERTEX] += t.positions.len() as u32;
            base[FIRST_SLOT] += t.ov_refs.len() as u32;
        }
        objects.push(base);
        Ok(Self { scene, objects })
    }

    /// The object bases with their sentinel (the [`TableBuffer::Objects`] buffer).
    #[must_use]
    pub fn objects(&self) -> &[[u32; 4]] {
        &self.objects
    }

    /// Elements of buffer `b` (with the sentinels of [`TableBuffer::OvOffsets`] and
    /// [`TableBuffer::Objects`]).
    #[must_use]
    pub fn elements(&self, b: TableBuffer) -> usize {
        let total = self.objects[self.objects.len() - 1];
        match b {
            TableBuffer::Positions => total[FIRST_VERTEX] as usize,
            TableBuffer::Edges => total[FIRST_EDGE] as usize,
            TableBuffer::OvOffsets => total[FIRST_EDGE] as usize + 1,
            TableBuffer::OvRefs | TableBuffer::OvVertices => total[FIRST_SLOT] as usize,
            TableBuffer::Triangles => total[FIRST_TRIANGLE] as usize,
            TableBuffer::Objects => self.objects.len(),
        }
    }

    /// Bytes of buffer `b`.
    #[must_use]
    pub fn bytes(&self, b: TableBuffer) -> u64 {
        (self.elements(b) * b.words() * 4) as u64
    }

    /// Appends to `out` the words of elements `first..first + count` of buffer `b`.
    ///
    /// # Panics
    /// Panics if the range is beyond [`TableWriter::elements`].
    pub fn write(&self, b: TableBuffer, first: usize, count: usize, out: &mut Vec<u32>) {
        let end = first + count;
        assert!(
            end <= self.elements(b),
            "{} {first}..{end} out of range",
            b.label()
        );
        out.reserve(count * b.words());
        if b == TableBuffer::Objects {
            out.extend(self.objects[first..end].iter().flatten());
            return;
        }
        let field = match b {
            TableBuffer::Positions => FIRST_VERTEX,
            TableBuffer::Edges | TableBuffer::OvOffsets => FIRST_EDGE,
            TableBuffer::OvRefs | TableBuffer::OvVertices => FIRST_SLOT,
            TableBuffer::Triangles | TableBuffer::Objects => FIRST_TRIANGLE,
        };
        let mut i = first;
        while i < end {
            if b == TableBuffer::OvOffsets && i == self.elements(b) - 1 {
                // The sentinel: the total OV count.
                out.push(self.objects[self.objects.len() - 1][FIRST_SLOT]);
                i += 1;
                continue;
            }
            let oi = object_of(&self.objects, field, i as u32);
            let base = self.objects[oi];
            let next = self.objects[oi + 1][field] as usize;
            let stop = end.min(next);
            assert!(stop > i, "object {oi} does not hold {} {i}", b.label());
            let local = i - base[field] as usize..stop - base[field] as usize;
            write_object(b, &self.scene.objects[oi].table, base, local, out);
            i = stop;
        }
    }

    /// The whole of buffer `b`.
    #[must_use]
    pub fn to_vec(&self, b: TableBuffer) -> Vec<u32> {
        let mut v = Vec::new();
        self.write(b, 0, self.elements(b), &mut v);
        v
    }
}

/// Appends the words of elements `local` of one object's table `t` (bases `base`) in buffer `b`.
fn write_object(
    b: TableBuffer,
    t: &EdgeTable,
    base: [u32; 4],
    local: std::ops::Range<usize>,
    out: &mut Vec<u32>,
) {
    let vb = base[FIRST_VERTEX];
    match b {
        TableBuffer::Positions => out.extend(
            t.positions[local]
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits)),
        ),
        TableBuffer::Edges => out.extend(t.edges[local].iter().flat_map(|e| e.map(|v| v + vb))),
        TableBuffer::OvOffsets => {
            out.extend(t.ov_offsets[local].iter().map(|&k| k + base[FIRST_SLOT]));
        }
        // `4 (t + tb) + r` = the table's reference plus `4 tb`.
        TableBuffer::OvRefs => out.extend(
            t.ov_refs[local]
                .iter()
                .map(|&r| r + 4 * base[FIRST_TRIANGLE]),
        ),
        TableBuffer::OvVertices => {
            out.extend(t.ov_refs[local].iter().map(|&r| t.ov_vertex(r) + vb));
        }
        TableBuffer::Triangles => out.extend(t.triangles[local].iter().flat_map(|tri| {
            let mut c = *tri;
            c.sort_unstable();
            c.map(|v| v + vb)
        })),
        TableBuffer::Objects => unreachable!("written from the bases"),
    }
}

/// Every buffer of the flattened tables on the host (see [`TableBuffer`] for the format): what
/// the CPU twins of the two-step kernels read.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TableLayout {
    /// Object-space positions, `3 * vertex_count` values.
    pub positions: Vec<f32>,
    /// Edge ends `(a, b)`, `a < b`, global vertex ids.
    pub edges: Vec<[u32; 2]>,
    /// First OV slot of each edge, `edge_count + 1` entries.
    pub ov_offsets: Vec<u32>,
    /// Per OV slot: `4 t + r` (global triangle `t`, rank `r` of the OV among its ids).
    pub ov_refs: Vec<u32>,
    /// Canonical (ascending) global vertex ids per global triangle.
    pub tris: Vec<[u32; 3]>,
    /// Per object `(first edge, first triangle, first vertex, first OV slot)`, plus a sentinel.
    pub objects: Vec<[u32; 4]>,
}

impl TableLayout {
    /// Flattens `scene` for `backend` (named in errors).
    ///
    /// # Errors
    /// As [`TableWriter::new`].
    pub fn build(scene: &TopologyScene, backend: &'static str) -> Result<Self, BackendError> {
        let w = TableWriter::new(scene, backend)?;
        let pairs = |v: Vec<u32>| v.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let triples = |v: Vec<u32>| v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Ok(Self {
            positions: w
                .to_vec(TableBuffer::Positions)
                .into_iter()
                .map(f32::from_bits)
                .collect(),
            edges: pairs(w.to_vec(TableBuffer::Edges)),
            ov_offsets: w.to_vec(TableBuffer::OvOffsets),
            ov_refs: w.to_vec(TableBuffer::OvRefs),
            tris: triples(w.to_vec(TableBuffer::Triangles)),
            objects: w.objects().to_vec(),
        })
    }

    /// Heap bytes of the layout's arrays (capacities).
    #[must_use]
    pub fn heap_bytes(&self) -> u64 {
        use crate::vec_bytes;
        vec_bytes(&self.positions)
            + vec_bytes(&self.edges)
            + vec_bytes(&self.ov_offsets)
            + vec_bytes(&self.ov_refs)
            + vec_bytes(&self.tris)
            + vec_bytes(&self.objects)
    }

    /// Number of edges.
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Number of triangles.
    #[must_use]
    pub fn tri_count(&self) -> usize {
        self.tris.len()
    }

    /// Number of objects.
    #[must_use]
    pub fn object_count(&self) -> usize {
        self.objects.len().saturating_sub(1)
    }

    /// The object-space position of global vertex `id`.
    ///
    /// # Panics
    /// Panics if `id` is out of range.
    #[must_use]
    pub fn position(&self, id: u32) -> [f32; 3] {
        super::xyz(&self.positions, id)
    }

    /// The OV slots of global edge `e`.
    ///
    /// # Panics
    /// Panics if `e` is out of range.
    #[must_use]
    pub fn ov_slots(&self, e: usize) -> std::ops::Range<usize> {
        self.ov_offsets[e] as usize..self.ov_offsets[e + 1] as usize
    }

    /// The object of global edge `e`.
    #[must_use]
    pub fn edge_object(&self, e: usize) -> usize {
        object_of(&self.objects, FIRST_EDGE, e as u32)
    }

    /// The object of global triangle `t`.
    #[must_use]
    pub fn tri_object(&self, t: usize) -> usize {
        object_of(&self.objects, FIRST_TRIANGLE, t as u32)
    }

    /// The global vertex a reference `4 t + r` names: vertex `r` of canonical triangle `t`.
    #[must_use]
    pub fn ref_vertex(&self, r: u32) -> u32 {
        self.tris[EdgeTable::ov_triangle(r) as usize][(r & 3) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowvol_test_support::shapes;

    fn two_objects() -> TopologyScene {
        let sphere = shapes::uv_sphere_y(7, 5, 1.0);
        let one = TopologyScene::single(EdgeTable::build(&sphere).unwrap());
        let mut scene = one.clone();
        let mut empty = one.objects[0].clone();
        empty.table = EdgeTable::build(&Default::default()).unwrap().into();
        scene.objects.push(empty);
        scene.objects.push(one.objects[0].clone());
        scene
    }

    #[test]
    fn every_reference_names_its_ov_triangle_and_parity() {
        let scene = two_objects();
        let l = TableLayout::build(&scene, "t").unwrap();
        assert_eq!(l.object_count(), 3);
        assert_eq!(l.tri_count(), scene.total_triangles());
        for e in 0..l.edge_count() {
            let [a, b] = l.edges[e];
            let object = l.edge_object(e);
            assert_ne!(object, 1, "the empty object owns no edge");
            let table = &scene.objects[object].table;
            let local = e - l.objects[object][FIRST_EDGE] as usize;
            let vb = l.objects[object][FIRST_VERTEX];
            assert_eq!([a, b], table.edges[local].map(|v| v + vb));
            let ovs: Vec<u32> = table.ovs_of(local).map(|v| v + vb).collect();
            let mine: Vec<u32> = l.ov_slots(e).map(|k| l.ref_vertex(l.ov_refs[k])).collect();
            assert_eq!(mine, ovs);
            for k in l.ov_slots(e) {
                let r = l.ov_refs[k];
                let t = EdgeTable::ov_triangle(r) as usize;
                assert_eq!(l.tri_object(t), object);
                let o = l.ref_vertex(r);
                let mut ids = [a, b, o];
                ids.sort_unstable();
                assert_eq!(l.tris[t], ids);
                assert_eq!(EdgeTable::ov_odd(r), a < o && o < b);
            }
        }
    }

    #[test]
    fn chunks_at_any_boundary_equal_the_whole() {
        let scene = two_objects();
        let w = TableWriter::new(&scene, "t").unwrap();
        let l = TableLayout::build(&scene, "t").unwrap();
        let named: Vec<u32> = l.ov_refs.iter().map(|&r| l.ref_vertex(r)).collect();
        assert_eq!(w.to_vec(TableBuffer::OvVertices), named);
        for b in TableBuffer::ALL
            .into_iter()
            .chain([TableBuffer::OvVertices])
        {
            let whole = w.to_vec(b);
            assert_eq!(whole.len(), w.elements(b) * b.words());
            assert_eq!(w.bytes(b), 4 * whole.len() as u64);
            for chunk in [1, 7, 64] {
                let mut v = Vec::new();
                let mut i = 0;
                while i < w.elements(b) {
                    let n = chunk.min(w.elements(b) - i);
                    w.write(b, i, n, &mut v);
                    i += n;
                }
                assert_eq!(v, whole, "{} in chunks of {chunk}", b.label());
            }
        }
    }

    #[test]
    fn object_of_passes_over_empty_objects() {
        let objects = [[0, 0, 0, 0], [5, 0, 0, 0], [5, 0, 0, 0], [9, 0, 0, 0]];
        let of = |id| object_of(&objects, FIRST_EDGE, id);
        assert_eq!([of(0), of(4), of(5), of(8)], [0, 0, 2, 2]);
    }
}
