//! The render world's side: shadowvol's resident pass on Bevy's device, in Bevy's encoder, in the
//! `Core3d` schedule before the main pass; and the resolve of each light's stencil into its
//! mask layer.

use bevy::core_pipeline::{schedule::Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::camera::TemporalJitter;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::{RenderAdapter, RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::sync_world::MainEntity;
use bevy::render::texture::GpuImage;
use bevy::render::view::ExtractedView;
use bevy::render::{Extract, ExtractSchedule, RenderApp};
use shadowvol_renderer::plan::plan_frame;
use shadowvol_renderer::resident::{texture_2d, PassFormats, PassFrame, ResidentScene, ShadowPass};
use shadowvol_renderer::world::World;
use shadowvol_renderer::{Camera, PlanPolicy, Technique};
use shadowvol_scenes::{Scene, SceneLight};

use crate::extract::VolumeFrame;
use crate::material::MaskTextures;
use crate::{Side, MAX_LIGHTS};

/// The pass's depth-stencil format (forward-Z, its own pre-pass) and the mask's format.
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;
/// `R16Float`: a soft light's `k / N` adds `1 / N` per sample, exact for a power of two `N`.
const MASK: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;
/// The pre-pass's colour target, which nothing reads: the smallest colour format.
const SCRATCH: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

pub(crate) fn build(app: &mut App) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .init_resource::<PassState>()
        .add_systems(ExtractSchedule, extract_textures)
        .add_systems(Core3d, draw_masks.in_set(Core3dSystems::Prepass));
}

fn extract_textures(mut commands: Commands, textures: Extract<Option<Res<MaskTextures>>>) {
    if let Some(t) = textures.as_ref() {
        commands.insert_resource(MaskTextures::clone(t));
    }
}

/// The pre-pass targets at one size.
struct Targets {
    size: (u32, u32),
    depth: wgpu::TextureView,
    scratch: wgpu::TextureView,
}

/// What the pass keeps between frames.
#[derive(Resource, Default)]
struct PassState {
    /// The pass, built on Bevy's device at the first frame that needs it.
    pass: Option<ShadowPass>,
    /// Why the pass could not be built: it is not tried again.
    failed: Option<String>,
    /// The casters on the device, and the scene generation they hold.
    resident: Option<(u64, ResidentScene)>,
    targets: Option<Targets>,
    resolve: Option<Resolve>,
    /// The plan's copy of the scene, with this frame's transforms and lights, and the world
    /// positions it plans from.
    planned: Option<(Scene, World)>,
}

/// The resolves of a stencil into a mask layer: `set` writes 1 where it is 0 (a hard light),
/// `add` adds the blend constant there (a sample of a light with a size: `1 / N`).
struct Resolve {
    set: wgpu::RenderPipeline,
    add: wgpu::RenderPipeline,
}

/// Bevy's view as shadowvol's camera, with the aspect its projection uses.
///
/// # Errors
/// A projection the mask cannot follow: jittered (`TemporalJitter`, as TAA uses), orthographic,
/// or off-centre (a sub-view), named.
fn view_camera(view: &ExtractedView, jittered: bool) -> Result<(Camera, f32), String> {
    if jittered {
        return Err(
            "the ShadowVolumes camera has TemporalJitter (TAA's sub-pixel jitter): the \
                    one-sample mask would not line up with the jittered image; remove \
                    TemporalJitter and TemporalAntiAliasing from that camera"
                .into(),
        );
    }
    let m = view.clip_from_view;
    if m.w_axis.w == 1.0 {
        return Err(
            "the ShadowVolumes camera is orthographic; shadow volumes support \
                    perspective cameras only"
                .into(),
        );
    }
    if m.z_axis.x != 0.0 || m.z_axis.y != 0.0 {
        return Err(
            "the ShadowVolumes camera's projection is off-centre (a sub-view or a custom \
             projection): shadow volumes need a centred perspective projection"
                .into(),
        );
    }
    let (f, fx, near) = (m.y_axis.y, m.x_axis.x, m.w_axis.z);
    let t = &view.world_from_view;
    let eye = t.translation();
    let eye = glam::Vec3::from(eye.to_array());
    let forward = glam::Vec3::from(t.forward().as_vec3().to_array());
    let up = glam::Vec3::from(t.up().as_vec3().to_array());
    let camera = Camera {
        eye,
        target: eye + forward,
        up,
        fov_y: 2.0 * (1.0 / f).atan(),
        near,
    };
    camera
        .validate()
        .map_err(|e| format!("the ShadowVolumes camera: {e}"))?;
    Ok((camera, f / fx))
}

/// The `Core3d` system: for the [`crate::ShadowVolumes`] camera's view, the pass and the
/// masks; for any other view, masks that say lit. On a failure the masks say lit, the error
/// goes to [`crate::ShadowVolumeStats`], and the main world gives the marked lights Bevy's
/// shadow maps from the next frame until the pass works again.
#[allow(clippy::too_many_arguments)]
fn draw_masks(
    view: ViewQuery<(&MainEntity, &ExtractedView, Has<TemporalJitter>)>,
    frame: Option<Res<VolumeFrame>>,
    textures: Option<Res<MaskTextures>>,
    images: Res<RenderAssets<GpuImage>>,
    mut state: ResMut<PassState>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    adapter: Res<RenderAdapter>,
    mut ctx: RenderContext,
) {
    let (main, extracted, jittered) = view.into_inner();
    let (Some(frame), Some(textures)) = (frame, textures) else {
        return;
    };
    let (Some(mask), Some(table)) = (images.get(&textures.mask), images.get(&textures.lights))
    else {
        return; // the textures reach the GPU in a later frame
    };
    // Every view writes the same table: with no volume lights it is empty, and the material
    // takes nothing away.
    write_light_table(&queue, &table.texture, &frame);
    let enc = ctx.command_encoder();
    if frame.camera.is_none() {
        frame.stats.clear(Side::Render); // no view draws volumes: nothing can be failing
    }
    if frame.camera.is_none_or(|(e, _)| main.id() != e) {
        // Another view, which shares the casters' material: its masks say lit. Recorded in this
        // view's pre-pass, so after an earlier view's main pass and before this view's.
        clear_masks(enc, &mask.texture, MAX_LIGHTS);
        return;
    }
    let gpu = Gpu {
        device: device.wgpu_device(),
        queue: &queue,
        adapter: &adapter,
    };
    let outcome = view_camera(extracted, jittered)
        .and_then(|camera| record(&gpu, &mut state, &frame, camera, &mask.texture, enc));
    match outcome {
        Ok(()) => {
            frame.stats.clear(Side::Render);
            frame.stats.with(|s| s.frames += 1);
        }
        Err(e) => {
            frame.stats.fail(Side::Render, e);
            clear_masks(enc, &mask.texture, MAX_LIGHTS);
        }
    }
}

/// Bevy's device, queue and adapter, as wgpu's.
struct Gpu<'a> {
    device: &'a wgpu::Device,
    queue: &'a wgpu::Queue,
    adapter: &'a wgpu::Adapter,
}

