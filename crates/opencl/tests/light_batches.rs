//! Light splitting: `extract` with at most 1, 2 or 3 lights per kernel launch
//! (`OpenClOptions::max_lights_per_batch`), or with a (pretended) small device allocation
//! limit, gives the same result as one launch: `exact` bit-identical to the `cpu` backend, 0 open
//! vertices in `robust` and `ordered`, the uncertain count equal to one launch's, and the
//! statistics summed over the launches. Only a light that does not fit alone is a `Limit` error.
//! A scene whose buffers exceed the (pretended) allocation limit is prepared in parts, with the
//! same results as the whole scene.
//!
//! Without an OpenCL platform each test is ignored with the reason, except under `CI=true`,
//! where a missing platform fails it (`shadowvol_test_support::skip`).

mod common;

use common::{start, tilted_grid};
use glam::{Affine3A, Vec3};
use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_opencl::{OpenClBackend, OpenClOptions};
use shadowvol_silhouette::{
    extract_once, invariant, Accuracy, BackendError, ExtractStats, Light, Multiplicities,
    SceneObject, SilhouetteBackend, TopologyScene,
};
use shadowvol_test_support::corpus;
use shadowvol_test_support::{main, Outcome};
use std::num::NonZeroUsize;
use std::sync::Arc;

main!(
    corpus_split_into_light_batches_matches_one_launch_and_cpu,
    uncertain_records_resolve_into_their_own_light_across_batches,
    allocation_limit_splits_lights_and_refuses_only_a_light_that_does_not_fit,
    too_many_uncertain_records_split_the_batch_further,
    scene_beyond_the_largest_allocation_is_prepared_in_parts,
);

/// Bytes of one uncertain record in the device buffer.
const RECORD_BYTES: u64 = (shadowvol_silhouette::gpu::UncertainRecord::WORDS * 4) as u64;

fn per_launch(n: usize) -> OpenClOptions {
    OpenClOptions {
        max_lights_per_batch: NonZeroUsize::new(n),
        ..OpenClOptions::from_env()
    }
}

/// One launch of `whole` over `lights` (asserted), and its result.
fn one_launch(
    whole: &mut OpenClBackend,
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    what: &str,
) -> (Multiplicities, ExtractStats) {
    let r = extract_once(whole, scene, lights, mode)
        .unwrap_or_else(|e| panic!("{what} (one launch): {e}"));
    assert_eq!(
        whole.batches_of_last_extract_for_tests(),
        1,
        "{what}: the reference should run in one launch"
    );
    r
}

/// `got` and its stats (split) against one launch of `whole` and, in exact mode, against `cpu`
/// ([`invariant::check_split_batches`]).
fn check_split(
    (got, stats): (&Multiplicities, &ExtractStats),
    whole: &mut OpenClBackend,
    cpu: &mut CpuBackend,
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    what: &str,
) {
    let (one, one_stats) = one_launch(whole, scene, lights, mode, what);
    let want = (mode == Accuracy::Exact).then(|| extract_once(cpu, scene, lights, mode).unwrap().0);
    invariant::check_split_batches(scene, mode, (got, stats), (&one, &one_stats), want.as_ref())
        .unwrap_or_else(|e| panic!("{what}: {e}"));
}

