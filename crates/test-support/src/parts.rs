//! The check every backend that cuts a scene into parts runs: on every corpus case, cut under a
//! limit of a third of the case's edge records, every mode gives the bits of the whole scene on
//! the same backend and, exact, those of an exact reference.

use crate::corpus;
use shadowvol_silhouette::{
    extract_once, invariant, Accuracy, Multiplicities, PartsBackend, PreparedId, SilhouetteBackend,
    TopologyScene,
};

/// A limit in bytes that a third of `scene`'s edge records (16 bytes an edge and one more)
/// exceeds: a backend held to it cuts every case of more than a few triangles into parts.
#[must_use]
pub fn third_of_the_edge_records(scene: &TopologyScene) -> u64 {
    ((scene.total_edges() as u64 + 1) * 16 / 3).max(64)
}

/// Runs the check on every corpus case: `prepare_cut(cut, scene, limit)` prepares the scene on
/// `cut` held to `limit` bytes ([`third_of_the_edge_records`]) and
/// [`PartsBackend::parts_of`] says into how many parts it went (`None` once released). Each mode's result, silhouettes included,
/// must equal `whole`'s (the same backend, unlimited), and `exact`'s in exact mode; some case
/// must be cut into 3 parts or more.
///
/// # Panics
/// On the first difference, naming the case, the mode and the number of parts.
pub fn check_parts_equal_whole<B: SilhouetteBackend + PartsBackend>(
    cut: &mut B,
    whole: &mut dyn SilhouetteBackend,
    exact: &mut dyn SilhouetteBackend,
    mut prepare_cut: impl FnMut(&mut B, &TopologyScene, u64) -> PreparedId,
) {
    let mut most_parts = 0;
    for case in corpus::cases() {
        let scene = case.scene().unwrap();
        let id = prepare_cut(cut, &scene, third_of_the_edge_records(&scene));
        let parts = cut.parts_of(id).expect("a prepared scene");
        most_parts = most_parts.max(parts);
        for mode in Accuracy::ALL {
            let what = format!("{} {mode}, {parts} parts", case.name);
            let mut got = Multiplicities::default();
            cut.extract(id, &case.lights, mode, &mut got)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            let (want, _) = extract_once(whole, &scene, &case.lights, mode).unwrap();
            assert_eq!(invariant::first_difference(&got, &want), None, "{what}");
            for l in 0..case.lights.len() {
                assert_eq!(got.silhouette(l), want.silhouette(l), "{what}: light {l}");
            }
            if mode == Accuracy::Exact {
                let (reference, _) = extract_once(exact, &scene, &case.lights, mode).unwrap();
                let diff = invariant::first_difference(&got, &reference);
                assert_eq!(diff, None, "{what}: exact reference");
            }
        }
        assert!(cut.prepared_bytes(id).is_ok());
        cut.release(id);
        assert!(cut.parts_of(id).is_none(), "{}: released", case.name);
    }
    assert!(most_parts >= 3, "no case was cut into 3 parts or more");
}
