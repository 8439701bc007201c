//! A scene cut into parts that each fit a backend's buffers, and the parts' multiplicities added
//! back onto the scene's edges.
//!
//! A backend whose device cannot bind the whole scene's arrays (the `wgpu` backend packs its
//! tables into one storage binding: 128 MiB, lavapipe's and WebGPU's default, holds those of
//! about 2.2 million triangles of a closed mesh) prepares and extracts each part on its own and
//! adds the parts up with [`SceneParts::add_part`].
//!
//! Why the sum is the scene's result, bit for bit, in every mode: a multiplicity is a sum over
//! the edge's (edge, opposite vertex) pairs, and each pair's term depends only on the edge's two
//! ends, the opposite vertex and the object-space light. Each pair lies in exactly one part (its
//! triangle's), with the same positions and transform. A part of a cut object renumbers its
//! vertices in ascending order of their ids in the object, so every `a < b` and every canonical
//! (sorted) triangle keeps its order, and with it the sign convention.

use crate::gpu::{SceneIndex, SceneLayout, TableRange};
use crate::{
    Accuracy, BackendError, ExtractStats, Light, Multiplicities, PreparedBytes, PreparedId,
    PreparedScenes, SceneObject, TopologyScene,
};
use shadowvol_mesh_topology::{EdgeTable, Mesh, MeshError};
use std::sync::Arc;

/// The parts of a scene: whole objects grouped up to a triangle budget, and objects beyond it cut
/// into triangle ranges.
///
/// A cut range is kept as a [`TableRange`] of the object's own table (about 8 bytes a range
/// edge); its table is built only when [`SceneParts::part`] asks for it, so that a backend
/// builds, uploads and drops one part at a time ([`SceneParts::prepare_each`]), and decides
/// its uncertain pairs through the range's [`SceneIndex`], which reads the scene's table.
#[derive(Debug, Clone)]
pub struct SceneParts {
    parts: Vec<Part>,
    /// For each part, each of its objects' `(object of the scene, its first triangle there)`:
    /// `(o, 0)` for a whole object, `(o, k · N)` for range `k` of a cut one.
    pub sources: Vec<Vec<(usize, u32)>>,
    /// Global edges of the whole scene.
    pub scene_edges: usize,
}

/// One part of a [`SceneParts`].
#[derive(Debug, Clone)]
enum Part {
    /// Whole objects sharing the scene's tables, and the scene's global edge index of each of
    /// the part's global edges.
    Group { scene: TopologyScene, map: Vec<u32> },
    /// Range `k` of one object: the object (its name and transform), the scene's global index
    /// of the object's first edge, and the range.
    Cut {
        object: SceneObject,
        k: usize,
        base: u32,
        range: TableRange,
    },
}

impl SceneParts {
    /// Cuts `scene` into parts of at most `max_triangles` triangles each (at least 1). Whole
    /// objects are grouped in order; an object with more triangles is cut into consecutive
    /// ranges of its triangles. No table is built here.
    #[must_use]
    pub fn split(scene: &TopologyScene, max_triangles: usize) -> Self {
        let max_triangles = max_triangles.max(1);
        let mut out = Self {
            parts: Vec::new(),
            sources: Vec::new(),
            scene_edges: scene.total_edges(),
        };
        let offsets = scene.edge_offsets();
        let (mut group, mut group_map, mut group_tris) = (Vec::new(), Vec::new(), 0usize);
        let mut group_sources = Vec::new();
        for (o, obj) in scene.objects.iter().enumerate() {
            let tris = obj.table.triangles.len();
            if tris > max_triangles {
                out.push(&mut group, &mut group_map, &mut group_sources);
                group_tris = 0;
                out.cut(obj, o, offsets[o] as u32, max_triangles);
                continue;
            }
            if group_tris + tris > max_triangles {
                out.push(&mut group, &mut group_map, &mut group_sources);
                group_tris = 0;
            }
            group.push(obj.clone());
            group_sources.push((o, 0));
            group_map.extend(offsets[o] as u32..offsets[o + 1] as u32);
            group_tris += tris;
        }
        out.push(&mut group, &mut group_map, &mut group_sources);
        out
    }

