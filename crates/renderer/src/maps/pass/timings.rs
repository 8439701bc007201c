//! The map passes' GPU time, from their timestamp queries.

use super::{MapPass, MapScene};
use crate::{RenderDevice, RenderError};

/// The GPU time of a frame's map passes, as [`crate::GpuTimings`] splits it.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct MapTimings {
    pub(crate) maps: f64,
    pub(crate) mask: f64,
    pub(crate) lighting: f64,
}

impl MapPass {
    /// Resolves the last frame's timestamps (after its submission finished); `None` without
    /// timestamp queries.
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails.
    pub(crate) fn read_timings(
        &self,
        rd: &RenderDevice,
        ms: &MapScene,
        written: &[bool],
    ) -> Result<Option<MapTimings>, RenderError> {
        let Some(q) = ms.queries.as_ref() else {
            return Ok(None);
        };
        if written.is_empty() || written.len() > 1 + 3 * q.lights {
            return Ok(None);
        }
        let mut enc = rd
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("map timestamps"),
            });
        // Each written pair on its own (resolve offsets are 256-aligned): an unwritten query
        // has no value to resolve.
        for (slot, _) in written.iter().enumerate().filter(|(_, w)| **w) {
            let first = 2 * slot as u32;
            enc.resolve_query_set(&q.set, first..first + 2, &q.resolve, 256 * slot as u64);
        }
        enc.copy_buffer_to_buffer(&q.resolve, 0, &q.read, 0, 256 * written.len() as u64);
        rd.queue.submit([enc.finish()]);
        let bytes = crate::raster::map_read(&rd.device, &q.read)?;
        let tick = |i: usize| {
            let o = 256 * (i / 2) + 8 * (i % 2);
            u64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"))
        };
        let period_ms = f64::from(rd.queue.get_timestamp_period()) * 1e-6;
        // Only the pairs the frame wrote: the others hold no defined value.
        let span = |slot: usize| {
            if written[slot] {
                tick(2 * slot + 1).saturating_sub(tick(2 * slot)) as f64 * period_ms
            } else {
                0.0
            }
        };
        let mut t = MapTimings {
            lighting: span(0),
            ..MapTimings::default()
        };
        for slot in (1..written.len()).step_by(3) {
            t.maps += span(slot);
            t.mask += span(slot + 1);
            t.lighting += span(slot + 2);
        }
        Ok(Some(t))
    }
}
