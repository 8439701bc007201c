//! A prepared scene and one extraction over it: the work items of every object, the two rayon
//! passes (triangles, then edges) and the assembly of the silhouette lists.

use crate::dispatch;
use crate::kernel::edge_pass::{EdgeSums, PackedSigns};
use crate::kernel::original::EdgeOriginal;
use crate::kernel::shared::{worth_sharing, SharedTriPass, SHARE_MIN_LIGHTS};
use crate::kernel::signs::PACK;
use crate::kernel::tri_pass::TriPass;
use crate::kernel::EdgeOut;
use crate::layout::{with_geometry, Geometry, Layout, LayoutChoice, COPY_MAX_TRIANGLES, LANES};
use crate::SimdLevel;
use glam::{Affine3A, DAffine3, DVec3};
use rayon::prelude::*;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::LightBox;
use shadowvol_silhouette::{Accuracy, BackendError, Light, Multiplicities, TopologyScene};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

/// Blocks of 8 per work item (2048 triangles or edges): small enough to balance two to many
/// threads, large enough that scheduling costs nothing.
const BLOCKS_PER_ITEM: usize = 256;

/// One object of a prepared scene.
#[derive(Debug)]
struct PreparedObject {
    layout: Arc<Layout>,
    /// Brings world-space lights into the object's frame.
    to_object: ToObject,
    /// First global edge index.
    edge_base: usize,
    /// First slot of the object's triangles in the per-light sign arrays (multiple of 8).
    tri_base: usize,
}

/// The object-from-world transform of an object, inverted once when the scene is prepared.
#[derive(Debug, Clone, Copy)]
enum ToObject {
    /// The object's frame is the world's.
    Identity,
    /// The inverse of the world-from-object transform, in `f64`.
    Inverse(DAffine3),
}

impl ToObject {
    /// The transform of an object placed by `world_from_object`: the same inverse as
    /// [`shadowvol_silhouette::object_lights`] computes, so [`ToObject::light`] gives its bits.
    fn new(world_from_object: &Affine3A) -> Self {
        if *world_from_object == Affine3A::IDENTITY {
            return Self::Identity;
        }
        let m = DAffine3::from_cols(
            world_from_object.matrix3.x_axis.as_dvec3(),
            world_from_object.matrix3.y_axis.as_dvec3(),
            world_from_object.matrix3.z_axis.as_dvec3(),
            world_from_object.translation.as_dvec3(),
        );
        Self::Inverse(m.inverse())
    }

    /// `light` in the object's frame, with the operations of
    /// [`shadowvol_silhouette::object_lights`].
    fn light(&self, light: &Light) -> [f32; 4] {
        let [x, y, z, w] = light.to_array();
        match self {
            Self::Identity => [x, y, z, w],
            Self::Inverse(inv) => {
                let v = DVec3::new(f64::from(x), f64::from(y), f64::from(z));
                let xyz = inv.matrix3 * v + inv.translation * f64::from(w);
                [xyz.x as f32, xyz.y as f32, xyz.z as f32, w]
            }
        }
    }
}

/// A work item: a range of blocks of one object.
#[derive(Debug, Clone)]
struct Item {
    object: usize,
    blocks: Range<usize>,
}

/// A scene laid out for the kernels, with its work items.
#[derive(Debug)]
pub(crate) struct Prepared {
    objects: Vec<PreparedObject>,
    total_edges: usize,
    /// Total triangle slots (padded per object).
    total_tri_slots: usize,
    tri_items: Vec<Item>,
    edge_items: Vec<Item>,
    /// Triangle-slot bounds of the triangle items (0, ..., total_tri_slots).
    tri_bounds: Vec<usize>,
    /// Global edge bounds of the edge items (0, ..., total_edges).
    edge_bounds: Vec<usize>,
}