    /// Ends the current group of whole objects as a part (if it has any).
    fn push(
        &mut self,
        group: &mut Vec<SceneObject>,
        map: &mut Vec<u32>,
        sources: &mut Vec<(usize, u32)>,
    ) {
        if !group.is_empty() {
            self.sources.push(std::mem::take(sources));
            self.parts.push(Part::Group {
                scene: TopologyScene {
                    objects: std::mem::take(group),
                },
                map: std::mem::take(map),
            });
        }
    }

    /// Cuts `obj` (object `index` of the scene, whose edges start at global edge `base`) into
    /// ranges of `max` triangles.
    fn cut(&mut self, obj: &SceneObject, index: usize, base: u32, max: usize) {
        for (k, range) in TableRange::cut(&obj.table, max).into_iter().enumerate() {
            self.sources.push(vec![(index, range.triangles.start)]);
            self.parts.push(Part::Cut {
                object: obj.clone(),
                k,
                base,
                range,
            });
        }
    }

    /// Number of parts.
    #[must_use]
    pub fn len(&self) -> usize {
        self.parts.len()
    }

    /// Whether there are no parts (an empty scene).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.parts.is_empty()
    }

    /// Part `k` as a scene: its whole objects, sharing the scene's tables, or for a range of a
    /// cut object one object named `NAME#partK` with the object's transform and the range's
    /// table, built here from the vertices the range uses (renumbered in ascending order, so
    /// that every edge and canonical triangle keeps its vertex order, and with it the sign
    /// convention).
    ///
    /// # Errors
    /// A [`MeshError`] if a range's table cannot be built (never for a table made by
    /// [`EdgeTable::build`], whose triangles are valid and positions distinct).
    ///
    /// # Panics
    /// If `k >= self.len()`.
    pub fn part(&self, k: usize) -> Result<TopologyScene, MeshError> {
        match &self.parts[k] {
            Part::Group { scene, .. } => Ok(scene.clone()),
            Part::Cut {
                object, k, range, ..
            } => Ok(TopologyScene {
                objects: vec![SceneObject {
                    name: format!("{}#part{k}", object.name),
                    table: Arc::new(range_table(range)?),
                    world_from_object: object.world_from_object,
                }],
            }),
        }
    }

    /// The index of part `k` ([`SceneParts::part`]) for the host's exact decisions, in the
    /// numbering of the part's layouts, reading the scene's own tables.
    ///
    /// # Panics
    /// If `k >= self.len()`.
    #[must_use]
    pub fn index(&self, k: usize) -> SceneIndex {
        match &self.parts[k] {
            Part::Group { scene, .. } => SceneIndex::new(scene),
            Part::Cut { range, .. } => SceneIndex::of_range(range.clone()),
        }
    }

    /// Heap bytes held beyond the scene's own tables: the groups' edge maps and the cut
    /// ranges' edges and slots (which the ranges' indices share).
    #[must_use]
    pub fn own_bytes(&self) -> u64 {
        self.parts
            .iter()
            .map(|p| match p {
                Part::Group { map, .. } => crate::vec_bytes(map),
                Part::Cut { range, .. } => range.heap_bytes(),
            })
            .sum()
    }

    /// Prepares each part, in order, with `prepare(part, index)` ([`SceneParts::part`] and
    /// [`SceneParts::index`]): each cut range's table is built just before and dropped just
    /// after, so that only one is held at a time.
    ///
    /// # Errors
    /// The first error, with what was prepared before it (for the caller to release): of
    /// `prepare`, or [`BackendError::InvalidInput`] when a range's table cannot be built.
    pub fn prepare_each<P>(
        &self,
        mut prepare: impl FnMut(&TopologyScene, SceneIndex) -> Result<P, BackendError>,
    ) -> Result<Vec<P>, (BackendError, Vec<P>)> {
        let mut done = Vec::with_capacity(self.len());
        for k in 0..self.len() {
            let prepared = self
                .part(k)
                .map_err(|e| {
                    BackendError::InvalidInput(format!("cutting the scene into parts: {e}"))
                })
                .and_then(|part| prepare(&part, self.index(k)));
            match prepared {
                Ok(p) => done.push(p),
                Err(e) => return Err((e, done)),
            }
        }
        Ok(done)
    }

    /// The scene's multiplicities for `lights` lights in `out`: `extract(k, part_out)` fills
    /// part `k`'s, which are added onto the scene's edges ([`SceneParts::add_part`]) in order,
    /// then the silhouette lists are rebuilt. Returns the parts' statistics summed.
    ///
    /// # Errors
    /// The first error of `extract` (`out` then holds the parts before it).
    pub fn extract_each(
        &self,
        lights: usize,
        out: &mut Multiplicities,
        mut extract: impl FnMut(usize, &mut Multiplicities) -> Result<ExtractStats, BackendError>,
    ) -> Result<ExtractStats, BackendError> {
        out.reset(self.scene_edges, lights);
        let (mut part, mut stats) = (Multiplicities::default(), ExtractStats::default());
        for k in 0..self.len() {
            let s = extract(k, &mut part)?;
            stats.upload += s.upload;
            stats.compute += s.compute;
            stats.readback += s.readback;
            stats.host_resolve += s.host_resolve;
            stats.uncertain += s.uncertain;
            self.add_part(k, &part, out);
        }
        out.rebuild_silhouettes();
        Ok(stats)
    }

    /// Adds part `part`'s multiplicities `from` onto the scene's edges in `into`, which must be
    /// shaped for the whole scene and the same lights. Call
    /// [`Multiplicities::rebuild_silhouettes`] on `into` once every part is added.
    ///
    /// # Panics
    /// If `from` is not shaped like the part, or `into` like the scene, for the same lights.
    pub fn add_part(&self, part: usize, from: &Multiplicities, into: &mut Multiplicities) {
        let (map, base) = match &self.parts[part] {
            Part::Group { map, .. } => (&map[..], 0),
            Part::Cut { base, range, .. } => (&range.edges[..], *base as usize),
        };
        assert_eq!(from.edge_count(), map.len(), "the part's edges");
        assert_eq!(into.edge_count(), self.scene_edges, "the scene's edges");
        assert_eq!(from.light_count(), into.light_count(), "the same lights");
        for l in 0..from.light_count() {
            let dst = into.values_mut(l);
            for (&g, &m) in map.iter().zip(from.values(l)) {
                dst[base + g as usize] += m;
            }
        }
    }
}