fn corpus_split_into_light_batches_matches_one_launch_and_cpu() -> Outcome {
    let mut whole = start(OpenClOptions::from_env())?;
    let mut cpu = CpuBackend::new();
    let cases = corpus::multi_light_cases(3);
    let mut split_runs = 0;
    for n_per in [1, 2, 3] {
        let mut cl = start(per_launch(n_per))?;
        for case in &cases {
            let scene = case.scene().unwrap();
            let n = case.lights.len();
            let mut reversed = case.lights.clone();
            reversed.reverse();
            let id = cl.prepare(&scene).unwrap();
            for (order, lights) in [("", &case.lights), (" reversed", &reversed)] {
                for mode in Accuracy::ALL {
                    let what = format!("{}{order} {mode}, {n_per} light(s) per launch", case.name);
                    let mut got = Multiplicities::default();
                    let stats = cl
                        .extract(id, lights, mode, &mut got)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!(
                        cl.batches_of_last_extract_for_tests(),
                        n.div_ceil(n_per),
                        "{what}: {n} lights should take that many launches"
                    );
                    split_runs += usize::from(n > n_per);
                    check_split(
                        (&got, &stats),
                        &mut whole,
                        &mut cpu,
                        &scene,
                        lights,
                        mode,
                        &what,
                    );
                }
            }
            cl.release(id);
        }
    }
    assert!(split_runs > 0, "no extraction was actually split");
    Ok(())
}

/// Uncertain records of a later batch land in that batch's lights: every case with two or more
/// lights (the corpus and the extra hard cases, such as lights in a face plane), in exact mode,
/// one light per launch, in the given and the reversed light order, equal to `cpu`. The test
/// also checks that uncertain records do come from batches after the first (so a wrong batch
/// offset in their resolution would be caught).
fn uncertain_records_resolve_into_their_own_light_across_batches() -> Outcome {
    let mut cl = start(per_launch(1))?;
    let mut cpu = CpuBackend::new();
    let mut uncertain_after_first = 0;
    for case in common::all_cases().iter().filter(|c| c.lights.len() >= 2) {
        let mut reversed = case.lights.clone();
        reversed.reverse();
        for (order, lights) in [("", &case.lights), (" reversed", &reversed)] {
            let what = format!("{}{order}", case.name);
            let (got, stats) = extract_once(&mut cl, &case.scene, lights, Accuracy::Exact)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(cl.batches_of_last_extract_for_tests(), lights.len());
            let (want, _) = extract_once(&mut cpu, &case.scene, lights, Accuracy::Exact).unwrap();
            assert_eq!(
                invariant::first_difference(&got, &want),
                None,
                "{what}: one light per launch differs from cpu (light, edge, opencl, cpu)"
            );
            // The uncertain records of each light alone; those of lights 1.. come from a batch
            // with a non-zero offset.
            let mut per_light = Vec::new();
            for l in lights {
                let (_, s) = extract_once(&mut cl, &case.scene, &[*l], Accuracy::Exact).unwrap();
                per_light.push(s.uncertain);
            }
            assert_eq!(
                stats.uncertain,
                per_light.iter().sum::<u64>(),
                "{what}: uncertain"
            );
            uncertain_after_first += per_light[1..].iter().sum::<u64>();
        }
    }
    assert!(
        uncertain_after_first > 0,
        "no uncertain record came from a batch after the first: the offset is not exercised"
    );
    Ok(())
}

/// A grid in the plane z = x with every light in that plane: every (edge, OV, light) is
/// uncertain in exact mode.
fn in_plane_scene() -> (TopologyScene, Vec<Light>) {
    let table = EdgeTable::build(&tilted_grid(12)).unwrap();
    let scene = TopologyScene {
        objects: vec![SceneObject {
            name: "tilted-grid".into(),
            table: Arc::new(table),
            world_from_object: Affine3A::IDENTITY,
        }],
    };
    let lights = vec![
        Light::point(Vec3::new(-1.0, 0.25, -1.0)),
        Light::point(Vec3::new(2.0, 0.5, 2.0)),
        Light::point(Vec3::new(0.5, -3.0, 0.5)),
        Light::point(Vec3::new(3.0, 4.0, 3.0)),
    ];
    (scene, lights)
}

