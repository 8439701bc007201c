//! Lights with a size, on the raster side: the visibility target each sample's stencil is
//! counted into, the light target its unshadowed lit pass draws into, and the composite that
//! adds `light × k / N` to the colour. Shared by the volume pipelines: each records, per light,
//! its stencil pass and then what [`crate::soft::LightPass`] says (see
//! [`crate::pipeline::light_output`]).

use super::pipelines::{color_target, pipeline_layout};
use super::states;
use crate::RenderError;

/// `shaders/render_soft.wgsl`: the count and composite passes.
pub const SOFT_WGSL: &str = include_str!("../../../../shaders/render_soft.wgsl");

/// The format of the visibility target: the count k of samples a pixel sees, exact up to 2048.
pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// The format of a light's unshadowed lit pass: the colour's, so that the lit pipelines draw
/// into it as they are.
const LIGHT_FORMAT: wgpu::TextureFormat = super::COLOR_FORMAT;

/// The targets and pipelines of lights with a size, for frames of one size.
pub(crate) struct SoftTargets {
    size: (u32, u32),
    visibility: wgpu::Texture,
    visibility_view: wgpu::TextureView,
    light_view: wgpu::TextureView,
    count: wgpu::RenderPipeline,
    composite: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    /// With readback: each soft light's visibility counts, one image a light.
    readback: Option<(wgpu::Buffer, usize)>,
}

impl SoftTargets {
    /// The targets of `w` x `h` frames whose stencil is in `depth_format`, with room to read
    /// back `readback_lights` lights' visibility (0: none).
    pub(crate) fn new(
        device: &wgpu::Device,
        depth_format: wgpu::TextureFormat,
        (w, h): (u32, u32),
        readback_lights: usize,
    ) -> Self {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let visibility = super::texture_2d(device, "visibility", w, h, VISIBILITY_FORMAT, usage);
        let light = super::texture_2d(device, "unshadowed light", w, h, LIGHT_FORMAT, usage);
        let visibility_view = visibility.create_view(&Default::default());
        let light_view = light.create_view(&Default::default());
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shaders/render_soft.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SOFT_WGSL.into()),
        });
        let texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let bgl = super::pipelines::bind_group_layout(
            device,
            "soft composite",
            &[texture(0), texture(1)],
        );
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("soft composite"),
            layout: &bgl,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&visibility_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&light_view),
                },
            ],
        });
        // The count: where the stencil is 0 (the sample sees the pixel), add 1.
        let face = states::stencil_op(wgpu::CompareFunction::Equal, wgpu::StencilOperation::Keep);
        let count_depth = states::stencil_only_depth(depth_format, face, 0xff, 0);
        let empty = pipeline_layout(device, "soft count", &[]);
        let count = fullscreen(
            device,
            &empty,
            &module,
            count_depth,
            ("vs_fullscreen", "fs_count"),
            VISIBILITY_FORMAT,
            states::additive(),
        );
        // The composite: colour += light × k / N; no depth or stencil test.
        let always =
            states::stencil_op(wgpu::CompareFunction::Always, wgpu::StencilOperation::Keep);
        let composite_depth = states::stencil_only_depth(depth_format, always, 0, 0);
        let layout = pipeline_layout(device, "soft composite", &[&bgl]);
        let composite = fullscreen(
            device,
            &layout,
            &module,
            composite_depth,
            ("vs_composite", "fs_composite"),
            super::COLOR_FORMAT,
            states::additive(),
        );
        let readback = (readback_lights > 0).then(|| {
            let bytes = super::targets::image_bytes(w, h, 2) * readback_lights as u64;
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("visibility-readback"),
                size: bytes,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            (buffer, readback_lights)
        });
        Self {
            size: (w, h),
            visibility,
            visibility_view,
            light_view,
            count,
            composite,
            bind_group,
            readback,
        }
    }

    /// Whether these targets serve `w` x `h` frames reading back `readback_lights` lights.
    pub(crate) fn fits(&self, size: (u32, u32), readback_lights: usize) -> bool {
        self.size == size && self.readback.as_ref().map_or(0, |r| r.1) == readback_lights
    }

    /// True when each light's visibility is read back.
    pub(crate) fn reads_back(&self) -> bool {
        self.readback.is_some()
    }

    /// A pass over the visibility target cleared to 1 (nothing shadows the background), which
    /// reads the depth and stencil of `depth_stencil`: where the map pipeline writes each
    /// light's visibility of its map.
    pub(crate) fn begin_visibility<'e>(
        &self,
        enc: &'e mut wgpu::CommandEncoder,
        label: &str,
        depth_stencil: &wgpu::TextureView,
    ) -> wgpu::RenderPass<'e> {
        let color = states::cleared(&self.visibility_view, wgpu::Color::WHITE);
        read_only_pass(enc, label, color, depth_stencil)
    }

    /// With readback: copies the visibility target into slot `slot` (nothing otherwise).
    pub(crate) fn copy_visibility(&self, enc: &mut wgpu::CommandEncoder, slot: usize) {
        if let Some((buffer, slots)) = &self.readback {
            if slot < *slots {
                super::targets::copy_image(enc, &self.visibility, buffer, 2, slot as u64);
            }
        }
    }

    /// The target a soft light's unshadowed lit pass draws into.
    pub(crate) fn light_view(&self) -> &wgpu::TextureView {
        &self.light_view
    }

    /// Records the count of one sample: 1 added to the visibility where the stencil of
    /// `depth_stencil` is 0; the visibility is cleared first for a light's first sample.
    pub(crate) fn count(
        &self,
        enc: &mut wgpu::CommandEncoder,
        depth_stencil: &wgpu::TextureView,
        first: bool,
    ) {
        let color = if first {
            states::cleared(&self.visibility_view, wgpu::Color::TRANSPARENT)
        } else {
            states::loaded(&self.visibility_view)
        };
        let mut pass = read_only_pass(enc, "soft count", color, depth_stencil);
        pass.set_pipeline(&self.count);
        pass.set_stencil_reference(0);
        pass.draw(0..3, 0..1);
    }

    /// Records the clear of the light target and of the stencil before a soft light's
    /// unshadowed lit pass (the stencil all 0: nothing shadows it).
    pub(crate) fn clear_for_light(
        &self,
        enc: &mut wgpu::CommandEncoder,
        depth_stencil: &wgpu::TextureView,
    ) {
        let color = states::cleared(&self.light_view, wgpu::Color::TRANSPARENT);
        let _ = pass_over(
            enc,
            "soft clear",
            color,
            depth_stencil,
            wgpu::LoadOp::Clear(0),
        );
    }

    /// Records the composite of a soft light of `samples` samples into `color` (limited to
    /// `scissor`), and with readback the copy of its visibility counts into slot `slot`.
    pub(crate) fn composite(
        &self,
        enc: &mut wgpu::CommandEncoder,
        color: &wgpu::TextureView,
        depth_stencil: &wgpu::TextureView,
        samples: u32,
        slot: usize,
    ) {
        {
            let mut pass =
                read_only_pass(enc, "soft composite", states::loaded(color), depth_stencil);
            pass.set_pipeline(&self.composite);
            pass.set_bind_group(0, &self.bind_group, &[]);
            // N as the instance index: the shader divides by it.
            let n = samples.max(1);
            pass.draw(0..3, n..n + 1);
        }
        self.copy_visibility(enc, slot);
    }

    /// Reads back each soft light's visibility counts (`k`, one `f32` a pixel, top row first),
    /// after the frame's submission; empty without readback.
    ///
    /// # Errors
    /// [`RenderError::Device`] when the map fails or the device does not finish in time.
    pub(crate) fn read(&self, device: &wgpu::Device) -> Result<Vec<Vec<f32>>, RenderError> {
        let Some((buffer, slots)) = &self.readback else {
            return Ok(Vec::new());
        };
        let (w, h) = self.size;
        let bytes = super::targets::read_images(device, buffer, (w, h), 2, *slots)?;
        let px = (w * h) as usize;
        Ok(bytes
            .chunks_exact(2 * px.max(1))
            .map(|img| {
                img.chunks_exact(2)
                    .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
                    .collect()
            })
            .collect())
    }
}

