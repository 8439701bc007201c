//! Device tests (Mesa lavapipe in CI, any wgpu adapter elsewhere). Every test is named `gpu_*`.
//! Without an adapter each is ignored with the reason (`ignored (wgpu backend unavailable:
//! ...)`), except under `CI=true`, where a missing adapter fails it
//! (`shadowvol_test_support::skip`).

mod common;
#[path = "../../../tests/support/values.rs"]
mod values;

use common::backend;
use shadowvol_cpu::CpuBackend;
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::gpu::{ExactFilter, TableWriter};
use shadowvol_silhouette::{
    extract_once, invariant, BackendError, Light, Multiplicities, SilhouetteBackend, TopologyScene,
};
use shadowvol_test_support::{main, Outcome};
use shadowvol_wgpu_compute::{WgpuBackend, WgpuOptions};
use values::Rule;

main!(
    gpu_corpus_exact_identical_to_cpu_decided_on_the_device,
    gpu_exact_on_device_regrows_its_list_or_decides_inline,
    gpu_corpus_exact_identical_to_cpu_with_preferred_filter,
    gpu_corpus_exact_identical_to_cpu_with_forced_f32_filter,
    gpu_corpus_f32_modes_values_and_closed_chains,
    gpu_full_readback_chunking_and_device_buffers_agree,
    gpu_errors_are_reported_not_panics,
    gpu_buffer_limits_chunk_lights_or_split_the_scene,
    gpu_scenes_in_parts_equal_whole_scenes_on_the_corpus,
    gpu_every_mode_is_the_same_without_the_ov_vertex_list,
    gpu_lost_device_is_an_error_not_a_panic
);

fn cpu_result(scene: &TopologyScene, lights: &[Light], mode: Accuracy) -> Multiplicities {
    extract_once(&mut CpuBackend::new(), scene, lights, mode)
        .unwrap()
        .0
}

/// Exact mode on every case equals `cpu` bit for bit, lists included; returns the total number
/// of uncertain triples per case.
fn exact_equals_cpu(b: &mut WgpuBackend) -> Vec<(String, u64)> {
    let mut counts = Vec::new();
    for case in common::all_cases() {
        let expected = cpu_result(&case.scene, &case.lights, Accuracy::Exact);
        let (got, stats) = extract_once(b, &case.scene, &case.lights, Accuracy::Exact)
            .unwrap_or_else(|e| panic!("{}: {e}", case.name));
        assert_eq!(
            invariant::first_difference(&got, &expected),
            None,
            "{}: exact differs from cpu (light, edge, wgpu, cpu)",
            case.name
        );
        assert_eq!(got, expected, "{}: compact lists differ", case.name);
        counts.push((case.name.clone(), stats.uncertain));
    }
    counts
}

/// The default: exact mode decides on the device what its filter cannot certify
/// (`orient_int`), with either filter, so nothing goes to the host.
fn gpu_corpus_exact_identical_to_cpu_decided_on_the_device() -> Outcome {
    for force_f32_filter in [false, true] {
        let options = WgpuOptions {
            force_f32_filter,
            ..WgpuOptions::default()
        };
        assert!(options.exact_on_device);
        let mut b = backend(
            "gpu_corpus_exact_identical_to_cpu_decided_on_the_device",
            options,
        )?;
        let counts = exact_equals_cpu(&mut b);
        for (name, n) in &counts {
            assert_eq!(
                *n,
                0,
                "{name} ({:?} filter): triples decided on the host",
                b.exact_filter()
            );
        }
        // The filter leaves pairs on these cases (the two tests below: the host decides them
        // without the device fallback); here the device's resolution step decided them.
        for name in [
            "light-in-face-plane",
            "flat-grid-grazing",
            "subnormal-coordinates",
        ] {
            let case = common::case(name);
            let id = b.prepare(&case.scene).unwrap();
            let mut m = Multiplicities::default();
            b.extract(id, &case.lights, Accuracy::Exact, &mut m)
                .unwrap();
            let res = b.gpu_results(id).unwrap();
            let (_, counts, _) = read_results(&b, &res);
            assert!(
                counts[res.light_count] > 0,
                "{name} ({:?} filter): no pair was left to the resolution step",
                b.exact_filter()
            );
            b.release(id);
        }
    }
    Ok(())
}

