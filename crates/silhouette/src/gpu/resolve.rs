//! The uncertain-record format of the GPU kernels and the host's exact decision of the records.

use super::HostScene;
use crate::{BackendError, Multiplicities};
use shadowvol_robust_math::orient_exact;
use std::ops::Range;

/// One `(edge, OV slot, light)` triple whose sign a kernel's exact-mode filter could not
/// certify. The kernel counted it as 0; the host adds its exact sign.
///
/// On the device a record is [`UncertainRecord::WORDS`] `u32`s: `edge`, `ov_slot`, `light`, 0
/// (16 bytes, the stride of a `vec4<u32>`/`uvec4` array element).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct UncertainRecord {
    /// Global edge index (into [`SceneLayout::edges`](super::SceneLayout::edges)).
    pub edge: u32,
    /// Global OV slot (index into [`SceneLayout::ovs`](super::SceneLayout::ovs)), one of the
    /// edge's slots.
    pub ov_slot: u32,
    /// Light index within the batch the kernel ran (0-based).
    pub light: u32,
}

impl UncertainRecord {
    /// `u32` words per record in device buffers.
    pub const WORDS: usize = 4;

    /// The records in `words` ([`Self::WORDS`] words each; a trailing partial record is
    /// ignored).
    #[must_use]
    pub fn read_all(words: &[u32]) -> Vec<Self> {
        words
            .chunks_exact(Self::WORDS)
            .map(|w| Self {
                edge: w[0],
                ov_slot: w[1],
                light: w[2],
            })
            .collect()
    }
}

/// Checks that a batch over the lights `batch` of an extraction fits: `out` has `edges` edges
/// and at least `batch.end` lights, and every object of `object_lights` has at least
/// `batch.end` lights.
///
/// # Errors
/// [`BackendError::InvalidInput`] saying which does not fit.
pub fn check_batch(
    edges: usize,
    object_lights: &[Vec<[f32; 4]>],
    batch: &Range<usize>,
    out: &Multiplicities,
) -> Result<(), BackendError> {
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
    Ok(())
}

