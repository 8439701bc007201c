//! The GPU pipeline and the `wgpu` backend within WebGPU's guaranteed limits: a device opened
//! with exactly `wgpu::Limits::default()` (8 storage buffers per shader stage, 128 MiB storage
//! bindings, ...), not the adapter's, plus the optional features the pass asks for. Every
//! pipeline of both is built on it, and the conformance corpus's exact multiplicities equal the
//! `cpu` backend's bit for bit, through the GPU pipeline's side records and through the
//! backend's readback.
//!
//! Needs a wgpu adapter (Mesa lavapipe on CI machines): without one each test is a visible skip,
//! and a failure under `CI=true`.

use glam::{Affine3A, Vec3};
use shadowvol_cpu::CpuBackend;
use shadowvol_renderer::resident::{LightRecords, PassFormats, PassFrame, ShadowPass};
use shadowvol_renderer::{volume, Camera, RenderDevice, Technique};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::SceneLight;
use shadowvol_silhouette::{extract_once, object_lights, Multiplicities, TopologyScene};
use shadowvol_test_support::{corpus, main, skip, Outcome, Skip};
use shadowvol_wgpu_compute::{WgpuBackend, WgpuOptions};

main!(
    gpu_pipeline_exact_multiplicities_equal_cpu_under_default_limits,
    wgpu_backend_exact_multiplicities_equal_cpu_under_default_limits
);

/// A device with exactly `wgpu::Limits::default()` and the pass's optional features.
fn default_device() -> Result<(wgpu::Adapter, wgpu::Device, wgpu::Queue), Skip> {
    let adapter = RenderDevice::headless_adapter()
        .map_err(|e| skip(format!("{e}; install Mesa lavapipe to run this test")))?;
    let limits = wgpu::Limits::default();
    assert_eq!(limits.max_storage_buffers_per_shader_stage, 8);
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: ShadowPass::optional_features(&adapter),
        required_limits: limits.clone(),
        ..Default::default()
    }))
    .map_err(|e| skip(format!("the adapter refuses the default limits: {e}")))?;
    // wgpu holds the device to what was asked for, not to what the adapter has.
    assert_eq!(device.limits(), limits);
    Ok((adapter, device, queue))
}

/// `cpu`'s exact multiplicities of light `li`, less the triangles touching a point light (they
/// have no volume in the GPU pipeline).
fn without_touching(
    scene: &TopologyScene,
    lights: &[Light],
    want: &Multiplicities,
    li: usize,
) -> Vec<i32> {
    let ol: Vec<[f32; 4]> = object_lights(scene.transforms(), lights)
        .iter()
        .map(|o| o[li])
        .collect();
    let mut m = want.values(li).to_vec();
    volume::remove_touching(scene, &ol, Accuracy::Exact, &mut m);
    m
}

/// Per light, the multiplicity of every global edge from the side records.
fn multiplicities(records: &[LightRecords], edges: usize) -> Vec<Vec<i32>> {
    records.iter().map(|r| r.multiplicities(edges)).collect()
}

/// The GPU pipeline (every compute and render pipeline built within the limits), each corpus
/// case uploaded as `prepare` does (packed tables written in chunks), extracted in exact mode
/// with z-pass and z-fail objects: the side records' multiplicities equal `cpu`'s.
fn gpu_pipeline_exact_multiplicities_equal_cpu_under_default_limits() -> Outcome {
    let (adapter, device, queue) = default_device()?;
    let formats = PassFormats {
        color: wgpu::TextureFormat::Rgba8Unorm,
        ids: None,
        depth: wgpu::TextureFormat::Depth24PlusStencil8,
    };
    let pass = ShadowPass::new(&adapter, &device, &queue, formats).unwrap();
    let mut cpu = CpuBackend::new();
    let camera = Camera::look_at(Vec3::new(5.0, 4.0, 6.0), Vec3::ZERO);
    for case in corpus::cases() {
        let scene = case.scene().unwrap();
        let n_obj = scene.objects.len();
        let n = case.lights.len();
        let mut rs = pass.prepare_topology(&scene).unwrap();
        let transforms: Vec<Affine3A> = scene.transforms().collect();
        let techniques: Vec<Technique> = (0..n * n_obj)
            .map(|i| [Technique::ZFail, Technique::ZPass][i % 2])
            .collect();
        let lights: Vec<SceneLight> = case.lights.iter().map(|&l| SceneLight::unit(l)).collect();
        let frame = PassFrame {
            camera: &camera,
            aspect: 1.0,
            lights: &lights,
            colors: &vec![[1.0; 3]; n],
            transforms: &transforms,
            albedo: &vec![[1.0; 3]; n_obj],
            techniques: &techniques,
            scissors: &vec![None; n],
            ambient: 0.1,
            mode: Accuracy::Exact,
            count: true,
            sample_groups: &[],
        };
        pass.update(&mut rs, &frame).unwrap();
        let mut enc = device.create_command_encoder(&Default::default());
        pass.encode_extract(&mut enc, &rs);
        queue.submit([enc.finish()]);
        let records = pass.read_records(&rs).unwrap();
        let got = multiplicities(&records, rs.edge_count());
        let (want, _) = extract_once(&mut cpu, &scene, &case.lights, Accuracy::Exact).unwrap();
        for (li, m) in got.iter().enumerate() {
            let want = without_touching(&scene, &case.lights, &want, li);
            assert_eq!(m, &want, "{}: light {li}", case.name);
        }
    }
    Ok(())
}

/// The `wgpu` backend on the same kind of device, every mode's pipelines built within the
/// limits, exact mode decided on the device and on the host: its multiplicities equal `cpu`'s.
fn wgpu_backend_exact_multiplicities_equal_cpu_under_default_limits() -> Outcome {
    let mut cpu = CpuBackend::new();
    for exact_on_device in [true, false] {
        let (_, device, queue) = default_device()?;
        let options = WgpuOptions {
            exact_on_device,
            ..WgpuOptions::default()
        };
        let mut b = WgpuBackend::from_device(device, queue, options).unwrap();
        for case in corpus::cases() {
            let scene = case.scene().unwrap();
            let (got, _) = extract_once(&mut b, &scene, &case.lights, Accuracy::Exact).unwrap();
            let (want, _) = extract_once(&mut cpu, &scene, &case.lights, Accuracy::Exact).unwrap();
            assert_eq!(
                got, want,
                "{} (exact on device: {exact_on_device})",
                case.name
            );
            // The other modes run too (their f32 results may differ from the CPU's in the
            // last bits: WGSL allows contraction).
            for mode in [Accuracy::Original, Accuracy::Robust, Accuracy::Ordered] {
                extract_once(&mut b, &scene, &case.lights, mode).unwrap();
            }
        }
    }
    Ok(())
}
