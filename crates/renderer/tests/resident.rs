//! The GPU-resident pass against its CPU twin, the `cpu` backend's exact multiplicities, the
//! host pipeline and the ray-traced reference.
mod common;

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_renderer::raster::read_texture;
use shadowvol_renderer::resident::{
    technique, texture_2d, twin, LightRecords, PassFormats, PassFrame, ResidentLayout,
    ResidentScene, ShadowPass,
};
use shadowvol_renderer::{
    hard, volume, Camera, HostPipeline, Pipeline, RenderOptions, Scene, Technique,
};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::SceneLight;
use shadowvol_silhouette::{object_lights, SceneObject, TopologyScene};
use shadowvol_test_support::corpus;
use shadowvol_test_support::{main, skip, Outcome, Skip};
use std::sync::Arc;

main!(
    exact_multiplicities_equal_cpu_bit_for_bit_on_the_corpus_with_no_host_resolution,
    each_sample_of_a_light_with_a_size_equals_cpu_as_a_point_light,
    every_mode_matches_its_twin_and_the_consistent_modes_close_their_chains,
    exact_mode_decides_subnormal_and_huge_inputs_on_the_device,
    gpu_pipeline_matches_the_host_pipeline_and_the_reference_on_hard_scenes,
    timed_gpu_frames_read_nothing_back,
    exact_gpu_multiplicities_equal_cpu_on_random_lattice_soups,
    grouped_chunked_pulled_and_batched_frames_draw_the_same_image
);

/// The first adapter, or a visible skip without one; under `CI=true` a missing adapter fails
/// ([`shadowvol_test_support::skip`]).
fn adapter() -> Result<wgpu::Adapter, Skip> {
    shadowvol_renderer::RenderDevice::headless_adapter()
        .map_err(|e| skip(format!("{e}; install Mesa lavapipe to run this test")))
}

/// A device on `adapter` with the pass's optional features and `limits`, and the pass on it.
fn open_pass(
    adapter: &wgpu::Adapter,
    limits: wgpu::Limits,
) -> (ShadowPass, wgpu::Device, wgpu::Queue) {
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: ShadowPass::optional_features(adapter),
        required_limits: limits,
        ..Default::default()
    }))
    .unwrap();
    let formats = PassFormats {
        color: wgpu::TextureFormat::Rgba8Unorm,
        ids: None,
        depth: wgpu::TextureFormat::Depth24PlusStencil8,
    };
    let pass = ShadowPass::new(adapter, &device, &queue, formats).unwrap();
    (pass, device, queue)
}

/// A device with the pass and its required limits, or a visible skip without an adapter.
fn device() -> Result<(ShadowPass, wgpu::Device, wgpu::Queue), Skip> {
    let adapter = adapter()?;
    let limits = ShadowPass::required_limits(&adapter).unwrap();
    Ok(open_pass(&adapter, limits))
}

/// One [`device`] for the whole process (the proptest's cases share it).
fn shared_device() -> Result<&'static (ShadowPass, wgpu::Device, wgpu::Queue), Skip> {
    use std::sync::OnceLock;
    static GPU: OnceLock<Result<(ShadowPass, wgpu::Device, wgpu::Queue), Skip>> = OnceLock::new();
    GPU.get_or_init(device).as_ref().map_err(Clone::clone)
}

/// Unit lights.
fn unit(lights: &[Light]) -> Vec<SceneLight> {
    lights.iter().map(|&l| SceneLight::unit(l)).collect()
}

/// What one extraction on the device gave, and what the twin gives for the same input.
struct Run {
    signs: Vec<i32>,
    shared: Vec<i32>,
    twin_shared: Vec<i32>,
    records: Vec<LightRecords>,
    twin_signs: Vec<i32>,
    twin_records: Vec<LightRecords>,
    twin_integer: u64,
    integer: u64,
}

