//! Embedding the GPU-resident shadow-volume pass in an application's own wgpu frame.
//!
//! The application owns the device, the colour and depth-stencil targets and the command
//! encoder; the pass uploads a scene once, and each frame takes only small inputs (camera,
//! lights, transforms, the plan's techniques). Nothing is read back during a frame; here the
//! image is read once at the end to write the PNG.
//!
//! Run with `cargo run -p shadowvol-renderer --example embed -- [OUT.png] [--check] [--maps]`
//! (needs a wgpu adapter, for example Mesa's lavapipe). `OUT.png` defaults to `embed.png`. With
//! `--check` the example also reads back the pre-pass ids and the stencil of the last frame and
//! compares its shadows with the ray-traced reference (`shadowvol_reference`); it fails when
//! more than 0.05 % of the pixels are artifacts. `cargo xtask test` runs it that way. With
//! `--maps` the same frames are drawn with shadow maps instead (`MapPipeline`, recorded through
//! the `ShadowPipeline` trait into the same encoder and attachments).

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_reference::Shot;
use shadowvol_renderer::pipeline::{FrameInputs, Recording};
use shadowvol_renderer::plan::plan_frame;
use shadowvol_renderer::raster::{read_texture, Attachments};
use shadowvol_renderer::resident::{texture_2d, PassFormats, PassFrame, ShadowPass};
use shadowvol_renderer::world::World;
use shadowvol_renderer::{Camera, FrameReport, Pipeline, RenderDevice, Scene, Technique};
use shadowvol_renderer::{MapPipeline, MapSettings, PlanPolicy, ShadowPipeline};
use shadowvol_robust_math::{Accuracy, Light};

const W: u32 = 320;
const H: u32 = 240;

/// The largest fraction of artifact pixels `--check` accepts (DESIGN's 0.05 %).
const MAX_ARTIFACT_FRACTION: f64 = 0.0005;

const USAGE: &str = "usage: embed [OUT.png] [--check] [--maps]";

fn main() -> std::process::ExitCode {
    // No `error: XDG_RUNTIME_DIR ...` line from Mesa on a machine without a display.
    shadowvol_silhouette::gpu::quiet_without_display();
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("embed: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut out = String::from("embed.png");
    let mut check = false;
    let mut maps = false;
    for a in std::env::args().skip(1) {
        match a.as_str() {
            "--check" => check = true,
            "--maps" => maps = true,
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            _ if a.starts_with('-') => return Err(format!("unknown option {a}\n{USAGE}").into()),
            _ => out = a,
        }
    }

    // 1. The application's device, opened with what the pass needs.
    let adapter = RenderDevice::headless_adapter()?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: ShadowPass::optional_features(&adapter),
        required_limits: ShadowPass::required_limits(&adapter)?,
        ..Default::default()
    }))?;
    let formats = PassFormats {
        color: wgpu::TextureFormat::Rgba8Unorm,
        // Only the check needs the pre-pass ids; an application leaves this `None`.
        ids: check.then_some(wgpu::TextureFormat::Rg32Uint),
        depth: wgpu::TextureFormat::Depth24PlusStencil8,
    };
    let pass = ShadowPass::new(&adapter, &device, &queue, formats)?;

    // 2. A scene uploaded once: a floor and a box, each with its own transform per frame.
    let floor = Mesh::new(
        vec![
            Vec3::new(-4.0, 0.0, -4.0),
            Vec3::new(4.0, 0.0, -4.0),
            Vec3::new(4.0, 0.0, 4.0),
            Vec3::new(-4.0, 0.0, 4.0),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    )?;
    let cube = Mesh::new(
        (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect(),
        vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ],
    )?;
    let mut scene = Scene::new("embed");
    for (name, mesh) in [("floor", &floor), ("box", &cube)] {
        let table = scene.add_mesh(name, mesh)?;
        scene.add_object(name, table, Affine3A::IDENTITY);
    }
    scene.add_unit_lights([Light::point(Vec3::new(1.5, 6.0, 1.0))]);
    scene.effects.ambient = 0.15;
    let mut resident = pass.prepare(&scene)?;

    // 3. The application's targets.
    let color = texture_2d(
        &device,
        "color",
        W,
        H,
        formats.color,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = texture_2d(
        &device,
        "depth",
        W,
        H,
        formats.depth,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let ids = formats.ids.map(|f| {
        texture_2d(
            &device,
            "ids",
            W,
            H,
            f,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        )
    });
    let color_view = color.create_view(&Default::default());
    let ids_view = ids.as_ref().map(|t| t.create_view(&Default::default()));
    let depth_view = depth.create_view(&Default::default());

    // 4. Frames: the box spins, the light stays; every frame re-extracts on the device. Only
    // small inputs change: the box's transform.
    let camera = Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0));
    let colors = [[0.9, 0.85, 0.8]];
    let albedo: Vec<[f32; 3]> = scene.surfaces().map(|s| s.albedo).collect();
    let mut transforms = [Affine3A::IDENTITY; 2];
    if maps {
        let targets = Attachments::new(&color_view, ids_view.as_ref(), &depth_view);
        let rd = RenderDevice::on_device(adapter.clone(), device.clone(), queue.clone());
        transforms[1] = map_frames(&rd, &mut scene, &camera, &colors, &targets)?;
    }
    for frame in 0..if maps { 0 } else { 30 } {
        transforms[1] = Affine3A::from_translation(Vec3::new(-0.5, 0.6, -0.5))
            * Affine3A::from_rotation_y(frame as f32 * 0.05);
        pass.update(
            &mut resident,
            &PassFrame {
                camera: &camera,
                aspect: W as f32 / H as f32,
                lights: &scene.lights,
                colors: &colors,
                transforms: &transforms,
                albedo: &albedo,
                // The camera is outside both volumes here; an application would run the plan
                // (`shadowvol_renderer::plan`) to choose.
                techniques: &[Technique::ZFail, Technique::ZFail],
                scissors: &[None],
                ambient: scene.effects.ambient,
                mode: Accuracy::Exact,
                count: false,
                sample_groups: &[],
            },
        )?;
        let mut enc = device.create_command_encoder(&Default::default());
        pass.encode_extract(&mut enc, &resident); // first: it places the vertices
        pass.encode_prepass(
            &mut enc,
            &resident,
            &color_view,
            ids_view.as_ref(),
            &depth_view,
            Some(wgpu::Color::BLACK),
        );
        pass.encode_stencil(&mut enc, &resident, 0, &depth_view, wgpu::LoadOp::Clear(0));
        pass.encode_lit(&mut enc, &resident, 0, &color_view, &depth_view);
        queue.submit([enc.finish()]);
    }

    // 5. Once, at the end: the image to a PNG.
    let rgba = read_texture(&device, &queue, &color, wgpu::TextureAspect::All, 4)?;
    image::save_buffer(&out, &rgba, W, H, image::ExtendedColorType::Rgba8)?;
    println!("wrote {out} ({W}x{H}) on {}", adapter.get_info().name);
    if !check {
        return Ok(());
    }

    // 6. `--check` only: the last frame's shadows against the ray-traced reference. The
    // reference reads the scene model (where the box stood in the last frame) and the pixels:
    // the pre-pass ids (which triangle each pixel shows) and the stencil (0 = lit).
    let ids: Vec<[u32; 2]> = read_texture(
        &device,
        &queue,
        ids_texture(&ids)?,
        wgpu::TextureAspect::All,
        8,
    )?
    .chunks_exact(8)
    .map(|c| {
        [
            u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
            u32::from_le_bytes([c[4], c[5], c[6], c[7]]),
        ]
    })
    .collect();
    let stencil = vec![read_texture(
        &device,
        &queue,
        &depth,
        wgpu::TextureAspect::StencilOnly,
        1,
    )?];
    scene.geometry.objects[1].world_from_object = transforms[1];
    let shot = Shot::new(&scene, camera, W, H, &rgba, &ids, &stencil, &colors);
    let cmp = shadowvol_reference::compare(&shot);
    let fraction = cmp.artifact_fraction((W * H) as usize);
    println!(
        "reference: {} artifact pixels ({:.4} %), {} undecidable, shadow pixels {} (reference {})",
        cmp.artifact_pixels,
        fraction * 100.0,
        cmp.undecidable_pixels,
        cmp.shadow_pixels,
        cmp.reference_shadow_pixels
    );
    if cmp.reference_shadow_pixels < 200 {
        return Err(format!(
            "the scene shows too little shadow to check ({} reference shadow pixels)",
            cmp.reference_shadow_pixels
        )
        .into());
    }
    if fraction > MAX_ARTIFACT_FRACTION {
        return Err(format!(
            "{} artifact pixels against the reference: over {} % of {W}x{H}",
            cmp.artifact_pixels,
            MAX_ARTIFACT_FRACTION * 100.0
        )
        .into());
    }
    Ok(())
}

