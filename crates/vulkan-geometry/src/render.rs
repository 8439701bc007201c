//! The render path: depth pre-pass, then the geometry shader's stencil pass, read back as a
//! shadow mask.
//!
//! # Techniques ([`StencilTechnique`])
//! **z-pass** (the default): the stencil pass counts, per pixel, the shadow-volume sides in front
//! of the visible surface: `+1` for front-facing and `-1` for back-facing sides (two-sided
//! stencil, wrapping arithmetic), with the depth test `LESS` against the pre-pass depth and no
//! depth writes. No caps are drawn. z-pass is correct when the near-clip volume (near rectangle +
//! light) meets no caster; the caller must ensure that (the renderer crate's planner decides).
//!
//! **z-fail**: the faces behind the visible surface are counted (`-1` front, `+1` back on depth
//! fail), and a second geometry-shader draw, one point per triangle, emits the caps: the triangle
//! itself (front cap, depth-biased away from the camera so it always fails on its own surface)
//! and, for point lights, the triangle projected to infinity (back cap). Each cap is oriented by
//! the triangle's sign in the mode (robust: 0 when its three evaluations disagree, exactly like
//! its sides; original uses ordered's sign), so sides and caps close every prism.
//! Sides are extruded to infinity (`w = 0`) and drawn with depth clamp where the device has it,
//! and the projection of [`ViewProjection::look_at`] has an infinite far plane, so no side is clipped.
//!
//! Side quads: for edge `(A, B)` with multiplicity `m`, `|m|` copies of `A, B, A∞, B∞` (reversed
//! for `m < 0`), `X∞ = (X * L.w - L.xyz, 0)`; see [`crate::twin::side_quad`].

use crate::backend::VulkanBackend;
use crate::device::{device_err, Buffer, Context};
use crate::dispatch::{begin_draws, host_barrier};
use crate::pipeline::Push;
use crate::twin::{touches_light, MODE_PRECOMPUTED};
use ash::vk;
use glam::{DMat4, DVec3, DVec4, Vec3};
use shadowvol_robust_math::{orient_exact, Accuracy, Light};
use shadowvol_silhouette::{
    object_lights, BackendError, ExtractStats, Multiplicities, PreparedId, SilhouetteBackend,
};
use std::time::{Duration, Instant};

/// The clip-from-world matrix of a pinhole camera, in `f64` (Vulkan clip space: depth in
/// `[0, 1]`, `y` down in framebuffer rows). The render path composes it with each object's
/// transform in `f64` and rounds once. The camera itself (eye, target, field of view) is the
/// workspace's one `Camera` type, `shadowvol_scenes::Camera`; this is only its matrix in this
/// crate's clip conventions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewProjection {
    /// Clip-from-world matrix.
    pub view_proj: DMat4,
}

impl ViewProjection {
    /// A right-handed look-at camera with an infinite far plane: depth 0 at `near`, 1 at
    /// infinity; `up` appears at the top of the image (row 0).
    ///
    /// `fov_y` in radians, `aspect` = width / height, `near` > 0 in world units. `up` must not be
    /// parallel to `target - eye`.
    #[must_use]
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, fov_y: f32, aspect: f32, near: f32) -> Self {
        let (eye, target, up) = (eye.as_dvec3(), target.as_dvec3(), up.as_dvec3());
        let f = (target - eye).normalize();
        let s = f.cross(up).normalize();
        let u = s.cross(f);
        let view = DMat4::from_cols(
            DVec4::new(s.x, u.x, -f.x, 0.0),
            DVec4::new(s.y, u.y, -f.y, 0.0),
            DVec4::new(s.z, u.z, -f.z, 0.0),
            DVec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
        );
        let g = 1.0 / (0.5 * f64::from(fov_y)).tan();
        let (aspect, near) = (f64::from(aspect), f64::from(near));
        // Vulkan clip space: y down, z_clip = -z_eye - near, w_clip = -z_eye.
        let proj = DMat4::from_cols(
            DVec4::new(g / aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -g, 0.0, 0.0),
            DVec4::new(0.0, 0.0, -1.0, -1.0),
            DVec4::new(0.0, 0.0, -near, 0.0),
        );
        Self {
            view_proj: proj * view,
        }
    }

    /// The world-space ray through the centre of pixel `(x, y)` of a `width` x `height` image, as
    /// `(point on the near plane, unit direction)`, in `f64`. Pixel rows go down (`y = 0` is the
    /// top row), as in the read-back mask.
    #[must_use]
    pub fn pixel_ray(&self, x: u32, y: u32, width: u32, height: u32) -> (DVec3, DVec3) {
        let inv = self.view_proj.inverse();
        let nx = (f64::from(x) + 0.5) / f64::from(width) * 2.0 - 1.0;
        let ny = (f64::from(y) + 0.5) / f64::from(height) * 2.0 - 1.0;
        let unproject = |z: f64| {
            let p: DVec4 = inv * DVec4::new(nx, ny, z, 1.0);
            p.truncate() / p.w
        };
        let near = unproject(0.0);
        let far = unproject(0.5);
        (near, (far - near).normalize())
    }
}

