//! The flat, all-objects-concatenated layout the kernel reads, and the host side of an extraction
//! (turning the kernel's compact lists and uncertain records into [`Multiplicities`]).
//!
//! Both the device path and the [CPU twin](crate::twin) use exactly this code, so a difference
//! between them can only come from the kernel itself.

use shadowvol_robust_math::orient_exact;
use shadowvol_silhouette::{BackendError, Multiplicities, TopologyScene};
use std::ops::Range;

/// Accuracy mode codes passed to the kernel (`mode` argument).
pub(crate) const MODE_ORIGINAL: u32 = 0;
pub(crate) const MODE_ROBUST: u32 = 1;
pub(crate) const MODE_ORDERED: u32 = 2;
pub(crate) const MODE_EXACT: u32 = 3;

/// The kernel's code for an accuracy mode.
pub(crate) fn mode_code(mode: shadowvol_robust_math::Accuracy) -> u32 {
    use shadowvol_robust_math::Accuracy;
    match mode {
        Accuracy::Original => MODE_ORIGINAL,
        Accuracy::Robust => MODE_ROBUST,
        Accuracy::Ordered => MODE_ORDERED,
        Accuracy::Exact => MODE_EXACT,
    }
}

/// A prepared scene in the kernel's layout: every object's edge table concatenated, with global
/// vertex ids (object base + compact id) and global OV offsets.
///
/// Adding the same base to all ids of an object keeps their order, so the canonical triangle
/// order and its parity are the same as with the object's compact ids.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FlatScene {
    /// Positions, 3 `f32` per vertex (object space of the vertex's object).
    pub positions: Vec<f32>,
    /// Edges, 2 global vertex ids per edge, `a < b`.
    pub edges: Vec<u32>,
    /// Object index of every edge.
    pub edge_obj: Vec<u32>,
    /// CSR offsets into [`FlatScene::ovs`], one per edge plus one.
    pub ov_offsets: Vec<u32>,
    /// Opposite vertices (global vertex ids).
    pub ovs: Vec<u32>,
    /// Number of objects.
    pub objects: usize,
}

impl FlatScene {
    /// Lays out `scene`.
    ///
    /// # Errors
    /// [`BackendError::Limit`] when vertex ids, OV offsets or edge indices do not fit in `u32`.
    pub fn build(scene: &TopologyScene, backend: &'static str) -> Result<Self, BackendError> {
        let limit = |what: &str, n: usize| BackendError::Limit {
            backend,
            message: format!(
                "the scene has {n} {what}, more than the kernel's 32-bit indices can address ({})",
                u32::MAX
            ),
        };
        let vertices = scene.total_vertices();
        let edges = scene.total_edges();
        let ovs = scene.total_ovs();
        if vertices >= u32::MAX as usize {
            return Err(limit("vertices", vertices));
        }
        if edges >= u32::MAX as usize {
            return Err(limit("edges", edges));
        }
        if ovs >= u32::MAX as usize {
            return Err(limit("opposite vertices", ovs));
        }
        if scene.objects.len() >= u32::MAX as usize {
            return Err(limit("objects", scene.objects.len()));
        }
        let mut flat = FlatScene {
            positions: Vec::with_capacity(vertices * 3),
            edges: Vec::with_capacity(edges * 2),
            edge_obj: Vec::with_capacity(edges),
            ov_offsets: Vec::with_capacity(edges + 1),
            ovs: Vec::with_capacity(ovs),
            objects: scene.objects.len(),
        };
        flat.ov_offsets.push(0);
        for (i, object) in scene.objects.iter().enumerate() {
            let t = &object.table;
            // Both fit: checked against the totals above.
            let vbase = (flat.positions.len() / 3) as u32;
            let obase = flat.ovs.len() as u32;
            flat.positions
                .extend(t.positions.iter().flat_map(|p| p.to_array()));
            for &[a, b] in &t.edges {
                flat.edges.push(vbase + a);
                flat.edges.push(vbase + b);
                flat.edge_obj.push(i as u32);
            }
            flat.ov_offsets
                .extend(t.ov_offsets.iter().skip(1).map(|&o| obase + o));
            flat.ovs.extend(t.ovs.iter().map(|&o| vbase + o));
        }
        Ok(flat)
    }