fn extract(
    gpu: &(ShadowPass, wgpu::Device, wgpu::Queue),
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    techniques: &[Technique],
    groups: &[std::ops::Range<usize>],
) -> (ResidentScene, Run) {
    let (pass, device, queue) = gpu;
    // The layout is object space; the transforms are per-frame inputs of the pass.
    let mut rs = pass
        .prepare_layout(ResidentLayout::build(scene).unwrap())
        .unwrap();
    let n_obj = scene.objects.len();
    let transforms: Vec<Affine3A> = scene.objects.iter().map(|o| o.world_from_object).collect();
    let camera = Camera::look_at(Vec3::new(5.0, 4.0, 6.0), Vec3::ZERO);
    pass.update(
        &mut rs,
        &PassFrame {
            camera: &camera,
            aspect: 1.0,
            lights: &unit(lights),
            colors: &vec![[1.0; 3]; lights.len()],
            transforms: &transforms,
            albedo: &vec![[1.0; 3]; n_obj],
            techniques,
            scissors: &vec![None; lights.len()],
            ambient: 0.1,
            mode,
            count: true,
            sample_groups: groups,
        },
    )
    .unwrap();
    let mut enc = device.create_command_encoder(&Default::default());
    pass.encode_extract(&mut enc, &rs);
    queue.submit([enc.finish()]);
    let signs = pass.read_signs(&rs).unwrap();
    let shared = pass.read_shared_signs(&rs).unwrap();
    let records = pass.read_records(&rs).unwrap();
    let integer = pass.read_counts(&rs).unwrap().integer_decided;
    let ol: Vec<[f32; 4]> = object_lights(scene.transforms(), lights)
        .into_iter()
        .flatten()
        .collect();
    let codes: Vec<u32> = techniques.iter().map(|&t| technique::code(t)).collect();
    // The pass keeps only the layout's sizes; the twin reads the same layout, built again.
    let layout = &ResidentLayout::build(scene).unwrap();
    let (twin_signs, twin_shared, twin_integer) = twin::triangle_signs_shared(
        layout,
        &ol,
        lights.len(),
        &codes,
        (mode, pass.exact_filter()),
        rs.sharing_groups(),
    );
    let (_, twin_records) =
        twin::side_records(layout, &twin_signs, &ol, lights.len(), &codes, mode);
    (
        rs,
        Run {
            signs,
            shared,
            twin_shared,
            records,
            twin_signs,
            twin_records,
            twin_integer,
            integer,
        },
    )
}

/// The host pipeline's multiplicities of light `li` (`ol[object][light]` object-space) from a
/// backend's `m`: less the triangles touching the point light (they have no volume).
fn without_touching(
    scene: &TopologyScene,
    ol: &[Vec<[f32; 4]>],
    li: usize,
    mut m: Vec<i32>,
) -> Vec<i32> {
    let lights: Vec<[f32; 4]> = ol.iter().map(|o| o[li]).collect();
    volume::remove_touching(scene, &lights, Accuracy::Exact, &mut m);
    m
}

/// Per light, the multiplicity of every global edge from the side records.
fn multiplicities(records: &[LightRecords], edges: usize) -> Vec<Vec<i32>> {
    records.iter().map(|r| r.multiplicities(edges)).collect()
}

/// Alternating techniques, so both lists and culling are exercised.
fn mixed_techniques(lights: usize, objects: usize) -> Vec<Technique> {
    (0..lights * objects)
        .map(|i| match i % 3 {
            0 => Technique::ZFail,
            1 => Technique::ZPass,
            _ if objects == 1 => Technique::ZFail,
            _ => Technique::Culled,
        })
        .collect()
}

