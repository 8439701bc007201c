//! Reading results back after a frame (tests, the final frame's plan counts, timestamps): never
//! between timed frames.

use super::*;
use crate::frame::GpuTimings;

impl ShadowPass {
    /// Reads back the counts of the last submitted frame (for tests and the final frame's plan;
    /// this maps a buffer, so never call it between timed frames).
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails or the device does not finish in time.
    pub fn read_counts(&self, rs: &ResidentScene) -> Result<PassCounts, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(PassCounts::default());
        };
        let objects = rs.counts.objects;
        let mut c = PassCounts::default();
        for b in fb
            .batches
            .iter()
            .filter(|b| b.lights_of(rs.state.lights) > 0)
        {
            let l = b.lights_of(rs.state.lights);
            let words = read_buffer(&self.device, &self.queue, &b.buffers.args)?;
            let base = 8 * l;
            c.integer_decided += u64::from(words[base]);
            c.records
                .extend((0..l).map(|li| [words[li * 8 + 1], words[li * 8 + 5]]));
            for i in 0..l * objects {
                let k = base + 1 + 3 * i;
                c.silhouette_edges.push(words[k]);
                c.side_quads.push(words[k + 1]);
                c.cap_triangles.push(words[k + 2]);
            }
        }
        Ok(c)
    }

    /// The GPU times of the passes of the last submitted frame, from timestamp queries (this maps
    /// a buffer: call it after the frame, not between timed frames). `None` when the device has
    /// no `TIMESTAMP_QUERY` or no frame was recorded.
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails.
    pub fn read_timings(&self, rs: &ResidentScene) -> Result<Option<GpuTimings>, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(None);
        };
        let Some((set, resolve, count)) = &fb.queries else {
            return Ok(None);
        };
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("resident timestamps"),
            });
        enc.resolve_query_set(set, 0..*count, resolve, 0);
        self.queue.submit([enc.finish()]);
        let words = read_buffer(&self.device, &self.queue, resolve)?;
        let ticks: Vec<u64> = words
            .chunks_exact(2)
            .map(|w| u64::from(w[0]) | (u64::from(w[1]) << 32))
            .collect();
        let period_ms = f64::from(self.queue.get_timestamp_period()) * 1e-6;
        let span = |slot: TimestampSlot| {
            let i = slot.index() as usize;
            ticks[i + 1].saturating_sub(ticks[i]) as f64 * period_ms
        };
        let lights = rs.state.lights;
        let sides: f64 = (0..lights).map(|l| span(TimestampSlot::Sides(l))).sum();
        let caps: f64 = (0..lights).map(|l| span(TimestampSlot::Caps(l))).sum();
        let lit: f64 = (0..lights).map(|l| span(TimestampSlot::Lit(l))).sum();
        Ok(Some(GpuTimings {
            extract: span(TimestampSlot::Extract),
            sides,
            caps,
            stencil: sides + caps,
            lighting: span(TimestampSlot::Prepass) + lit,
            shadow_maps: 0.0,
        }))
    }

    /// Reads back the triangle signs `[light * tri_count + triangle]` of the last submitted frame
    /// (tests only); a sharing group's shared sign stands for each of its lights'.
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails.
    pub fn read_signs(&self, rs: &ResidentScene) -> Result<Vec<i32>, RenderError> {
        let mut signs = self.read_sign_rows(rs, |_, nb| (0, nb))?;
        // The triangle pass writes no per-light sign where a group shares one: fill them in.
        let shared = self.read_shared_signs(rs)?;
        let t = rs.counts.tris;
        for (k, g) in rs.state.groups.iter().enumerate() {
            for (tri, &s) in shared[k * t..(k + 1) * t].iter().enumerate() {
                if s != NOT_SHARED {
                    for li in g.first..g.first + g.count {
                        signs[li * t + tri] = s;
                    }
                }
            }
        }
        Ok(signs)
    }

    /// Reads back the sharing groups' signs of the last submitted frame (tests only): for each
    /// of [`ResidentScene::sharing_groups`], `[group * tri_count + triangle]`, the sign the
    /// triangle pass certified for every light of the group, or [`NOT_SHARED`].
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails.
    pub fn read_shared_signs(&self, rs: &ResidentScene) -> Result<Vec<i32>, RenderError> {
        let groups = &rs.state.groups;
        self.read_sign_rows(rs, |b, nb| (nb, b.groups(groups, nb).len()))
    }

    /// Rows `first .. first + count` of each batch's signs (`rows(batch, its lights)`), in
    /// batch order.
    fn read_sign_rows(
        &self,
        rs: &ResidentScene,
        rows: impl Fn(&batch::Batch, usize) -> (usize, usize),
    ) -> Result<Vec<i32>, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(Vec::new());
        };
        let t = rs.counts.tris;
        let mut out = Vec::new();
        for b in fb
            .batches
            .iter()
            .filter(|b| b.lights_of(rs.state.lights) > 0)
        {
            let (first, count) = rows(b, b.lights_of(rs.state.lights));
            let words = read_buffer(&self.device, &self.queue, &b.buffers.signs)?;
            out.extend(
                words[first * t..(first + count) * t]
                    .iter()
                    .map(|&w| w as i32),
            );
        }
        Ok(out)
    }

    /// Reads back each light's side records of the last submitted frame, sorted (tests only).
    ///
    /// # Errors
    /// [`RenderError::Device`] when mapping fails, or when the counts the device wrote exceed a
    /// light's record region.
    pub fn read_records(&self, rs: &ResidentScene) -> Result<Vec<LightRecords>, RenderError> {
        let Some(fb) = rs.frame.as_ref() else {
            return Ok(Vec::new());
        };
        let counts = self.read_counts(rs)?;
        let cap = rs.counts.capacity;
        let mut out = Vec::with_capacity(counts.records.len());
        for b in fb
            .batches
            .iter()
            .filter(|b| b.lights_of(rs.state.lights) > 0)
        {
            let words = read_buffer(&self.device, &self.queue, &b.buffers.records)?;
            for j in 0..b.lights_of(rs.state.lights) {
                let li = b.first + j;
                let [zp, zf] = counts.records[li].map(|c| c as usize);
                if zp + zf > cap {
                    return Err(RenderError::Device(format!(
                        "light {li}: {zp} z-pass and {zf} z-fail side records exceed the region of {cap}"
                    )));
                }
                let region = &words[j * cap..(j + 1) * cap];
                let mut zpass = region[..zp].to_vec();
                let mut zfail = region[cap - zf..].to_vec();
                zpass.sort_unstable();
                zfail.sort_unstable();
                out.push(LightRecords { zpass, zfail });
            }
        }
        Ok(out)
    }
}

/// Copies `buffer` to a mappable one and reads it as `u32` words.
fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u32>, RenderError> {
    let size = buffer.size();
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("resident readback"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("resident readback"),
    });
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    queue.submit([enc.finish()]);
    let bytes = crate::raster::map_read(device, &staging)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