/// An IEEE half-precision value as `f32` (exact: every half is an `f32`).
#[must_use]
pub(crate) fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f32::from(h & 0x3ff);
    let magnitude = match exp {
        0 => frac * 2f32.powi(-24),
        31 if frac == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        _ => (1.0 + frac / 1024.0) * 2f32.powi(exp - 15),
    };
    sign * magnitude
}

/// A pass over `color` that only reads the depth and stencil of `depth_stencil`.
fn read_only_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: Option<wgpu::RenderPassColorAttachment<'_>>,
    depth_stencil: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    pass_over(enc, label, color, depth_stencil, wgpu::LoadOp::Load)
}

/// A pass over `color` and `depth_stencil`, its depth loaded and its stencil loaded or cleared
/// by `stencil`.
fn pass_over<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: Option<wgpu::RenderPassColorAttachment<'_>>,
    depth_stencil: &wgpu::TextureView,
    stencil: wgpu::LoadOp<u32>,
) -> wgpu::RenderPass<'e> {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[color],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth_stencil,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: Some(wgpu::Operations {
                load: stencil,
                store: wgpu::StoreOp::Store,
            }),
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// The full-screen triangle of `module` (the vertex and fragment entry points `vs`, `fs`)
/// blended by `blend` into a `format` target, over `depth`.
fn fullscreen(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    depth: wgpu::DepthStencilState,
    (vs, fs): (&str, &str),
    format: wgpu::TextureFormat,
    blend: wgpu::BlendState,
) -> wgpu::RenderPipeline {
    let targets = [color_target(format, Some(blend))];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fs),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vs),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(depth),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    #[test]
    fn halves_convert_exactly() {
        assert_eq!(f16_to_f32(0x0000), 0.0);
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0x4000), 2.0);
        assert_eq!(f16_to_f32(0x5400), 64.0);
        assert_eq!(f16_to_f32(0x6800), 2048.0);
        assert_eq!(f16_to_f32(0x3800), 0.5);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
    }
}