fn exact_multiplicities_equal_cpu_bit_for_bit_on_the_corpus_with_no_host_resolution() -> Outcome {
    let gpu = device()?;
    let mut cpu = shadowvol_cpu::CpuBackend::new();
    let mut integer_total = 0;
    for case in corpus::cases() {
        let scene = case.scene().unwrap();
        let n_obj = scene.objects.len();
        let techniques = vec![Technique::ZFail; case.lights.len() * n_obj];
        let (rs, run) = extract(
            &gpu,
            &scene,
            &case.lights,
            Accuracy::Exact,
            &techniques,
            &[],
        );
        let (want, _) =
            shadowvol_silhouette::extract_once(&mut cpu, &scene, &case.lights, Accuracy::Exact)
                .unwrap();
        let got = multiplicities(&run.records, rs.edge_count());
        let ol = object_lights(scene.transforms(), &case.lights);
        for (li, m) in got.iter().enumerate() {
            // The host pipeline's multiplicities: the backend's, less the triangles touching a
            // point light (they have no volume).
            let want = without_touching(&scene, &ol, li, want.values(li).to_vec());
            assert_eq!(m, &want, "{}: light {li}", case.name);
        }
        assert_eq!(
            run.signs, run.twin_signs,
            "{}: signs differ from the twin",
            case.name
        );
        assert_eq!(run.records, run.twin_records, "{}", case.name);
        assert_eq!(
            run.integer, run.twin_integer,
            "{}: integer-path count",
            case.name
        );
        integer_total += run.integer;
    }
    // The corpus has degenerate cases the filter cannot certify: the integer path is exercised.
    assert!(integer_total > 0, "no triangle reached the integer path");
    Ok(())
}

/// Lights with a size: the GPU pipeline extracts each light's samples as one sharing group; each
/// sample's multiplicities equal the `cpu` backend's for that sample alone, as a point light, on
/// every corpus case (8 samples of radius 0.05 world units or 0.05 rad) and on spheres with
/// samples near and far; the device's shared signs equal the twin's, and each is the exact sign
/// of every sample of its group.
fn each_sample_of_a_light_with_a_size_equals_cpu_as_a_point_light() -> Outcome {
    let one = device_with(|_| {})?;
    // A binding of 96 KiB: the sphere's packed tables (71 KB) fit, its samples go in batches
    // of 2 lights (34 KB of side records each).
    let small = device_with(|l| l.max_storage_buffer_binding_size = 96 << 10)?;
    let mut cpu = shadowvol_cpu::CpuBackend::new();
    let (mut shared, mut left) = (0usize, 0usize);
    let mut cases: Vec<(String, TopologyScene, Vec<SceneLight>)> = corpus::cases()
        .iter()
        .map(|case| {
            let lights = case.lights.iter().map(|&l| with_radius(l, 0.05)).collect();
            (case.name.to_string(), case.scene().unwrap(), lights)
        })
        .collect();
    let sphere = shadowvol_test_support::shapes::uv_sphere_y(24, 31, 1.5);
    for (light, r) in [
        (Light::point(Vec3::new(3.0, 4.0, -2.0)), 0.02),
        (Light::point(Vec3::new(0.4, 1.9, 0.3)), 0.3),
        (Light::directional(Vec3::new(-0.3, 1.0, 0.45)), 0.01),
    ] {
        let table = shadowvol_mesh_topology::EdgeTable::build(&sphere).unwrap();
        let scene = TopologyScene::single(table);
        cases.push((
            format!("sphere, light {light}"),
            scene,
            vec![with_radius(light, r)],
        ));
    }
    let mut batched = 0;
    for ((name, scene, lights), gpu) in cases.iter().flat_map(|c| [(c, &one), (c, &small)]) {
        let n_obj = scene.objects.len();
        let per = if name.starts_with("sphere") { 16 } else { 8 };
        let samples: Vec<Light> = lights
            .iter()
            .flat_map(|sl| sl.samples(per, Vec3::ZERO))
            .collect();
        let groups: Vec<std::ops::Range<usize>> = (0..lights.len())
            .map(|k| k * per as usize..(k + 1) * per as usize)
            .collect();
        let techniques = vec![Technique::ZFail; samples.len() * n_obj];
        let (rs, run) = extract(gpu, scene, &samples, Accuracy::Exact, &techniques, &groups);
        if rs.light_batches() > 1 {
            batched += 1;
        } else {
            assert_eq!(rs.sharing_groups().len(), lights.len(), "{name}");
        }
        for (what, got, twin) in [
            ("shared sign", &run.shared, &run.twin_shared),
            ("sign", &run.signs, &run.twin_signs),
        ] {
            assert_eq!(got.len(), twin.len(), "{name}: {what}s");
            if let Some(k) = (0..got.len()).find(|&k| got[k] != twin[k]) {
                panic!(
                    "{name}: {what} {k} is {} on the device, {} in the twin",
                    got[k], twin[k]
                );
            }
        }
        let ol = object_lights(scene.transforms(), &samples);
        let (s, l) = check_shared_signs(scene, &rs, &run.shared, &ol);
        (shared, left) = (shared + s, left + l);
        let got = multiplicities(&run.records, rs.edge_count());
        for (si, m) in got.iter().enumerate() {
            let (one, _) = shadowvol_silhouette::extract_once(
                &mut cpu,
                scene,
                &samples[si..=si],
                Accuracy::Exact,
            )
            .unwrap();
            let want = without_touching(scene, &ol, si, one.values(0).to_vec());
            assert_eq!(m, &want, "{name}: sample {si}");
        }
    }
    // The sphere's samples went in batches.
    assert!(batched >= 3, "{batched} runs in batches");
    // Both paths ran: triangles decided once for a group, and triangles decided per sample.
    assert!(
        shared > 10_000 && left > 100,
        "shared {shared}, left {left}"
    );
    Ok(())
}