/// What one extraction writes besides its output, kept by the backend between calls so that a
/// call allocates only the silhouette lists it hands over.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    /// Triangle signs, one byte per triangle slot in each pack of up to four lights (see
    /// [`PACK`]).
    signs: Vec<i8>,
    /// Per edge item and light (item-major): the item's silhouette edges.
    sil: Vec<Vec<u32>>,
    /// Per object and light (object-major): the light in the object's frame.
    lights: Vec<[f32; 4]>,
    /// Exact mode with several lights of one `w`: per object, the box of its lights where
    /// sharing pays ([`worth_sharing`]); empty when the lights span no box.
    boxes: Vec<Option<LightBox>>,
    /// With `boxes`: per triangle slot, the sign the object's box shares, or `NOT_SHARED`.
    shared: Vec<i8>,
}

/// Splits `buf` (`parts` equal light slices of `len`) at the item `bounds` (ascending, from 0
/// to `len`), item-major: entry `item * parts + light`.
fn split_rows<'a, T>(buf: &'a mut [T], len: usize, bounds: &[usize]) -> Vec<&'a mut [T]> {
    let items = bounds.len() - 1;
    if len == 0 {
        return Vec::new();
    }
    let mut rests: Vec<&mut [T]> = buf.chunks_mut(len).collect();
    let mut res = Vec::with_capacity(items * rests.len());
    for w in bounds.windows(2) {
        for rest in &mut rests {
            let (head, tail) = std::mem::take(rest).split_at_mut(w[1] - w[0]);
            res.push(head);
            *rest = tail;
        }
    }
    res
}

/// The work items over `counts[o]` triangles or edges of each object `o`, in blocks of [`LANES`].
fn items_for(counts: &[usize]) -> Vec<Item> {
    let mut items = Vec::new();
    for (object, &n) in counts.iter().enumerate() {
        let blocks = n.div_ceil(LANES);
        let mut b = 0;
        while b < blocks {
            let e = (b + BLOCKS_PER_ITEM).min(blocks);
            items.push(Item {
                object,
                blocks: b..e,
            });
            b = e;
        }
    }
    items
}

/// Triangles of the distinct tables of `scene` (instances counted once).
fn distinct_triangles(scene: &TopologyScene) -> usize {
    let tables = scene.objects.iter().map(|o| &o.table);
    shadowvol_silhouette::unique_arc_bytes(tables, |t| t.triangles.len() as u64) as usize
}