/// The table of `range`'s triangles over the vertices they use, renumbered in ascending order.
fn range_table(range: &TableRange) -> Result<EdgeTable, MeshError> {
    let table = &range.table;
    let tris = &table.triangles[range.triangles.start as usize..range.triangles.end as usize];
    let mut used: Vec<u32> = tris.iter().flatten().copied().collect();
    used.sort_unstable();
    used.dedup();
    let local = |v: u32| used.partition_point(|&u| u < v) as u32;
    let triangles = tris.iter().map(|t| t.map(local)).collect();
    let positions = used.iter().map(|&v| table.positions[v as usize]).collect();
    drop(used);
    EdgeTable::build_owned(Mesh::new(positions, triangles)?)
}

/// What a backend's prepared id names when the backend keeps its uploaded scenes under ids of
/// their own and may cut a scene into parts: one uploaded scene, or the parts of a cut one with
/// each part's id.
#[derive(Debug)]
pub enum PartsEntry {
    /// Uploaded whole.
    Whole(PreparedId),
    /// Uploaded in parts.
    Split {
        /// The cut.
        parts: SceneParts,
        /// Each part's id, in order.
        ids: Vec<PreparedId>,
    },
}

impl PartsEntry {
    /// `scene` uploaded whole by `prepare(scene, its index)` when `max_triangles` is `None`,
    /// else cut into parts of at most that many triangles, each uploaded by `prepare` in turn
    /// ([`SceneParts::prepare_each`]). The [`SceneIndex`] given with each scene is what the
    /// backend keeps for its host's exact decisions.
    ///
    /// # Errors
    /// The first error, with the ids uploaded before it (for the caller to release): of
    /// `prepare`, or [`BackendError::InvalidInput`] when a part's table cannot be built.
    pub fn prepare(
        scene: &TopologyScene,
        max_triangles: Option<usize>,
        mut prepare: impl FnMut(&TopologyScene, SceneIndex) -> Result<PreparedId, BackendError>,
    ) -> Result<Self, (BackendError, Vec<PreparedId>)> {
        let Some(max) = max_triangles else {
            return prepare(scene, SceneIndex::new(scene))
                .map(Self::Whole)
                .map_err(|e| (e, Vec::new()));
        };
        let parts = SceneParts::split(scene, max);
        let ids = parts.prepare_each(prepare)?;
        Ok(Self::Split { parts, ids })
    }

