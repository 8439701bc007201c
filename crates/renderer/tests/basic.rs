//! Basic rendering against the ray-traced reference.
mod common;

use glam::Vec3;
use shadowvol_renderer::{Camera, PlanPolicy, Technique};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_test_support::{main, Outcome};

main!(box_on_floor_matches_reference_zpass_and_zfail);

fn box_on_floor_matches_reference_zpass_and_zfail() -> Outcome {
    let mut r = common::renderer(128, 128, Accuracy::Exact)?;
    let scene = common::box_on_floor(
        Light::point(Vec3::new(1.5, 6.0, 1.0)),
        Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0)),
    );
    for policy in [
        PlanPolicy::Auto,
        PlanPolicy::AlwaysZFail,
        PlanPolicy::AlwaysZPass,
    ] {
        let mut o = r.options();
        o.policy = policy;
        r.set_options(o).unwrap();
        let frame = r.render(&scene).unwrap();
        let cmp = common::compare(&frame, &scene);
        println!("{policy:?}: {}", frame.report.explain());
        println!(
            "artifacts {} differing {} shadow {} ref shadow {} covered {}",
            cmp.artifact_pixels,
            cmp.differing_pixels,
            cmp.shadow_pixels,
            cmp.reference_shadow_pixels,
            cmp.covered_pixels
        );
        frame
            .save_png(format!("/tmp/sv_box_{policy:?}.png"))
            .unwrap();
        shadowvol_reference::diff_image(&frame.shot(&scene).unwrap(), &cmp)
            .save(format!("/tmp/sv_box_{policy:?}_diff.png"))
            .unwrap();
        assert!(
            cmp.reference_shadow_pixels > 200,
            "the box casts a visible shadow"
        );
        assert_eq!(cmp.artifact_pixels, 0, "{policy:?}");
        if policy == PlanPolicy::Auto {
            assert!(frame
                .report
                .plan
                .iter()
                .all(|e| e.technique == Technique::ZPass));
        }
    }
    Ok(())
}