/// The light table: one texel a light; unused slots are zero.
fn write_light_table(queue: &wgpu::Queue, table: &wgpu::Texture, frame: &VolumeFrame) {
    let mut texels = [[0f32; 4]; MAX_LIGHTS];
    for (t, l) in texels.iter_mut().zip(&frame.lights) {
        *t = l.texel;
    }
    queue.write_texture(
        table.as_image_copy(),
        bytemuck::cast_slice(&texels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(16 * MAX_LIGHTS as u32),
            rows_per_image: None,
        },
        wgpu::Extent3d {
            width: MAX_LIGHTS as u32,
            height: 1,
            depth_or_array_layers: 1,
        },
    );
}

/// Builds the pass and the resolve pipelines at the first frame that needs them.
///
/// # Errors
/// Why the pass cannot run on Bevy's device (kept: it is not tried again).
fn ensure_pass(gpu: &Gpu<'_>, state: &mut PassState) -> Result<(), String> {
    if let Some(e) = &state.failed {
        return Err(e.clone());
    }
    if state.pass.is_none() {
        let formats = PassFormats {
            color: SCRATCH,
            ids: None,
            depth: DEPTH,
        };
        let pass = ShadowPass::new(gpu.adapter, gpu.device, gpu.queue, formats).map_err(|e| {
            let msg = format!("GPU: the shadow-volume pass cannot run on Bevy's device: {e}");
            state.failed = Some(msg.clone());
            msg
        })?;
        state.pass = Some(pass);
        state.resolve = Some(Resolve {
            set: resolve_pipeline(gpu.device, false),
            add: resolve_pipeline(gpu.device, true),
        });
    }
    Ok(())
}