    /// The uploaded scenes' ids: one, or one per part.
    #[must_use]
    pub fn ids(&self) -> &[PreparedId] {
        match self {
            Self::Whole(id) => std::slice::from_ref(id),
            Self::Split { ids, .. } => ids,
        }
    }

    /// What the entry holds: its uploaded scenes' bytes (`bytes_of` each) and the cut's own
    /// ([`SceneParts::own_bytes`]).
    ///
    /// # Errors
    /// The first error of `bytes_of`.
    pub fn bytes(
        &self,
        bytes_of: impl Fn(PreparedId) -> Result<PreparedBytes, BackendError>,
    ) -> Result<PreparedBytes, BackendError> {
        let mut b = PreparedBytes {
            host: match self {
                Self::Whole(_) => 0,
                Self::Split { parts, .. } => parts.own_bytes(),
            },
            device: 0,
        };
        for &id in self.ids() {
            let pb = bytes_of(id)?;
            b.host += pb.host;
            b.device += pb.device;
        }
        Ok(b)
    }

    /// The scene's multiplicities for `lights` lights in `out`: `extract(id, out)` on the
    /// uploaded scene, or on each part, added up ([`SceneParts::extract_each`]).
    ///
    /// # Errors
    /// The first error of `extract`.
    pub fn extract(
        &self,
        lights: usize,
        out: &mut Multiplicities,
        mut extract: impl FnMut(PreparedId, &mut Multiplicities) -> Result<ExtractStats, BackendError>,
    ) -> Result<ExtractStats, BackendError> {
        match self {
            Self::Whole(id) => extract(*id, out),
            Self::Split { parts, ids } => {
                parts.extract_each(lights, out, |k, part| extract(ids[k], part))
            }
        }
    }
}

/// What [`PartsBackend::prepare_whole`] uploads: a scene, or one part of a cut scene, laid out.
#[derive(Debug)]
pub struct WholeScene<'a> {
    /// The scene or part (its objects' transforms).
    pub scene: &'a TopologyScene,
    /// Its flat layout, which the backend uploads and may then drop.
    pub layout: SceneLayout,
    /// What the host's exact decisions read the tables through: [`SceneIndex::new`] of the
    /// scene, or of the range a part of a cut scene is.
    pub index: SceneIndex,
}