/// Timings and counters of one [`VulkanBackend::render_shadow_mask`] call.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RenderStats {
    /// The extraction that preceded the stencil pass (exact mode only).
    pub extract: Option<ExtractStats>,
    /// Recording, drawing (depth pre-pass and stencil pass) and waiting.
    pub render: Duration,
    /// Copying the stencil and depth images back.
    pub readback: Duration,
    /// Edges whose `|m|` exceeded the shader's 16 quads per edge (their emission was clamped and
    /// the mask may be wrong there); 0 on every mesh with at most 16 triangles per edge.
    pub clamped_edges: u32,
}

/// A read-back shadow mask, row-major, `y = 0` at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowMask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// True where the depth pre-pass covered the pixel (some scene surface is visible).
    pub covered: Vec<bool>,
    /// True where the stencil count is non-zero on a covered pixel: in shadow.
    pub shadowed: Vec<bool>,
    /// The raw stencil values.
    pub stencil: Vec<u8>,
    /// The depth buffer (`[0, 1]`, 1 = background).
    pub depth: Vec<f32>,
    /// Timings.
    pub stats: RenderStats,
}

struct Target {
    image: vk::Image,
    memory: vk::DeviceMemory,
    view: vk::ImageView,
    framebuffer: vk::Framebuffer,
}

impl Target {
    fn new(
        ctx: &Context,
        pass: vk::RenderPass,
        format: vk::Format,
        width: u32,
        height: u32,
    ) -> Result<Self, BackendError> {
        let d = &ctx.device;
        let mut t = Target {
            image: vk::Image::null(),
            memory: vk::DeviceMemory::null(),
            view: vk::ImageView::null(),
            framebuffer: vk::Framebuffer::null(),
        };
        // SAFETY: valid device and infos; on error, `destroy` frees what was created.
        let r = unsafe {
            (|| {
                t.image = d
                    .create_image(
                        &vk::ImageCreateInfo::default()
                            .image_type(vk::ImageType::TYPE_2D)
                            .format(format)
                            .extent(vk::Extent3D {
                                width,
                                height,
                                depth: 1,
                            })
                            .mip_levels(1)
                            .array_layers(1)
                            .samples(vk::SampleCountFlags::TYPE_1)
                            .tiling(vk::ImageTiling::OPTIMAL)
                            .usage(
                                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                                    | vk::ImageUsageFlags::TRANSFER_SRC,
                            )
                            .sharing_mode(vk::SharingMode::EXCLUSIVE)
                            .initial_layout(vk::ImageLayout::UNDEFINED),
                        None,
                    )
                    .map_err(|e| device_err("vkCreateImage", e))?;
                let req = d.get_image_memory_requirements(t.image);
                let ty = ctx
                    .memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::DEVICE_LOCAL)
                    .or_else(|| {
                        ctx.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::empty())
                    })
                    .ok_or_else(|| device_err("finding image memory", vk::Result::ERROR_UNKNOWN))?;
                t.memory = d
                    .allocate_memory(
                        &vk::MemoryAllocateInfo::default()
                            .allocation_size(req.size)
                            .memory_type_index(ty),
                        None,
                    )
                    .map_err(|e| device_err("vkAllocateMemory (depth/stencil image)", e))?;
                d.bind_image_memory(t.image, t.memory, 0)
                    .map_err(|e| device_err("vkBindImageMemory", e))?;
                t.view = d
                    .create_image_view(
                        &vk::ImageViewCreateInfo::default()
                            .image(t.image)
                            .view_type(vk::ImageViewType::TYPE_2D)
                            .format(format)
                            .subresource_range(vk::ImageSubresourceRange {
                                aspect_mask: vk::ImageAspectFlags::DEPTH
                                    | vk::ImageAspectFlags::STENCIL,
                                base_mip_level: 0,
                                level_count: 1,
                                base_array_layer: 0,
                                layer_count: 1,
                            }),
                        None,
                    )
                    .map_err(|e| device_err("vkCreateImageView", e))?;
                let views = [t.view];
                t.framebuffer = d
                    .create_framebuffer(
                        &vk::FramebufferCreateInfo::default()
                            .render_pass(pass)
                            .attachments(&views)
                            .width(width)
                            .height(height)
                            .layers(1),
                        None,
                    )
                    .map_err(|e| device_err("vkCreateFramebuffer", e))?;
                Ok::<(), BackendError>(())
            })()
        };
        match r {
            Ok(()) => Ok(t),
            Err(e) => {
                t.destroy(ctx);
                Err(e)
            }
        }
    }

    fn destroy(self, ctx: &Context) {
        let d = &ctx.device;
        // SAFETY: the device is idle; null handles are ignored.
        unsafe {
            d.destroy_framebuffer(self.framebuffer, None);
            d.destroy_image_view(self.view, None);
            d.destroy_image(self.image, None);
            d.free_memory(self.memory, None);
        }
    }
}

