//! The buffers sized by the number of lights, in batches: a frame whose lights' buffers would
//! exceed one storage binding (`max_storage_buffer_binding_size`) is extracted in batches of
//! lights, each with its own buffers, parameters and bind groups, one after the other in the
//! same compute pass. Each light's stencil and lit passes read its batch's buffers.

use super::*;

/// Buffers sized by the number of lights of one batch: object-space lights (and the sharing
/// groups' boxes), light points, techniques (and the groups' words), triangle signs (and the
/// groups' shared signs), indirect arguments, side records, light uniforms.
pub(super) struct LightBuffers {
    pub(super) lights: wgpu::Buffer,
    pub(super) light_points: wgpu::Buffer,
    pub(super) technique: wgpu::Buffer,
    pub(super) signs: wgpu::Buffer,
    pub(super) args: wgpu::Buffer,
    pub(super) records: wgpu::Buffer,
    pub(super) light_u: wgpu::Buffer,
}

/// Lights `first .. first + slots` of a frame: their buffers, the extraction's parameters for
/// them, and the bind groups over both and the scene's.
pub(super) struct Batch {
    pub(super) first: usize,
    pub(super) slots: usize,
    pub(super) buffers: LightBuffers,
    pub(super) params: wgpu::Buffer,
    pub(super) rparams: wgpu::Buffer,
    pub(super) c0: wgpu::BindGroup,
    pub(super) c1: wgpu::BindGroup,
    pub(super) d0: wgpu::BindGroup,
    pub(super) dl: wgpu::BindGroup,
}

impl Batch {
    /// How many of a frame's `n` lights are this batch's.
    pub(super) fn lights_of(&self, n: usize) -> usize {
        n.saturating_sub(self.first).min(self.slots)
    }

    /// The sharing groups of `groups` (a frame's, in light order) in this batch of `nb` lights.
    pub(super) fn groups<'g>(&self, groups: &'g [SharingGroup], nb: usize) -> &'g [SharingGroup] {
        let inside = |g: &SharingGroup| (self.first..self.first + nb).contains(&g.first);
        let start = groups.iter().position(inside).unwrap_or(groups.len());
        let len = groups[start..].iter().take_while(|g| inside(g)).count();
        &groups[start..start + len]
    }
}

/// The batches of a frame of up to `lights` lights, the per-frame object rows, and the
/// timestamp queries.
pub(super) struct FrameBuffers {
    pub(super) lights: usize,
    /// Lights per batch (every batch but the last has this many slots).
    pub(super) per_batch: usize,
    /// With `TIMESTAMP_QUERY`: begin/end of the extraction, the pre-pass, and per light its
    /// side, cap and lit passes (see `TimestampSlot`), and the buffer they resolve into.
    pub(super) queries: Option<(wgpu::QuerySet, wgpu::Buffer, u32)>,
    pub(super) objects: wgpu::Buffer,
    pub(super) batches: Vec<Batch>,
    pub(super) v0: wgpu::BindGroup,
    pub(super) s0: wgpu::BindGroup,
}

impl FrameBuffers {
    /// The batch of light `light` and the light's index in it.
    ///
    /// # Panics
    /// Panics if `light` is past the buffers' lights.
    pub(super) fn batch_of(&self, light: usize) -> (&Batch, usize) {
        let b = &self.batches[light / self.per_batch];
        (b, light - b.first)
    }

    /// Every device buffer of the frame.
    pub(super) fn all(&self) -> Vec<&wgpu::Buffer> {
        let mut v = vec![&self.objects];
        for b in &self.batches {
            let l = &b.buffers;
            v.extend([
                &l.lights,
                &l.light_points,
                &l.technique,
                &l.signs,
                &l.args,
                &l.records,
                &l.light_u,
                &b.params,
                &b.rparams,
            ]);
        }
        if let Some((_, q, _)) = &self.queries {
            v.push(q);
        }
        v
    }
}

