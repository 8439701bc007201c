//! Frame targets and readback: the attachments of one frame, the buffers its images are copied
//! to, and the bounded waits and maps every GPU read goes through.

use super::stencil_bits::StencilBits;
use crate::RenderError;

/// Maps `buffer` (`MAP_READ`, its copies already submitted) and returns its bytes, with the
/// bounded wait of every GPU read (`SHADOWVOL_GPU_TIMEOUT`).
pub(crate) fn map_read(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u8>, RenderError> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    wait(device)?;
    rx.try_recv()
        .map_err(|e| RenderError::Device(format!("map_async did not complete: {e}")))?
        .map_err(|e| RenderError::Device(format!("map_async: {e}")))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| RenderError::Device(format!("get_mapped_range: {e}")))?;
    let out = data.to_vec();
    drop(data);
    buffer.unmap();
    Ok(out)
}

/// Completes the uploads made so far. `create_buffer_init` copies its contents through staging
/// memory that lives until the next submission completes; submitting nothing and waiting frees
/// it now, before the next upload or frame allocates on top of it.
pub(crate) fn finish_uploads(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> Result<(), RenderError> {
    queue.submit([]);
    wait(device)
}

/// Waits for all submitted work, bounded by `SHADOWVOL_GPU_TIMEOUT`: a hung device is an error.
pub(crate) fn wait(device: &wgpu::Device) -> Result<(), RenderError> {
    let limit =
        shadowvol_silhouette::gpu::wait_limit().map_err(|e| RenderError::Device(e.to_string()))?;
    device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(limit),
        })
        .map_err(|e| match e {
            wgpu::PollError::Timeout => RenderError::Device(format!(
                "the device did not finish the frame within {}",
                shadowvol_silhouette::gpu::describe_wait_limit(limit)
            )),
            other => RenderError::Device(format!("poll: {other}")),
        })?;
    Ok(())
}

/// Bytes of one image row in a readback buffer: `w` pixels of `bytes_per_px`, padded to 256.
fn padded_row(w: u32, bytes_per_px: u32) -> u32 {
    (w * bytes_per_px).div_ceil(256) * 256
}

/// What a pipeline draws one frame into: the colour attachment, the optional ids attachment
/// (`[surface + 1, triangle]`, [`super::IDS_FORMAT`]), the depth-stencil attachment, and, when
/// the frame is read back, where each light's stencil is copied after its stencil pass.
#[derive(Clone, Copy)]
pub struct Attachments<'a> {
    /// The colour target of the pre-pass and the lit passes.
    pub color: &'a wgpu::TextureView,
    /// The ids target of the pre-pass, if any.
    pub ids: Option<&'a wgpu::TextureView>,
    /// The depth-stencil attachment (a format with a stencil aspect).
    pub depth_stencil: &'a wgpu::TextureView,
    readback: Option<&'a FrameTargets>,
    /// The visibility and light targets of lights with a size (the renderer's own).
    pub(crate) soft: Option<&'a super::soft::SoftTargets>,
    /// Leave each light's shadow state in the stencil even without readback
    /// ([`Attachments::with_shadow_stencil`]).
    shadow_stencil: bool,
}

impl std::fmt::Debug for Attachments<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Attachments")
            .field("ids", &self.ids.is_some())
            .field("readback", &self.readback.is_some())
            .finish_non_exhaustive()
    }
}

impl<'a> Attachments<'a> {
    /// The caller's own views: nothing is copied back.
    #[must_use]
    pub fn new(
        color: &'a wgpu::TextureView,
        ids: Option<&'a wgpu::TextureView>,
        depth_stencil: &'a wgpu::TextureView,
    ) -> Self {
        Self {
            color,
            ids,
            depth_stencil,
            readback: None,
            soft: None,
            shadow_stencil: false,
        }
    }

    /// These attachments, with each light's shadow state written into the stencil (0 = lit)
    /// by every pipeline, so that the caller can read the last light's stencil after the frame
    /// (to compare it with the reference, for example). The volume pipelines always leave it
    /// there; the shadow-map pipeline then adds its mask pass.
    #[must_use]
    pub fn with_shadow_stencil(mut self) -> Self {
        self.shadow_stencil = true;
        self
    }

