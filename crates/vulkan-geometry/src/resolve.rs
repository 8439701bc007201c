//! The host side of a pass: the multiplicities read into their rows of the result, the
//! uncertain records read back, and those decided exactly with
//! [`gpu::resolve_uncertain`]. The CPU twin finishes its passes with the same code.

use crate::layout::{Prepared, UNCERTAIN_HEADER};
use crate::NAME;
use shadowvol_silhouette::gpu::{self, HostScene, UncertainRecord};
use shadowvol_silhouette::{BackendError, Multiplicities};
use std::ops::Range;

/// Reads one pass over the lights `batch` back from `p`'s buffers: the multiplicities into the
/// batch's rows of `out` (shaped to the scene's edges and every light of the extraction) and
/// the first `count` uncertain records, which it returns.
///
/// # Panics
/// If `out` does not have the rows of `batch`, or `count` exceeds the uncertain buffer.
pub(crate) fn read_pass(
    p: &Prepared,
    batch: Range<usize>,
    count: u32,
    out: &mut Multiplicities,
) -> Vec<UncertainRecord> {
    let edges = p.index.edge_count();
    let rows = &mut out.all_values_mut()[batch.start * edges..batch.end * edges];
    p.mult.read(0, bytemuck::cast_slice_mut(rows));
    let mut words = vec![0u32; UncertainRecord::WORDS * count as usize];
    if count > 0 {
        p.uncertain
            .read(UNCERTAIN_HEADER, bytemuck::cast_slice_mut(&mut words));
    }
    UncertainRecord::read_all(&words)
}

/// Decides the uncertain `records` of one pass over the lights `batch` exactly, on the same
/// object-space `f32` inputs (`object_lights`: every light of the extraction, per object), and
/// writes the decisions into `out`, whose rows of `batch` hold the pass's multiplicities. The
/// compact silhouette lists are left to the caller (built once from `m` after every batch).
///
/// # Errors
/// [`BackendError::Device`] for a record out of range (a malformed device output).
pub(crate) fn finish_batch<H: HostScene>(
    layout: &H,
    object_lights: &[Vec<[f32; 4]>],
    batch: Range<usize>,
    records: &[UncertainRecord],
    out: &mut Multiplicities,
) -> Result<(), BackendError> {
    gpu::resolve_uncertain(layout, object_lights, batch, records, out, NAME)
}
