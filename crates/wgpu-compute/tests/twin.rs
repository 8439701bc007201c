//! CPU-only: the CPU twin of the WGSL kernel against the scalar `cpu` backend, and the twin's
//! device filters against the exact predicate.

mod common;

use shadowvol_cpu::CpuBackend;
use shadowvol_robust_math::{orient_exact, orient_filter_f32, Accuracy};
use shadowvol_silhouette::gpu::{ExactFilter, TableLayout};
use shadowvol_silhouette::{extract_once, invariant, object_lights, Multiplicities};
use shadowvol_test_support::shapes::Rng;
use shadowvol_wgpu_compute::twin;

#[test]
fn twin_equals_cpu_in_every_mode_with_both_filters() {
    let mut cpu = CpuBackend::new();
    for case in common::all_cases() {
        for mode in Accuracy::ALL {
            let (expected, _) = extract_once(&mut cpu, &case.scene, &case.lights, mode).unwrap();
            for filter in [ExactFilter::F64, ExactFilter::F32] {
                let mut got = Multiplicities::default();
                let uncertain =
                    twin::extract(&case.scene, &case.lights, mode, filter, &mut got).unwrap();
                assert_eq!(
                    invariant::first_difference(&got, &expected),
                    None,
                    "{} {mode} {filter:?}: (light, edge, twin, cpu)",
                    case.name
                );
                assert_eq!(
                    got, expected,
                    "{} {mode} {filter:?}: compact lists",
                    case.name
                );
                assert!(got.silhouettes_consistent());
                if mode != Accuracy::Exact {
                    assert_eq!(uncertain, 0);
                }
            }
        }
    }
}

/// The backend's exact pipelines on the device: the triangle step appends exactly the pairs it
/// would leave to the host, `resolve_uncertain` decides them, and the values equal `cpu`'s.
#[test]
fn deferred_resolution_decides_every_pair_the_host_would() {
    let mut cpu = CpuBackend::new();
    let mut resolved = 0;
    for case in common::all_cases() {
        let (expected, _) =
            extract_once(&mut cpu, &case.scene, &case.lights, Accuracy::Exact).unwrap();
        let layout = TableLayout::build(&case.scene, "wgpu").unwrap();
        let obj = object_lights(case.scene.transforms(), &case.lights);
        let n = case.lights.len();
        let packed: Vec<[f32; 4]> = obj.iter().flat_map(|v| v.iter().copied()).collect();
        for filter in [ExactFilter::F64, ExactFilter::F32] {
            let run = |device_exact| {
                twin::run_kernel_with(&layout, &packed, n, Accuracy::Exact, filter, device_exact)
            };
            let (host, device) = (run(false), run(true));
            assert!(device.uncertain.is_empty(), "{}", case.name);
            assert_eq!(device.resolved, host.uncertain, "{} {filter:?}", case.name);
            resolved += device.resolved.len();
            let e = layout.edge_count();
            for l in 0..n {
                assert_eq!(
                    &device.mult[l * e..(l + 1) * e],
                    expected.values(l),
                    "{} {filter:?} light {l}",
                    case.name
                );
            }
            assert_eq!(device.silhouettes.len(), n);
        }
    }
    assert!(resolved > 0, "no case left a pair to the resolution step");
}

#[test]
fn hard_cases_send_triples_to_the_host() {
    // Exact zeros with a non-zero permanent can never be certified; subnormal inputs never are;
    // the f32 filter rejects coordinates outside its range. The host path must run on these.
    for case in common::extra_cases() {
        let mut m = Multiplicities::default();
        let u64_ = twin::extract(
            &case.scene,
            &case.lights,
            Accuracy::Exact,
            ExactFilter::F64,
            &mut m,
        )
        .unwrap();
        let u32_ = twin::extract(
            &case.scene,
            &case.lights,
            Accuracy::Exact,
            ExactFilter::F32,
            &mut m,
        )
        .unwrap();
        match case.name.as_str() {
            "light-in-face-plane" | "flat-grid-grazing" | "subnormal-coordinates" => {
                assert!(u64_ > 0 && u32_ > 0, "{}: {u64_} / {u32_}", case.name);
            }
            "tiny-coordinates" | "huge-coordinates" => {
                assert!(u32_ > 0, "{}: f32 filter certified everything", case.name);
            }
            _ => {}
        }
        assert!(
            u64_ <= u32_ || case.name == "many-objects-transformed",
            "{}: {u64_} > {u32_}",
            case.name
        );
    }
}

#[test]
fn kernel_records_are_well_formed() {
    for case in common::all_cases() {
        let layout = TableLayout::build(&case.scene, "wgpu").unwrap();
        let obj = object_lights(case.scene.transforms(), &case.lights);
        let n = case.lights.len();
        let packed: Vec<[f32; 4]> = obj.iter().flat_map(|v| v.iter().copied()).collect();
        let k = twin::run_kernel(&layout, &packed, n, Accuracy::Exact, ExactFilter::F32);
        let e = layout.edge_count();
        assert_eq!(k.mult.len(), e * n);
        assert_eq!(k.signs.len(), layout.tri_count() * n);
        assert!(k.signs.iter().all(|s| (-1..=1).contains(s)));
        for (li, list) in k.silhouettes.iter().enumerate() {
            let nonzero = k.mult[li * e..(li + 1) * e]
                .iter()
                .filter(|&&m| m != 0)
                .count();
            assert_eq!(list.len(), nonzero);
            assert!(list
                .iter()
                .all(|&(edge, m)| k.mult[li * e + edge as usize] == m));
        }
        for r in &k.uncertain {
            assert!((r.triangle as usize) < layout.tri_count());
            assert!((r.light as usize) < n);
            assert_eq!(
                k.signs[r.light as usize * layout.tri_count() + r.triangle as usize],
                0
            );
        }
    }
}