/// The device's allocation limit splits the lights by itself: with the limit pretended to be
/// two lights' silhouette lists, an extraction takes ceil(n / 2) launches and equals one launch;
/// just below one light's list it is a `Limit` error with the numbers, and the backend works
/// again afterwards.
fn allocation_limit_splits_lights_and_refuses_only_a_light_that_does_not_fit() -> Outcome {
    let mut cl = start(OpenClOptions::from_env())?;
    let mut whole = start(OpenClOptions::from_env())?;
    let mut cpu = CpuBackend::new();
    let (mut checked, mut refused) = (0, 0);
    for case in &corpus::multi_light_cases(3) {
        let scene = case.scene().unwrap();
        let (edges, objects) = (scene.total_edges(), scene.objects.len());
        let n = case.lights.len();
        let id = cl.prepare(&scene).unwrap();
        // Two lights' silhouette lists (8 bytes per edge and light); the light buffer (16 bytes
        // per object and light) is far smaller in these cases.
        let two = 2 * 8 * edges as u64;
        assert!(2 * 16 * objects as u64 <= two, "{}", case.name);
        cl.set_max_alloc_for_tests(two);
        // The most uncertain records (`RECORD_BYTES` each) of one light alone in exact mode.
        let most_uncertain = case
            .lights
            .iter()
            .map(|l| {
                let (_, s) = extract_once(&mut whole, &scene, &[*l], Accuracy::Exact).unwrap();
                s.uncertain
            })
            .max()
            .unwrap();
        for mode in Accuracy::ALL {
            let what = format!("{} {mode}, allocation limit {two} bytes", case.name);
            let mut got = Multiplicities::default();
            let result = cl.extract(id, &case.lights, mode, &mut got);
            if mode == Accuracy::Exact && RECORD_BYTES * most_uncertain > two {
                // One light's records alone exceed the limit: no split can help.
                match result {
                    Err(BackendError::Limit { message, .. }) => {
                        assert!(message.contains("uncertain"), "{what}: {message}");
                        assert!(message.contains(&two.to_string()), "{what}: {message}");
                    }
                    other => panic!("{what}: expected a Limit error, got {other:?}"),
                }
                refused += 1;
                continue;
            }
            let stats = result.unwrap_or_else(|e| panic!("{what}: {e}"));
            checked += 1;
            // Exact mode may split further when a batch's uncertain records exceed the limit.
            let launches = cl.batches_of_last_extract_for_tests();
            if mode == Accuracy::Exact {
                assert!(
                    (n.div_ceil(2)..=n).contains(&launches),
                    "{what}: {launches} launches"
                );
            } else {
                assert_eq!(launches, n.div_ceil(2), "{what}");
            }
            check_split(
                (&got, &stats),
                &mut whole,
                &mut cpu,
                &scene,
                &case.lights,
                mode,
                &what,
            );
        }
        // One byte short of a single light's list.
        let one = 8 * edges as u64;
        cl.set_max_alloc_for_tests(one - 1);
        let mut got = Multiplicities::default();
        match cl.extract(id, &case.lights, Accuracy::Robust, &mut got) {
            Err(BackendError::Limit { message, .. }) => {
                for number in [
                    one.to_string(),
                    (one - 1).to_string(),
                    format!("{edges} edges"),
                ] {
                    assert!(message.contains(&number), "{}: {message}", case.name);
                }
            }
            other => panic!("{}: expected a Limit error, got {other:?}", case.name),
        }
        cl.set_max_alloc_for_tests(u64::MAX);
        cl.extract(id, &case.lights, Accuracy::Exact, &mut got)
            .unwrap_or_else(|e| panic!("{}: after the Limit error: {e}", case.name));
        assert_eq!(cl.batches_of_last_extract_for_tests(), 1);
        let (want, _) = extract_once(&mut cpu, &scene, &case.lights, Accuracy::Exact).unwrap();
        assert_eq!(
            invariant::first_difference(&got, &want),
            None,
            "{}: after the Limit error",
            case.name
        );
        cl.release(id);
    }
    eprintln!("{checked} split extractions checked, {refused} refused (uncertain records)");
    assert!(
        checked > 0 && refused < checked,
        "{checked} checked, {refused} refused"
    );
    Ok(())
}

