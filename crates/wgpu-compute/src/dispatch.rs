//! One `extract` on the device: the batches of lights, each uploaded, dispatched, read back and
//! resolved on the host, and the host's exact decisions patched into the device buffers.

use crate::backend::WgpuBackend;
use crate::device::{device_error, limit_error, wait_error};
use crate::layout::{pack_lights, Frame, Prepared};
use crate::pipeline::DeferredExact;
use crate::resolve::{expand_uncertain, finish_batch, BatchOutput, Patch, UncertainTriangle};
use shadowvol_gpu::shaders;
use shadowvol_gpu::{ErrorScopes, TableBuffers};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{
    check_lights, gpu, object_lights, BackendError, ExtractStats, Multiplicities,
};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

/// Most workgroups of the grid-stride resolution of exact mode's uncertain list (262,144
/// invocations).
const RESOLVE_MAX_GROUPS: u32 = 1024;

/// One batch of the lights of an `extract`: what [`WgpuBackend::run_batch`] uploads and where
/// its rows of the result go.
struct LightBatch<'a> {
    /// Every light of the extraction, per object (object space).
    object_lights: &'a [Vec<[f32; 4]>],
    /// The batch's lights packed object-major, as uploaded.
    packed: Vec<[f32; 4]>,
    /// The batch's lights within the extraction.
    lights: std::ops::Range<usize>,
    /// Whether this is the extraction's last batch (its device buffers stay readable).
    last: bool,
    /// Exact mode with the host fallback: uncertain records are read back and resolved.
    host_resolves: bool,
}

/// The pipelines of one `extract`'s mode.
#[derive(Clone, Copy)]
struct Steps<'a> {
    /// The triangle step (`None` in `original`).
    triangles: Option<&'a wgpu::ComputePipeline>,
    /// The edge step.
    edges: &'a wgpu::ComputePipeline,
    /// Exact mode with `exact_on_device`: the deferred resolution and the inline fallback.
    deferred: Option<&'a DeferredExact>,
}

/// What the first round trip of a batch brought back: the counts (per light, then the
/// uncertain records), and the first `k` list entries and `ku` records.
struct FirstTrip {
    counts: Vec<u32>,
    output: DeviceOutput,
    k: u64,
    ku: u64,
    /// Uncertain records the host decides: all of them with the host fallback, else none (the
    /// device decided them).
    host_records: u64,
}

/// The sizes and workgroup grids of one batch's dispatch.
struct Dims {
    /// Edges of the scene (the stride between lights in the device buffers).
    edges: u64,
    /// Triangles of the scene.
    triangles: u64,
    /// Objects of the scene.
    objects: u64,
    /// Lights of the batch.
    lights: usize,
    /// Workgroups of the edge step.
    edge_grid: (u32, u32),
    /// Workgroups of the triangle step.
    triangle_grid: (u32, u32),
}

/// Where the first round trip's staging buffer holds what it brings back (byte offsets).
struct Staging {
    /// Bytes of the counts: one list length per light, then the uncertain count.
    counters_bytes: u64,
    /// Offset of the list prefixes, `k` entries of 8 bytes per light.
    lists_at: u64,
    /// List entries brought back per light.
    k: u64,
    /// Offset of the uncertain records, 16 bytes each.
    uncertain_at: u64,
    /// Uncertain records brought back.
    ku: u64,
    /// Bytes in all.
    bytes: u64,
}

/// What one dispatch brought back, before the host decides its undecided triangles.
struct DeviceOutput {
    /// The whole multiplicity buffer, with `full_readback`.
    mult: Option<Vec<i32>>,
    /// Per light, the compact list `(edge, m)`.
    lists: Vec<Vec<(u32, i32)>>,
    /// Undecided `(triangle, light)` pairs.
    uncertain: Vec<UncertainTriangle>,
}