    /// Records the copy of light `light`'s stencil (its shadow state, which the reference
    /// compares) where the frame is read back; nothing otherwise. A pipeline calls it after each
    /// light's stencil pass, before the next light's clears it.
    pub fn after_stencil(&self, enc: &mut wgpu::CommandEncoder, light: usize) {
        self.copy_stencil(enc, light);
    }

    /// True when the frame is read back, so that [`Attachments::after_stencil`] copies each
    /// light's stencil: a pipeline whose shadows are not in the stencil otherwise (the shadow-map
    /// pipeline) writes them there only then.
    #[must_use]
    pub fn reads_stencil(&self) -> bool {
        self.readback.is_some() || self.shadow_stencil
    }

    fn copy_stencil(&self, enc: &mut wgpu::CommandEncoder, light: usize) {
        if let Some(t) = self.readback {
            t.copy_stencil(enc, light);
        }
    }
}

/// One frame's own attachments and readback buffers (`[colour, ids, stencil per light]`).
pub(crate) struct FrameTargets {
    size: wgpu::Extent3d,
    lights: usize,
    color: wgpu::Texture,
    ids: wgpu::Texture,
    depth: wgpu::Texture,
    color_view: wgpu::TextureView,
    ids_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    readbacks: Option<[wgpu::Buffer; 3]>,
    /// With readback on a device that cannot copy a stencil aspect: the draws that copy it
    /// through a colour target.
    stencil_bits: Option<StencilBits>,
    /// For frames with lights of several samples: their targets.
    pub(crate) soft: Option<super::soft::SoftTargets>,
}

impl FrameTargets {
    /// The attachments of a `w` x `h` frame of `lights` lights and, with `readback`, the
    /// buffers its images are copied to (each light's stencil copied directly where
    /// `stencil_copies`, else through [`StencilBits`]).
    pub(crate) fn new(
        device: &wgpu::Device,
        depth_format: wgpu::TextureFormat,
        (w, h): (u32, u32),
        lights: usize,
        readback: bool,
        stencil_copies: bool,
    ) -> Self {
        let size = wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let tex = |label: &str, format: wgpu::TextureFormat| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
            super::texture_2d(device, label, w, h, format, usage)
        };
        let color = tex("color", super::COLOR_FORMAT);
        let ids = tex("ids", super::IDS_FORMAT);
        let depth = tex("depth-stencil", depth_format);
        let buffer = |label: &str, bytes_per_px: u32, count: usize| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: u64::from(padded_row(w, bytes_per_px)) * u64::from(h) * count.max(1) as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        };
        Self {
            size,
            lights,
            color_view: color.create_view(&Default::default()),
            ids_view: ids.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            readbacks: readback.then(|| {
                [
                    buffer("color-readback", 4, 1),
                    buffer("ids-readback", 8, 1),
                    buffer("stencil-readback", 1, lights),
                ]
            }),
            stencil_bits: (readback && !stencil_copies)
                .then(|| StencilBits::new(device, depth_format, (w, h))),
            soft: None,
            color,
            ids,
            depth,
        }
    }

    /// Whether these targets serve a frame of `size` and `lights` lights, read back or not.
    pub(crate) fn fits(&self, (w, h): (u32, u32), lights: usize, readback: bool) -> bool {
        self.size.width == w
            && self.size.height == h
            && self.lights == lights
            && self.readbacks.is_some() == readback
    }

    /// The attachments a pipeline draws into: these targets' own, or `color` instead of the
    /// own colour target.
    pub(crate) fn attachments<'a>(
        &'a self,
        color: Option<&'a wgpu::TextureView>,
    ) -> Attachments<'a> {
        Attachments {
            color: color.unwrap_or(&self.color_view),
            ids: Some(&self.ids_view),
            depth_stencil: &self.depth_view,
            readback: self.readbacks.is_some().then_some(self),
            soft: self.soft.as_ref(),
            shadow_stencil: false,
        }
    }

    /// Reads the frame back after its submission: colour, ids and each light's stencil, or
    /// `None` (after waiting for the device) when the targets have no readback buffers.
    pub(crate) fn read(
        &self,
        device: &wgpu::Device,
    ) -> Result<Option<crate::FrameImage>, RenderError> {
        let Some([color_rb, ids_rb, stencil_rb]) = &self.readbacks else {
            wait(device)?;
            return Ok(None);
        };
        let (w, h) = (self.size.width, self.size.height);
        let rgba = read_rows(device, color_rb, (w, h), 4, 1)?;
        let ids_bytes = read_rows(device, ids_rb, (w, h), 8, 1)?;
        let stencil_bytes = if self.lights == 0 {
            Vec::new()
        } else {
            read_rows(device, stencil_rb, (w, h), 1, self.lights)?
        };
        let ids = ids_bytes
            .chunks_exact(8)
            .map(|c| {
                [
                    u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                    u32::from_le_bytes([c[4], c[5], c[6], c[7]]),
                ]
            })
            .collect();
        let px = (w * h) as usize;
        Ok(Some(crate::FrameImage {
            width: w,
            height: h,
            rgba,
            ids,
            stencil: stencil_bytes
                .chunks_exact(px.max(1))
                .map(<[u8]>::to_vec)
                .collect(),
            visibility: Vec::new(),
        }))
    }

    /// With readback: copies the stencil aspect (light `light`'s shadow state) to its slot.
    fn copy_stencil(&self, enc: &mut wgpu::CommandEncoder, light: usize) {
        let Some([_, _, stencil]) = &self.readbacks else {
            return;
        };
        let (texture, aspect) = match &self.stencil_bits {
            Some(bits) => {
                bits.encode(enc, &self.depth_view);
                (bits.target(), wgpu::TextureAspect::All)
            }
            None => (&self.depth, wgpu::TextureAspect::StencilOnly),
        };
        copy_rows(enc, texture, aspect, stencil, 1, light as u64);
    }

    /// With readback: copies the colour and ids images (the colour of these targets, so not
    /// after a frame drawn into another colour view).
    pub(crate) fn copy_color_ids(&self, enc: &mut wgpu::CommandEncoder) {
        if let Some([color, ids, _]) = &self.readbacks {
            copy_rows(enc, &self.color, wgpu::TextureAspect::All, color, 4, 0);
            copy_rows(enc, &self.ids, wgpu::TextureAspect::All, ids, 8, 0);
        }
    }
}