/// `light` with a disk of radius `r` (world units, or radians for a directional light).
fn with_radius(light: Light, r: f32) -> SceneLight {
    let mut sl = SceneLight::unit(light);
    sl.radius = r;
    sl
}

/// Every shared sign the device certified is the exact sign (`orient_exact` on the canonical
/// triangle) of every sample of its group; returns the triangles shared and left.
fn check_shared_signs(
    scene: &TopologyScene,
    rs: &ResidentScene,
    shared: &[i32],
    ol: &[Vec<[f32; 4]>],
) -> (usize, usize) {
    let layout = ResidentLayout::build(scene).unwrap();
    let n = layout.tri_count();
    let (mut yes, mut no) = (0, 0);
    for (g, grp) in rs.sharing_groups().iter().enumerate() {
        for (t, tr) in layout.tables.tris.iter().enumerate() {
            let s = shared[g * n + t];
            if s == shadowvol_renderer::resident::NOT_SHARED {
                no += 1;
                continue;
            }
            yes += 1;
            let p = tr.map(|v| layout.tables.position(v));
            let obj = layout.tables.tri_object(t);
            for l in &ol[obj][grp.first..grp.first + grp.count] {
                let exact = shadowvol_robust_math::orient_exact(p[0], p[1], *l, p[2]);
                assert_eq!(i32::from(exact), s, "group {g} triangle {t} light {l:?}");
            }
        }
    }
    (yes, no)
}

fn every_mode_matches_its_twin_and_the_consistent_modes_close_their_chains() -> Outcome {
    let gpu = device()?;
    for mode in Accuracy::ALL {
        let mut original_cracked = false;
        for case in corpus::cases() {
            let scene = case.scene().unwrap();
            let techniques = mixed_techniques(case.lights.len(), scene.objects.len());
            let (rs, run) = extract(&gpu, &scene, &case.lights, mode, &techniques, &[]);
            // WGSL may contract f32 arithmetic where Rust does not; lavapipe does not, so the
            // f32 modes are compared exactly too (a driver that contracts would show here).
            assert_eq!(run.signs, run.twin_signs, "{mode} {}: signs", case.name);
            assert_eq!(
                run.records, run.twin_records,
                "{mode} {}: records",
                case.name
            );
            let m = multiplicities(&run.records, rs.edge_count());
            let offsets = scene.edge_offsets();
            for (li, m) in m.iter().enumerate() {
                for (oi, o) in scene.objects.iter().enumerate() {
                    if techniques[li * scene.objects.len() + oi] == Technique::Culled {
                        assert!(m[offsets[oi]..offsets[oi + 1]].iter().all(|&x| x == 0));
                        continue;
                    }
                    let open = shadowvol_silhouette::invariant::open_vertices(
                        &o.table,
                        &m[offsets[oi]..offsets[oi + 1]],
                    );
                    if mode.is_consistent() {
                        assert_eq!(open, 0, "{mode} {} light {li} object {oi}", case.name);
                    } else if open > 0 {
                        original_cracked = true;
                    }
                }
            }
        }
        if mode == Accuracy::Original {
            assert!(
                original_cracked,
                "original must keep its cracks somewhere in the corpus"
            );
        }
    }
    Ok(())
}