/// What the pass draws this frame, with the planning copy of the scene `planned`: each object's
/// transform (those not drawn parked behind the eye), the lights (a light with a size as its
/// samples, `runs` per marked light, the runs of several its sample groups), the plan's
/// techniques (culled where an object does not cast for the light) and scissors.
struct Inputs {
    transforms: Vec<glam::Affine3A>,
    lights: Vec<SceneLight>,
    runs: Vec<std::ops::Range<usize>>,
    groups: Vec<std::ops::Range<usize>>,
    techniques: Vec<Technique>,
    scissors: Vec<Option<[u32; 4]>>,
}

/// The frame's [`Inputs`].
///
/// # Errors
/// The casters' world positions cannot be computed.
fn frame_inputs(
    (plan_scene, world): &mut (Scene, World),
    frame: &VolumeFrame,
    camera: &Camera,
    size: (u32, u32),
) -> Result<Inputs, String> {
    let objects = frame.transforms.len();
    // Objects that are not drawn this frame (hidden, on other layers, a zero scale, gone) are
    // parked behind the eye, scaled down: clipped from the pre-pass, and invertible for the
    // plan's world positions.
    let parked = park(camera);
    let transforms: Vec<glam::Affine3A> = frame
        .transforms
        .iter()
        .zip(&frame.drawn)
        .map(|(t, &drawn)| if drawn { *t } else { parked })
        .collect();
    for (o, t) in plan_scene.geometry.objects.iter_mut().zip(&transforms) {
        o.world_from_object = *t;
    }
    // A light with a size is its samples, consecutive (one of the pass's sample groups), each a
    // point (or direction) casting its own hard shadow; the others are themselves. The disk of
    // a point light faces the centre of the drawn objects' box (the renderer's
    // `Scene::light_aim`), which needs their world positions first.
    plan_scene.lights.clear();
    world
        .sync(plan_scene)
        .map_err(|e| format!("the casters' world positions: {e}"))?;
    let aim = aim_of(world, &frame.drawn);
    let (lights, runs) = expand(&frame.lights, aim);
    plan_scene.lights.clone_from(&lights);
    let plan = plan_frame(plan_scene, world, camera, size, PlanPolicy::Auto, true);
    // Light-major: an object that does not cast for a light (`NotShadowCaster`, not drawn, or
    // on no render layer of the light) draws no volume for it, nor for any of its samples; it
    // still receives, through the pre-pass.
    let of_light: Vec<usize> = runs
        .iter()
        .enumerate()
        .flat_map(|(k, r)| r.clone().map(move |_| k))
        .collect();
    let techniques: Vec<_> = plan
        .entries
        .iter()
        .enumerate()
        .map(|(i, e)| {
            if frame.casts[of_light[i / objects] * objects + i % objects] {
                e.technique
            } else {
                Technique::Culled
            }
        })
        .collect();
    let groups = runs.iter().filter(|r| r.len() > 1).cloned().collect();
    Ok(Inputs {
        transforms,
        lights,
        runs,
        groups,
        techniques,
        scissors: plan.scissors,
    })
}