/// The storage buffers of a batch of `slots` lights, with their labels and sizes in bytes, for a
/// scene of `counts`: object-space lights and the sharing groups' boxes (at most one group per
/// two lights), light points, techniques and the groups' words, triangle signs and the groups'
/// shared rows, indirect draws and counts, side records.
fn batch_buffer_bytes(counts: &LayoutCounts, slots: usize) -> [(&'static str, u64); 6] {
    let objects = counts.objects.max(1) as u64;
    let tri = counts.tris.max(1) as u64;
    let s = slots as u64;
    let g = s / 2;
    [
        ("object-space lights", 16 * (s + 2 * g) * objects),
        ("light points", 32 * s * objects),
        ("techniques", 4 * s * (objects + 1)),
        ("triangle signs", 4 * (s + g) * tri),
        ("indirect draws", 4 * (8 * s + 1 + 3 * s * objects)),
        ("side records", 4 * s * counts.capacity as u64),
    ]
}

impl ShadowPass {
    /// The buffers of `slots` lights, in batches that each fit one storage binding, and the
    /// bind groups over them and the scene's.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when one light's buffers exceed a binding.
    pub(super) fn frame_buffers(
        &self,
        rs: &ResidentScene,
        slots: usize,
    ) -> Result<FrameBuffers, RenderError> {
        let max = self.device.limits().max_storage_buffer_binding_size;
        let fits = |n: usize| batch_buffer_bytes(&rs.counts, n).iter().all(|b| b.1 <= max);
        if let Some((label, bytes)) = batch_buffer_bytes(&rs.counts, 1)
            .into_iter()
            .find(|b| b.1 > max)
        {
            return Err(RenderError::InvalidInput(format!(
                "the GPU pipeline's {label} for one light take {bytes} bytes; the device binds at most {max} (max_storage_buffer_binding_size)"
            )));
        }
        // The most lights whose buffers fit (the sizes grow with the lights).
        let (mut per_batch, mut too_many) = (1, slots + 1);
        while too_many - per_batch > 1 {
            let mid = per_batch + (too_many - per_batch) / 2;
            if fits(mid) {
                per_batch = mid;
            } else {
                too_many = mid;
            }
        }
        let objects_n = rs.counts.objects.max(1) as u64;
        let objects = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("objects"),
            size: 80 * objects_n,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let batches = (0..slots.div_ceil(per_batch))
            .map(|k| {
                let first = k * per_batch;
                self.batch(rs, &objects, first, per_batch.min(slots - first))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let [s0, v0] = self.world_groups(rs, &objects);
        Ok(FrameBuffers {
            lights: slots,
            per_batch,
            queries: self.timestamp_queries(slots),
            objects,
            batches,
            v0,
            s0,
        })
    }

    /// The batch of lights `first .. first + slots`.
    fn batch(
        &self,
        rs: &ResidentScene,
        objects: &wgpu::Buffer,
        first: usize,
        slots: usize,
    ) -> Result<Batch, RenderError> {
        let buffers = self.light_buffers(rs, slots)?;
        let params = self.uniform_buffer("resident params", 32);
        let rparams = self.uniform_buffer("resident frame params", 16);
        let [c0, c1] = self.extract_groups(rs, &buffers, [&params, &rparams]);
        let [d0, dl] = self.draw_groups(rs, &buffers, objects);
        Ok(Batch {
            first,
            slots,
            buffers,
            params,
            rparams,
            c0,
            c1,
            d0,
            dl,
        })
    }

    /// The buffers sized by `slots` lights, each checked against what the device binds.
    fn light_buffers(&self, rs: &ResidentScene, slots: usize) -> Result<LightBuffers, RenderError> {
        let max = self.device.limits().max_storage_buffer_binding_size;
        let sized = |label: &str,
                     size: u64,
                     usage: wgpu::BufferUsages|
         -> Result<wgpu::Buffer, RenderError> {
            if size > max {
                return Err(RenderError::InvalidInput(format!(
                    "the GPU pipeline's {label} for {slots} light(s) take {size} bytes; the device binds at most {max} (max_storage_buffer_binding_size): use fewer lights per frame"
                )));
            }
            Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            }))
        };
        let st = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let readable = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let indirect = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::INDIRECT
            | wgpu::BufferUsages::COPY_SRC;
        let [lights, points, technique, signs, args, records] =
            batch_buffer_bytes(&rs.counts, slots);
        let s = slots as u64;
        Ok(LightBuffers {
            lights: sized(lights.0, lights.1, st)?,
            light_points: sized(points.0, points.1, st)?,
            technique: sized(technique.0, technique.1, st)?,
            signs: sized(signs.0, signs.1, readable)?,
            args: sized(args.0, args.1, indirect)?,
            records: sized(records.0, records.1, readable)?,
            light_u: self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("resident lights"),
                size: LIGHT_STRIDE * s,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        })
    }

    /// The extraction's bind groups of a batch: `c0` (scene, lights, signs), `c1` (frame,
    /// records).
    fn extract_groups(
        &self,
        rs: &ResidentScene,
        b: &LightBuffers,
        [params, rparams]: [&wgpu::Buffer; 2],
    ) -> [wgpu::BindGroup; 2] {
        let mut entries = vec![entry(0, params), entry(4, &b.lights), entry(11, &b.signs)];
        entries.extend(rs.tables.entries());
        let c0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident extract scene"),
            layout: &self.extract.c0,
            entries: &entries,
        });
        let c1 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident extract frame"),
            layout: &self.extract.c1,
            entries: &[
                entry(0, rparams),
                entry(3, &b.technique),
                entry(5, &b.args),
                entry(6, &b.records),
            ],
        });
        [c0, c1]
    }

    /// The draws' bind groups of a batch: `d0` (what sides and caps read), `dl` (one light's
    /// uniform).
    fn draw_groups(
        &self,
        rs: &ResidentScene,
        b: &LightBuffers,
        objects: &wgpu::Buffer,
    ) -> [wgpu::BindGroup; 2] {
        let d0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident draw"),
            layout: &self.draw.d0,
            entries: &[
                entry(0, &rs.globals),
                entry(1, &rs.tables.tables),
                entry(9, &rs.tables.offsets),
                entry(4, &b.signs),
                entry(5, &b.records),
                entry(6, objects),
                entry(7, &rs.world),
                entry(12, &b.light_points),
            ],
        });
        let dl = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident light"),
            layout: &self.draw.dl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &b.light_u,
                    offset: 0,
                    size: std::num::NonZeroU64::new(LIGHT_BYTES),
                }),
            }],
        });
        [d0, dl]
    }

    /// The bind groups of the surface pass (`s0`) and of the vertex pass (`v0`).
    fn world_groups(&self, rs: &ResidentScene, objects: &wgpu::Buffer) -> [wgpu::BindGroup; 2] {
        let s0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident surfaces"),
            layout: &self.world.s0,
            entries: &[
                entry(1, &rs.tables.tables),
                entry(6, objects),
                entry(7, &rs.world),
                entry(9, &rs.tables.offsets),
            ],
        });
        let v0 = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident vertices"),
            layout: &self.world.v0,
            entries: &[
                entry(1, &rs.tables.tables),
                entry(6, objects),
                entry(9, &rs.tables.offsets),
            ],
        });
        [s0, v0]
    }

    /// With `TIMESTAMP_QUERY`: the query set of a frame's passes and its resolve buffer.
    fn timestamp_queries(&self, slots: usize) -> Option<(wgpu::QuerySet, wgpu::Buffer, u32)> {
        self.timestamps.then(|| {
            let count = 2 * (2 + 3 * slots as u32);
            let set = self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("resident timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            });
            let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("resident timestamps resolve"),
                size: 8 * u64::from(count),
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve, count)
        })
    }
}