impl WgpuBackend {
    pub(crate) fn extract_prepared(
        &self,
        p: &mut Prepared,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        check_lights(lights)?;
        let mut stats = ExtractStats::default();
        let edge_count = p.index.edge_count();
        // Zeroing the host result is part of bringing results back (the device sends only the
        // non-zero entries).
        let t_reset = Instant::now();
        out.reset(edge_count, lights.len());
        stats.readback += t_reset.elapsed();
        p.last = None;
        let Some(gpu) = p.gpu.clone() else {
            // No edges: nothing to compute, every list is empty.
            return Ok(stats);
        };
        let t_upload = Instant::now();
        let obj_lights = object_lights(p.transforms.iter().copied(), lights);
        let edges = edge_count as u64;
        let objects = p.index.object_count() as u64;
        let tris = p.index.tri_count() as u64;
        let per_batch = self.lights_per_batch(edges, tris, objects, lights.len())?;
        let needs_new_frame = p
            .frame
            .as_ref()
            .is_none_or(|f| f.light_capacity < per_batch);
        if needs_new_frame {
            let capacity = self.options.initial_uncertain_capacity;
            let lists = p
                .frame
                .as_ref()
                .map_or_else(|| self.initial_list_capacity(edges), |f| f.list_capacity);
            let scope = ErrorScopes::push(&self.device);
            let frame = self.create_frame(&gpu, (edges, tris, objects), per_batch, capacity, lists);
            if let Some(e) = scope.pop() {
                return Err(device_error(format!("allocating frame buffers: {e}")));
            }
            p.frame = Some(frame?);
        }
        stats.upload += t_upload.elapsed();
        let m = gpu::mode_code(mode) as usize;
        let exact = mode == Accuracy::Exact;
        let set = self.pipelines.steps(p.index.object_count());
        let steps = Steps {
            triangles: set.triangles[m].as_ref(),
            edges: if mode == Accuracy::Original && !gpu.has_ov_vertices() {
                &set.original_by_triangles
            } else {
                &set.edges[m]
            },
            deferred: self.pipelines.deferred.as_ref().filter(|_| exact),
        };
        for range in gpu::batches(lights.len(), per_batch) {
            let batch = LightBatch {
                object_lights: &obj_lights,
                packed: pack_lights(&obj_lights, range.start, range.len()),
                last: range.end == lights.len(),
                lights: range,
                host_resolves: exact && steps.deferred.is_none(),
            };
            let scope = ErrorScopes::push(&self.device);
            let r = self.run_batch(p, &gpu, steps, &batch, out, &mut stats);
            if let Some(e) = scope.pop() {
                return Err(device_error(e));
            }
            r?;
            if batch.last {
                p.last = Some((batch.lights.start, batch.lights.len()));
            }
        }
        Ok(stats)
    }

    /// Workgroups `(x, y)` for `items` invocations, folded into a 2-D grid when one dimension
    /// cannot hold them.
    fn grid(&self, items: usize, what: &str) -> Result<(u32, u32), BackendError> {
        let groups = items.div_ceil(shaders::WORKGROUP_SIZE as usize) as u64;
        let max_dim = u64::from(self.limits.max_compute_workgroups_per_dimension);
        let gx = groups.min(max_dim).max(1);
        let gy = groups.div_ceil(gx);
        if gy > max_dim {
            return Err(limit_error(format!(
                "{items} {what} need {groups} workgroups; the device allows {max_dim} x {max_dim}"
            )));
        }
        Ok((gx as u32, gy as u32))
    }

