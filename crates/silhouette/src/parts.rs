//! A scene cut into parts that each fit a backend's buffers, and the parts' multiplicities added
//! back onto the scene's edges.
//!
//! A backend whose device cannot bind the whole scene's arrays (a storage binding of 128 MiB on
//! lavapipe holds the edge records of 5.6 million triangles) prepares and extracts each part on
//! its own and adds the parts up with [`SceneParts::add_part`].
//!
//! Why the sum is the scene's result, bit for bit, in every mode: a multiplicity is a sum over
//! the edge's (edge, opposite vertex) pairs, and each pair's term depends only on the edge's two
//! ends, the opposite vertex and the object-space light. Each pair lies in exactly one part (its
//! triangle's), with the same positions and transform. A part of a cut object renumbers its
//! vertices in ascending order of their ids in the object, so every `a < b` and every canonical
//! (sorted) triangle keeps its order, and with it the sign convention.

use crate::{
    BackendError, ExtractStats, Multiplicities, PreparedBytes, PreparedId, SceneObject,
    TopologyScene,
};
use shadowvol_mesh_topology::{EdgeTable, Mesh, MeshError};
use std::sync::Arc;

/// The parts of a scene: whole objects grouped up to a triangle budget, and objects beyond it cut
/// into triangle ranges.
#[derive(Debug, Clone)]
pub struct SceneParts {
    /// The parts, in order. A part of a cut object is one object named `NAME#partK`, with the
    /// object's transform.
    pub parts: Vec<TopologyScene>,
    /// For each part, the scene's global edge index of each of the part's global edges.
    pub edge_maps: Vec<Vec<u32>>,
    /// For each part, each of its objects' `(object of the scene, its first triangle there)`:
    /// `(o, 0)` for a whole object, `(o, k · N)` for range `k` of a cut one.
    pub sources: Vec<Vec<(usize, u32)>>,
    /// Global edges of the whole scene.
    pub scene_edges: usize,
    /// Heap bytes of the cut ranges' tables that [`SceneParts::take_parts`] handed out.
    handed_out: u64,
    /// For each part, whether its table was built here (a range of a cut object) rather than
    /// shared with the scene.
    built: Vec<bool>,
}