/// Records one frame's pass and masks into `enc`: the pass built at the first frame, the casters
/// prepared when their generation changed, then extraction, pre-pass, and per light the
/// stencil and its resolve.
///
/// # Errors
/// What went wrong, in words: the device lacks what the pass needs (not tried again), the
/// casters cannot be prepared, or the frame's inputs do not fit the prepared casters.
fn record(
    gpu: &Gpu<'_>,
    state: &mut PassState,
    frame: &VolumeFrame,
    (camera, aspect): (Camera, f32),
    mask: &wgpu::Texture,
    enc: &mut wgpu::CommandEncoder,
) -> Result<(), String> {
    ensure_pass(gpu, state)?;
    let (Some(pass), Some(resolve)) = (&state.pass, &state.resolve) else {
        return Ok(());
    };
    let Some(scene) = &frame.scene else {
        clear_masks(enc, mask, frame.lights.len());
        return Ok(());
    };
    if state
        .resident
        .as_ref()
        .is_none_or(|(g, _)| *g != frame.generation)
    {
        state.resident = None;
        state.planned = None;
        let rs = pass
            .prepare(scene)
            .map_err(|e| format!("GPU: preparing the casters: {e}"))?;
        state.resident = Some((frame.generation, rs));
        frame.stats.with(|s| s.prepares += 1);
    }
    let Some((_, resident)) = &mut state.resident else {
        return Ok(());
    };
    let objects = scene.geometry.objects.len();
    if frame.transforms.len() != objects || frame.casts.len() != objects * frame.lights.len() {
        return Ok(()); // a rebuild is pending; the last masks stay
    }
    let size = (mask.size().width, mask.size().height);
    // The plan: per (light, object) z-pass where the camera is outside the volume, z-fail where
    // it may be inside, nothing where the light cannot reach; per light a scissor.
    let planned = state
        .planned
        .get_or_insert_with(|| ((**scene).clone(), World::default()));
    let inputs = frame_inputs(planned, frame, &camera, size)?;
    let (transforms, lights, runs) = (&inputs.transforms, &inputs.lights, &inputs.runs);
    let (n, groups) = (lights.len(), &inputs.groups);
    pass.update(
        resident,
        &PassFrame {
            camera: &camera,
            aspect,
            lights,
            colors: &vec![[1.0f32; 3]; n],
            transforms,
            albedo: &vec![[1.0f32; 3]; objects],
            techniques: &inputs.techniques,
            scissors: &inputs.scissors,
            ambient: 0.0,
            mode: frame
                .camera
                .map_or(shadowvol_robust_math::Accuracy::Exact, |c| c.1),
            count: false,
            sample_groups: groups,
        },
    )
    .map_err(|e| format!("GPU: the frame's inputs: {e}"))?;
    if state.targets.as_ref().is_none_or(|t| t.size != size) {
        state.targets = Some(make_targets(gpu.device, size));
    }
    let Some(targets) = &state.targets else {
        return Ok(());
    };
    pass.encode_extract(enc, resident);
    pass.encode_prepass(
        enc,
        resident,
        &targets.scratch,
        None,
        &targets.depth,
        Some(wgpu::Color::BLACK),
    );
    for (k, run) in runs.iter().enumerate() {
        let share = 1.0 / run.len() as f64;
        for (j, sample) in run.clone().enumerate() {
            pass.encode_stencil(
                enc,
                resident,
                sample,
                &targets.depth,
                wgpu::LoadOp::Clear(0),
            );
            if run.len() == 1 {
                resolve_layer(enc, &resolve.set, mask, k, &targets.depth, None);
            } else {
                resolve_layer(enc, &resolve.add, mask, k, &targets.depth, Some((j, share)));
            }
        }
    }
    Ok(())
}

/// The frame's lights for the pass: each marked light in order, a light with a size as its
/// samples ([`SceneLight::samples`] aimed at `aim`), the others as themselves; and per marked
/// light its run of them.
fn expand(
    marked: &[crate::extract::VolumeLight],
    aim: glam::Vec3,
) -> (Vec<SceneLight>, Vec<std::ops::Range<usize>>) {
    let mut lights = Vec::new();
    let mut runs = Vec::with_capacity(marked.len());
    for l in marked {
        let first = lights.len();
        if l.samples > 1 {
            let samples = l.scene_light().samples(l.samples, aim);
            lights.extend(samples.into_iter().map(SceneLight::unit));
        } else {
            lights.push(SceneLight::unit(l.light));
        }
        runs.push(first..lights.len());
    }
    (lights, runs)
}