impl Prepared {
    /// The layout the scene's tables were given: `copy` or `in-place`.
    pub(crate) fn layout_name(&self) -> &'static str {
        self.objects
            .first()
            .map_or(LayoutChoice::Copy.name(), |o| o.layout.name())
    }

    /// Heap bytes of the layouts (each shared layout once) and the work lists.
    pub(crate) fn heap_bytes(&self) -> u64 {
        use shadowvol_silhouette::{unique_arc_bytes, vec_bytes};
        let layouts = self.objects.iter().map(|o| &o.layout);
        vec_bytes(&self.objects)
            + vec_bytes(&self.tri_items)
            + vec_bytes(&self.edge_items)
            + vec_bytes(&self.tri_bounds)
            + vec_bytes(&self.edge_bounds)
            + unique_arc_bytes(layouts, Layout::heap_bytes)
    }

    /// Lays out every object of `scene` (instances of one table share a layout), copied or in
    /// place as `choice` says, and makes the work items.
    ///
    /// # Errors
    /// [`BackendError::Limit`] when an object is too large for the layout's 32-bit indices.
    pub(crate) fn build(scene: &TopologyScene, choice: LayoutChoice) -> Result<Self, BackendError> {
        let copy = match choice {
            LayoutChoice::Copy => true,
            LayoutChoice::InPlace => false,
            LayoutChoice::Auto => distinct_triangles(scene) <= COPY_MAX_TRIANGLES,
        };
        // Objects sharing one table (instances) share one layout.
        let mut cache: HashMap<*const EdgeTable, Arc<Layout>> = HashMap::new();
        let mut objects = Vec::with_capacity(scene.objects.len());
        let (mut edge_base, mut tri_base) = (0usize, 0usize);
        for (i, o) in scene.objects.iter().enumerate() {
            let key = Arc::as_ptr(&o.table);
            let layout = match cache.get(&key) {
                Some(l) => Arc::clone(l),
                None => {
                    let l = Arc::new(Layout::build(&o.table, copy).map_err(|e| {
                        BackendError::Limit {
                            backend: crate::NAME,
                            message: format!("object {i} ({}): {}", o.name, e.0),
                        }
                    })?);
                    cache.insert(key, Arc::clone(&l));
                    l
                }
            };
            let (ne, nt) = (
                layout.edge_count(),
                with_geometry!(&*layout, g => g.tri_slots()),
            );
            objects.push(PreparedObject {
                layout,
                to_object: ToObject::new(&o.world_from_object),
                edge_base,
                tri_base,
            });
            edge_base += ne;
            tri_base += nt;
        }
        let tri_counts: Vec<usize> = objects.iter().map(|o| o.layout.tri_count()).collect();
        let edge_counts: Vec<usize> = objects.iter().map(|o| o.layout.edge_count()).collect();
        let (tri_items, edge_items) = (items_for(&tri_counts), items_for(&edge_counts));
        let tri_bounds = std::iter::once(0)
            .chain(
                tri_items
                    .iter()
                    .map(|it| objects[it.object].tri_base + it.blocks.end * LANES),
            )
            .collect();
        let edge_bounds = std::iter::once(0)
            .chain(edge_items.iter().map(|it| {
                let o = &objects[it.object];
                o.edge_base + (it.blocks.end * LANES).min(o.layout.edge_count())
            }))
            .collect();
        Ok(Self {
            objects,
            total_edges: edge_base,
            total_tri_slots: tri_base,
            tri_items,
            edge_items,
            tri_bounds,
            edge_bounds,
        })
    }
}

/// One extraction of the prepared scene `p` at `level` for the world-space `lights`: `scratch`
/// is kept between calls, `out` receives every light's multiplicities and silhouette. Returns
/// `ExtractStats::uncertain`: the (edge, OV, light) pairs decided by the scalar exact predicate.
pub(crate) fn run_extract(
    level: SimdLevel,
    p: &Prepared,
    scratch: &mut Scratch,
    lights: &[Light],
    mode: Accuracy,
    out: &mut Multiplicities,
) -> u64 {
    let nl = lights.len();
    let ne = p.total_edges;
    if out.edge_count() != ne || out.light_count() != nl {
        out.reset(ne, nl);
    }
    if nl == 0 {
        return 0;
    }
    stage_lights(p, scratch, lights, mode);
    let share_any = scratch.boxes.iter().any(Option::is_some);
    if share_any && !out.zero_listed(ne, nl) {
        // The shared edge pass writes only the multiplicities that are not 0.
        out.reset(ne, nl);
    }
    let uncertain = if mode == Accuracy::Original {
        0
    } else {
        tri_signs(level, p, scratch, nl, mode, share_any)
    };
    edge_pass(level, p, scratch, nl, mode, out);
    collect_silhouettes(&scratch.sil, p.edge_items.len(), nl, out);
    uncertain * 3
}

/// Fills `scratch.lights` with every light in every object's frame and, in exact mode with
/// several lights of one `w`, `scratch.boxes`: each triangle of an object where it pays is
/// classified once against the box of the lights in the object's frame (`kernel::shared`).
fn stage_lights(p: &Prepared, scratch: &mut Scratch, lights: &[Light], mode: Accuracy) {
    let nl = lights.len();
    scratch.lights.clear();
    for o in &p.objects {
        scratch
            .lights
            .extend(lights.iter().map(|l| o.to_object.light(l)));
    }
    scratch.boxes.clear();
    if mode == Accuracy::Exact && nl >= SHARE_MIN_LIGHTS {
        for (object, o) in p.objects.iter().enumerate() {
            let bx = LightBox::of(&scratch.lights[object * nl..(object + 1) * nl]);
            if bx.is_none() {
                scratch.boxes.clear();
                break;
            }
            scratch
                .boxes
                .push(bx.filter(|bx| with_geometry!(&*o.layout, lay => worth_sharing(lay, bx))));
        }
    }
}