/// How the stencil pass counts volume faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum StencilTechnique {
    /// Count the sides in front of the visible surface; no caps. Valid when the near-clip volume
    /// (near rectangle + light) meets no caster.
    #[default]
    ZPass,
    /// Count the sides and caps behind the visible surface (Carmack's reverse): the triangles'
    /// front caps (depth-biased away so they fail on their own surface) and, for point lights,
    /// back caps at infinity. Valid wherever the camera is.
    ZFail,
}

/// Largest mask side accepted (pixels).
pub const MAX_MASK_SIDE: u32 = 8192;

impl VulkanBackend {
    /// Renders the shadow mask of `light` over the prepared scene `id` as seen by `camera`, with
    /// the z-pass technique: [`VulkanBackend::render_shadow_mask_with`] with
    /// [`StencilTechnique::ZPass`].
    ///
    /// # Errors
    /// As [`VulkanBackend::render_shadow_mask_with`].
    pub fn render_shadow_mask(
        &mut self,
        id: PreparedId,
        light: Light,
        camera: &ViewProjection,
        width: u32,
        height: u32,
        mode: Accuracy,
    ) -> Result<ShadowMask, BackendError> {
        self.render_shadow_mask_with(
            id,
            light,
            camera,
            (width, height),
            mode,
            StencilTechnique::ZPass,
        )
    }

