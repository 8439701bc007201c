//! Bad input gets an error that names the problem, never a panic.

mod common;

use glam::Vec3;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{BackendError, Multiplicities, SilhouetteBackend, TopologyScene};
use shadowvol_test_support::corpus;
use shadowvol_test_support::{main, Outcome};
use shadowvol_vulkan_geometry::VulkanOptions;

main!(
    bad_input_is_an_error,
    many_lights_in_one_call_match_one_light_at_a_time
);

fn bad_input_is_an_error() -> Outcome {
    let mut vk = common::backend(VulkanOptions::default())?;
    let case = &corpus::cases()[0];
    let scene = case.scene().unwrap();
    let id = vk.prepare(&scene).unwrap();
    let mut out = Multiplicities::default();

    let e = vk.extract(id, &[], Accuracy::Exact, &mut out).unwrap_err();
    assert!(
        matches!(e, BackendError::InvalidInput(ref m) if m.contains("no lights")),
        "{e}"
    );

    let bogus = vk.prepare(&scene).unwrap();
    vk.release(bogus);
    let e = vk
        .extract(bogus, &case.lights, Accuracy::Exact, &mut out)
        .unwrap_err();
    assert!(
        matches!(e, BackendError::UnknownScene { id, .. } if id == bogus),
        "{e}"
    );

    // Released scenes are unknown afterwards; the backend keeps working.
    vk.release(id);
    assert!(vk
        .extract(id, &case.lights, Accuracy::Exact, &mut out)
        .is_err());
    let id2 = vk.prepare(&scene).unwrap();
    vk.extract(id2, &case.lights, Accuracy::Exact, &mut out)
        .unwrap();
    assert!(out.silhouettes_consistent());

    // An empty scene is fine: zero edges.
    let empty = vk.prepare(&TopologyScene::default()).unwrap();
    let stats = vk
        .extract(empty, &[Light::point(Vec3::ONE)], Accuracy::Exact, &mut out)
        .unwrap();
    assert_eq!((out.edge_count(), stats.uncertain), (0, 0));
    Ok(())
}

fn many_lights_in_one_call_match_one_light_at_a_time() -> Outcome {
    let mut vk = common::backend(VulkanOptions::default())?;
    for case in corpus::cases() {
        let scene = case.scene().unwrap();
        let id = vk.prepare(&scene).unwrap();
        let mut all = Multiplicities::default();
        vk.extract(id, &case.lights, Accuracy::Exact, &mut all)
            .unwrap();
        for (li, &light) in case.lights.iter().enumerate() {
            let mut one = Multiplicities::default();
            vk.extract(id, &[light], Accuracy::Exact, &mut one).unwrap();
            assert_eq!(one.values(0), all.values(li), "{} light {li}", case.name);
            assert_eq!(
                one.silhouette(0),
                all.silhouette(li),
                "{} light {li}",
                case.name
            );
        }
        vk.release(id);
    }
    Ok(())
}