    /// Number of edges (all objects).
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edge_obj.len()
    }

    /// Number of vertices (all objects).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.positions.len() / 3
    }

    /// Position of global vertex `i`.
    ///
    /// # Panics
    /// Panics if `i` is out of range.
    #[must_use]
    pub fn position(&self, i: u32) -> [f32; 3] {
        let i = i as usize * 3;
        [
            self.positions[i],
            self.positions[i + 1],
            self.positions[i + 2],
        ]
    }
}

/// Object-space lights flattened for the kernel: 4 `f32` per (object, light), index
/// `object * lights + light`.
#[must_use]
pub fn flat_lights(object_lights: &[Vec<[f32; 4]>]) -> Vec<f32> {
    object_lights
        .iter()
        .flat_map(|per_object| per_object.iter().flatten().copied())
        .collect()
}

/// The lights `batch` of `object_lights` flattened for one kernel launch: 4 `f32` per (object,
/// light of the batch), index `object * batch.len() + (light - batch.start)`. The whole range
/// gives [`flat_lights`].
///
/// # Errors
/// [`BackendError::InvalidInput`] when `batch` is not a range of every object's lights.
pub fn flat_light_batch(
    object_lights: &[Vec<[f32; 4]>],
    batch: Range<usize>,
) -> Result<Vec<f32>, BackendError> {
    let mut flat = Vec::with_capacity(object_lights.len() * batch.len() * 4);
    for (i, per_object) in object_lights.iter().enumerate() {
        let lights = per_object.get(batch.clone()).ok_or_else(|| {
            BackendError::InvalidInput(format!(
                "light batch {batch:?} out of range: object {i} has {} lights",
                per_object.len()
            ))
        })?;
        flat.extend(lights.iter().flatten());
    }
    Ok(flat)
}

/// What one kernel run produced, as read back from the device (or produced by the twin).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct KernelOutput {
    /// `counts[0]`: uncertain records appended (possibly more than stored);
    /// `counts[1]`: silhouette entries appended.
    pub counts: Vec<u32>,
    /// The compact silhouette list of all lights: `(light * edges + edge, m)` pairs, any order.
    pub silhouettes: Vec<(u32, i32)>,
    /// `(edge, ov slot, light)` records the filter could not certify.
    pub uncertain: Vec<[u32; 3]>,
}

/// Fills `out` from a kernel run over all `lights`: scatters the compact list, decides the
/// uncertain records with [`orient_exact`] and adds them, and sets the per-light compact
/// silhouette lists. The same as [`finish_batch`] over `0..lights` after resetting `out`.
///
/// # Errors
/// [`BackendError::Device`] when the kernel's output is malformed (an index, slot or light out
/// of range, an edge listed twice, or fewer records than counted): a device or driver fault.
/// [`BackendError::InvalidInput`] when `object_lights` has fewer than `lights` lights per object.
pub fn finish(
    flat: &FlatScene,
    object_lights: &[Vec<[f32; 4]>],
    lights: usize,
    output: KernelOutput,
    out: &mut Multiplicities,
    backend: &'static str,
) -> Result<(), BackendError> {
    out.reset(flat.edge_count(), lights);
    finish_batch(flat, object_lights, 0..lights, output, out, backend)
}