/// Subnormal and near-`f32::MAX` coordinates: the filter certifies none of them, the integer
/// path decides them on the device, equal to `cpu`.
fn exact_mode_decides_subnormal_and_huge_inputs_on_the_device() -> Outcome {
    let gpu = device()?;
    let mut cpu = shadowvol_cpu::CpuBackend::new();
    let tet = |s: f32| {
        Mesh::new(
            vec![
                Vec3::ZERO,
                Vec3::new(s, 0.0, 0.0),
                Vec3::new(0.0, 0.0, s),
                Vec3::new(0.0, s, 0.0),
                Vec3::new(s, s, s * 0.5),
            ],
            vec![
                [0, 2, 1],
                [0, 1, 3],
                [1, 2, 3],
                [0, 3, 2],
                [1, 4, 3],
                [3, 4, 2],
            ],
        )
        .unwrap()
    };
    for (s, light) in [
        (1e-40f32, Light::point(Vec3::new(3e-40, 2e-40, 1e-40))),
        (1e-44, Light::directional(Vec3::new(1.0, 2.0, 0.5))),
        (1e37, Light::point(Vec3::new(3e37, 2e37, 1e37))),
        (3e38, Light::directional(Vec3::new(-1.0, 3.0, 0.25))),
    ] {
        let table = Arc::new(shadowvol_mesh_topology::EdgeTable::build(&tet(s)).unwrap());
        let scene = TopologyScene {
            objects: vec![SceneObject {
                name: format!("tet {s:e}"),
                table,
                world_from_object: Affine3A::IDENTITY,
            }],
        };
        let lights = [light];
        let (rs, run) = extract(
            &gpu,
            &scene,
            &lights,
            Accuracy::Exact,
            &[Technique::ZFail],
            &[],
        );
        let (want, _) =
            shadowvol_silhouette::extract_once(&mut cpu, &scene, &lights, Accuracy::Exact).unwrap();
        let got = multiplicities(&run.records, rs.edge_count());
        assert_eq!(got[0].as_slice(), want.values(0), "scale {s:e}");
        if s < 1e-30 {
            assert!(
                run.integer > 0,
                "scale {s:e}: subnormals must go to the integer path"
            );
        }
    }
    Ok(())
}

const SIZE: u32 = 128;
/// 0.05 % of the image.
const MAX_PIXELS: usize = (SIZE * SIZE) as usize * 5 / 10_000;
/// (scene, mode) pairs that are compared, not bounded: those of tests/hard.rs, where the mode's
/// own signs bound another shadow than the exact geometry's (the host pipeline leaves the same
/// pixels there).
const FINDINGS: [(&str, Accuracy); 3] = [
    ("hard-edge-on-tilted-fan", Accuracy::Robust),
    ("hard-homogeneous-w", Accuracy::Robust),
    ("hard-homogeneous-w", Accuracy::Ordered),
];

