//! The host side of a kernel launch: turning the kernel's compact lists and uncertain records
//! into [`Multiplicities`], deciding the uncertain records exactly on the host.
//!
//! Both the device path and the [CPU twin](crate::twin) use exactly this code, so a difference
//! between them can only come from the kernel itself.

use shadowvol_silhouette::gpu::{check_batch, resolve_uncertain, HostScene, UncertainRecord};
use shadowvol_silhouette::{BackendError, Multiplicities};
use std::ops::Range;

/// What one kernel run produced, as read back from the device (or produced by the twin).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct KernelOutput {
    /// `counts[0]`: uncertain records appended (possibly more than stored);
    /// `counts[1]`: silhouette entries appended.
    pub counts: Vec<u32>,
    /// The compact silhouette list of all lights: `(light * edges + edge, m)` pairs, any order.
    pub silhouettes: Vec<(u32, i32)>,
    /// The records the filter could not certify.
    pub uncertain: Vec<UncertainRecord>,
}

/// Fills `out` from a kernel run over all `lights`: scatters the compact list, decides the
/// uncertain records with [`resolve_uncertain`] and adds them, and sets the per-light compact
/// silhouette lists. The same as [`finish_batch`] over `0..lights` after resetting `out`.
///
/// # Errors
/// [`BackendError::Device`] when the kernel's output is malformed (an index, slot or light out
/// of range, an edge listed twice, or fewer records than counted): a device or driver fault.
/// [`BackendError::InvalidInput`] when `object_lights` has fewer than `lights` lights per object.
pub fn finish<H: HostScene + ?Sized>(
    layout: &H,
    object_lights: &[Vec<[f32; 4]>],
    lights: usize,
    output: KernelOutput,
    out: &mut Multiplicities,
    backend: &'static str,
) -> Result<(), BackendError> {
    out.reset(layout.edge_count(), lights);
    finish_batch(layout, object_lights, 0..lights, output, out, backend)
}

/// Fills the rows of the lights `batch` of `out` from one kernel launch over those lights:
/// scatters the compact list, decides the uncertain records with [`resolve_uncertain`] and adds them,
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
/// [`BackendError::InvalidInput`] when `out` does not have the layout's edges and at least
/// `batch.end` lights, or an object of `object_lights` has fewer than `batch.end` lights.
pub fn finish_batch<H: HostScene + ?Sized>(
    layout: &H,
    object_lights: &[Vec<[f32; 4]>],
    batch: Range<usize>,
    output: KernelOutput,
    out: &mut Multiplicities,
    backend: &'static str,
) -> Result<(), BackendError> {
    let edges = layout.edge_count();
    let lights = batch.len();
    check_batch(edges, object_lights, &batch, out)?;
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
    resolve_uncertain(
        layout,
        object_lights,
        batch.clone(),
        &uncertain,
        out,
        backend,
    )?;
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