/// Exact mode on the device with a one-record uncertain list: the list grows and the dispatch
/// is repeated, with the same results. Where the undecided pairs cannot fit the largest list
/// the device binds (a memory cap here), the host fallback refuses the batch and the device
/// path decides it with the integer fallback inline.
fn gpu_exact_on_device_regrows_its_list_or_decides_inline() -> Outcome {
    let name = "gpu_exact_on_device_regrows_its_list_or_decides_inline";
    let mut b = backend(
        name,
        WgpuOptions {
            initial_uncertain_capacity: 1,
            max_lights_per_batch: std::num::NonZeroUsize::new(2),
            ..WgpuOptions::default()
        },
    )?;
    let counts = exact_equals_cpu(&mut b);
    assert!(counts.iter().all(|(_, n)| *n == 0), "{counts:?}");

    // Every pair of a light with w = 0.5 is left by the f32 filter (w not in {0, 1}).
    let case = common::case("many-objects-transformed");
    // Its point lights, each written with w = 0.5, four times over.
    let lights: Vec<Light> = case
        .lights
        .iter()
        .filter(|l| l.to_vec4().w != 0.0)
        .map(|&l| {
            let v = l.to_vec4();
            // The same point, written with w = 0.5.
            let h = v * (0.5 / v.w);
            Light::new(h.x, h.y, h.z, h.w).unwrap()
        })
        .cycle()
        .take(12)
        .collect();
    assert!(lights.iter().all(|l| l.to_vec4().w == 0.5));
    let edges = case.scene.total_edges() as u64;
    let tris = case.scene.total_triangles() as u64;
    // The cap of the buffer-limit test: the scene's packed tables in one binding, as many
    // lights per dispatch as their compact lists (8 bytes an edge) allow, and an uncertain list
    // of cap / 16 records, fewer than the pairs of a batch.
    let cap = packed_bytes(&case.scene);
    let per_batch = (cap / (8 * edges))
        .min(cap / (4 * tris))
        .min(lights.len() as u64);
    assert!(per_batch * tris > cap / 16, "the list would hold the batch");
    let capped = |exact_on_device| WgpuOptions {
        max_buffer_bytes: Some(cap),
        force_f32_filter: true,
        exact_on_device,
        ..WgpuOptions::default()
    };
    let mut host = WgpuBackend::new(capped(false)).unwrap();
    match extract_once(&mut host, &case.scene, &lights, Accuracy::Exact) {
        Err(BackendError::Limit { message, .. }) => {
            assert!(message.contains("undecided"), "{message}");
        }
        Err(e) => panic!("expected a limit error, got {e}"),
        Ok((_, stats)) => panic!("expected a limit error, got a result with {stats:?}"),
    }
    let mut device = WgpuBackend::new(capped(true)).unwrap();
    let expected = cpu_result(&case.scene, &lights, Accuracy::Exact);
    let id = device.prepare(&case.scene).unwrap();
    // Twice: the second frame starts with the inline fallback.
    for frame in 0..2 {
        let mut got = Multiplicities::default();
        let stats = device
            .extract(id, &lights, Accuracy::Exact, &mut got)
            .unwrap();
        assert_eq!(
            invariant::first_difference(&got, &expected),
            None,
            "frame {frame}: (light, edge, wgpu, cpu)"
        );
        assert_eq!(got, expected, "frame {frame}");
        assert_eq!(stats.uncertain, 0, "frame {frame}");
    }
    Ok(())
}

fn gpu_corpus_exact_identical_to_cpu_with_preferred_filter() -> Outcome {
    let mut b = backend(
        "gpu_corpus_exact_identical_to_cpu_with_preferred_filter",
        WgpuOptions {
            exact_on_device: false,
            ..WgpuOptions::default()
        },
    )?;
    // SHADER_F64 is requested whenever the adapter has it.
    let f64_device = b.device().features().contains(wgpu::Features::SHADER_F64);
    assert_eq!(b.exact_filter() == ExactFilter::F64, f64_device);
    let counts = exact_equals_cpu(&mut b);
    eprintln!(
        "{:?} filter, uncertain triples per case: {counts:?}",
        b.exact_filter()
    );
    // Exact zeros with a non-zero permanent can't be certified: the host path really ran.
    for name in [
        "light-in-face-plane",
        "flat-grid-grazing",
        "subnormal-coordinates",
    ] {
        let n = counts.iter().find(|(c, _)| c == name).unwrap().1;
        assert!(n > 0, "{name}: no uncertain triples");
    }
    Ok(())
}