/// Phase 1: one sign per (canonical triangle, light) of the `nl` staged lights: one byte per
/// triangle slot in each pack of up to `PACK` lights; with sharing (`share_any`), also one
/// shared byte per slot. Returns the triangles decided by the scalar exact predicate.
fn tri_signs(
    level: SimdLevel,
    p: &Prepared,
    scratch: &mut Scratch,
    nl: usize,
    mode: Accuracy,
    share_any: bool,
) -> u64 {
    let slots = p.total_tri_slots;
    let packs = nl.div_ceil(PACK);
    let obj_lights = |object: usize| &scratch.lights[object * nl..(object + 1) * nl];
    let boxes = &scratch.boxes;
    let signs = &mut scratch.signs;
    if share_any {
        // Not cleared: every pass writes the sign bytes the edge pass reads (a shared pass
        // those of the blocks with a cut triangle) and every shared byte of its object.
        if signs.len() < slots * packs {
            signs.resize(slots * packs, 0);
        }
    } else {
        signs.clear();
        signs.resize(slots * packs, 0);
    }
    let shared = &mut scratch.shared;
    shared.resize(slots, 0);
    let mut parts = split_rows(&mut signs[..slots * packs], slots, &p.tri_bounds);
    let mut shared_parts = split_rows(shared, slots, &p.tri_bounds);
    if parts.is_empty() {
        return 0;
    }
    p.tri_items
        .par_iter()
        .zip(parts.par_chunks_mut(packs))
        .zip(shared_parts.par_iter_mut())
        .map(|((it, dst), sh)| {
            let o = &p.objects[it.object];
            let (blocks, lights) = (it.blocks.clone(), obj_lights(it.object));
            match boxes.get(it.object).copied().flatten() {
                Some(bx) => with_geometry!(&*o.layout, lay => {
                    let pass = SharedTriPass {
                        lay,
                        blocks,
                        lights,
                        bx: &bx,
                        out: dst,
                        shared: sh,
                    };
                    dispatch::run(level, pass)
                }),
                None => with_geometry!(&*o.layout, lay => {
                    let pass = TriPass {
                        lay,
                        blocks,
                        lights,
                        mode,
                        out: dst,
                    };
                    dispatch::run(level, pass)
                }),
            }
        })
        .sum()
}