fn gpu_pipeline_matches_the_host_pipeline_and_the_reference_on_hard_scenes() -> Outcome {
    let mut opts = RenderOptions::new(SIZE, SIZE);
    let mut host = common::renderer_with(opts)?;
    let mut gpu = common::gpu_renderer(opts)?;
    let mut report = String::new();
    for mode in [Accuracy::Robust, Accuracy::Ordered, Accuracy::Exact] {
        opts.mode = mode;
        host.set_options(opts).unwrap();
        gpu.set_options(opts).unwrap();
        for name in hard::hard_preset_names() {
            let scene = hard::hard_preset(&name).unwrap();
            let h = host.render(&scene).unwrap();
            let g = gpu.render(&scene).unwrap();
            assert_eq!(g.report.pipeline, Pipeline::Gpu);
            assert_eq!(g.report.host_resolved, 0, "{name} {mode}");
            // The images: pixels where a channel differs by more than rounding (the pipelines
            // compute positions and normals in f32 in different orders).
            let differ = h
                .read_image()
                .unwrap()
                .rgba
                .chunks_exact(4)
                .zip(g.image.as_ref().unwrap().rgba.chunks_exact(4))
                .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.abs_diff(*y) > 3))
                .count();
            let cmp = common::compare(&g, &scene);
            report.push_str(&format!(
                "{mode} {name}: {differ} pixels differ from host, {} artifacts (host {})\n",
                cmp.artifact_pixels,
                common::compare(&h, &scene).artifact_pixels
            ));
            if FINDINGS.contains(&(name.as_str(), mode)) {
                continue;
            }
            assert!(
                differ <= MAX_PIXELS,
                "{mode} {name}: {differ} pixels differ from the host pipeline\n{report}"
            );
            assert!(
                cmp.artifact_pixels <= MAX_PIXELS,
                "{mode} {name}: {} artifact pixels\n{report}",
                cmp.artifact_pixels
            );
            // The plan's counts come from the device: the same silhouettes as the host's.
            for (eh, eg) in h.report.plan.iter().zip(&g.report.plan) {
                assert_eq!(eh.technique, eg.technique, "{mode} {name}");
                if mode == Accuracy::Exact {
                    assert_eq!(
                        eh.side_quads, eg.side_quads,
                        "{mode} {name}: {eh:?} vs {eg:?}"
                    );
                    assert_eq!(
                        eh.cap_triangles, eg.cap_triangles,
                        "{mode} {name}: {eh:?} vs {eg:?}"
                    );
                }
            }
        }
    }
    eprintln!("{report}");
    Ok(())
}

fn timed_gpu_frames_read_nothing_back() -> Outcome {
    let mut r = common::gpu_renderer(RenderOptions::new(64, 64))?;
    let scene = common::box_on_floor(
        Light::point(Vec3::new(1.0, 5.0, 1.0)),
        Camera::look_at(Vec3::new(4.0, 4.0, 6.0), Vec3::ZERO),
    );
    let t = r.render_timed(&scene).unwrap();
    assert_eq!(t.readback_bytes, 0);
    r.set_pipeline(Box::new(HostPipeline::new(Box::new(
        shadowvol_cpu::CpuBackend::new(),
    ))));
    let t = r.render_timed(&scene).unwrap();
    assert!(
        t.readback_bytes > 0,
        "the host pipeline brings multiplicities back"
    );
    Ok(())
}

/// A coordinate for the proptest: small integers (coplanar and collinear points, shared
/// planes with the light) times a power of two from the subnormal range to near `f32::MAX`.
fn coordinate() -> impl proptest::strategy::Strategy<Value = f32> {
    use proptest::prelude::*;
    (
        -3i32..=3,
        prop::sample::select(vec![-140i32, -60, -20, 0, 20, 60, 100]),
    )
        .prop_map(|(m, e)| m as f32 * 2f32.powi(e))
}