/// A value whose exponent ranges over the whole `f32` range, subnormals and zeros included.
fn scaled(rng: &mut Rng) -> f32 {
    match rng.below(8) {
        0 => 0.0,
        1 => rng.unit() * 1e-40,
        2 => rng.unit() * 1e30,
        3 => rng.unit() * 1e-20,
        _ => rng.unit() * 4.0,
    }
}

fn v3(rng: &mut Rng, f: impl Fn(&mut Rng) -> f32) -> [f32; 3] {
    [f(rng), f(rng), f(rng)]
}

fn check(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3], stats: &mut [usize; 3]) {
    let exact = orient_exact(a, b, l, o);
    for (i, filter) in [ExactFilter::F64, ExactFilter::F32].into_iter().enumerate() {
        match twin::exact_filter(filter, a, b, l, o) {
            Some(s) => assert_eq!(
                s, exact,
                "{filter:?} certified a wrong sign for {a:?} {b:?} {l:?} {o:?}"
            ),
            None => stats[i] += 1,
        }
    }
    if let Some(s) = twin::filter_f32(a, b, l, o) {
        // The device guards only add uncertainty to robust-math's f32 filter.
        assert_eq!(
            orient_filter_f32(a, b, l, o),
            Some(s),
            "{a:?} {b:?} {l:?} {o:?}"
        );
    }
    stats[2] += 1;
}

#[test]
fn device_filters_certify_only_exact_signs() {
    let mut rng = Rng::new(0x5eed_1234_abcd_0001);
    let mut stats = [0usize; 3];
    for _ in 0..20_000 {
        // Random inputs over many exponents.
        let (a, b, o) = (
            v3(&mut rng, scaled),
            v3(&mut rng, scaled),
            v3(&mut rng, scaled),
        );
        // w = 0, 1, and others (which the f32 filter must leave to the host).
        let w = [0.0, 1.0, 0.5, 3.0, 1e-30][rng.below(5) as usize];
        let l = [scaled(&mut rng), scaled(&mut rng), scaled(&mut rng), w];
        check(a, b, l, o, &mut stats);
        // Point lights with w != 1 whose V = L.xyz - w A nearly cancels.
        let w = [0.1f32, 0.3, 3.0, 7.0][rng.below(4) as usize];
        let a2 = v3(&mut rng, Rng::unit);
        let l2 = [a2[0] * w, a2[1] * w + 1e-6 * rng.unit(), a2[2] * w, w];
        check(
            a2,
            v3(&mut rng, Rng::unit),
            l2,
            v3(&mut rng, Rng::unit),
            &mut stats,
        );
        // Nearly degenerate: O close to the plane through A, B and the light.
        let a = v3(&mut rng, Rng::unit);
        let b = v3(&mut rng, Rng::unit);
        let lp = v3(&mut rng, Rng::unit);
        let (s, t) = (rng.unit(), rng.unit());
        let eps = [0.0, 1e-7, 1e-4][rng.below(3) as usize];
        let o = [0, 1, 2].map(|i| a[i] + s * (b[i] - a[i]) + t * (lp[i] - a[i]) + eps * rng.unit());
        check(a, b, [lp[0], lp[1], lp[2], 1.0], o, &mut stats);
        // Directional light in the plane of the triangle.
        let dir = [0, 1, 2].map(|i| (b[i] - a[i]) * s + eps * rng.unit());
        check(a, b, [dir[0], dir[1], dir[2], 0.0], o, &mut stats);
    }
    // Exact zeros are frequent here: both filters must leave some triples to the host.
    assert!(stats[0] > 0 && stats[1] > 0, "{stats:?}");
}

#[test]
fn device_filters_certify_generic_input() {
    // Well-conditioned input (unit-cube coordinates) must almost never need the host.
    let mut rng = Rng::new(0x0dd_ba11);
    let mut uncertain = [0usize; 2];
    let n = 20_000;
    for _ in 0..n {
        let (a, b, o) = (
            v3(&mut rng, Rng::unit),
            v3(&mut rng, Rng::unit),
            v3(&mut rng, Rng::unit),
        );
        let l = [rng.unit() * 4.0, rng.unit() * 4.0, rng.unit() * 4.0, 1.0];
        for (i, filter) in [ExactFilter::F64, ExactFilter::F32].into_iter().enumerate() {
            match twin::exact_filter(filter, a, b, l, o) {
                Some(s) => assert_eq!(s, orient_exact(a, b, l, o)),
                None => uncertain[i] += 1,
            }
        }
    }
    assert!(
        uncertain[0] == 0 && uncertain[1] < n / 1000,
        "{uncertain:?} of {n}"
    );
}