    /// Renders the shadow mask of `light` over the prepared scene `id` as seen by `camera`, in a
    /// `size = (width, height)` image.
    ///
    /// Depth pre-pass of every triangle, then one point per edge through the geometry shader,
    /// which computes `m` in `mode` and emits `|m|` side quads into the stencil buffer; with
    /// [`StencilTechnique::ZFail`] a second geometry-shader draw over the triangles adds the caps
    /// (see the module documentation). In [`Accuracy::Exact`] the multiplicities are first
    /// extracted and host-resolved (as in `extract`) and the shader emits from the resolved
    /// buffer; exact cap signs are computed on the host with `orient_exact`. Pixels are shadowed
    /// where the stencil is non-zero.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a zero or oversized image or an invalid
    /// `SHADOWVOL_GPU_TIMEOUT`, [`BackendError::UnknownScene`], [`BackendError::Device`] on driver
    /// failures, when the device does not finish within
    /// [`shadowvol_silhouette::gpu::wait_limit`], or while an earlier timed-out submission is
    /// still running.
    pub fn render_shadow_mask_with(
        &mut self,
        id: PreparedId,
        light: Light,
        camera: &ViewProjection,
        (width, height): (u32, u32),
        mode: Accuracy,
        technique: StencilTechnique,
    ) -> Result<ShadowMask, BackendError> {
        if width == 0 || height == 0 || width > MAX_MASK_SIDE || height > MAX_MASK_SIDE {
            return Err(BackendError::InvalidInput(format!(
                "shadow mask size {width}x{height}: each side must be 1..={MAX_MASK_SIDE}"
            )));
        }
        // Nothing below may touch the buffers while a timed-out submission still runs.
        self.settle()?;
        let mut stats = RenderStats::default();
        let mode_code = if mode == Accuracy::Exact {
            let mut m = Multiplicities::default();
            stats.extract = Some(self.extract(id, &[light], mode, &mut m)?);
            let p = self.scene(id)?;
            let l = object_lights(p.scene.transforms(), &[light]);
            let ds = &p.ds;
            let pos = |v: u32| ds.layout.position(v);
            let touch: Vec<bool> = (0..ds.layout.vertex_count() as u32)
                .zip(&ds.vertex_object)
                .map(|(v, &o)| touches_light(pos(v), l[o as usize][0]))
                .collect();
            if touch.iter().any(|&t| t) {
                // Triangles touching the point light cast no volume: take their exact
                // contributions out of the multiplicities the shader emits from.
                for (e, value) in m.values_mut(0).iter_mut().enumerate() {
                    let (a, b, object) = ds.layout.edge(e);
                    let lo = l[object as usize][0];
                    for k in ds.layout.ov_slots(e) {
                        let o = ds.layout.ovs[k];
                        if touch[a as usize] || touch[b as usize] || touch[o as usize] {
                            *value -= i32::from(orient_exact(pos(a), pos(b), lo, pos(o)));
                        }
                    }
                }
            }
            p.mult.write(0, bytemuck::cast_slice(m.all_values()));
            if technique == StencilTechnique::ZFail {
                let signs: Vec<i32> = ds
                    .corners
                    .chunks_exact(3)
                    .map(|t| {
                        let mut c = [t[0], t[1], t[2]];
                        c.sort_unstable();
                        if c.iter().any(|&v| touch[v as usize]) {
                            return 0;
                        }
                        let obj = ds.vertex_object[c[0] as usize] as usize;
                        i32::from(orient_exact(pos(c[0]), pos(c[1]), l[obj][0], pos(c[2])))
                    })
                    .collect();
                if !signs.is_empty() {
                    p.tri_sign.write(0, bytemuck::cast_slice(&signs));
                }
            }
            MODE_PRECOMPUTED
        } else {
            let obj_lights = object_lights(self.scene(id)?.scene.transforms(), &[light]);
            self.upload_lights(id, &obj_lights, 0..1)?;
            shadowvol_silhouette::gpu::mode_code(mode)
        };
        let t = Instant::now();
        let pixels = width as usize * height as usize;
        let target = Target::new(
            &self.ctx,
            self.pipes.render_pass,
            self.pipes.depth_format,
            width,
            height,
        )?;
        let bufs = Buffer::host_read(&self.ctx, pixels as u64, vk::BufferUsageFlags::TRANSFER_DST)
            .and_then(|s| {
                Buffer::host_read(
                    &self.ctx,
                    4 * pixels as u64,
                    vk::BufferUsageFlags::TRANSFER_DST,
                )
                .map(|d| (s, d))
            });
        let (stencil_buf, depth_buf) = match bufs {
            Ok(b) => b,
            Err(e) => {
                target.destroy(&self.ctx);
                return Err(e);
            }
        };
        let result = self.draw_mask(
            id,
            &target,
            (&stencil_buf, &depth_buf),
            camera,
            (width, height),
            (mode_code, technique),
        );
        stats.render = t.elapsed();
        let t = Instant::now();
        let out = result.map(|()| {
            let mut stencil = vec![0u8; pixels];
            stencil_buf.read(0, &mut stencil);
            let mut raw = vec![0u32; pixels];
            depth_buf.read(0, bytemuck::cast_slice_mut(&mut raw));
            let depth: Vec<f32> = if self.pipes.depth_format == vk::Format::D24_UNORM_S8_UINT {
                raw.iter()
                    .map(|&v| (v & 0x00ff_ffff) as f32 / 16_777_215.0)
                    .collect()
            } else {
                raw.iter().map(|&v| f32::from_bits(v)).collect()
            };
            (stencil, depth)
        });
        let clamped = match (&out, self.scene(id)) {
            (Ok(_), Ok(p)) => VulkanBackend::uncertain_header(p).1,
            _ => 0,
        };
        // After a timeout the draw may still be running: the target and copies are freed once
        // it has finished (or leaked if it never does).
        self.retire(move |ctx| {
            stencil_buf.destroy(ctx);
            depth_buf.destroy(ctx);
            target.destroy(ctx);
        });
        let (stencil, depth) = out?;
        stats.readback = t.elapsed();
        stats.clamped_edges = clamped;
        let covered: Vec<bool> = depth.iter().map(|&d| d < 1.0).collect();
        let shadowed = stencil
            .iter()
            .zip(&covered)
            .map(|(&s, &c)| c && s != 0)
            .collect();
        Ok(ShadowMask {
            width,
            height,
            covered,
            shadowed,
            stencil,
            depth,
            stats,
        })
    }

