//! The CPU twin of the kernel against the `cpu` reference backend and robust-math (no device
//! needed).

mod common;

use common::{all_cases, Lcg};
use shadowvol_cpu::CpuBackend;
use shadowvol_opencl::twin;
use shadowvol_robust_math::{orient_exact, orient_filter_f32, orient_filter_f64, sign_f32};
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_silhouette::{extract_once, invariant, Accuracy, Multiplicities};
use shadowvol_test_support::filters;

#[test]
fn twin_equals_cpu_in_every_mode_on_every_case() {
    let mut cpu = CpuBackend::new();
    for filter in [ExactFilter::F64, ExactFilter::F32] {
        for case in all_cases() {
            for mode in Accuracy::ALL {
                let (want, _) = extract_once(&mut cpu, &case.scene, &case.lights, mode).unwrap();
                let mut got = Multiplicities::default();
                twin::extract(&case.scene, &case.lights, mode, filter, &mut got).unwrap();
                assert_eq!(
                    invariant::first_difference(&want, &got),
                    None,
                    "{} {mode} ({filter:?} filter): (light, edge, cpu, twin)",
                    case.name
                );
                assert!(got.silhouettes_consistent(), "{} {mode}", case.name);
            }
        }
    }
}

#[test]
fn twin_exact_mode_resolves_uncertain_pairs_on_the_host() {
    // The in-plane grid makes every (edge, OV) uncertain in both filters; the result must still
    // be exact (all zero, as the cpu backend says).
    let case = all_cases()
        .into_iter()
        .find(|c| c.name == "flat-in-plane")
        .unwrap();
    for filter in [ExactFilter::F64, ExactFilter::F32] {
        let mut m = Multiplicities::default();
        let uncertain =
            twin::extract(&case.scene, &case.lights, Accuracy::Exact, filter, &mut m).unwrap();
        assert_eq!(uncertain as usize, case.scene.total_ovs());
        assert!(m.all_values().iter().all(|&v| v == 0));
    }
}

fn random_point(rng: &mut Lcg, scale: f32) -> [f32; 3] {
    [
        (rng.next_f32() - 0.5) * scale,
        (rng.next_f32() - 0.5) * scale,
        (rng.next_f32() - 0.5) * scale,
    ]
}

/// Near-degenerate inputs: `o` almost in the plane of (a, b, light), snapped to a grid.
fn hard_quad(rng: &mut Lcg) -> ([f32; 3], [f32; 3], [f32; 4], [f32; 3]) {
    let a = random_point(rng, 2.0);
    let b = random_point(rng, 2.0);
    let lp = random_point(rng, 10.0);
    let t = rng.next_f32();
    let u = rng.next_f32();
    // A point of the plane through a, b, lp, slightly perturbed.
    let mut o = [0f32; 3];
    for i in 0..3 {
        o[i] = a[i] + t * (b[i] - a[i]) + u * (lp[i] - a[i]);
        if rng.next_f32() < 0.5 {
            o[i] += (rng.next_f32() - 0.5) * 1e-6;
        }
    }
    let w = if rng.next_f32() < 0.2 { 0.0 } else { 1.0 };
    (a, b, [lp[0], lp[1], lp[2], w], o)
}

