//! The OpenCL backend on a real OpenCL platform (PoCL in CI), against the `cpu` reference.
//!
//! Without a platform each test is ignored with the reason (`ignored (opencl backend unavailable: ...)`),
//! except under `CI=true`, where a missing platform fails it (`shadowvol_test_support::skip`).

mod common;

use common::{all_cases, start};
use shadowvol_cpu::CpuBackend;
use shadowvol_opencl::twin;
use shadowvol_opencl::{
    list_devices, select_device, KernelSource, OpenClBackend, OpenClOptions, DEVICE_ENV,
};
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_silhouette::{
    extract_once, invariant, Accuracy, BackendError, Light, Multiplicities, SilhouetteBackend,
};
use shadowvol_test_support::{main, skip, Outcome};

main!(
    conformance_exact_with_device_default_filter,
    conformance_exact_with_forced_f32_filter,
    pocl_has_fp64_so_both_exact_paths_are_covered,
    broken_kernel_reports_the_compiler_log,
    kernel_without_entry_point_is_a_build_error,
    kernel_loads_from_a_path,
    device_selection_by_index_and_name,
    bad_calls_are_errors,
    prepared_scene_is_reused_across_calls_light_counts_and_modes,
);

fn options(force_f32_filter: bool) -> OpenClOptions {
    OpenClOptions {
        force_f32_filter,
        ..OpenClOptions::from_env()
    }
}

/// Every case, every mode: exact identical to cpu (and the uncertain count equal to the twin's
/// with the same filter), robust and ordered closed, and (with contraction off) the f32 modes
/// identical to cpu too.
fn conformance(force_f32_filter: bool, test: &str) -> Outcome {
    let mut cl = start(options(force_f32_filter))?;
    let filter = cl.exact_filter();
    assert_eq!(
        filter == ExactFilter::F64,
        !force_f32_filter && cl.device().fp64
    );
    eprintln!("{test}: {} ({filter:?} filter)", cl.info().device);
    let mut cpu = CpuBackend::new();
    let mut total_uncertain = 0;
    for case in all_cases() {
        for mode in Accuracy::ALL {
            let (want, _) = extract_once(&mut cpu, &case.scene, &case.lights, mode).unwrap();
            let (got, stats) = extract_once(&mut cl, &case.scene, &case.lights, mode)
                .unwrap_or_else(|e| panic!("{} {mode}: {e}", case.name));
            let mut twin_m = Multiplicities::default();
            let twin_uncertain =
                twin::extract(&case.scene, &case.lights, mode, filter, &mut twin_m).unwrap();
            assert!(
                got.silhouettes_consistent(),
                "{} {mode}: compact lists",
                case.name
            );
            assert_eq!(got.light_count(), case.lights.len());
            assert_eq!(got.edge_count(), case.scene.total_edges());
            match mode {
                Accuracy::Exact => {
                    assert_eq!(
                        invariant::first_difference(&want, &got),
                        None,
                        "{} exact: (light, edge, cpu, opencl)",
                        case.name
                    );
                    assert_eq!(
                        stats.uncertain, twin_uncertain,
                        "{} exact: uncertain count of the device filter vs its twin",
                        case.name
                    );
                    total_uncertain += stats.uncertain;
                }
                Accuracy::Robust | Accuracy::Ordered => {
                    for l in 0..case.lights.len() {
                        assert_eq!(
                            invariant::open_vertices_scene(&case.scene, &got, l),
                            0,
                            "{} {mode} light {l}: open vertices",
                            case.name
                        );
                    }
                    assert_eq!(stats.uncertain, 0);
                }
                Accuracy::Original => assert_eq!(stats.uncertain, 0),
            }
            // FP_CONTRACT OFF: the f32 modes evaluate exactly robust-math's expression, so on a
            // device with IEEE f32 (PoCL) they agree with cpu bit for bit as well.
            if mode != Accuracy::Exact && cl.device().device_type == "CPU" {
                assert_eq!(
                    invariant::first_difference(&want, &got),
                    None,
                    "{} {mode}: (light, edge, cpu, opencl)",
                    case.name
                );
            }
        }
    }
    // The extra cases include pairs no filter can certify (light in a face plane).
    assert!(total_uncertain > 4096, "{total_uncertain} uncertain pairs");
    Ok(())
}

fn conformance_exact_with_device_default_filter() -> Outcome {
    conformance(false, "conformance_exact_with_device_default_filter")
}

fn conformance_exact_with_forced_f32_filter() -> Outcome {
    conformance(true, "conformance_exact_with_forced_f32_filter")
}

fn pocl_has_fp64_so_both_exact_paths_are_covered() -> Outcome {
    let cl = start(options(false))?;
    if cl
        .device()
        .platform_name
        .contains("Portable Computing Language")
    {
        assert_eq!(
            cl.exact_filter(),
            ExactFilter::F64,
            "PoCL reports cl_khr_fp64; the f64 path must be used"
        );
    } else {
        eprintln!(
            "not PoCL ({}); exact filter: {:?}",
            cl.info().device,
            cl.exact_filter()
        );
    }
    Ok(())
}