/// A backend that keeps its uploaded scenes under ids of its own and cuts a scene whose
/// [`SceneLayout`](crate::gpu::SceneLayout) buffers exceed its device's largest buffer into
/// parts: the caller's ids name [`PartsEntry`]s. `opencl` and `vulkan` implement the required
/// methods (one uploaded scene each); the provided ones are their [`SilhouetteBackend`]
/// `prepare`, `extract` (after the backend's own checks), `prepared_bytes` and `release`.
///
/// [`SilhouetteBackend`]: crate::SilhouetteBackend
pub trait PartsBackend {
    /// The backend's registry name, for errors.
    const NAME: &'static str;

    /// What the caller's ids name.
    fn entries(&self) -> &PreparedScenes<PartsEntry>;

    /// What the caller's ids name, to change.
    fn entries_mut(&mut self) -> &mut PreparedScenes<PartsEntry>;

    /// The largest buffer the device takes, bytes: a scene whose largest layout buffer exceeds
    /// it is cut into parts.
    fn largest_buffer(&self) -> u64;

    /// Uploads a scene, or a part of one, whole ([`WholeScene`]: laid out, with its index).
    /// Returns the uploaded scene's own id.
    ///
    /// # Errors
    /// The backend's, naming what failed.
    fn prepare_whole(&mut self, whole: WholeScene<'_>) -> Result<PreparedId, BackendError>;

    /// The multiplicities of the uploaded scene (or part) `id` for `lights` in `mode`, in `out`.
    ///
    /// # Errors
    /// The backend's, as [`SilhouetteBackend::extract`](crate::SilhouetteBackend::extract).
    fn extract_whole(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError>;

    /// What the uploaded scene (or part) `id` holds.
    ///
    /// # Errors
    /// [`BackendError::UnknownScene`] for an unknown `id`.
    fn whole_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError>;

    /// Releases the uploaded scene (or part) `id`; an unknown `id` is ignored.
    fn release_whole(&mut self, id: PreparedId);

    /// Triangles per part when `scene`'s largest [`SceneLayout`](crate::gpu::SceneLayout)
    /// buffer (positions 12 bytes a vertex, edge records 16 an edge and one more, OVs 4 each)
    /// exceeds [`largest_buffer`](Self::largest_buffer); `None` when it fits whole. A part's
    /// edge records take at most 48 bytes a triangle.
    fn part_triangles(&self, scene: &TopologyScene) -> Option<usize> {
        let limit = self.largest_buffer();
        let (v, e, ov) = (
            scene.total_vertices() as u64,
            scene.total_edges() as u64,
            scene.total_ovs() as u64,
        );
        let largest = [12 * v, 16 * (e + 1), 4 * ov].into_iter().max()?;
        (largest > limit).then(|| (limit.saturating_sub(64) / 48).max(1) as usize)
    }

    /// Uploads `scene`, whole or in parts ([`PartsEntry::prepare`]), and returns the caller's id
    /// for it; what was uploaded before a failure is released.
    ///
    /// # Errors
    /// [`BackendError::Limit`] for a scene (or part) beyond the layout's `u32` indices, the
    /// first error of [`prepare_whole`](Self::prepare_whole), or
    /// [`BackendError::InvalidInput`] when a part's table cannot be built.
    fn prepare_parts(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        let max = self.part_triangles(scene);
        let prepare = |part: &TopologyScene, index| {
            let layout = SceneLayout::build(part, Self::NAME)?;
            self.prepare_whole(WholeScene {
                scene: part,
                layout,
                index,
            })
        };
        match PartsEntry::prepare(scene, max, prepare) {
            Ok(entry) => Ok(self.entries_mut().insert(entry)),
            Err((e, done)) => {
                for id in done {
                    self.release_whole(id);
                }
                Err(e)
            }
        }
    }

    /// The multiplicities of the caller's scene `id`: [`extract_whole`](Self::extract_whole) on
    /// the uploaded scene, or on each part, added up ([`PartsEntry::extract`]).
    ///
    /// # Errors
    /// [`BackendError::UnknownScene`] for an unknown `id`; the first error of `extract_whole`.
    fn extract_parts(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        // Taken out while its parts are extracted, which borrow the backend.
        let entry = self.entries_mut().take(id)?;
        let result = entry.extract(lights.len(), out, |inner, out| {
            self.extract_whole(inner, lights, mode, out)
        });
        self.entries_mut().restore(id, entry);
        result
    }

    /// What the caller's scene `id` holds ([`PartsEntry::bytes`]).
    ///
    /// # Errors
    /// [`BackendError::UnknownScene`] for an unknown `id`.
    fn parts_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        self.entries()
            .get(id)?
            .bytes(|inner| self.whole_bytes(inner))
    }

    /// Releases the caller's scene `id` and every uploaded part of it; an unknown `id` is
    /// ignored.
    fn release_parts(&mut self, id: PreparedId) {
        if let Some(entry) = self.entries_mut().remove(id) {
            for &inner in entry.ids() {
                self.release_whole(inner);
            }
        }
    }

    /// Into how many parts the caller's scene `id` was cut (1: uploaded whole); `None` for an
    /// unknown or released `id`.
    fn parts_of(&self, id: PreparedId) -> Option<usize> {
        Some(self.entries().get(id).ok()?.ids().len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Affine3A, Vec3};
    use shadowvol_robust_math::{ov_sign, Accuracy};

    /// A bumpy `n × n` height field (open: its rim edges have one triangle).
    fn bumpy(n: u32) -> EdgeTable {
        let h = |x: u32, y: u32| ((x * 7 + y * 13) % 5) as f32 * 0.25;
        let mut positions = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                positions.push(Vec3::new(x as f32, y as f32, h(x, y)));
            }
        }
        let at = |x: u32, y: u32| y * (n + 1) + x;
        let mut triangles = Vec::new();
        for y in 0..n {
            for x in 0..n {
                triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
        // A book: a third triangle on one inner edge (non-manifold).
        positions.push(Vec3::new(1.5, 0.5, 3.0));
        let top = positions.len() as u32 - 1;
        triangles.push([at(1, 1), at(2, 2), top]);
        EdgeTable::build(&Mesh::new(positions, triangles).unwrap()).unwrap()
    }

    /// Every (edge, OV) term of every object, in object space, as [`Multiplicities`].
    fn reference(scene: &TopologyScene, mode: Accuracy, lights: &[[f32; 4]]) -> Multiplicities {
        let mut m = Multiplicities::zeroed(scene.total_edges(), lights.len());
        for (l, &light) in lights.iter().enumerate() {
            let mut g = 0;
            for o in &scene.objects {
                let local = crate::object_light(
                    o.world_from_object,
                    shadowvol_robust_math::Light::new(light[0], light[1], light[2], light[3])
                        .unwrap(),
                );
                let t = &o.table;
                for (e, &[a, b]) in t.edges.iter().enumerate() {
                    m.values_mut(l)[g + e] = t
                        .ovs_of(e)
                        .map(|ov| i32::from(ov_sign(mode, &t.positions, a, b, ov, local)))
                        .sum();
                }
                g += t.edges.len();
            }
        }
        m
    }

    #[test]
    fn the_parts_add_up_to_the_scene_in_every_mode() {
        let big = Arc::new(bumpy(20));
        let small = Arc::new(bumpy(3));
        let place = |name: &str, table: &Arc<EdgeTable>, x: f32| SceneObject {
            name: name.to_owned(),
            table: Arc::clone(table),
            world_from_object: Affine3A::from_translation(Vec3::new(x, 0.0, 0.0)),
        };
        let scene = TopologyScene {
            objects: vec![
                place("small", &small, -10.0),
                place("big", &big, 0.0),
                place("small2", &small, 30.0),
                place("small3", &small, 40.0),
            ],
        };
        // 801 triangles in `big`: cut into 9 ranges; the smalls grouped.
        let parts = SceneParts::split(&scene, 97);
        assert_eq!(parts.len(), 1 + 9 + 1);
        let tris: usize = (0..parts.len())
            .map(|k| parts.part(k).unwrap().total_triangles())
            .sum();
        assert_eq!(tris, scene.total_triangles());
        let big_ranges: Vec<(usize, u32)> = (0..9).map(|k| (1, 97 * k)).collect();
        let sources: Vec<(usize, u32)> = parts.sources.iter().flatten().copied().collect();
        assert_eq!(sources[0], (0, 0));
        assert_eq!(sources[1..10], big_ranges[..]);
        assert_eq!(sources[10..], [(2, 0), (3, 0)]);
        // A point light level with some vertices, one above, a directional one.
        let lights = [
            [5.0, 5.0, 0.5, 1.0],
            [3.0, 9.0, 6.0, 1.0],
            [1.0, 2.0, 3.0, 0.0],
        ];
        for mode in [
            Accuracy::Original,
            Accuracy::Robust,
            Accuracy::Ordered,
            Accuracy::Exact,
        ] {
            let whole = reference(&scene, mode, &lights);
            let mut sum = Multiplicities::zeroed(scene.total_edges(), lights.len());
            for k in 0..parts.len() {
                let part = parts.part(k).unwrap();
                parts.add_part(k, &reference(&part, mode, &lights), &mut sum);
            }
            assert_eq!(sum, whole, "{mode:?}");
            assert!(
                whole.all_values().iter().any(|&v| v != 0),
                "{mode:?}: nothing to compare"
            );
        }
    }

    /// A cut range's index, which reads the object's table, answers every question of the
    /// host's exact decisions as the index of the range's own table (built by
    /// `EdgeTable::build`) does; and the cut holds a few bytes a range edge, not the tables.
    #[test]
    fn a_cut_part_is_indexed_through_the_scene_table_as_its_own_table() {
        use crate::gpu::HostScene;
        let big = Arc::new(bumpy(12));
        let scene = TopologyScene {
            objects: vec![SceneObject {
                name: "big".to_owned(),
                table: Arc::clone(&big),
                world_from_object: Affine3A::from_translation(Vec3::X),
            }],
        };
        let parts = SceneParts::split(&scene, 50);
        let tris = big.triangles.len() as u32;
        assert_eq!(parts.len(), big.triangles.len().div_ceil(50));
        let mut tables = 0;
        for k in 0..parts.len() {
            let part = parts.part(k).unwrap();
            tables += part.table_bytes();
            let own = SceneIndex::new(&part);
            // The range as the cut found it, and found alone.
            let first = (50 * k) as u32;
            let alone = TableRange::new(Arc::clone(&big), first..(first + 50).min(tris));
            for range in [parts.index(k), SceneIndex::of_range(alone)] {
                assert_eq!(range.edge_count(), own.edge_count(), "part {k}");
                assert_eq!(range.slot_count(), own.slot_count(), "part {k}");
                assert_eq!(range.tri_count(), own.tri_count(), "part {k}");
                for e in 0..own.edge_count() {
                    let at = format!("part {k} edge {e}");
                    assert_eq!(range.ov_slots(e), own.ov_slots(e), "{at}");
                    assert_eq!(range.edge_points(e), own.edge_points(e), "{at}");
                    for s in own.ov_slots(e) {
                        assert_eq!(range.ov_point(e, s), own.ov_point(e, s), "{at} slot {s}");
                    }
                }
                for t in 0..=own.tri_count() {
                    let at = format!("part {k} triangle {t}");
                    assert_eq!(range.edge_slots(t), own.edge_slots(t), "{at}");
                }
            }
        }
        let ranges: usize = (0..parts.len())
            .map(|k| parts.index(k).edge_count() * 8 + 4)
            .sum();
        assert_eq!(parts.own_bytes(), ranges as u64);
        assert!(
            parts.own_bytes() * 3 < tables,
            "the cut holds no tables: {} bytes against {tables}",
            parts.own_bytes()
        );
    }
}
