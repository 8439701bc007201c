//! Host side of a dispatch: fill [`Multiplicities`] from the device's output and decide the
//! uncertain triples exactly. Shared by the wgpu backend and the CPU twin.

use shadowvol_silhouette::gpu::{resolve_uncertain, HostScene, UncertainRecord};
use shadowvol_silhouette::{BackendError, Multiplicities};
use std::ops::Range;

/// A `(triangle, light)` pair whose sign the triangle step's exact filter could not certify (with
/// [`WgpuOptions::exact_on_device`](crate::WgpuOptions::exact_on_device) off). The device counted
/// the triangle's sign as 0; the host decides the three `(edge, OV, light)` triples it
/// contributes to.
///
/// On the device a record is 4 `u32`s: `triangle`, `light`, 0, 0.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct UncertainTriangle {
    /// Global triangle (index into
    /// [`TableLayout::tris`](shadowvol_silhouette::gpu::TableLayout::tris)).
    pub triangle: u32,
    /// Light index within the dispatch (0-based).
    pub light: u32,
}

/// The `(edge, OV slot, light)` triples of `pairs`, three per pair: `edge_slots(t)` gives
/// triangle `t`'s pairs (as
/// [`SceneIndex::edge_slots`](shadowvol_silhouette::gpu::SceneIndex::edge_slots)), `None` past the
/// last of the scene's `triangles` triangles.
///
/// # Errors
/// [`BackendError::Device`] for a pair out of range (a malformed device output).
pub(crate) fn expand_uncertain(
    pairs: &[UncertainTriangle],
    edge_slots: impl Fn(usize) -> Option<[(u32, u32); 3]>,
    triangles: usize,
    light_count: usize,
) -> Result<Vec<UncertainRecord>, BackendError> {
    let mut out = Vec::with_capacity(3 * pairs.len());
    for p in pairs {
        let Some(slots) = edge_slots(p.triangle as usize) else {
            return Err(malformed(p, triangles, light_count));
        };
        if p.light as usize >= light_count {
            return Err(malformed(p, triangles, light_count));
        }
        out.extend(slots.iter().map(|&(edge, ov_slot)| UncertainRecord {
            edge,
            ov_slot,
            light: p.light,
        }));
    }
    Ok(out)
}

fn malformed(p: &UncertainTriangle, triangles: usize, lights: usize) -> BackendError {
    BackendError::Device {
        backend: crate::NAME,
        message: format!(
            "malformed kernel output: uncertain record (triangle {}, light {}) out of range \
             ({triangles} triangles, a {lights}-light batch)",
            p.triangle, p.light
        ),
    }
}

/// The device output of one dispatch (a batch of lights).
pub(crate) struct BatchOutput {
    /// Full per-edge values `[light * edge_count + edge]`, when read back.
    pub mult: Option<Vec<i32>>,
    /// Per light, the compact list `(edge, m)`, any order.
    pub lists: Vec<Vec<(u32, i32)>>,
    /// Uncertain triples (expanded from the device's undecided triangles).
    pub uncertain: Vec<UncertainRecord>,
}

/// What the host changed: the device buffers must be patched the same way.
#[derive(Debug, Default)]
pub(crate) struct Patch {
    /// `(light within the batch, edge, final m)` for every edge an uncertain triple touched.
    pub mult: Vec<(u32, u32, i32)>,
    /// `(light within the batch, final compact list)` for every light whose list changed.
    pub lists: Vec<(u32, Vec<(u32, i32)>)>,
}