impl SceneParts {
    /// Cuts `scene` into parts of at most `max_triangles` triangles each (at least 1). Whole
    /// objects are grouped in order; an object with more triangles is cut into consecutive
    /// ranges, each rebuilt as an edge table of the vertices it uses.
    ///
    /// # Errors
    /// A [`MeshError`] if a range's table cannot be built (never for a table made by
    /// [`EdgeTable::build`], whose triangles are valid and positions distinct).
    pub fn split(scene: &TopologyScene, max_triangles: usize) -> Result<Self, MeshError> {
        let max_triangles = max_triangles.max(1);
        let mut out = Self {
            parts: Vec::new(),
            edge_maps: Vec::new(),
            sources: Vec::new(),
            scene_edges: scene.total_edges(),
            built: Vec::new(),
            handed_out: 0,
        };
        let offsets = scene.edge_offsets();
        let (mut group, mut group_map, mut group_tris) = (Vec::new(), Vec::new(), 0usize);
        let mut group_sources = Vec::new();
        for (o, obj) in scene.objects.iter().enumerate() {
            let tris = obj.table.triangles.len();
            if tris > max_triangles {
                out.push(&mut group, &mut group_map, &mut group_sources);
                group_tris = 0;
                out.cut(obj, o, offsets[o] as u32, max_triangles)?;
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
        Ok(out)
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
            self.parts.push(TopologyScene {
                objects: std::mem::take(group),
            });
            self.edge_maps.push(std::mem::take(map));
            self.built.push(false);
        }
    }

    /// Cuts `obj` (object `index` of the scene, whose edges start at global edge `base`) into
    /// parts of `max` triangles.
    fn cut(
        &mut self,
        obj: &SceneObject,
        index: usize,
        base: u32,
        max: usize,
    ) -> Result<(), MeshError> {
        let table = &obj.table;
        // Compact id in the part of each of the object's vertices (u32::MAX: not in it).
        let mut local = vec![u32::MAX; table.positions.len()];
        for (k, range) in table.triangles.chunks(max).enumerate() {
            let mut used: Vec<u32> = range.iter().flatten().copied().collect();
            used.sort_unstable();
            used.dedup();
            for (i, &v) in used.iter().enumerate() {
                local[v as usize] = i as u32;
            }
            let mesh = Mesh::new(
                used.iter().map(|&v| table.positions[v as usize]).collect(),
                range.iter().map(|t| t.map(|v| local[v as usize])).collect(),
            )?;
            let part = EdgeTable::build_owned(mesh)?;
            let map = part
                .edges
                .iter()
                .map(|&[a, b]| {
                    let e = table
                        .edge_index(used[a as usize], used[b as usize])
                        .expect("a part's edge is an edge of its object");
                    base + e
                })
                .collect();
            for &v in &used {
                local[v as usize] = u32::MAX;
            }
            self.parts.push(TopologyScene {
                objects: vec![SceneObject {
                    name: format!("{}#part{k}", obj.name),
                    table: Arc::new(part),
                    world_from_object: obj.world_from_object,
                }],
            });
            self.edge_maps.push(map);
            self.sources.push(vec![(index, (k * max) as u32)]);
            self.built.push(true);
        }
        Ok(())
    }

    /// Heap bytes held beyond the scene's own tables: the tables built for cut objects' ranges
    /// and the edge maps.
    #[must_use]
    pub fn own_bytes(&self) -> u64 {
        let tables: u64 = self
            .parts
            .iter()
            .zip(&self.built)
            .filter(|(_, &b)| b)
            .map(|(p, _)| p.table_bytes())
            .sum();
        tables + self.edge_maps.iter().map(crate::vec_bytes).sum::<u64>()
    }

    /// Moves the parts out, leaving the maps that [`SceneParts::add_part`] needs: a backend that
    /// lays each part out and no longer reads its table frees each cut range's table as soon as
    /// it is prepared. [`SceneParts::own_bytes`] then counts the edge maps only, and
    /// [`SceneParts::handed_out_bytes`] the tables handed out.
    #[must_use]
    pub fn take_parts(&mut self) -> Vec<TopologyScene> {
        self.handed_out += self
            .parts
            .iter()
            .zip(&self.built)
            .filter(|(_, &b)| b)
            .map(|(p, _)| p.table_bytes())
            .sum::<u64>();
        self.built.iter_mut().for_each(|b| *b = false);
        std::mem::take(&mut self.parts)
    }

    /// Heap bytes of the cut ranges' tables that [`SceneParts::take_parts`] (or
    /// [`SceneParts::prepare_each`]) handed out: a backend that keeps the parts' tables (to
    /// decide uncertain pairs on the host, through a
    /// [`SceneIndex`](crate::gpu::SceneIndex)) holds these too.
    #[must_use]
    pub fn handed_out_bytes(&self) -> u64 {
        self.handed_out
    }

    /// Prepares each part, in order, with `prepare`, moving the parts out as
    /// [`SceneParts::take_parts`] does (so each cut range's table is freed once prepared).
    ///
    /// # Errors
    /// The first error of `prepare`, with what was prepared before it (for the caller to
    /// release).
    pub fn prepare_each<P>(
        &mut self,
        mut prepare: impl FnMut(&TopologyScene) -> Result<P, BackendError>,
    ) -> Result<Vec<P>, (BackendError, Vec<P>)> {
        let mut done = Vec::with_capacity(self.parts.len());
        for part in self.take_parts() {
            match prepare(&part) {
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
        for k in 0..self.edge_maps.len() {
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
        let map = &self.edge_maps[part];
        assert_eq!(from.edge_count(), map.len(), "the part's edges");
        assert_eq!(into.edge_count(), self.scene_edges, "the scene's edges");
        assert_eq!(from.light_count(), into.light_count(), "the same lights");
        for l in 0..from.light_count() {
            let dst = into.values_mut(l);
            for (&g, &m) in map.iter().zip(from.values(l)) {
                dst[g as usize] += m;
            }
        }
    }
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
    /// `scene` uploaded whole by `prepare` when `max_triangles` is `None`, else cut into parts
    /// of at most that many triangles, each uploaded by `prepare` in turn.
    ///
    /// # Errors
    /// The first error, with the ids uploaded before it (for the caller to release): of
    /// `prepare`, or [`BackendError::InvalidInput`] when a part cannot be cut.
    pub fn prepare(
        scene: &TopologyScene,
        max_triangles: Option<usize>,
        mut prepare: impl FnMut(&TopologyScene) -> Result<PreparedId, BackendError>,
    ) -> Result<Self, (BackendError, Vec<PreparedId>)> {
        let cut_error =
            |e: MeshError| BackendError::InvalidInput(format!("cutting the scene into parts: {e}"));
        let Some(max) = max_triangles else {
            return prepare(scene).map(Self::Whole).map_err(|e| (e, Vec::new()));
        };
        let mut parts = SceneParts::split(scene, max).map_err(|e| (cut_error(e), Vec::new()))?;
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

    /// What the entry holds: its uploaded scenes' bytes (`bytes_of` each), the cut's own and the
    /// cut ranges' tables its parts keep.
    ///
    /// # Errors
    /// The first error of `bytes_of`.
    pub fn bytes(
        &self,
        bytes_of: impl Fn(PreparedId) -> Result<PreparedBytes, BackendError>,
    ) -> Result<PreparedBytes, BackendError> {
        // A split scene's parts keep their cut ranges' tables (the backends' indices read them).
        let mut b = PreparedBytes {
            host: match self {
                Self::Whole(_) => 0,
                Self::Split { parts, .. } => parts.own_bytes() + parts.handed_out_bytes(),
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
        let parts = SceneParts::split(&scene, 97).unwrap();
        assert_eq!(parts.parts.len(), 1 + 9 + 1);
        let tris: usize = parts.parts.iter().map(TopologyScene::total_triangles).sum();
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
            for (k, part) in parts.parts.iter().enumerate() {
                parts.add_part(k, &reference(part, mode, &lights), &mut sum);
            }
            assert_eq!(sum, whole, "{mode:?}");
            assert!(
                whole.all_values().iter().any(|&v| v != 0),
                "{mode:?}: nothing to compare"
            );
        }
    }

    /// Parts taken out (and dropped one by one, as the `wgpu` backend does) leave maps that
    /// still add them up to the scene; the bytes then count the maps alone.
    #[test]
    fn taken_parts_still_add_up_and_free_their_tables() {
        let big = Arc::new(bumpy(12));
        let scene = TopologyScene {
            objects: vec![SceneObject {
                name: "big".to_owned(),
                table: Arc::clone(&big),
                world_from_object: Affine3A::IDENTITY,
            }],
        };
        let mut parts = SceneParts::split(&scene, 50).unwrap();
        let maps: u64 = parts.edge_maps.iter().map(crate::vec_bytes).sum();
        let before = parts.own_bytes();
        assert!(before > maps, "cut ranges hold tables before");
        assert_eq!(parts.handed_out_bytes(), 0);
        let taken = parts.take_parts();
        assert!(parts.parts.is_empty());
        assert_eq!(parts.own_bytes(), maps);
        // What was handed out is counted, for the backends that keep it.
        assert_eq!(parts.handed_out_bytes(), before - maps);
        let tables: u64 = taken.iter().map(TopologyScene::table_bytes).sum();
        assert_eq!(parts.handed_out_bytes(), tables);
        let lights = [[5.0, 5.0, 0.5, 1.0], [1.0, 2.0, 3.0, 0.0]];
        let whole = reference(&scene, Accuracy::Exact, &lights);
        let mut sum = Multiplicities::zeroed(scene.total_edges(), lights.len());
        for (k, part) in taken.into_iter().enumerate() {
            parts.add_part(k, &reference(&part, Accuracy::Exact, &lights), &mut sum);
        }
        assert_eq!(sum, whole);
        assert!(whole.all_values().iter().any(|&v| v != 0));
    }
}