fn gpu_corpus_exact_identical_to_cpu_with_forced_f32_filter() -> Outcome {
    let options = WgpuOptions {
        force_f32_filter: true,
        exact_on_device: false,
        ..WgpuOptions::default()
    };
    let mut b = backend(
        "gpu_corpus_exact_identical_to_cpu_with_forced_f32_filter",
        options,
    )?;
    assert_eq!(b.exact_filter(), ExactFilter::F32);
    assert!(!b.device().features().contains(wgpu::Features::SHADER_F64));
    let counts = exact_equals_cpu(&mut b);
    eprintln!("f32 filter, uncertain triples per case: {counts:?}");
    for name in [
        "tiny-coordinates",
        "huge-coordinates",
        "subnormal-coordinates",
    ] {
        let n = counts.iter().find(|(c, _)| c == name).unwrap().1;
        assert!(n > 0, "{name}: the f32 filter certified out-of-range input");
    }
    Ok(())
}

fn gpu_corpus_f32_modes_values_and_closed_chains() -> Outcome {
    let mut b = backend(
        "gpu_corpus_f32_modes_values_and_closed_chains",
        WgpuOptions::default(),
    )?;
    let rule = Rule::for_device(&b.info().device);
    eprintln!("f32 modes compared by the {} rule", rule.name());
    for case in common::all_cases() {
        // One prepare for all modes: later frames read the lists with adapted prefixes.
        let id = b.prepare(&case.scene).unwrap();
        for mode in Accuracy::ALL {
            let mut got = Multiplicities::default();
            let stats = b.extract(id, &case.lights, mode, &mut got).unwrap();
            assert!(got.silhouettes_consistent(), "{} {mode}", case.name);
            assert_eq!(got.edge_count(), case.scene.total_edges());
            if mode != Accuracy::Exact {
                assert_eq!(stats.uncertain, 0);
            }
            if mode == Accuracy::Exact {
                let expected = cpu_result(&case.scene, &case.lights, mode);
                assert_eq!(got, expected, "{}: exact after other modes", case.name);
            }
            for l in 0..case.lights.len() {
                let open = invariant::open_vertices_scene(&case.scene, &got, l);
                if mode.is_consistent() {
                    assert_eq!(open, 0, "{} {mode} light {l}: open vertices", case.name);
                }
            }
            // The values, against the independent reference: bit for bit on devices that do
            // not contract (lavapipe), else on the certified edges; the certified comparison
            // holds everywhere.
            let reference = values::reference(&case.scene, &case.lights, mode);
            for r in [Rule::Certified, rule] {
                let note = values::check(&case.scene, &case.lights, mode, r, &reference, &got)
                    .unwrap_or_else(|e| panic!("{} ({} rule): {e}", case.name, r.name()));
                eprintln!("{}: {note}", case.name);
            }
        }
    }
    Ok(())
}

fn gpu_full_readback_chunking_and_device_buffers_agree() -> Outcome {
    // The host fallback, so that uncertain records exist and their buffer must grow.
    let host_fallback = WgpuOptions {
        exact_on_device: false,
        ..WgpuOptions::default()
    };
    let mut compact = backend(
        "gpu_full_readback_chunking_and_device_buffers_agree",
        host_fallback.clone(),
    )?;
    let cases = common::all_cases();
    // The smallest per-dimension cap that still holds the largest case: every case with more
    // workgroups than the cap runs on the 2-D workgroup fold.
    let max_groups = cases
        .iter()
        .map(|c| c.scene.total_edges().div_ceil(256))
        .max()
        .unwrap();
    let cap = (1..).find(|c| c * c >= max_groups).unwrap();
    assert!(max_groups > cap, "no case uses the fold");
    // Two lights per dispatch and a one-entry uncertain buffer: several dispatches, and the
    // uncertain buffer must grow (the dispatch is repeated).
    let mut full = WgpuBackend::new(WgpuOptions {
        full_readback: true,
        max_lights_per_batch: std::num::NonZeroUsize::new(2),
        initial_uncertain_capacity: 1,
        max_workgroups_per_dimension: Some(cap as u32),
        // No prefix in the first round trip: every list comes in the second.
        min_list_prefix: 0,
        // One entry per list at first: the lists grow (with room for the host's decisions)
        // and the dispatch is repeated.
        initial_list_capacity: Some(1),
        ..host_fallback
    })
    .unwrap();
    for case in cases {
        for mode in Accuracy::ALL {
            let (a, sa) = extract_once(&mut compact, &case.scene, &case.lights, mode).unwrap();
            let id = full.prepare(&case.scene).unwrap();
            let mut b = Multiplicities::default();
            let sb = full.extract(id, &case.lights, mode, &mut b).unwrap();
            // Same device, same kernel: identical in every mode.
            assert_eq!(
                invariant::first_difference(&a, &b),
                None,
                "{} {mode}: compact vs full readback (light, edge, a, b)",
                case.name
            );
            assert_eq!(a, b, "{} {mode}: compact lists", case.name);
            assert_eq!(sa.uncertain, sb.uncertain, "{} {mode}", case.name);
            // The device buffers hold the (patched) results of the last dispatch.
            let res = full.gpu_results(id).expect("results after extract");
            assert_eq!(res.first_light + res.light_count, case.lights.len());
            let (mult, counts, lists) = read_results(&full, &res);
            let e = res.edge_count as usize;
            for li in 0..res.light_count {
                let l = res.first_light + li;
                assert_eq!(
                    &mult[li * e..(li + 1) * e],
                    b.values(l),
                    "{} {mode} light {l}",
                    case.name
                );
                let c = res.list_capacity as usize;
                assert!(c <= e && counts[li] as usize <= c);
                let mut list: Vec<(u32, i32)> =
                    lists[li * c..li * c + counts[li] as usize].to_vec();
                list.sort_unstable();
                let expected: Vec<(u32, i32)> = b
                    .silhouette(l)
                    .iter()
                    .map(|&x| (x, b.values(l)[x as usize]))
                    .collect();
                assert_eq!(
                    list, expected,
                    "{} {mode} light {l}: device list",
                    case.name
                );
            }
            full.release(id);
            assert!(full.gpu_results(id).is_none());
        }
    }
    Ok(())
}