/// Writes one batch into `out` (the rows of the lights `batch`), resolves its uncertain triples
/// with [`resolve_uncertain`] on the same object-space `f32` inputs (`object_lights`, all lights
/// of the extraction per object), fixes the compact lists and returns the patch.
///
/// # Errors
/// [`BackendError::Device`] for an uncertain record out of range.
pub(crate) fn finish_batch<H: HostScene>(
    scene: &H,
    object_lights: &[Vec<[f32; 4]>],
    batch: Range<usize>,
    output: BatchOutput,
    out: &mut Multiplicities,
) -> Result<Patch, BackendError> {
    let first = batch.start;
    let edge_count = scene.edge_count();
    let BatchOutput {
        mult,
        mut lists,
        mut uncertain,
    } = output;
    for (li, list) in lists.iter().enumerate() {
        let values = out.values_mut(first + li);
        match &mult {
            Some(m) => values.copy_from_slice(&m[li * edge_count..(li + 1) * edge_count]),
            None => {
                for &(e, m) in list {
                    values[e as usize] = m;
                }
            }
        }
    }
    let mut patch = Patch::default();
    if !uncertain.is_empty() {
        uncertain.sort_unstable_by_key(|r| (r.light, r.edge, r.ov_slot));
        resolve_uncertain(scene, object_lights, batch, &uncertain, out, crate::NAME)?;
        let mut touched: Vec<(u32, u32)> = uncertain.iter().map(|r| (r.light, r.edge)).collect();
        touched.dedup();
        for &(li, e) in &touched {
            patch
                .mult
                .push((li, e, out.values(first + li as usize)[e as usize]));
        }
        for group in touched.chunk_by(|x, y| x.0 == y.0) {
            let li = group[0].0;
            let list = &mut lists[li as usize];
            // `group` is sorted by edge: binary search decides membership.
            list.retain(|(e, _)| group.binary_search(&(li, *e)).is_err());
            let values = out.values(first + li as usize);
            list.extend(
                group
                    .iter()
                    .map(|&(_, e)| (e, values[e as usize]))
                    .filter(|&(_, m)| m != 0),
            );
            patch.lists.push((li, list.clone()));
        }
    }
    for (li, list) in lists.into_iter().enumerate() {
        let mut edges: Vec<u32> = list.into_iter().map(|(e, _)| e).collect();
        radix_sort(&mut edges);
        // Already sorted: `set_silhouette`'s own sort only confirms it (linear).
        out.set_silhouette(first + li, edges);
    }
    Ok(patch)
}

/// Sorts distinct-or-not `u32` keys ascending with an LSD radix sort (11-bit digits, passes
/// whose digit is the same for every key skipped). The device appends silhouette edges in
/// atomic order; this keeps the host's ordering cost linear in the silhouette size.
pub(crate) fn radix_sort(keys: &mut Vec<u32>) {
    const BITS: u32 = 11;
    const BUCKETS: usize = 1 << BITS;
    if keys.len() < 256 {
        keys.sort_unstable();
        return;
    }
    let max = keys.iter().copied().max().unwrap_or(0);
    let mut tmp = vec![0u32; keys.len()];
    let mut shift = 0;
    while shift < 32 && (max >> shift) != 0 {
        let digit = |k: u32| ((k >> shift) as usize) & (BUCKETS - 1);
        let mut count = [0usize; BUCKETS];
        for &k in keys.iter() {
            count[digit(k)] += 1;
        }
        let mut sum = 0;
        for c in &mut count {
            let n = *c;
            *c = sum;
            sum += n;
        }
        for &k in keys.iter() {
            let d = digit(k);
            tmp[count[d]] = k;
            count[d] += 1;
        }
        std::mem::swap(keys, &mut tmp);
        shift += BITS;
    }
}

#[cfg(test)]
mod tests {
    use super::{expand_uncertain, radix_sort, UncertainTriangle};

    #[test]
    fn out_of_range_pairs_are_errors_not_panics() {
        let slots = [[(0, 0), (1, 2), (2, 4)]];
        let of = |t: usize| slots.get(t).copied();
        let ok = expand_uncertain(
            &[UncertainTriangle {
                triangle: 0,
                light: 1,
            }],
            of,
            1,
            2,
        )
        .unwrap();
        assert_eq!(ok.len(), 3);
        assert!(ok.iter().all(|r| r.light == 1));
        assert_eq!(ok[1].edge, 1);
        assert_eq!(ok[1].ov_slot, 2);
        for bad in [
            UncertainTriangle {
                triangle: 1,
                light: 0,
            },
            UncertainTriangle {
                triangle: 0,
                light: 2,
            },
        ] {
            let e = expand_uncertain(&[bad], of, 1, 2).unwrap_err().to_string();
            assert!(e.contains("out of range"), "{e}");
        }
    }

    #[test]
    fn radix_sort_sorts_like_the_standard_sort() {
        let mut state = 0x1234_5678_9abc_def0u64;
        for len in [0usize, 1, 255, 256, 257, 5000, 70_000] {
            for max_bits in [1u32, 11, 12, 22, 23, 32] {
                let mut keys: Vec<u32> = (0..len)
                    .map(|_| {
                        state ^= state << 13;
                        state ^= state >> 7;
                        state ^= state << 17;
                        (state >> 32) as u32 >> (32 - max_bits)
                    })
                    .collect();
                let mut expected = keys.clone();
                expected.sort_unstable();
                radix_sort(&mut keys);
                assert_eq!(keys, expected, "len {len}, bits {max_bits}");
            }
        }
    }
}
