//! How many lights one batch (a kernel launch, a geometry-shader pass) can take.

use std::num::NonZeroUsize;
use std::ops::Range;

/// The most lights one batch can take: the smallest `capacity / per_light` over `budgets` (each
/// a device limit and what one light consumes of it, in the same unit: bytes, indices), and at
/// most `cap`. A `per_light` of 0 is counted as 1. Returns 0 when not even one light fits; the
/// caller turns that into its own `Limit` error naming its limits.
///
/// ```
/// use shadowvol_silhouette::gpu::lights_per_batch;
/// use std::num::NonZeroUsize;
///
/// // 1000 bytes for 96 bytes a light, 2^32 - 1 indices for 10 a light: 10 lights by memory.
/// assert_eq!(lights_per_batch(&[(1000, 96), (u64::from(u32::MAX), 10)], None), 10);
/// assert_eq!(lights_per_batch(&[(1000, 96)], NonZeroUsize::new(3)), 3);
/// assert_eq!(lights_per_batch(&[(50, 96)], None), 0);
/// ```
#[must_use]
pub fn lights_per_batch(budgets: &[(u64, u64)], cap: Option<NonZeroUsize>) -> usize {
    let n = budgets
        .iter()
        .map(|&(capacity, per_light)| capacity / per_light.max(1))
        .min()
        .unwrap_or(u64::MAX)
        .min(cap.map_or(u64::MAX, |c| c.get() as u64));
    usize::try_from(n).unwrap_or(usize::MAX)
}

/// The batches of `lights` lights at most `per_batch` each, in order: `0..per_batch`,
/// `per_batch..2 * per_batch`, ..., the last one shorter. No batch when `lights` is 0.
///
/// # Panics
/// If `per_batch` is 0 and `lights` is not.
///
/// ```
/// use shadowvol_silhouette::gpu::batches;
/// assert_eq!(batches(5, 2).collect::<Vec<_>>(), [0..2, 2..4, 4..5]);
/// ```
pub fn batches(lights: usize, per_batch: usize) -> impl Iterator<Item = Range<usize>> {
    assert!(
        per_batch > 0 || lights == 0,
        "a batch must take at least one light"
    );
    (0..lights)
        .step_by(per_batch.max(1))
        .map(move |start| start..lights.min(start + per_batch))
}
