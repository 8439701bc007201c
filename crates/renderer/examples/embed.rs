//! Embedding the GPU-resident shadow-volume pass in an application's own wgpu frame.
//!
//! The application owns the device, the colour and depth-stencil targets and the command
//! encoder; the pass uploads a scene once, and each frame takes only small inputs (camera,
//! lights, transforms, the plan's techniques). Nothing is read back during a frame; here the
//! image is read once at the end to write `embed.png`.
//!
//! Run with `cargo run -p shadowvol-renderer --example embed` (needs a wgpu adapter, for example
//! Mesa's lavapipe).

use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_renderer::resident::{texture_2d, PassFormats, PassFrame, ShadowPass};
use shadowvol_renderer::{Camera, RenderError, Technique};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{SceneObject, TopologyScene};
use std::sync::Arc;

const W: u32 = 320;
const H: u32 = 240;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // 1. The application's device, opened with what the pass needs.
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: ShadowPass::optional_features(&adapter),
        required_limits: ShadowPass::required_limits(&adapter)?,
        ..Default::default()
    }))?;
    let formats = PassFormats {
        color: wgpu::TextureFormat::Rgba8Unorm,
        ids: None,
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
    let object = |name: &str, mesh: &Mesh| -> Result<SceneObject, RenderError> {
        Ok(SceneObject {
            name: name.to_owned(),
            table: Arc::new(EdgeTable::build(mesh).map_err(|source| RenderError::Mesh {
                object: name.to_owned(),
                source,
            })?),
            world_from_object: Affine3A::IDENTITY,
        })
    };
    let scene = TopologyScene {
        objects: vec![object("floor", &floor)?, object("box", &cube)?],
    };
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
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let color_view = color.create_view(&Default::default());
    let depth_view = depth.create_view(&Default::default());

    // 4. Frames: the box spins, the light stays; every frame re-extracts on the device.
    let camera = Camera::look_at(Vec3::new(4.0, 5.0, 7.0), Vec3::new(0.0, 0.5, 0.0));
    let lights = [Light::point(Vec3::new(1.5, 6.0, 1.0))];
    for frame in 0..30 {
        let spin = Affine3A::from_translation(Vec3::new(-0.5, 0.6, -0.5))
            * Affine3A::from_rotation_y(frame as f32 * 0.05);
        pass.update(
            &mut resident,
            &PassFrame {
                camera: &camera,
                aspect: W as f32 / H as f32,
                lights: &lights,
                colors: &[[0.9, 0.85, 0.8]],
                emission: &[],
                transforms: &[Affine3A::IDENTITY, spin],
                albedo: &[[0.8, 0.8, 0.8], [0.9, 0.4, 0.3]],
                // The camera is outside both volumes here; an application would run the plan
                // (`shadowvol_renderer::plan`) to choose.
                techniques: &[Technique::ZFail, Technique::ZFail],
                scissors: &[None],
                ambient: 0.15,
                mode: Accuracy::Exact,
                count: false,
            },
        )?;
        let mut enc = device.create_command_encoder(&Default::default());
        pass.encode_extract(&mut enc, &resident); // first: it places the vertices
        pass.encode_prepass(
            &mut enc,
            &resident,
            &color_view,
            None,
            &depth_view,
            wgpu::Color::BLACK,
        );
        pass.encode_stencil(&mut enc, &resident, 0, &depth_view);
        pass.encode_lit(&mut enc, &resident, 0, &color_view, &depth_view);
        queue.submit([enc.finish()]);
    }

    // 5. Once, at the end: the image to a PNG.
    let row = (W * 4).div_ceil(256) * 256;
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: u64::from(row * H),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        color.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(H),
            },
        },
        color.size(),
    );
    queue.submit([enc.finish()]);
    let slice = staging.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    device.poll(wgpu::PollType::wait_indefinitely())?;
    let data = slice.get_mapped_range()?;
    let mut rgba = Vec::with_capacity((W * H * 4) as usize);
    for y in 0..H as usize {
        rgba.extend_from_slice(&data[y * row as usize..y * row as usize + W as usize * 4]);
    }
    image::RgbaImage::from_raw(W, H, rgba)
        .ok_or("image size")?
        .save("embed.png")?;
    println!("wrote embed.png ({W}x{H}) on {}", adapter.get_info().name);
    Ok(())
}