/// Fills the rows of the lights `batch` of `out` from one kernel launch over those lights:
/// scatters the compact list, decides the uncertain records with [`orient_exact`] and adds them,
/// and sets those lights' compact silhouette lists. Other rows are left as they are.
///
/// The launch numbers its lights from 0: light `l` of `output` (in its silhouette indices
/// `l * edges + edge` and its uncertain records) is light `batch.start + l` of `out` and of
/// `object_lights` (all lights of the extraction, per object). The rows of `batch` must be zero
/// (as [`Multiplicities::reset`] leaves them).
///
/// # Errors
/// [`BackendError::Device`] when the kernel's output is malformed (an index, slot or light out
/// of range, an edge listed twice, or fewer records than counted): a device or driver fault.
/// [`BackendError::InvalidInput`] when `out` does not have `flat`'s edges and at least
/// `batch.end` lights, or an object of `object_lights` has fewer than `batch.end` lights.
pub fn finish_batch(
    flat: &FlatScene,
    object_lights: &[Vec<[f32; 4]>],
    batch: Range<usize>,
    output: KernelOutput,
    out: &mut Multiplicities,
    backend: &'static str,
) -> Result<(), BackendError> {
    let edges = flat.edge_count();
    let lights = batch.len();
    if out.edge_count() != edges || out.light_count() < batch.end {
        return Err(BackendError::InvalidInput(format!(
            "light batch {batch:?} over {edges} edges does not fit multiplicities of {} edges \
             and {} lights",
            out.edge_count(),
            out.light_count()
        )));
    }
    if let Some((i, l)) = object_lights
        .iter()
        .enumerate()
        .find(|(_, l)| l.len() < batch.end)
    {
        return Err(BackendError::InvalidInput(format!(
            "light batch {batch:?} out of range: object {i} has {} lights",
            l.len()
        )));
    }
    let bad = |what: String| BackendError::Device {
        backend,
        message: format!("malformed kernel output: {what}"),
    };
    let KernelOutput {
        counts,
        silhouettes,
        uncertain,
    } = output;
    let counted = |i: usize| counts.get(i).copied().unwrap_or(0) as usize;
    if counted(0) != uncertain.len() || counted(1) != silhouettes.len() {
        return Err(bad(format!(
            "{} uncertain records and {} silhouette entries counted, {} and {} read back",
            counted(0),
            counted(1),
            uncertain.len(),
            silhouettes.len()
        )));
    }
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); lights];
    {
        let values = &mut out.all_values_mut()[batch.start * edges..batch.end * edges];
        for &(index, m) in &silhouettes {
            let slot = values.get_mut(index as usize).ok_or_else(|| {
                bad(format!(
                    "silhouette index {index} out of range ({edges} edges x {lights} lights)"
                ))
            })?;
            if *slot != 0 || m == 0 {
                return Err(bad(format!(
                    "silhouette index {index} listed twice or with m = 0"
                )));
            }
            *slot = m;
            let (l, e) = (index as usize / edges, index as usize % edges);
            lists[l].push(e as u32);
        }
    }
    if uncertain.is_empty() {
        for (l, list) in lists.into_iter().enumerate() {
            out.set_silhouette(batch.start + l, list);
        }
        return Ok(());
    }
    for &[e, k, l] in &uncertain {
        let (ei, ki, li) = (e as usize, k as usize, l as usize);
        if ei >= edges || li >= lights {
            return Err(bad(format!(
                "uncertain record ({e}, {k}, {l}) out of range ({edges} edges x {lights} lights)"
            )));
        }
        if ki < flat.ov_offsets[ei] as usize || ki >= flat.ov_offsets[ei + 1] as usize {
            return Err(bad(format!(
                "uncertain record ({e}, {k}, {l}): slot {k} is not an opposite vertex of edge {e}"
            )));
        }
        let a = flat.position(flat.edges[2 * ei]);
        let b = flat.position(flat.edges[2 * ei + 1]);
        let o = flat.position(flat.ovs[ki]);
        let li = batch.start + li;
        let light = object_lights[flat.edge_obj[ei] as usize][li];
        out.values_mut(li)[ei] += i32::from(orient_exact(a, b, light, o));
    }
    // Host decisions may add or remove silhouette edges: rebuild the batch's lists from the
    // values.
    for l in batch {
        let list = out
            .values(l)
            .iter()
            .enumerate()
            .filter(|(_, &m)| m != 0)
            .map(|(e, _)| e as u32)
            .collect();
        out.set_silhouette(l, list);
    }
    Ok(())
}