/// The bytes of one `w` x `h` image of `bytes_per_px` in a readback buffer (rows padded).
pub(crate) fn image_bytes(w: u32, h: u32, bytes_per_px: u32) -> u64 {
    u64::from(padded_row(w, bytes_per_px)) * u64::from(h)
}

/// Records a copy of all of `texture` (`bytes_per_px` bytes per pixel) into image slot
/// `image` of `buffer`.
pub(crate) fn copy_image(
    enc: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    buffer: &wgpu::Buffer,
    bytes_per_px: u32,
    image: u64,
) {
    copy_rows(
        enc,
        texture,
        wgpu::TextureAspect::All,
        buffer,
        bytes_per_px,
        image,
    );
}

/// Maps `buffer` and returns its `images` images of `w` x `h` pixels, rows unpadded.
///
/// # Errors
/// [`RenderError::Device`] when the map fails or the device does not finish in time.
pub(crate) fn read_images(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    size: (u32, u32),
    bytes_per_px: u32,
    images: usize,
) -> Result<Vec<u8>, RenderError> {
    read_rows(device, buffer, size, bytes_per_px, images)
}

/// Records a copy of one aspect of all of `texture` (`bytes_per_px` bytes per pixel) into
/// image slot `image` of `buffer`, rows padded by [`padded_row`].
fn copy_rows(
    enc: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
    buffer: &wgpu::Buffer,
    bytes_per_px: u32,
    image: u64,
) {
    let row = padded_row(texture.width(), bytes_per_px);
    let offset = u64::from(row) * u64::from(texture.height()) * image;
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset,
                bytes_per_row: Some(row),
                rows_per_image: Some(texture.height()),
            },
        },
        texture.size(),
    );
}