/// The centre of the box of the drawn objects' world positions, as `Scene::light_aim` has it
/// for a scene of those objects (the origin without any).
fn aim_of(world: &World, drawn: &[bool]) -> glam::Vec3 {
    world
        .surfaces()
        .iter()
        .zip(drawn)
        .filter(|(_, &d)| d)
        .map(|(s, _)| (s.bounds.0.as_vec3(), s.bounds.1.as_vec3()))
        .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)))
        .map_or(glam::Vec3::ZERO, |(lo, hi)| (lo + hi) * 0.5)
}

/// Where an object that is not drawn goes: a millionth of its size, one unit behind the eye, so
/// the pre-pass clips it whole and its transform stays invertible.
fn park(camera: &Camera) -> glam::Affine3A {
    let back = (camera.eye - camera.target).normalize_or(glam::Vec3::Z);
    glam::Affine3A::from_scale_rotation_translation(
        glam::Vec3::splat(1e-6),
        glam::Quat::IDENTITY,
        camera.eye + back,
    )
}

fn make_targets(device: &wgpu::Device, (w, h): (u32, u32)) -> Targets {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let depth = texture_2d(device, "shadowvol-bevy depth-stencil", w, h, DEPTH, usage);
    let scratch = texture_2d(
        device,
        "shadowvol-bevy pre-pass colour",
        w,
        h,
        SCRATCH,
        usage,
    );
    Targets {
        size: (w, h),
        depth: depth.create_view(&Default::default()),
        scratch: scratch.create_view(&Default::default()),
    }
}

/// A view of one layer of the mask.
fn layer_view(mask: &wgpu::Texture, k: usize) -> wgpu::TextureView {
    mask.create_view(&wgpu::TextureViewDescriptor {
        label: Some("shadowvol-bevy mask layer"),
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: k as u32,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

/// No casters yet: every marked light's layer says lit.
fn clear_masks(enc: &mut wgpu::CommandEncoder, mask: &wgpu::Texture, lights: usize) {
    for k in 0..lights {
        let view = layer_view(mask, k);
        let _ = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadowvol-bevy mask clear"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
    }
}

/// Layer `k` of the mask: cleared to 0 (shadow), then 1 wherever the stencil is 0 (lit). For
/// sample `j` of a light with a size (`add`, with `Some((j, 1 / N))`): the first clears it,
/// and each adds `1 / N` wherever its stencil is 0, so the layer ends at `k / N`.
fn resolve_layer(
    enc: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::RenderPipeline,
    mask: &wgpu::Texture,
    k: usize,
    depth: &wgpu::TextureView,
    sample: Option<(usize, f64)>,
) {
    let load = match sample {
        Some((j, _)) if j > 0 => wgpu::LoadOp::Load,
        _ => wgpu::LoadOp::Clear(wgpu::Color::BLACK),
    };
    let view = layer_view(mask, k);
    let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("shadowvol-bevy mask resolve"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: None,
            stencil_ops: None,
        }),
        ..Default::default()
    });
    rp.set_pipeline(pipeline);
    if let Some((_, share)) = sample {
        rp.set_blend_constant(wgpu::Color {
            r: share,
            g: share,
            b: share,
            a: share,
        });
    }
    rp.set_stencil_reference(0);
    rp.draw(0..3, 0..1);
}

/// A full-screen triangle that writes 1 where the stencil equals the reference (0), or with
/// `add`, adds the blend constant there.
fn resolve_pipeline(device: &wgpu::Device, add: bool) -> wgpu::RenderPipeline {
    let sum = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::Constant,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    let target = wgpu::ColorTargetState {
        format: MASK,
        blend: add.then_some(wgpu::BlendState {
            color: sum,
            alpha: sum,
        }),
        write_mask: wgpu::ColorWrites::ALL,
    };
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowvol-bevy mask resolve"),
        source: wgpu::ShaderSource::Wgsl(RESOLVE_WGSL.into()),
    });
    let stencil = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Equal,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: wgpu::StencilOperation::Keep,
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("shadowvol-bevy mask resolve"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(target)],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: wgpu::StencilState {
                front: stencil,
                back: stencil,
                read_mask: 0xff,
                write_mask: 0,
            },
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// The resolve's shader (`shaders/bevy_mask_resolve.wgsl`): a triangle that covers the target,
/// writing 1.
const RESOLVE_WGSL: &str = include_str!("../../../shaders/bevy_mask_resolve.wgsl");