/// Decides every record of `records` exactly and adds its sign to `out`: record `r` of a batch
/// over the lights `batch` adds `orient_exact(A, B, L, O)` to edge `r.edge` of light
/// `batch.start + r.light`, with the positions `scene` gives (a [`SceneLayout`] in host memory,
/// or a [`SceneIndex`] over the edge tables) and the object-space light
/// `object_lights[object of the edge][batch.start + r.light]`, the very `f32` inputs the kernel
/// filtered. Compact silhouette lists are left to the caller.
///
/// # Errors
/// * [`BackendError::Device`] naming `backend` when a record is out of range (an edge, a light
///   outside the batch, or a slot that is not one of the edge's opposite vertices): a device or
///   driver fault, reported instead of a panic.
/// * [`BackendError::InvalidInput`] when `out` does not have the layout's edges and
///   `batch.end` lights, or an object of `object_lights` has fewer than `batch.end` lights.
///
/// [`SceneLayout`]: super::SceneLayout
/// [`SceneIndex`]: super::SceneIndex
pub fn resolve_uncertain<H: HostScene + ?Sized>(
    scene: &H,
    object_lights: &[Vec<[f32; 4]>],
    batch: Range<usize>,
    records: &[UncertainRecord],
    out: &mut Multiplicities,
    backend: &'static str,
) -> Result<(), BackendError> {
    let edges = scene.edge_count();
    check_batch(edges, object_lights, &batch, out)?;
    for r in records {
        let (e, k, li) = (r.edge as usize, r.ov_slot as usize, r.light as usize);
        if e >= edges || li >= batch.len() || !scene.ov_slots(e).contains(&k) {
            return Err(BackendError::Device {
                backend,
                message: format!(
                    "malformed kernel output: uncertain record (edge {e}, opposite-vertex slot \
                     {k}, light {li}) out of range ({edges} edges, a {}-light batch)",
                    batch.len()
                ),
            });
        }
        let (a, b, object) = scene.edge_points(e);
        let light = batch.start + li;
        let s = orient_exact(a, b, object_lights[object][light], scene.ov_point(e, k));
        out.values_mut(light)[e] += i32::from(s);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::{SceneIndex, SceneLayout};
    use crate::{object_lights, TopologyScene};
    use shadowvol_mesh_topology::EdgeTable;
    use shadowvol_robust_math::{ov_sign, Accuracy, Light};
    use shadowvol_test_support::shapes;

    fn scene() -> TopologyScene {
        TopologyScene::single(EdgeTable::build(&shapes::uv_sphere_y(5, 6, 1.0)).unwrap())
    }

    #[test]
    fn resolving_every_pair_gives_the_exact_multiplicities() {
        let scene = scene();
        let layout = SceneLayout::build(&scene, "t").unwrap();
        let lights = [
            Light::point(glam::Vec3::new(0.3, 2.0, 0.1)),
            Light::directional(glam::Vec3::new(1.0, 0.5, 0.0)),
        ];
        let ol = object_lights(scene.transforms(), &lights);
        // A batch over the second light only: its records name light 0 of the batch.
        let records: Vec<UncertainRecord> = (0..layout.edge_count())
            .flat_map(|e| {
                layout.ov_slots(e).map(move |k| UncertainRecord {
                    edge: e as u32,
                    ov_slot: k as u32,
                    light: 0,
                })
            })
            .collect();
        let mut out = Multiplicities::zeroed(layout.edge_count(), 2);
        resolve_uncertain(&layout, &ol, 1..2, &records, &mut out, "t").unwrap();
        // The same from the edge tables.
        let mut from_tables = Multiplicities::zeroed(layout.edge_count(), 2);
        let index = SceneIndex::new(&scene);
        resolve_uncertain(&index, &ol, 1..2, &records, &mut from_tables, "t").unwrap();
        assert_eq!(from_tables.values(1), out.values(1));
        let t = &scene.objects[0].table;
        for (e, &[a, b]) in t.edges.iter().enumerate() {
            let want: i32 = t
                .ovs_of(e)
                .map(|o| i32::from(ov_sign(Accuracy::Exact, &t.positions, a, b, o, ol[0][1])))
                .sum();
            assert_eq!(out.values(1)[e], want, "edge {e}");
            assert_eq!(out.values(0)[e], 0, "light 0 is outside the batch");
        }
    }

    #[test]
    fn malformed_records_are_device_errors() {
        let scene = scene();
        let layout = SceneLayout::build(&scene, "t").unwrap();
        let ol = object_lights(scene.transforms(), &[Light::point(glam::Vec3::Y * 3.0)]);
        let mut out = Multiplicities::zeroed(layout.edge_count(), 1);
        let wrong_slot = layout.ov_slots(1).start as u32;
        for r in [
            UncertainRecord {
                edge: layout.edge_count() as u32,
                ov_slot: 0,
                light: 0,
            },
            UncertainRecord {
                edge: 0,
                ov_slot: 0,
                light: 1,
            },
            UncertainRecord {
                edge: 0,
                ov_slot: wrong_slot,
                light: 0,
            },
        ] {
            let e = resolve_uncertain(&layout, &ol, 0..1, &[r], &mut out, "t").unwrap_err();
            assert!(
                matches!(e, BackendError::Device { backend: "t", .. }),
                "{r:?}: {e}"
            );
        }
        let e = resolve_uncertain(&layout, &ol, 0..2, &[], &mut out, "t").unwrap_err();
        assert!(matches!(e, BackendError::InvalidInput(_)), "{e}");
    }

    #[test]
    fn records_are_read_four_words_at_a_time() {
        let r = UncertainRecord::read_all(&[1, 2, 3, 0, 4, 5, 6, 0, 9]);
        assert_eq!(
            r,
            [
                UncertainRecord {
                    edge: 1,
                    ov_slot: 2,
                    light: 3
                },
                UncertainRecord {
                    edge: 4,
                    ov_slot: 5,
                    light: 6
                }
            ]
        );
    }
}