/// Maps `buffer` (rows padded by [`padded_row`]), strips the padding and returns `images`
/// images of `w` × `h` pixels of `bytes_per_px` bytes.
fn read_rows(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    (w, h): (u32, u32),
    bytes_per_px: u32,
    images: usize,
) -> Result<Vec<u8>, RenderError> {
    let data = map_read(device, buffer)?;
    let (row, w_bytes) = (
        padded_row(w, bytes_per_px) as usize,
        (w * bytes_per_px) as usize,
    );
    let mut out = Vec::with_capacity(w_bytes * h as usize * images);
    for y in 0..h as usize * images {
        out.extend_from_slice(&data[y * row..y * row + w_bytes]);
    }
    Ok(out)
}

/// Copies one aspect of a 2-D texture on `device` (`bytes_per_px` bytes per pixel: 4 for RGBA8,
/// 8 for the ids, 1 for the stencil aspect) to the host, rows unpadded, top row first, with the
/// bounded wait of every GPU read (`SHADOWVOL_GPU_TIMEOUT`). The texture needs `COPY_SRC`.
///
/// # Errors
/// [`RenderError::Device`] when the copy or the map fails or the device does not finish in time.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
    bytes_per_px: u32,
) -> Result<Vec<u8>, RenderError> {
    let (w, h) = (texture.width(), texture.height());
    let row = padded_row(w, bytes_per_px);
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: u64::from(row) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    copy_rows(&mut enc, texture, aspect, &staging, bytes_per_px, 0);
    queue.submit([enc.finish()]);
    read_rows(device, &staging, (w, h), bytes_per_px, 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::states;
    use crate::RenderDevice;

    /// A pipeline that writes its stencil reference wherever it draws (the stencil-bits
    /// module's full-screen triangle, no colour).
    fn stencil_writer(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("stencil writer"),
            source: wgpu::ShaderSource::Wgsl(super::super::STENCIL_BITS_WGSL.into()),
        });
        let face = states::stencil_op(
            wgpu::CompareFunction::Always,
            wgpu::StencilOperation::Replace,
        );
        let depth = states::stencil_only_depth(format, face, 0xff, 0xff);
        super::super::stencil_bits::fullscreen(device, None, &module, depth, None)
    }

    /// Column `x` of a 256 x 3 frame holds stencil `x`, every value of the 8 bits; the frame
    /// read back with `stencil_copies` set or not.
    fn every_stencil_value(rd: &RenderDevice, stencil_copies: bool) -> Vec<u8> {
        let targets = FrameTargets::new(
            &rd.device,
            rd.depth_format,
            (256, 3),
            1,
            true,
            stencil_copies,
        );
        let writer = stencil_writer(&rd.device, rd.depth_format);
        rd.submit("every stencil value", |enc| {
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("write stencil"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &targets.depth_view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(0),
                            store: wgpu::StoreOp::Store,
                        }),
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&writer);
                for x in 0..256 {
                    pass.set_scissor_rect(x, 0, 1, 3);
                    pass.set_stencil_reference(x);
                    pass.draw(0..3, 0..1);
                }
            }
            targets.copy_stencil(enc, 0);
            targets.copy_color_ids(enc);
            Ok(())
        })
        .expect("submit");
        let image = targets.read(&rd.device).expect("read").expect("read back");
        image.stencil.into_iter().next().expect("one light")
    }

    #[test]
    fn every_stencil_value_reads_back_through_colour_as_copied(
    ) -> Result<(), shadowvol_test_support::Skip> {
        // The one unit test that opens a device: no `error: XDG_RUNTIME_DIR ...` from Mesa.
        shadowvol_silhouette::gpu::quiet_without_display();
        let rd = match RenderDevice::open() {
            Ok(rd) => rd,
            Err(e) => return Err(shadowvol_test_support::skip(format!("no GPU adapter: {e}"))),
        };
        let want: Vec<u8> = (0..3).flat_map(|_| 0..=255u8).collect();
        let check = |got: Vec<u8>, how: &str| {
            let wrong = got.iter().zip(&want).position(|(a, b)| a != b);
            assert!(
                got.len() == want.len() && wrong.is_none(),
                "{how}: pixel {wrong:?} reads {:?}",
                wrong.map(|i| (got[i], want[i]))
            );
        };
        if rd.stencil_copies {
            check(every_stencil_value(&rd, true), "the direct copy");
        }
        check(every_stencil_value(&rd, false), "through the colour target");
        Ok(())
    }
}