    /// Runs one batch of lights: the first round trip (upload, the triangle step except in
    /// `original`, the edge step, the counts and list prefixes back), the second (the rest of
    /// long lists and of the uncertain records), and the host's exact decisions.
    fn run_batch(
        &self,
        p: &mut Prepared,
        gpu: &TableBuffers,
        steps: Steps<'_>,
        batch: &LightBatch<'_>,
        out: &mut Multiplicities,
        stats: &mut ExtractStats,
    ) -> Result<(), BackendError> {
        let count = batch.lights.len();
        let first = self.first_round_trip(p, gpu, steps, batch, stats)?;
        let counts = &first.counts;
        let uncertain_count = first.host_records;
        // Adapt the prefixes to this frame's sizes.
        let grow = |n: u64| (n + n / 4).max(1).next_power_of_two();
        let longest = counts[..count].iter().copied().max().unwrap_or(0);
        p.list_prefix = grow(u64::from(longest)).max(u64::from(self.options.min_list_prefix));
        p.uncertain_prefix = grow(uncertain_count).max(u64::from(self.options.min_list_prefix));

        let frame = p
            .frame
            .as_mut()
            .ok_or_else(|| device_error("no frame buffers"))?;
        let output = self.second_round_trip(frame, p.index.edge_count(), count, first, stats)?;
        self.resolve_batch(p, batch, output, out, stats)
    }

    /// Uploads the batch's lights, dispatches the triangle step (and, in exact mode on the
    /// device, the resolution of what its filter left) and the edge step, and brings back the
    /// counts, the first `k` entries of every list and `ku` uncertain records; dispatches again
    /// with a bigger uncertain buffer when the records overflowed it, or, on the device, with the
    /// integer fallback inline when the buffer cannot grow enough, and with longer compact lists
    /// when a list overflowed its own or has no room for the host's exact decisions.
    fn first_round_trip(
        &self,
        p: &mut Prepared,
        gpu: &TableBuffers,
        steps: Steps<'_>,
        batch: &LightBatch<'_>,
        stats: &mut ExtractStats,
    ) -> Result<FirstTrip, BackendError> {
        let count = batch.lights.len();
        let dims = Dims {
            edges: p.index.edge_count() as u64,
            triangles: p.index.tri_count() as u64,
            objects: p.index.object_count() as u64,
            lights: count,
            edge_grid: self.grid(p.index.edge_count(), "edges")?,
            triangle_grid: self.grid(p.index.tri_count(), "triangles")?,
        };
        // Repeated with a bigger uncertain buffer (or the fallback inline) after an overflow.
        loop {
            let t = Instant::now();
            let frame = p
                .frame
                .as_mut()
                .ok_or_else(|| device_error("no frame buffers"))?;
            let prefixes = (p.list_prefix, p.uncertain_prefix);
            let at = self.upload_batch(frame, &dims, batch, prefixes)?;
            stats.upload += t.elapsed();
            let t = Instant::now();
            self.dispatch_batch(frame, steps, p.inline_exact, &dims, &at)?;
            stats.compute += t.elapsed();
            let t = Instant::now();
            let (counts, output) = self.read_first_trip(frame, count, &at)?;
            stats.readback += t.elapsed();
            let uncertain = counts[count];
            let host_records = if batch.host_resolves {
                u64::from(uncertain)
            } else {
                0
            };
            // Each undecided pair the host decides changes at most 3 edges of its light's list.
            let longest = counts[..count].iter().copied().max().unwrap_or(0);
            let lists_need = (u64::from(longest) + 3 * host_records).min(dims.edges);
            let lists_fit = lists_need <= frame.list_capacity;
            if uncertain <= frame.uncertain_capacity && lists_fit {
                return Ok(FirstTrip {
                    host_records,
                    counts,
                    output,
                    k: at.k,
                    ku: at.ku,
                });
            }
            if uncertain > frame.uncertain_capacity {
                self.after_overflow(p, gpu, steps, uncertain, stats)?;
            }
            if !lists_fit {
                let t = Instant::now();
                let lists = lists_need.next_power_of_two().min(dims.edges);
                self.replace_frame(p, gpu, None, Some(lists))?;
                stats.upload += t.elapsed();
            }
        }
    }