    fn draw_mask(
        &self,
        id: PreparedId,
        target: &Target,
        (stencil_buf, depth_buf): (&Buffer, &Buffer),
        camera: &ViewProjection,
        (width, height): (u32, u32),
        (mode_code, technique): (u32, StencilTechnique),
    ) -> Result<(), BackendError> {
        let p = self.scene(id)?;
        // Per object: clip_from_anchor = view_proj * world_from_object * translate(anchor), in f64.
        let mut xforms: Vec<f32> = Vec::with_capacity(20 * p.ds.models.len());
        for (model, anchor) in p.ds.models.iter().zip(&p.ds.anchors) {
            let model = DMat4::from_cols_array(&model.map(f64::from));
            let c = Vec3::from_array(*anchor).as_dvec3();
            let m = camera.view_proj * model * DMat4::from_translation(c);
            xforms.extend(m.to_cols_array().map(|x| x as f32));
            xforms.extend([anchor[0], anchor[1], anchor[2], 0.0]);
        }
        if !xforms.is_empty() {
            p.models.write(0, bytemuck::cast_slice(&xforms));
        }
        let push = Push {
            mode: mode_code,
            edge_count: p.ds.layout.edge_count() as u32,
            light_count: 1,
            uncertain_capacity: p.uncertain_capacity,
            emit: 1,
            pass: 0,
        };
        let caps_push = Push {
            edge_count: (p.ds.corners.len() / 3) as u32,
            pass: 1,
            ..push
        };
        let triangles = caps_push.edge_count;
        // Reset the counters (uncertain appends do not happen here; clamped emissions do).
        p.uncertain_reset();
        let corners = p.ds.corners.len() as u32;
        let edges = p.ds.layout.edge_count() as u32;
        let extent = vk::Extent2D { width, height };
        let clear = [vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            },
        }];
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::GEOMETRY;
        self.ctx.submit_and_wait(|d, cmd| {
            // SAFETY: all handles are live; the command buffer is recording.
            unsafe {
                d.cmd_begin_render_pass(
                    cmd,
                    &vk::RenderPassBeginInfo::default()
                        .render_pass(self.pipes.render_pass)
                        .framebuffer(target.framebuffer)
                        .render_area(vk::Rect2D {
                            offset: vk::Offset2D { x: 0, y: 0 },
                            extent,
                        })
                        .clear_values(&clear),
                    vk::SubpassContents::INLINE,
                );
                begin_draws(d, cmd, extent, self.pipes.layout, p.set);
                d.cmd_push_constants(cmd, self.pipes.layout, stages, 0, bytemuck::bytes_of(&push));
                if corners > 0 {
                    d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipes.depth);
                    d.cmd_draw(cmd, corners, 1, 0, 0);
                }
                let (sides, caps) = match technique {
                    StencilTechnique::ZPass => (self.pipes.stencil, None),
                    StencilTechnique::ZFail => {
                        (self.pipes.stencil_zfail, Some(self.pipes.caps_zfail))
                    }
                };
                if edges > 0 {
                    d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, sides);
                    d.cmd_draw(cmd, edges, 1, 0, 0);
                }
                if let Some(caps) = caps.filter(|_| triangles > 0) {
                    d.cmd_push_constants(
                        cmd,
                        self.pipes.layout,
                        stages,
                        0,
                        bytemuck::bytes_of(&caps_push),
                    );
                    d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, caps);
                    d.cmd_draw(cmd, triangles, 1, 0, 0);
                }
                d.cmd_end_render_pass(cmd);
                let region = |aspect, buffer_offset| vk::BufferImageCopy {
                    buffer_offset,
                    buffer_row_length: 0,
                    buffer_image_height: 0,
                    image_subresource: vk::ImageSubresourceLayers {
                        aspect_mask: aspect,
                        mip_level: 0,
                        base_array_layer: 0,
                        layer_count: 1,
                    },
                    image_offset: vk::Offset3D { x: 0, y: 0, z: 0 },
                    image_extent: vk::Extent3D {
                        width,
                        height,
                        depth: 1,
                    },
                };
                d.cmd_copy_image_to_buffer(
                    cmd,
                    target.image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    stencil_buf.buffer,
                    &[region(vk::ImageAspectFlags::STENCIL, 0)],
                );
                d.cmd_copy_image_to_buffer(
                    cmd,
                    target.image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    depth_buf.buffer,
                    &[region(vk::ImageAspectFlags::DEPTH, 0)],
                );
                host_barrier(d, cmd);
            }
        })
    }
}