/// Phase 2: one pass over all edges of all objects for the `nl` staged lights, from the
/// triangle signs of phase 1 (or, in original mode, from the lights): multiplicities into
/// `out`, each edge item's silhouette edges into `scratch.sil`.
fn edge_pass(
    level: SimdLevel,
    p: &Prepared,
    scratch: &mut Scratch,
    nl: usize,
    mode: Accuracy,
    out: &mut Multiplicities,
) {
    let slots = p.total_tri_slots;
    let packs = nl.div_ceil(PACK);
    let items = p.edge_items.len();
    let sil = &mut scratch.sil;
    sil.resize_with(items * nl, Vec::new);
    for s in sil.iter_mut() {
        s.clear();
    }
    let mut rows = split_rows(out.all_values_mut(), p.total_edges, &p.edge_bounds);
    if rows.is_empty() {
        return;
    }
    let obj_lights = |object: usize| &scratch.lights[object * nl..(object + 1) * nl];
    let boxes: &[Option<LightBox>] = &scratch.boxes;
    let signs: &[i8] = &scratch.signs;
    let shared: &[i8] = &scratch.shared;
    p.edge_items
        .par_iter()
        .zip(rows.par_chunks_mut(nl))
        .zip(sil.par_chunks_mut(nl))
        .for_each(|((it, rows), sil)| {
            let o = &p.objects[it.object];
            let out = EdgeOut {
                rows,
                sil,
                edge_base: o.edge_base,
            };
            if mode == Accuracy::Original {
                with_geometry!(&*o.layout, lay => {
                    let pass = EdgeOriginal {
                        lay,
                        blocks: it.blocks.clone(),
                        lights: obj_lights(it.object),
                        out,
                    };
                    dispatch::run(level, pass);
                });
            } else {
                // Per pack of lights, where the object's slot 0 is (up to 64 lights on the
                // stack).
                let mut small = [0usize; 16];
                let mut large = Vec::new();
                let bases: &mut [usize] = if packs <= small.len() {
                    &mut small[..packs]
                } else {
                    large.resize(packs, 0);
                    &mut large
                };
                for (pack, b) in bases.iter_mut().enumerate() {
                    *b = pack * slots + o.tri_base;
                }
                with_geometry!(&*o.layout, lay => {
                    let pass = EdgeSums {
                        lay,
                        blocks: it.blocks.clone(),
                        signs: PackedSigns {
                            all: signs,
                            bases,
                            shared: boxes
                                .get(it.object)
                                .is_some_and(Option::is_some)
                                .then(|| &shared[o.tri_base..]),
                        },
                        out,
                    };
                    dispatch::run(level, pass);
                });
            }
        });
}

/// Gives `out` each of the `nl` lights' silhouette: the lists of the `items` edge items in
/// `sil` (item-major), concatenated in item order.
fn collect_silhouettes(sil: &[Vec<u32>], items: usize, nl: usize, out: &mut Multiplicities) {
    for l in 0..nl {
        let lists = || (0..items).map(|i| &sil[i * nl + l]);
        let mut all = Vec::with_capacity(lists().map(Vec::len).sum());
        for s in lists() {
            all.extend_from_slice(s);
        }
        out.set_silhouette(l, all);
    }
    out.mark_silhouettes_complete();
}

#[cfg(test)]
mod tests {
    use super::ToObject;
    use glam::{Affine3A, Quat, Vec3};
    use shadowvol_mesh_topology::EdgeTable;
    use shadowvol_silhouette::{object_lights, Light, SceneObject, TopologyScene};
    use shadowvol_test_support::shapes;
    use std::sync::Arc;

    #[test]
    fn object_lights_match_the_shared_transform_bit_for_bit() {
        let table = Arc::new(EdgeTable::build(&shapes::tetrahedron(1.0)).unwrap());
        let transforms = [
            Affine3A::IDENTITY,
            Affine3A::from_translation(Vec3::new(3.0, 1.0, -6.0)),
            Affine3A::from_scale_rotation_translation(
                Vec3::new(1.3, 0.7, 2.1),
                Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.5),
                Vec3::new(-0.1, 1e3, 7.25),
            ),
            Affine3A::from_rotation_translation(
                Quat::from_rotation_y(0.1),
                Vec3::new(1e-3, -2.0, 0.5),
            ),
        ];
        let objects = transforms
            .iter()
            .enumerate()
            .map(|(i, &world_from_object)| SceneObject {
                name: format!("o{i}"),
                table: Arc::clone(&table),
                world_from_object,
            })
            .collect();
        let scene = TopologyScene { objects };
        let lights = [
            Light::point(Vec3::new(-18.0, 64.0, 15.0)),
            Light::point(Vec3::new(0.1, -0.3, 1e-4)),
            Light::directional(Vec3::new(-0.3, 1.0, 0.45)),
        ];
        let reference = object_lights(scene.transforms(), &lights);
        for (o, want) in scene.objects.iter().zip(&reference) {
            let xf = ToObject::new(&o.world_from_object);
            for (light, want) in lights.iter().zip(want) {
                let got = xf.light(light);
                assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits), "{}", o.name);
            }
        }
    }
}