    /// Writes the batch's lights and parameters, and makes the staging buffer large enough for
    /// what the first round trip brings back: the list lengths, the first `k` entries of every
    /// list and (when the host resolves) `ku` uncertain records, `k` and `ku` the scene's
    /// adapted `prefixes` shrunk to keep the staging buffer within the buffer limit.
    fn upload_batch(
        &self,
        frame: &mut Frame,
        dims: &Dims,
        batch: &LightBatch<'_>,
        (list_prefix, uncertain_prefix): (u64, u64),
    ) -> Result<Staging, BackendError> {
        let count = dims.lights as u64;
        let params = [
            dims.edges as u32,
            count as u32,
            frame.uncertain_capacity,
            dims.triangles as u32,
            frame.list_capacity as u32,
            dims.objects as u32,
            0,
            0,
        ];
        self.queue
            .write_buffer(&frame.lights, 0, bytemuck::cast_slice(&batch.packed));
        self.queue
            .write_buffer(&frame.params, 0, bytemuck::cast_slice(&params));
        let counters_bytes = (count + 1) * 4;
        let lists_at = counters_bytes.next_multiple_of(8);
        // The second round trip brings what the prefixes leave.
        let room = self.limits.max_buffer_size.saturating_sub(lists_at);
        let k = list_prefix
            .min(frame.list_capacity)
            .min(room / (count * 8).max(1));
        let ku = if batch.host_resolves {
            uncertain_prefix
                .min(u64::from(frame.uncertain_capacity))
                .min((room - count * k * 8) / 16)
        } else {
            0
        };
        let uncertain_at = lists_at + count * k * 8;
        let at = Staging {
            counters_bytes,
            lists_at,
            k,
            uncertain_at,
            ku,
            bytes: uncertain_at + ku * 16,
        };
        if frame.staging.as_ref().is_none_or(|b| b.size() < at.bytes) {
            self.check_buffer("the staging buffer", at.bytes, false)?;
            frame.staging = Some(
                self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("counts and list prefixes"),
                    size: at
                        .bytes
                        .next_power_of_two()
                        .min(self.limits.max_buffer_size)
                        .max(at.bytes),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
            );
        }
        Ok(at)
    }