/// `--maps`: the same 30 frames with the shadow-map pipeline, through the `ShadowPipeline` trait
/// on the application's device, encoder and attachments. Each frame syncs the world positions
/// (only the box moved), plans it, and records; the stencil keeps each light's map test for
/// `--check`. Returns the box's last transform.
fn map_frames(
    rd: &RenderDevice,
    scene: &mut Scene,
    camera: &Camera,
    colors: &[[f32; 3]],
    targets: &Attachments<'_>,
) -> Result<Affine3A, Box<dyn std::error::Error>> {
    let mut pipeline = MapPipeline::new(MapSettings::default());
    pipeline.prepare(rd, scene)?;
    let mut world = World::default();
    let targets = targets.with_shadow_stencil();
    let mut t = Affine3A::IDENTITY;
    for frame in 0..30 {
        t = Affine3A::from_translation(Vec3::new(-0.5, 0.6, -0.5))
            * Affine3A::from_rotation_y(frame as f32 * 0.05);
        scene.geometry.objects[1].world_from_object = t;
        let changes = world.sync(scene)?;
        let plan = plan_frame(scene, &world, camera, (W, H), PlanPolicy::Auto, false);
        let mut report = FrameReport::new(Pipeline::Map, Accuracy::Exact);
        report.plan = plan.entries;
        let inputs = FrameInputs {
            device: rd,
            scene,
            world: &world,
            changes: &changes,
            camera,
            size: (W, H),
            mode: Accuracy::Exact,
            scissors: &plan.scissors,
            light_colors: colors,
            count: false,
            passes: &[],
        };
        let mut enc = rd.device.create_command_encoder(&Default::default());
        let rec = Recording {
            report: &mut report,
            target: &targets,
            enc: &mut enc,
        };
        pipeline.record(&inputs, rec)?;
        rd.queue.submit([enc.finish()]);
    }
    Ok(t)
}

/// The ids texture, made with `--check`.
fn ids_texture(ids: &Option<wgpu::Texture>) -> Result<&wgpu::Texture, String> {
    ids.as_ref()
        .ok_or_else(|| "no ids texture: made with --check only".to_owned())
}
