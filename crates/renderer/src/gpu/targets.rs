//! Frame targets and readback: the attachments of one frame, the buffers its images are copied
//! to, and the bounded waits and maps every GPU read goes through.

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
pub(super) fn padded_row(w: u32, bytes_per_px: u32) -> u32 {
    (w * bytes_per_px).div_ceil(256) * 256
}

/// One frame's attachments and readback buffers (`[colour, ids, stencil per light]`).
pub(super) struct FrameTargets {
    pub(super) size: wgpu::Extent3d,
    pub(super) lights: usize,
    pub(super) color: wgpu::Texture,
    pub(super) ids: wgpu::Texture,
    pub(super) depth: wgpu::Texture,
    pub(super) color_view: wgpu::TextureView,
    pub(super) ids_view: wgpu::TextureView,
    pub(super) depth_view: wgpu::TextureView,
    pub(super) readbacks: Option<[wgpu::Buffer; 3]>,
}

impl FrameTargets {
    fn copy(
        &self,
        enc: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
        buffer: &wgpu::Buffer,
        bytes_per_px: u32,
        image: u64,
    ) {
        let row = padded_row(self.size.width, bytes_per_px);
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
                    offset: u64::from(row) * u64::from(self.size.height) * image,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(self.size.height),
                },
            },
            self.size,
        );
    }

    /// With readback: copies the stencil aspect (light `light`'s shadow state) to its slot.
    pub(super) fn copy_stencil(&self, enc: &mut wgpu::CommandEncoder, light: usize) {
        if let Some([_, _, stencil]) = &self.readbacks {
            self.copy(
                enc,
                &self.depth,
                wgpu::TextureAspect::StencilOnly,
                stencil,
                1,
                light as u64,
            );
        }
    }

    /// With readback: copies the colour and ids images.
    pub(super) fn copy_color_ids(&self, enc: &mut wgpu::CommandEncoder) {
        if let Some([color, ids, _]) = &self.readbacks {
            self.copy(enc, &self.color, wgpu::TextureAspect::All, color, 4, 0);
            self.copy(enc, &self.ids, wgpu::TextureAspect::All, ids, 8, 0);
        }
    }
}