proptest::proptest! {
    #![proptest_config(proptest::test_runner::Config { cases: 48, ..Default::default() })]

    /// The cases of [`exact_gpu_multiplicities_equal_cpu_on_random_lattice_soups`].
    fn lattice_soup_cases(
        points in proptest::collection::vec((coordinate(), coordinate(), coordinate()), 4..9),
        tris in proptest::collection::vec((0usize..8, 0usize..8, 0usize..8), 1..10),
        light in (coordinate(), coordinate(), coordinate(), proptest::bool::ANY),
    ) {
        let gpu = shared_device().expect("checked before the cases run");
        let n = points.len();
        let positions: Vec<Vec3> = points.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        let triangles: Vec<[u32; 3]> = tris
            .iter()
            .map(|&(a, b, c)| [(a % n) as u32, (b % n) as u32, (c % n) as u32])
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        proptest::prop_assume!(!triangles.is_empty());
        let Ok(mesh) = Mesh::new(positions, triangles) else { return Ok(()) };
        let Ok(table) = shadowvol_mesh_topology::EdgeTable::build(&mesh) else { return Ok(()) };
        proptest::prop_assume!(!table.triangles.is_empty());
        let (lx, ly, lz, directional) = light;
        let l = if directional {
            match Light::new(lx, ly, lz, 0.0) { Ok(l) => l, Err(_) => return Ok(()) }
        } else {
            Light::point(Vec3::new(lx, ly, lz))
        };
        let scene = TopologyScene {
            objects: vec![SceneObject {
                name: "soup".into(),
                table: Arc::new(table),
                world_from_object: Affine3A::IDENTITY,
            }],
        };
        let lights = [l];
        let (rs, run) = extract(gpu, &scene, &lights, Accuracy::Exact, &[Technique::ZFail], &[]);
        proptest::prop_assert_eq!(&run.signs, &run.twin_signs);
        let mut cpu = shadowvol_cpu::CpuBackend::new();
        let (want, _) =
            shadowvol_silhouette::extract_once(&mut cpu, &scene, &lights, Accuracy::Exact).unwrap();
        let mut want = want.values(0).to_vec();
        let o = &scene.objects[0];
        let ol = object_lights(scene.transforms(), &lights)[0][0];
        let touching = volume::touching_triangles(&o.table, ol);
        if !touching.is_empty() {
            volume::remove_triangles(&o.table, ol, Accuracy::Exact, &touching, &mut want);
        }
        let got = multiplicities(&run.records, rs.edge_count());
        proptest::prop_assert_eq!(&got[0], &want);
    }
}

/// Random triangle soups on a lattice (degenerate by construction: duplicate points, shared
/// planes, the light on a vertex or in a plane), one light: the device's exact multiplicities
/// equal `cpu`'s, its signs the twin's, with nothing decided on the host.
fn exact_gpu_multiplicities_equal_cpu_on_random_lattice_soups() -> Outcome {
    shared_device()?;
    lattice_soup_cases();
    Ok(())
}

/// A device for the pass with its required limits lowered by `lower`, or a visible skip
/// without an adapter.
fn device_with(
    lower: impl FnOnce(&mut wgpu::Limits),
) -> Result<(ShadowPass, wgpu::Device, wgpu::Queue), Skip> {
    let adapter = adapter()?;
    let mut limits = ShadowPass::required_limits(&adapter).unwrap();
    lower(&mut limits);
    Ok(open_pass(&adapter, limits))
}

