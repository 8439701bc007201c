//! A prepared scene and one extraction over it: the work items of every object, the two rayon
//! passes (triangles, then edges) and the assembly of the silhouette lists.

use crate::dispatch;
use crate::kernel::edge_pass::{EdgeSums, PackedSigns};
use crate::kernel::original::EdgeOriginal;
use crate::kernel::signs::PACK;
use crate::kernel::tri_pass::TriPass;
use crate::kernel::EdgeOut;
use crate::layout::{Layout, LANES};
use crate::SimdLevel;
use rayon::prelude::*;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_silhouette::{Accuracy, BackendError, Multiplicities, TopologyScene};
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
    /// First global edge index.
    edge_base: usize,
    /// First slot of the object's triangles in the per-light sign arrays (multiple of 8).
    tri_base: usize,
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
    /// The scene as prepared (its objects' transforms place the lights in each object's frame).
    pub(crate) scene: TopologyScene,
    objects: Vec<PreparedObject>,
    total_edges: usize,
    /// Total triangle slots (padded per object).
    total_tri_slots: usize,
    tri_items: Vec<Item>,
    edge_items: Vec<Item>,
}

/// Splits `buf` (`parts` equal light slices of `len`) at the item `bounds` (ascending, from 0
/// to `len`): result\[item\]\[light\].
fn split_items<'a, T>(buf: &'a mut [T], len: usize, bounds: &[usize]) -> Vec<Vec<&'a mut [T]>> {
    let items = bounds.len() - 1;
    let mut res: Vec<Vec<&mut [T]>> = (0..items).map(|_| Vec::new()).collect();
    if len == 0 {
        return res;
    }
    for light in buf.chunks_mut(len) {
        let mut rest = light;
        for (i, w) in bounds.windows(2).enumerate() {
            let (head, tail) = rest.split_at_mut(w[1] - w[0]);
            res[i].push(head);
            rest = tail;
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

impl Prepared {
    /// Lays out every object of `scene` (instances of one table share a layout) and makes the
    /// work items.
    ///
    /// # Errors
    /// [`BackendError::Limit`] when an object is too large for the layout's 32-bit indices.
    pub(crate) fn build(scene: &TopologyScene) -> Result<Self, BackendError> {
        // Objects sharing one table (instances) share one layout.
        let mut cache: HashMap<*const EdgeTable, Arc<Layout>> = HashMap::new();
        let mut objects = Vec::with_capacity(scene.objects.len());
        let (mut edge_base, mut tri_base) = (0usize, 0usize);
        for (i, o) in scene.objects.iter().enumerate() {
            let key = Arc::as_ptr(&o.table);
            let layout = match cache.get(&key) {
                Some(l) => Arc::clone(l),
                None => {
                    let l = Arc::new(Layout::build(&o.table).map_err(|e| BackendError::Limit {
                        backend: crate::NAME,
                        message: format!("object {i} ({}): {}", o.name, e.0),
                    })?);
                    cache.insert(key, Arc::clone(&l));
                    l
                }
            };
            let (ne, nt) = (layout.edge_count, layout.t0.len());
            objects.push(PreparedObject {
                layout,
                edge_base,
                tri_base,
            });
            edge_base += ne;
            tri_base += nt;
        }
        let tri_counts: Vec<usize> = objects.iter().map(|o| o.layout.tri_count).collect();
        let edge_counts: Vec<usize> = objects.iter().map(|o| o.layout.edge_count).collect();
        Ok(Self {
            scene: scene.clone(),
            objects,
            total_edges: edge_base,
            total_tri_slots: tri_base,
            tri_items: items_for(&tri_counts),
            edge_items: items_for(&edge_counts),
        })
    }

    /// Global edge bounds of the edge items (0, ..., total_edges).
    fn edge_bounds(&self) -> Vec<usize> {
        let mut b = vec![0];
        for it in &self.edge_items {
            let o = &self.objects[it.object];
            b.push(o.edge_base + (it.blocks.end * LANES).min(o.layout.edge_count));
        }
        b
    }

    /// Triangle-slot bounds of the triangle items.
    fn tri_bounds(&self) -> Vec<usize> {
        let mut b = vec![0];
        for it in &self.tri_items {
            b.push(self.objects[it.object].tri_base + it.blocks.end * LANES);
        }
        b
    }
}

/// One extraction of the prepared scene `p` at `level`: `obj_lights[o]` are the lights in
/// object `o`'s frame, `signs` is the scratch of the triangle signs, `out` receives every
/// light's multiplicities and silhouette. Returns `ExtractStats::uncertain`: the (edge, OV,
/// light) pairs decided by the scalar exact predicate.
pub(crate) fn run_extract(
    level: SimdLevel,
    p: &Prepared,
    signs: &mut Vec<i8>,
    obj_lights: &[Vec<[f32; 4]>],
    mode: Accuracy,
    out: &mut Multiplicities,
) -> u64 {
    let nl = obj_lights.first().map_or(0, Vec::len);
    let ne = p.total_edges;
    if out.edge_count() != ne || out.light_count() != nl {
        out.reset(ne, nl);
    }
    let mut uncertain = 0u64;
    if mode != Accuracy::Original {
        // Phase 1: one sign per (canonical triangle, light).
        // One byte per triangle slot in each pack of up to `PACK` lights.
        let slots = p.total_tri_slots;
        let packs = nl.div_ceil(PACK);
        signs.clear();
        signs.resize(slots * packs, 0);
        let parts = split_items(signs, slots, &p.tri_bounds());
        uncertain = p
            .tri_items
            .par_iter()
            .zip(parts)
            .map(|(it, mut dst)| {
                let lay = &p.objects[it.object].layout;
                let pass = TriPass {
                    lay,
                    blocks: it.blocks.clone(),
                    lights: &obj_lights[it.object],
                    mode,
                    out: &mut dst,
                };
                dispatch::run(level, pass)
            })
            .sum();
    }
    // Phase 2: one pass over all edges of all objects.
    let signs: &[i8] = signs;
    let slots = p.total_tri_slots;
    let parts = split_items(out.all_values_mut(), ne, &p.edge_bounds());
    let lists: Vec<Vec<Vec<u32>>> = p
        .edge_items
        .par_iter()
        .zip(parts)
        .map(|(it, mut dst)| {
            let o = &p.objects[it.object];
            let mut sil = vec![Vec::new(); nl];
            let out = EdgeOut {
                rows: &mut dst,
                sil: &mut sil,
                edge_base: o.edge_base,
            };
            if mode == Accuracy::Original {
                let pass = EdgeOriginal {
                    lay: &o.layout,
                    blocks: it.blocks.clone(),
                    lights: &obj_lights[it.object],
                    out,
                };
                dispatch::run(level, pass);
            } else {
                let bases: Vec<usize> = (0..nl.div_ceil(PACK))
                    .map(|pack| pack * slots + o.tri_base)
                    .collect();
                let pass = EdgeSums {
                    lay: &o.layout,
                    blocks: it.blocks.clone(),
                    signs: PackedSigns {
                        all: signs,
                        bases: &bases,
                    },
                    out,
                };
                dispatch::run(level, pass);
            }
            sil
        })
        .collect();
    for l in 0..nl {
        let total = lists.iter().map(|s| s[l].len()).sum();
        let mut all = Vec::with_capacity(total);
        for s in &lists {
            all.extend_from_slice(&s[l]);
        }
        out.set_silhouette(l, all);
    }
    uncertain * 3
}