#[test]
fn twin_filters_certify_only_correct_signs_and_match_robust_math() {
    let mut rng = Lcg(42);
    let (mut f32_certified, mut f64_certified) = (0, 0);
    for i in 0..200_000 {
        let (a, b, l, o) = if i % 2 == 0 {
            hard_quad(&mut rng)
        } else {
            let lp = random_point(&mut rng, 10.0);
            (
                random_point(&mut rng, 2.0),
                random_point(&mut rng, 2.0),
                [lp[0], lp[1], lp[2], 1.0],
                random_point(&mut rng, 2.0),
            )
        };
        if l[3] == 0.0 && l[..3].iter().all(|&x| x == 0.0) {
            continue;
        }
        let exact = orient_exact(a, b, l, o);
        let s32 = twin::filter_f32(a, b, l, o);
        let s64 = twin::filter_f64(a, b, l, o);
        // Certified signs are always the exact sign.
        if let Some(s) = s32 {
            assert_eq!(s, exact, "f32 filter at {a:?} {b:?} {l:?} {o:?}");
            f32_certified += 1;
        }
        if let Some(s) = s64 {
            assert_eq!(s, exact, "f64 filter at {a:?} {b:?} {l:?} {o:?}");
            f64_certified += 1;
        }
        // Inputs here are normal and moderate, so the kernel's extra flush-to-zero guards never
        // fire: the decisions are exactly robust-math's filters.
        let rm32 = orient_filter_f32(a, b, l, o);
        let rm64 = orient_filter_f64(a, b, l, o);
        assert_eq!(s32, rm32, "f32 filter decision at {a:?} {b:?} {l:?} {o:?}");
        assert_eq!(s64, rm64, "f64 filter decision at {a:?} {b:?} {l:?} {o:?}");
        assert_eq!(twin::sign_f32(a, b, l, o), i32::from(sign_f32(a, b, l, o)));
    }
    // The filters are not vacuous: they certify the vast majority.
    assert!(f32_certified > 100_000, "{f32_certified}");
    assert!(
        f64_certified > f32_certified,
        "{f64_certified} <= {f32_certified}"
    );
}

#[test]
fn twin_guards_subnormal_and_underflowing_inputs() {
    let tiny = f32::from_bits(1); // smallest subnormal
    assert!(twin::is_subnormal(tiny));
    assert!(!twin::is_subnormal(f32::MIN_POSITIVE));
    assert!(!twin::is_subnormal(0.0) && !twin::is_subnormal(-0.0));
    let a = [0.0, 0.0, 0.0];
    let b = [1.0, 0.0, 0.0];
    let o = [0.0, 1.0, tiny];
    let l = [0.3, 0.3, 2.0, 1.0];
    assert_eq!(twin::filter_f32(a, b, l, o), None);
    assert_eq!(twin::filter_f64(a, b, l, o), None);
    // w * a underflows: uncertain in the f32 filter.
    let a2 = [1e-30, 0.0, 0.0];
    let l2 = [0.0, 0.3, 2.0, 1e-10];
    assert_eq!(twin::filter_f32(a2, b, l2, [0.0, 1.0, 0.0]), None);
    // The host still decides them exactly: on a mesh with subnormal coordinates the twin's exact
    // mode sends pairs to the host and agrees with cpu.
    let mesh = shadowvol_mesh_topology::Mesh {
        positions: vec![
            glam::Vec3::new(tiny, 0.0, 0.0),
            glam::Vec3::X,
            glam::Vec3::new(0.0, 1.0, tiny),
            glam::Vec3::Z,
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    };
    let scene = shadowvol_silhouette::TopologyScene::single(
        shadowvol_mesh_topology::EdgeTable::build(&mesh).unwrap(),
    );
    let lights = [shadowvol_silhouette::Light::point(glam::Vec3::new(
        0.3, 0.2, 0.0,
    ))];
    for filter in [ExactFilter::F64, ExactFilter::F32] {
        let mut got = Multiplicities::default();
        let uncertain = twin::extract(&scene, &lights, Accuracy::Exact, filter, &mut got).unwrap();
        let (want, _) =
            extract_once(&mut CpuBackend::new(), &scene, &lights, Accuracy::Exact).unwrap();
        assert!(uncertain > 0);
        assert_eq!(got, want);
    }
}

/// Regression: with `w` other than 0 or 1, `fl(w * A)` can round to exactly `L.xyz`, so the
/// computed V is 0 while the exact V is not. The kernel's filters (and this twin) must leave
/// such lights to the host instead of certifying a wrong 0, and stay sound near them.
#[test]
fn filters_are_sound_for_general_w() {
    filters::assert_general_w_left_to_host("f32 filter", twin::filter_f32);
    filters::assert_sound("f32 filter", twin::filter_f32, 20_000);
    filters::assert_sound("f64 filter", twin::filter_f64, 20_000);
}