    /// Records and submits one batch's compute pass (the triangle step, exact mode's resolution
    /// on the device, the edge step) and the copies of the counts, list prefixes and uncertain
    /// records into the staging buffer, and waits for them.
    fn dispatch_batch(
        &self,
        frame: &Frame,
        steps: Steps<'_>,
        inline_exact: bool,
        dims: &Dims,
        at: &Staging,
    ) -> Result<(), BackendError> {
        let staging = frame
            .staging
            .as_ref()
            .ok_or_else(|| device_error("no staging buffer"))?;
        // Exact mode on the device: the integer fallback inline, or the resolution of the
        // list over one invocation per record it holds, up to a grid that fills a large GPU.
        let (triangles, resolve) = match steps.deferred {
            Some(d) if inline_exact => (Some(d.inline_triangles(&self.device)?), None),
            Some(d) => {
                let records = frame
                    .uncertain_capacity
                    .min(RESOLVE_MAX_GROUPS * shaders::WORKGROUP_SIZE);
                let grid = self.grid(records as usize, "uncertain records")?;
                (steps.triangles, Some((&d.resolve, grid)))
            }
            None => (steps.triangles, None),
        };
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("extract"),
            });
        encoder.clear_buffer(&frame.counters, 0, Some(at.counters_bytes));
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("silhouette"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &frame.bind_group, &[]);
            if let Some(triangles) = triangles {
                let (tx, ty) = dims.triangle_grid;
                pass.set_pipeline(triangles);
                pass.dispatch_workgroups(tx, ty, 1);
            }
            if let Some((resolve, (rx, ry))) = resolve {
                pass.set_pipeline(resolve);
                pass.dispatch_workgroups(rx, ry, 1);
            }
            let (gx, gy) = dims.edge_grid;
            pass.set_pipeline(steps.edges);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        encoder.copy_buffer_to_buffer(&frame.counters, 0, staging, 0, at.counters_bytes);
        if at.k > 0 {
            for li in 0..dims.lights as u64 {
                encoder.copy_buffer_to_buffer(
                    &frame.silhouettes,
                    li * frame.list_capacity * 8,
                    staging,
                    at.lists_at + li * at.k * 8,
                    at.k * 8,
                );
            }
        }
        if at.ku > 0 {
            encoder.copy_buffer_to_buffer(
                &frame.uncertain,
                0,
                staging,
                at.uncertain_at,
                at.ku * 16,
            );
        }
        let index = self.queue.submit([encoder.finish()]);
        self.wait(index)
    }

    /// Maps the staging buffer and reads the counts (per light, then the uncertain records),
    /// the list prefixes and the uncertain records the first round trip brought back.
    fn read_first_trip(
        &self,
        frame: &Frame,
        count: usize,
        at: &Staging,
    ) -> Result<(Vec<u32>, DeviceOutput), BackendError> {
        let staging = frame
            .staging
            .as_ref()
            .ok_or_else(|| device_error("no staging buffer"))?;
        self.read_mapped(staging, at.bytes, |b| {
            let counts: Vec<u32> = read_u32s(&b[..at.counters_bytes as usize]).collect();
            let lists = (0..count)
                .map(|li| {
                    let n = u64::from(counts[li]).min(at.k) as usize;
                    let from = (at.lists_at + li as u64 * at.k * 8) as usize;
                    read_pairs(&b[from..from + n * 8])
                })
                .collect();
            let n = u64::from(counts[count]).min(at.ku) as usize;
            let from = at.uncertain_at as usize;
            let uncertain = read_records(&b[from..from + n * 16]);
            (
                counts,
                DeviceOutput {
                    mult: None,
                    lists,
                    uncertain,
                },
            )
        })
    }

    /// After a dispatch whose `uncertain` records overflowed the list: a bigger list, or, where
    /// no list the device binds can hold them, the integer fallback inline from now on (exact
    /// mode on the device; the host fallback has no way out and returns
    /// [`BackendError::Limit`]). The caller dispatches again.
    fn after_overflow(
        &self,
        p: &mut Prepared,
        gpu: &TableBuffers,
        steps: Steps<'_>,
        uncertain: u32,
        stats: &mut ExtractStats,
    ) -> Result<(), BackendError> {
        if uncertain > self.max_uncertain_records() {
            if steps.deferred.is_none() {
                return Err(limit_error(format!(
                    "{uncertain} undecided (triangle, light) pairs need {} bytes, but the device allows storage bindings of {} bytes; pass fewer lights per call",
                    u64::from(uncertain) * 16,
                    self.limits.max_storage_buffer_binding_size.min(self.limits.max_buffer_size)
                )));
            }
            // Decided on the device all the same, with the integer fallback inline: slower per
            // triangle, but no list, so the frame keeps its buffers. This prepared scene keeps
            // the fallback inline from now on.
            p.inline_exact = true;
            return Ok(());
        }
        let t = Instant::now();
        let capacity = uncertain.checked_next_power_of_two().unwrap_or(uncertain);
        self.replace_frame(p, gpu, Some(capacity), None)?;
        stats.upload += t.elapsed();
        Ok(())
    }

    /// Brings back what the first round trip left: the rest of long lists and of the uncertain
    /// records, and with `full_readback` the whole multiplicity buffer.
    fn second_round_trip(
        &self,
        frame: &mut Frame,
        edge_count: usize,
        count: usize,
        first: FirstTrip,
        stats: &mut ExtractStats,
    ) -> Result<DeviceOutput, BackendError> {
        let FirstTrip {
            counts,
            mut output,
            k,
            ku,
            host_records,
        } = first;
        let edges = edge_count as u64;
        let uncertain_count = host_records;
        let t = Instant::now();
        let rest: Vec<(usize, u64, u64)> = counts[..count]
            .iter()
            .enumerate()
            .filter(|&(_, &c)| u64::from(c) > k)
            .map(|(li, &c)| (li, k, u64::from(c) - k))
            .collect();
        let rest_bytes: u64 = rest.iter().map(|r| r.2 * 8).sum();
        let uncertain_rest = uncertain_count.saturating_sub(ku);
        let uncertain_bytes = uncertain_rest * 16;
        let mult_bytes = if self.options.full_readback {
            edges * count as u64 * 4
        } else {
            0
        };
        let total = rest_bytes + uncertain_bytes + mult_bytes;
        if total > 0 {
            if frame.readback.as_ref().is_none_or(|b| b.size() < total) {
                self.check_buffer("the readback buffer", total, false)?;
                frame.readback = Some(
                    self.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("readback"),
                        size: total
                            .next_power_of_two()
                            .min(self.limits.max_buffer_size)
                            .max(total),
                        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                );
            }
            let readback = frame
                .readback
                .as_ref()
                .ok_or_else(|| device_error("no readback buffer"))?;
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("readback"),
                });
            let mut offset = 0;
            for &(li, from, n) in &rest {
                encoder.copy_buffer_to_buffer(
                    &frame.silhouettes,
                    (li as u64 * frame.list_capacity + from) * 8,
                    readback,
                    offset,
                    n * 8,
                );
                offset += n * 8;
            }
            if uncertain_bytes > 0 {
                encoder.copy_buffer_to_buffer(
                    &frame.uncertain,
                    ku * 16,
                    readback,
                    offset,
                    uncertain_bytes,
                );
                offset += uncertain_bytes;
            }
            if mult_bytes > 0 {
                encoder.copy_buffer_to_buffer(&frame.mult, 0, readback, offset, mult_bytes);
            }
            let index = self.queue.submit([encoder.finish()]);
            self.wait(index)?;
            self.read_mapped(readback, total, |bytes| {
                let mut at = 0usize;
                for &(li, _, n) in &rest {
                    let b = n as usize * 8;
                    output.lists[li].extend(read_pairs(&bytes[at..at + b]));
                    at += b;
                }
                let b = uncertain_bytes as usize;
                output.uncertain.extend(read_records(&bytes[at..at + b]));
                at += b;
                if mult_bytes > 0 {
                    output.mult = Some(
                        read_u32s(&bytes[at..at + mult_bytes as usize])
                            .map(|w| w as i32)
                            .collect(),
                    );
                }
            })?;
        } else if self.options.full_readback {
            output.mult = Some(vec![0; edge_count * count]);
        }
        stats.readback += t.elapsed();

        Ok(output)
    }

    /// The host's exact decisions for the undecided triangles' triples, the batch's rows of
    /// `out`, and (last batch) the patch of the device copy.
    fn resolve_batch(
        &self,
        p: &mut Prepared,
        batch: &LightBatch<'_>,
        output: DeviceOutput,
        out: &mut Multiplicities,
        stats: &mut ExtractStats,
    ) -> Result<(), BackendError> {
        let count = batch.lights.len();
        let edges = p.index.edge_count() as u64;
        let t = Instant::now();
        validate_lists(&output.lists, p.index.edge_count())?;
        let records = if output.uncertain.is_empty() {
            Vec::new()
        } else {
            let index = &p.index;
            let of = |t: usize| index.edge_slots(t);
            expand_uncertain(&output.uncertain, of, index.tri_count(), count)?
        };
        stats.uncertain += records.len() as u64;
        let patch = finish_batch(
            &p.index,
            batch.object_lights,
            batch.lights.clone(),
            BatchOutput {
                mult: output.mult,
                lists: output.lists,
                uncertain: records,
            },
            out,
        )?;
        if batch.last {
            let frame = p
                .frame
                .as_ref()
                .ok_or_else(|| device_error("no frame buffers"))?;
            self.apply_patch(frame, edges, &patch);
        }
        stats.host_resolve += t.elapsed();
        Ok(())
    }

    /// Writes the host's exact decisions into the device buffers, so that [`GpuResults`](crate::GpuResults) is final.
    fn apply_patch(&self, frame: &Frame, edges: u64, patch: &Patch) {
        if patch.mult.is_empty() && patch.lists.is_empty() {
            return;
        }
        for &(li, e, m) in &patch.mult {
            self.queue.write_buffer(
                &frame.mult,
                (u64::from(li) * edges + u64::from(e)) * 4,
                bytemuck::bytes_of(&m),
            );
        }
        for (li, list) in &patch.lists {
            let words: Vec<u32> = list.iter().flat_map(|&(e, m)| [e, m as u32]).collect();
            if !words.is_empty() {
                self.queue.write_buffer(
                    &frame.silhouettes,
                    u64::from(*li) * frame.list_capacity * 8,
                    bytemuck::cast_slice(&words),
                );
            }
            let len = list.len() as u32;
            self.queue.write_buffer(
                &frame.counters,
                u64::from(*li) * 4,
                bytemuck::bytes_of(&len),
            );
        }
        // Flush the staged writes.
        self.queue.submit(std::iter::empty::<wgpu::CommandBuffer>());
    }
}