fn broken_kernel_reports_the_compiler_log() -> Outcome {
    let opts = OpenClOptions {
        kernel: KernelSource::Text(
            "__kernel void silhouette(__global int* x) { x[0] = undeclared_thing + ; }".into(),
        ),
        ..OpenClOptions::from_env()
    };
    let err = match OpenClBackend::with_options(opts) {
        Ok(_) => panic!("a broken kernel must not build"),
        Err(e @ BackendError::Unavailable { .. }) => return Err(skip(e)),
        Err(e) => e,
    };
    match &err {
        BackendError::Build { what, log, .. } => {
            assert!(what.contains("kernel source text"), "{what}");
            assert!(log.contains("clBuildProgram failed"), "{log}");
            assert!(
                log.contains("undeclared_thing"),
                "the compiler's log names the error: {log}"
            );
        }
        other => panic!("expected BackendError::Build, got {other:?}"),
    }
    // The message shown to users carries the log.
    assert!(err.to_string().contains("undeclared_thing"));
    Ok(())
}

fn kernel_without_entry_point_is_a_build_error() -> Outcome {
    let opts = OpenClOptions {
        kernel: KernelSource::Text("__kernel void other(__global int* x) { x[0] = 1; }".into()),
        ..OpenClOptions::from_env()
    };
    match OpenClBackend::with_options(opts) {
        Err(BackendError::Build { log, .. }) => assert!(log.contains("silhouette"), "{log}"),
        Err(e @ BackendError::Unavailable { .. }) => return Err(skip(e)),
        other => panic!("expected BackendError::Build, got {other:?}"),
    }
    Ok(())
}

fn kernel_loads_from_a_path() -> Outcome {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../kernels/silhouette.cl");
    let opts = OpenClOptions {
        kernel: KernelSource::Path(path.clone()),
        ..OpenClOptions::from_env()
    };
    let mut cl = start(opts)?;
    assert!(cl
        .info()
        .details
        .iter()
        .any(|(_, v)| v.contains("silhouette.cl")));
    let case = &all_cases()[0];
    let (got, _) = extract_once(&mut cl, &case.scene, &case.lights, Accuracy::Exact).unwrap();
    let (want, _) = extract_once(
        &mut CpuBackend::new(),
        &case.scene,
        &case.lights,
        Accuracy::Exact,
    )
    .unwrap();
    assert_eq!(got, want);
    // A missing file is reported with its path.
    let missing = OpenClOptions {
        kernel: KernelSource::Path(path.with_file_name("no-such-kernel.cl")),
        ..OpenClOptions::from_env()
    };
    let err = OpenClBackend::with_options(missing).unwrap_err();
    assert!(err.to_string().contains("no-such-kernel.cl"), "{err}");
    Ok(())
}

fn device_selection_by_index_and_name() -> Outcome {
    let devices = list_devices().map_err(skip)?;
    let first = &devices[0];
    let by_index = select_device(
        &devices,
        Some(&format!("{}:{}", first.platform_index, first.device_index)),
    )
    .unwrap();
    assert_eq!(by_index, *first);
    let by_name = select_device(&devices, Some(&first.device_name.to_uppercase())).unwrap();
    assert_eq!(by_name.device_name, first.device_name);
    let default = select_device(&devices, None).unwrap();
    let expected_type = if devices.iter().any(|d| d.device_type == "GPU") {
        "GPU"
    } else {
        "CPU"
    };
    assert_eq!(default.device_type, expected_type);
    for bad in ["99:0", "0:99", "no-such-device-xyz"] {
        match select_device(&devices, Some(bad)) {
            Err(BackendError::Unavailable { reason, .. }) => {
                assert!(
                    reason.contains(DEVICE_ENV) && reason.contains(bad),
                    "{reason}"
                );
            }
            other => panic!("selector {bad:?}: expected Unavailable, got {other:?}"),
        }
    }
    let cl = start(OpenClOptions {
        device: Some("0:0".into()),
        ..OpenClOptions::default()
    })?;
    let info = cl.info();
    assert!(
        info.device.contains(&devices[0].platform_name)
            && info.device.contains(&devices[0].device_name)
    );
    Ok(())
}

fn bad_calls_are_errors() -> Outcome {
    let mut cl = start(options(false))?;
    let case = &all_cases()[0];
    let id = cl.prepare(&case.scene).unwrap();
    let mut out = Multiplicities::default();
    assert!(matches!(
        cl.extract(id, &[], Accuracy::Exact, &mut out),
        Err(BackendError::InvalidInput(_))
    ));
    cl.release(id);
    assert!(matches!(
        cl.extract(id, &case.lights, Accuracy::Exact, &mut out),
        Err(BackendError::UnknownScene { .. })
    ));
    Ok(())
}

fn prepared_scene_is_reused_across_calls_light_counts_and_modes() -> Outcome {
    let mut cl = start(options(false))?;
    let mut cpu = CpuBackend::new();
    let cases = all_cases();
    let case = cases
        .iter()
        .find(|c| c.name == "twelve-objects-transformed")
        .unwrap();
    let id = cl.prepare(&case.scene).unwrap();
    let cid = cpu.prepare(&case.scene).unwrap();
    let mut out = Multiplicities::default();
    let mut want = Multiplicities::default();
    // Growing and shrinking light counts on the same prepared buffers.
    for n in [1, case.lights.len(), 2, case.lights.len()] {
        let lights: Vec<Light> = case
            .lights
            .iter()
            .copied()
            .cycle()
            .skip(n)
            .take(n)
            .collect();
        for mode in [Accuracy::Exact, Accuracy::Robust] {
            let stats = cl.extract(id, &lights, mode, &mut out).unwrap();
            cpu.extract(cid, &lights, mode, &mut want).unwrap();
            assert_eq!(out, want, "{n} lights, {mode}");
            assert!(stats.compute > std::time::Duration::ZERO);
        }
    }
    Ok(())
}