/// Bytes of `scene`'s tables packed into one storage binding, as the backend uploads them
/// (with the OV vertex list, as [`WgpuOptions::default`] does for small scenes).
fn packed_bytes(scene: &TopologyScene) -> u64 {
    let writer = TableWriter::new(scene, "wgpu").unwrap();
    let extras = shadowvol_gpu::Extras {
        ov_vertices: true,
        vertex_objects: false,
    };
    shadowvol_gpu::TablePacking::new(&writer, extras).bytes()
}

/// Reads the device result buffers back (test helper).
fn read_results(
    b: &WgpuBackend,
    res: &shadowvol_wgpu_compute::GpuResults<'_>,
) -> (Vec<i32>, Vec<u32>, Vec<(u32, i32)>) {
    let read = |buf: &wgpu::Buffer| -> Vec<u32> {
        let staging = b.device().create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: buf.size(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = b.device().create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buf, 0, &staging, 0, buf.size());
        b.queue().submit([enc.finish()]);
        staging.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
        b.device()
            .poll(wgpu::PollType::wait_indefinitely())
            .unwrap();
        let v = staging.get_mapped_range(..).unwrap();
        v.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let mult = read(res.multiplicities)
        .into_iter()
        .map(|x| x as i32)
        .collect();
    let counts = read(res.counters);
    let lists = read(res.silhouettes)
        .chunks_exact(2)
        .map(|w| (w[0], w[1] as i32))
        .collect();
    (mult, counts, lists)
}

fn gpu_errors_are_reported_not_panics() -> Outcome {
    let mut b = backend("gpu_errors_are_reported_not_panics", WgpuOptions::default())?;
    let case = &common::all_cases()[0];
    let mut m = Multiplicities::default();
    let released = b.prepare(&case.scene).unwrap();
    b.release(released);
    assert!(matches!(
        b.extract(released, &case.lights, Accuracy::Exact, &mut m),
        Err(BackendError::UnknownScene { .. })
    ));
    let id = b.prepare(&case.scene).unwrap();
    assert!(matches!(
        b.extract(id, &[], Accuracy::Exact, &mut m),
        Err(BackendError::InvalidInput(_))
    ));
    b.release(id);
    assert!(matches!(
        b.extract(id, &case.lights, Accuracy::Exact, &mut m),
        Err(BackendError::UnknownScene { .. })
    ));
    // A scene without edges extracts to empty results.
    let empty = TopologyScene::default();
    let id = b.prepare(&empty).unwrap();
    let stats = b
        .extract(id, &case.lights, Accuracy::Robust, &mut m)
        .unwrap();
    assert_eq!(
        (m.edge_count(), m.light_count(), stats.uncertain),
        (0, case.lights.len(), 0)
    );
    // Info names the device and the filter.
    let info = b.info();
    assert_eq!(info.name, "wgpu");
    assert_eq!(info.modes, Accuracy::ALL.to_vec());
    assert!(info
        .details
        .iter()
        .any(|(k, v)| k == "exact_filter" && v == b.exact_filter().name()));
    Ok(())
}

fn gpu_buffer_limits_chunk_lights_or_split_the_scene() -> Outcome {
    let mut unlimited = backend(
        "gpu_buffer_limits_chunk_lights_or_split_the_scene",
        WgpuOptions::default(),
    )?;
    let case = common::case("many-objects-transformed");
    let edges = case.scene.total_edges() as u64;
    // The scene's tables, packed into one storage binding.
    let largest = packed_bytes(&case.scene);
    // A cap below the packed tables prepares the scene in parts, with the same results in
    // every mode.
    let mut small = WgpuBackend::new(WgpuOptions {
        max_buffer_bytes: Some(largest - 4),
        ..WgpuOptions::default()
    })
    .unwrap();
    let id = small.prepare(&case.scene).unwrap();
    assert!(
        small.index(id).is_none(),
        "prepared in parts, not as one layout"
    );
    for mode in Accuracy::ALL {
        let mut got = Multiplicities::default();
        small.extract(id, &case.lights, mode, &mut got).unwrap();
        let (expected, _) = extract_once(&mut unlimited, &case.scene, &case.lights, mode).unwrap();
        assert_eq!(got, expected, "{mode}");
    }
    // A soup (three vertices of its own a triangle) cut under a cap of half its packed tables
    // (108 bytes a triangle, the most a triangle can take): every part must fit.
    let n = 200u32;
    let soup = shadowvol_mesh_topology::Mesh::new(
        (0..n)
            .flat_map(|i| {
                let x = i as f32;
                [
                    glam::Vec3::new(x, 0.0, 0.0),
                    glam::Vec3::new(x, 1.0, 0.0),
                    glam::Vec3::new(x, 0.0, 1.0),
                ]
            })
            .collect(),
        (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
    )
    .unwrap();
    let soup = TopologyScene::single(shadowvol_mesh_topology::EdgeTable::build(&soup).unwrap());
    let mut halved = WgpuBackend::new(WgpuOptions {
        max_buffer_bytes: Some(108 * u64::from(n) / 2),
        ..WgpuOptions::default()
    })
    .unwrap();
    let id = halved
        .prepare(&soup)
        .unwrap_or_else(|e| panic!("a soup in parts: {e}"));
    assert!(halved.index(id).is_none(), "prepared in parts");
    for mode in Accuracy::ALL {
        let mut got = Multiplicities::default();
        halved.extract(id, &case.lights, mode, &mut got).unwrap();
        let (expected, _) = extract_once(&mut unlimited, &soup, &case.lights, mode).unwrap();
        assert_eq!(got, expected, "soup {mode}");
    }
    // A cap that holds the packed scene but fewer lights' compact lists (8 bytes per edge
    // each) than the call has: the lights run `per` per dispatch, with the same result.
    let cap = largest.max((edges + 1) * 16);
    let tris = case.scene.total_triangles() as u64;
    let per = (cap / (8 * edges)).min(cap / (4 * tris)) as usize;
    let mut capped = WgpuBackend::new(WgpuOptions {
        max_buffer_bytes: Some(cap),
        ..WgpuOptions::default()
    })
    .unwrap();
    let id = capped.prepare(&case.scene).unwrap();
    let mut lights = case.lights.clone();
    lights.extend(case.lights.iter().copied());
    assert!(per >= 1 && lights.len() > per, "{per} lights per dispatch");
    let last = match lights.len() % per {
        0 => per,
        r => r,
    };
    for mode in Accuracy::ALL {
        let mut got = Multiplicities::default();
        capped.extract(id, &lights, mode, &mut got).unwrap();
        let (expected, _) = extract_once(&mut unlimited, &case.scene, &lights, mode).unwrap();
        assert_eq!(got, expected, "{mode}");
        let res = capped.gpu_results(id).unwrap();
        assert_eq!(res.light_count, last);
        assert_eq!(res.first_light + res.light_count, lights.len());
    }
    Ok(())
}

/// Every corpus case, with a buffer cap that cuts it into parts (objects grouped, big objects
/// cut into triangle ranges): exact mode equals `cpu` bit for bit, the other modes equal the
/// whole scene on the same device.
fn gpu_scenes_in_parts_equal_whole_scenes_on_the_corpus() -> Outcome {
    let mut whole = backend(
        "gpu_scenes_in_parts_equal_whole_scenes_on_the_corpus",
        WgpuOptions::default(),
    )?;
    let (mut split_somewhere, mut host_decided) = (false, 0);
    for case in common::all_cases() {
        // A third of the packed tables: at least three parts, each of at least one triangle
        // (108 bytes at most) with its object bases.
        let objects = 16 * (case.scene.objects.len() as u64 + 1);
        let cap = (packed_bytes(&case.scene) / 3).max(256 + objects);
        let mut parts = WgpuBackend::new(WgpuOptions {
            max_buffer_bytes: Some(cap),
            ..WgpuOptions::default()
        })
        .unwrap();
        let id = parts.prepare(&case.scene).unwrap();
        split_somewhere |= parts.index(id).is_none();
        for mode in Accuracy::ALL {
            let mut got = Multiplicities::default();
            parts
                .extract(id, &case.lights, mode, &mut got)
                .unwrap_or_else(|e| panic!("{} {mode}: {e}", case.name));
            let expected = if mode == Accuracy::Exact {
                cpu_result(&case.scene, &case.lights, mode)
            } else {
                extract_once(&mut whole, &case.scene, &case.lights, mode)
                    .unwrap()
                    .0
            };
            assert_eq!(
                invariant::first_difference(&got, &expected),
                None,
                "{} {mode}: (light, edge, parts, whole)",
                case.name
            );
            assert_eq!(got, expected, "{} {mode}: compact lists", case.name);
        }
        // Exact mode decided on the host (each part's index reads its table): the same bits.
        let mut host = WgpuBackend::new(WgpuOptions {
            max_buffer_bytes: Some(cap),
            exact_on_device: false,
            ..WgpuOptions::default()
        })
        .unwrap();
        let (got, stats) =
            extract_once(&mut host, &case.scene, &case.lights, Accuracy::Exact).unwrap();
        let expected = cpu_result(&case.scene, &case.lights, Accuracy::Exact);
        assert_eq!(got, expected, "{} exact, decided on the host", case.name);
        host_decided += stats.uncertain;
    }
    assert!(split_somewhere, "the cap cut no scene into parts");
    assert!(host_decided > 0, "no part left a pair to the host");
    Ok(())
}

fn gpu_lost_device_is_an_error_not_a_panic() -> Outcome {
    let mut b = backend(
        "gpu_lost_device_is_an_error_not_a_panic",
        WgpuOptions::default(),
    )?;
    let case = &common::all_cases()[0];
    let id = b.prepare(&case.scene).unwrap();
    let mut m = Multiplicities::default();
    b.extract(id, &case.lights, Accuracy::Exact, &mut m)
        .unwrap();
    b.device().destroy();
    let _ = b.device().poll(wgpu::PollType::wait_indefinitely());
    for mode in Accuracy::ALL {
        match b.extract(id, &case.lights, mode, &mut m) {
            Err(BackendError::Device { message, .. }) => assert!(!message.is_empty()),
            other => panic!("{mode}: expected a device error, got {other:?}"),
        }
    }
    assert!(matches!(
        b.prepare(&case.scene),
        Err(BackendError::Device { .. })
    ));
    Ok(())
}

/// Scenes beyond `ov_vertices_up_to` triangles keep no OV vertex list on the device, and
/// `original` reads each OV through its triangle: every mode gives the same bits either way, on
/// every corpus case (the default keeps the list for all of them).
fn gpu_every_mode_is_the_same_without_the_ov_vertex_list() -> Outcome {
    let mut with = backend(
        "gpu_every_mode_is_the_same_without_the_ov_vertex_list",
        WgpuOptions::default(),
    )?;
    let mut without = WgpuBackend::new(WgpuOptions {
        ov_vertices_up_to: 0,
        ..WgpuOptions::default()
    })
    .unwrap();
    for case in common::all_cases() {
        for mode in Accuracy::ALL {
            let (a, _) = extract_once(&mut with, &case.scene, &case.lights, mode).unwrap();
            let (b, _) = extract_once(&mut without, &case.scene, &case.lights, mode).unwrap();
            assert_eq!(
                invariant::first_difference(&b, &a),
                None,
                "{} {mode}: (light, edge, without, with)",
                case.name
            );
            assert_eq!(b, a, "{} {mode}: compact lists", case.name);
        }
    }
    Ok(())
}