/// Rejects compact lists that cannot be right (an edge out of range, m = 0), instead of
/// panicking. Uncertain records are checked by [`resolve_uncertain`](gpu::resolve_uncertain).
fn validate_lists(lists: &[Vec<(u32, i32)>], edges: usize) -> Result<(), BackendError> {
    for (li, list) in lists.iter().enumerate() {
        if let Some(&(e, m)) = list.iter().find(|&&(e, m)| e as usize >= edges || m == 0) {
            return Err(device_error(format!(
                "the device returned an invalid silhouette entry (edge {e}, m {m}) for light {li}"
            )));
        }
    }
    Ok(())
}

impl WgpuBackend {
    pub(crate) fn wait(&self, index: wgpu::SubmissionIndex) -> Result<(), BackendError> {
        let limit = gpu::wait_limit()?;
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: Some(limit),
            })
            .map_err(|e| wait_error("waiting for the device", &e, limit))?;
        self.check_health()
    }

    /// Maps `buffer[0..size]` for reading and hands the bytes to `f`.
    fn read_mapped<T>(
        &self,
        buffer: &wgpu::Buffer,
        size: u64,
        f: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, BackendError> {
        let slot = Arc::new(Mutex::new(None));
        let s = Arc::clone(&slot);
        buffer.map_async(wgpu::MapMode::Read, 0..size, move |r| {
            *s.lock().unwrap_or_else(PoisonError::into_inner) = Some(r);
        });
        let limit = gpu::wait_limit()?;
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(limit),
            })
            .map_err(|e| wait_error("waiting for a buffer mapping", &e, limit))?;
        self.check_health()?;
        let state = slot.lock().unwrap_or_else(PoisonError::into_inner).take();
        match state {
            Some(Ok(())) => {}
            Some(Err(e)) => return Err(device_error(format!("mapping a readback buffer: {e}"))),
            None => return Err(device_error("a readback mapping did not complete")),
        }
        let result = {
            let view = buffer
                .get_mapped_range(0..size)
                .map_err(|e| device_error(format!("reading a mapped buffer: {e}")))?;
            f(&view)
        };
        buffer.unmap();
        Ok(result)
    }
}

/// Compact-list entries `(edge, m)` from little-endian `u32` pairs.
fn read_pairs(bytes: &[u8]) -> Vec<(u32, i32)> {
    let words: Vec<u32> = read_u32s(bytes).collect();
    words.chunks_exact(2).map(|w| (w[0], w[1] as i32)).collect()
}

/// Undecided `(triangle, light)` records (4 little-endian `u32` words each).
fn read_records(bytes: &[u8]) -> Vec<UncertainTriangle> {
    let words: Vec<u32> = read_u32s(bytes).collect();
    words
        .chunks_exact(4)
        .map(|w| UncertainTriangle {
            triangle: w[0],
            light: w[1],
        })
        .collect()
}

fn read_u32s(bytes: &[u8]) -> impl Iterator<Item = u32> + '_ {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}