/// Exact mode's uncertain records count against the allocation limit too: when a batch's
/// records do not fit, the batch is split further (down to one light per launch) with the same
/// result; when one light's records alone do not fit, it is a `Limit` error naming them.
fn too_many_uncertain_records_split_the_batch_further() -> Outcome {
    let mut cl = start(OpenClOptions::from_env())?;
    let mut whole = start(OpenClOptions::from_env())?;
    let mut cpu = CpuBackend::new();
    let (scene, lights) = in_plane_scene();
    let edges = scene.total_edges() as u64;
    let id = cl.prepare(&scene).unwrap();
    let mut per_light = Vec::new();
    for l in &lights {
        let (_, s) = extract_once(&mut cl, &scene, &[*l], Accuracy::Exact).unwrap();
        per_light.push(s.uncertain);
    }
    let (most, least) = (
        *per_light.iter().max().unwrap(),
        *per_light.iter().min().unwrap(),
    );
    // Room for 1.5 lights' records (`RECORD_BYTES` each), so only one light per launch fits them,
    // while the silhouette lists alone would allow several lights per launch.
    let records = most + most / 2;
    assert!(
        2 * least > records,
        "every light should leave about as many records uncertain: {per_light:?}"
    );
    let limit = RECORD_BYTES * records;
    assert!(limit >= 2 * 8 * edges, "{limit} bytes, {edges} edges");
    cl.set_max_alloc_for_tests(limit);
    let mut got = Multiplicities::default();
    let stats = cl
        .extract(id, &lights, Accuracy::Exact, &mut got)
        .unwrap_or_else(|e| panic!("in-plane lights, limit {limit} bytes: {e}"));
    assert_eq!(cl.batches_of_last_extract_for_tests(), lights.len());
    assert_eq!(stats.uncertain, per_light.iter().sum::<u64>());
    check_split(
        (&got, &stats),
        &mut whole,
        &mut cpu,
        &scene,
        &lights,
        Accuracy::Exact,
        "in-plane lights, one light per launch for the uncertain records",
    );

    // One light's records no longer fit: Limit, naming the count and the bytes.
    let limit = RECORD_BYTES * least - 1;
    assert!(limit >= 8 * edges, "{limit} bytes, {edges} edges");
    cl.set_max_alloc_for_tests(limit);
    match cl.extract(id, &lights, Accuracy::Exact, &mut got) {
        Err(BackendError::Limit { message, .. }) => {
            assert!(message.contains("uncertain"), "{message}");
            assert!(message.contains(&limit.to_string()), "{message}");
        }
        other => panic!("expected a Limit error, got {other:?}"),
    }
    cl.set_max_alloc_for_tests(u64::MAX);
    let (again, _) = extract_once(&mut cl, &scene, &lights, Accuracy::Exact).unwrap();
    let (want, _) = extract_once(&mut cpu, &scene, &lights, Accuracy::Exact).unwrap();
    assert_eq!(invariant::first_difference(&again, &want), None);
    cl.release(id);
    Ok(())
}

/// With the allocation limit pretended to be a third of a scene's edge records when it is
/// prepared, the scene is cut into parts; every mode gives the bits of the whole scene on the
/// same device (and, exact, of `cpu`), silhouettes included.
fn scene_beyond_the_largest_allocation_is_prepared_in_parts() -> Outcome {
    let mut whole = start(OpenClOptions::from_env())?;
    let mut cut = start(OpenClOptions::from_env())?;
    shadowvol_test_support::parts::check_parts_equal_whole(
        &mut cut,
        &mut whole,
        &mut CpuBackend::new(),
        |cut, scene, limit| {
            cut.set_max_alloc_for_tests(limit);
            let id = cut.prepare(scene).unwrap();
            // Extraction with the real limit: only the preparation is under test here.
            cut.set_max_alloc_for_tests(u64::MAX);
            id
        },
    );
    Ok(())
}