/// One frame of a sphere over a floor under eight lights through the pass, as an application
/// records it (with `grouped`, the eight as one light's samples); returns the colour image
/// (RGBA8, `64 x 48`), the number of light batches and of sharing groups.
fn embedded_frame(
    gpu: &(ShadowPass, wgpu::Device, wgpu::Queue),
    grouped: bool,
) -> (Vec<u8>, usize, usize) {
    let (pass, device, queue) = gpu;
    let (w, h) = (64u32, 48u32);
    let sphere = shadowvol_scenes::procedural::icosphere(20_000, 1.0);
    let floor = common::floor(4.0, 2);
    let mut scene = Scene::new("embedded");
    for (name, mesh) in [("floor", &floor), ("sphere", &sphere)] {
        let table = scene.add_mesh(name, mesh).unwrap();
        scene.add_object(name, table, Affine3A::IDENTITY);
    }
    let mut rs = pass.prepare(&scene).unwrap();
    let camera = Camera::look_at(Vec3::new(3.0, 4.0, 5.0), Vec3::ZERO);
    // Eight lights close together, so that a device with small bindings extracts them in
    // batches, and grouped they share most triangles.
    let lights: Vec<Light> = (0..8)
        .map(|k| {
            let a = k as f32 * 0.8;
            Light::point(Vec3::new(
                1.0 + 0.3 * a.cos(),
                6.0 + 0.02 * k as f32,
                0.5 + 0.3 * a.sin(),
            ))
        })
        .collect();
    let groups = [std::ops::Range {
        start: 0,
        end: lights.len(),
    }];
    pass.update(
        &mut rs,
        &PassFrame {
            camera: &camera,
            aspect: w as f32 / h as f32,
            lights: &unit(&lights),
            colors: &[[0.125; 3]; 8],
            transforms: &[
                Affine3A::IDENTITY,
                Affine3A::from_translation(Vec3::Y * 1.5),
            ],
            albedo: &[[0.8; 3], [0.9, 0.5, 0.4]],
            techniques: &[Technique::ZFail; 16],
            scissors: &[None; 8],
            ambient: 0.1,
            mode: Accuracy::Exact,
            count: false,
            sample_groups: &groups[..usize::from(grouped)],
        },
    )
    .unwrap();
    let target = |label, format, usage| texture_2d(device, label, w, h, format, usage);
    let color = target(
        "color",
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = target(
        "depth",
        wgpu::TextureFormat::Depth24PlusStencil8,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let (cv, dv) = (
        color.create_view(&Default::default()),
        depth.create_view(&Default::default()),
    );
    let mut enc = device.create_command_encoder(&Default::default());
    pass.encode_extract(&mut enc, &rs);
    pass.encode_prepass(&mut enc, &rs, &cv, None, &dv, Some(wgpu::Color::BLACK));
    for li in 0..lights.len() {
        pass.encode_stencil(&mut enc, &rs, li, &dv, wgpu::LoadOp::Clear(0));
        pass.encode_lit(&mut enc, &rs, li, &cv, &dv);
    }
    queue.submit([enc.finish()]);
    (
        read_texture(device, queue, &color, wgpu::TextureAspect::All, 4).unwrap(),
        rs.light_batches(),
        rs.sharing_groups().len(),
    )
}

/// The surface vertex buffer written in several chunks (a 1 MiB storage-binding limit against
/// 3.8 MB of surface vertices), the vertex-pulling fallback (a 2 MiB buffer limit), a device
/// with exactly `wgpu::Limits::default()`, lights in batches and lights as one light's samples
/// draw the same image as eight point lights in one batch: the same shadows, pixel for pixel up
/// to shading rounding.
fn grouped_chunked_pulled_and_batched_frames_draw_the_same_image() -> Outcome {
    let one = device_with(|_| {})?;
    let chunked = device_with(|l| l.max_storage_buffer_binding_size = 1 << 20)?;
    let pulled = device_with(|l| l.max_buffer_size = 2 << 20)?;
    // Exactly WebGPU's guaranteed limits (8 storage buffers per stage), not the adapter's.
    let webgpu = device_with(|l| *l = wgpu::Limits::default())?;
    assert_eq!(webgpu.1.limits(), wgpu::Limits::default());
    // Bindings of 1.2 MiB: the scene's tables, packed into one binding (1.0 MB), fit, and the
    // eight lights' side records (240 KB each) go in batches of 5.
    let batched = device_with(|l| l.max_storage_buffer_binding_size = 1200 << 10)?;
    let (want, batches, groups) = embedded_frame(&one, false);
    assert_eq!((batches, groups), (1, 0));
    let lit = want.chunks_exact(4).filter(|p| p[0] > 60).count();
    let dark = want
        .chunks_exact(4)
        .filter(|p| p[0] < 40 && p[0] > 0)
        .count();
    assert!(
        lit > 100 && dark > 20,
        "a lit scene with a shadow: {lit} lit, {dark} dark"
    );
    // Grouped, the z-fail caps of the triangles the group shares read the group's signs.
    for (name, gpu, grouped, want_batches, want_groups) in [
        ("grouped", &one, true, 1, 1),
        ("chunked", &chunked, true, 2, 2),
        ("pulled", &pulled, false, 1, 0),
        ("default limits", &webgpu, true, 1, 1),
        ("batched", &batched, false, 2, 0),
        ("batched and grouped", &batched, true, 2, 2),
    ] {
        let (got, batches, groups) = embedded_frame(gpu, grouped);
        assert_eq!((batches, groups), (want_batches, want_groups), "{name}");
        let differ = want
            .chunks_exact(4)
            .zip(got.chunks_exact(4))
            .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.abs_diff(*y) > 3))
            .count();
        assert_eq!(differ, 0, "{name}: {differ} pixels differ");
    }
    Ok(())
}
