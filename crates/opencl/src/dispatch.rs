//! One light batch of an `extract` on the device: the light and counter upload, the kernel
//! enqueue, the bounded waits for each submission (and for work an earlier wait abandoned), and
//! the read-back of the silhouette list and uncertain records, finished on the host by
//! [`crate::resolve::finish_batch`].

use crate::backend::OpenClBackend;
use crate::device::device_error;
use crate::layout::{ensure, flat_light_batch, Prepared};
use crate::pipeline::GROUP;
use crate::resolve::{finish_batch, KernelOutput};
use crate::{wait, NAME};
use opencl3::command_queue::CommandQueue;
use opencl3::error_codes::ClError;
use opencl3::event::Event;
use opencl3::kernel::Kernel;
use opencl3::memory::ClMem;
use opencl3::types::CL_NON_BLOCKING;
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::gpu::{describe_wait_limit, mode_code, UncertainRecord, TIMEOUT_ENV};
use shadowvol_silhouette::{BackendError, ExtractStats, Multiplicities, PreparedId};
use std::any::Any;
use std::ops::Range;
use std::ptr;
use std::time::{Duration, Instant};

/// Initial capacity of the uncertain-record buffer (records); it grows when a run needs more.
const INITIAL_UNCERTAIN_CAPACITY: usize = 4096;

/// What every batch of one `extract` call shares: the prepared scene, the object-space lights
/// of all the call's lights (per object), the accuracy mode, and the bound on each wait.
pub(crate) struct Extraction<'a> {
    /// The prepared scene.
    pub(crate) id: PreparedId,
    /// Per object, every light of the call in that object's space.
    pub(crate) obj_lights: &'a [Vec<[f32; 4]>],
    /// The accuracy mode.
    pub(crate) mode: Accuracy,
    /// The longest any single wait for the device may take.
    pub(crate) limit: Duration,
}

/// Device work that a wait gave up on (it timed out or a command failed before the rest ended),
/// with the host memory its commands may still read or write.
pub(crate) struct Pending {
    /// The last command of the abandoned submission. The queue is in order, so once this has
    /// ended (finished or failed), nothing of the submission touches host memory any more.
    pub(crate) last: Event,
    /// What that command was, for messages.
    pub(crate) what: &'static str,
    /// Host memory the commands use (light data, read-back targets), kept alive until `last`
    /// has ended, and leaked by `Drop` if it never does.
    pub(crate) _host: Vec<Box<dyn Any + Send>>,
}

/// Static zeros for the counter reset: a non-blocking write reads them whenever it runs.
static ZEROS: [u32; 2] = [0; 2];

/// What one light batch of an `extract` came to.
pub(crate) enum Batch {
    /// Its rows of the result are filled.
    Done,
    /// Its uncertain records (exact mode) need more than the device's largest allocation; the
    /// batch has two or more lights and is to be split. Its rows are untouched.
    TooManyUncertain,
}

impl OpenClBackend {
    /// How long a wait spins before it sleeps: [`wait::GPU_SPIN`], or nothing on a CPU device,
    /// whose worker threads need the cores (see the `wait` module).
    fn spin(&self) -> Duration {
        if self.device.device_type == "CPU" {
            Duration::ZERO
        } else {
            wait::GPU_SPIN
        }
    }

    /// Flushes the queue and waits for `events` in order (they were enqueued in this order on
    /// the in-order queue), all within `limit` from now, and returns the instant each was seen
    /// finished. `enqueued` is the result of enqueueing them: after a failed enqueue the commands
    /// already enqueued are waited for all the same and the enqueue error is returned.
    ///
    /// On any error, if the last command has not ended, `host` is called to take the host memory
    /// the commands use, which is kept in [`OpenClBackend::pending`] until the command ends.
    /// `events` is left empty.
    ///
    /// # Errors
    /// [`BackendError::Device`]: a failed flush, a command that ended with an error (decoded),
    /// a status query that failed, or a deadline that passed (naming [`TIMEOUT_ENV`]).
    fn wait_for(
        &mut self,
        events: &mut Vec<(&'static str, Event)>,
        enqueued: Result<(), BackendError>,
        limit: Duration,
        host: impl FnOnce() -> Vec<Box<dyn Any + Send>>,
    ) -> Result<Vec<Instant>, BackendError> {
        let waited = self.await_events(events, limit);
        let result = enqueued.and(waited);
        if result.is_err() {
            if let Some((what, last)) = events.pop() {
                if !wait::has_ended(&last) {
                    self.pending = Some(Pending {
                        last,
                        what,
                        _host: host(),
                    });
                }
            }
        }
        events.clear();
        result
    }

    /// The waiting part of [`OpenClBackend::wait_for`].
    fn await_events(
        &self,
        events: &[(&'static str, Event)],
        limit: Duration,
    ) -> Result<Vec<Instant>, BackendError> {
        if events.is_empty() {
            return Ok(Vec::new());
        }
        self.queue
            .flush()
            .map_err(|e| device_error("flushing the command queue", e))?;
        let deadline = wait::deadline_after(limit);
        let mut times = Vec::with_capacity(events.len());
        for (what, event) in events {
            match wait::wait(event, deadline, self.spin()) {
                wait::Outcome::Complete => times.push(Instant::now()),
                wait::Outcome::Failed(status) => {
                    return Err(BackendError::Device {
                        backend: NAME,
                        message: format!(
                            "{what} failed on the device with {} ({status})",
                            ClError(status)
                        ),
                    })
                }
                wait::Outcome::QueryFailed(e) => {
                    return Err(device_error(&format!("querying the status of {what}"), e))
                }
                wait::Outcome::TimedOut => {
                    return Err(BackendError::Device {
                        backend: NAME,
                        message: format!(
                            "the device did not finish {what} within {}; raise \
                             {TIMEOUT_ENV} for larger scenes or slower devices. The next extract on this backend first \
                             waits (as long again) for the unfinished work",
                            describe_wait_limit(limit),
                        ),
                    })
                }
            }
        }
        Ok(times)
    }

    /// Waits (within `limit`) for work abandoned by an earlier call, and frees the host memory
    /// it held once it has ended.
    ///
    /// # Errors
    /// [`BackendError::Device`] when it has still not ended, or its status cannot be read.
    pub(crate) fn settle(&mut self, limit: Duration) -> Result<(), BackendError> {
        let Some(p) = &self.pending else {
            return Ok(());
        };
        // Ignore a flush error here: the status query below reports the state either way.
        let _ = self.queue.flush();
        match wait::wait(&p.last, wait::deadline_after(limit), self.spin()) {
            // A failed command has ended too; if the device is broken, new work reports it.
            wait::Outcome::Complete | wait::Outcome::Failed(_) => {
                self.pending = None;
                Ok(())
            }
            wait::Outcome::QueryFailed(e) => Err(device_error(
                &format!(
                    "querying the status of {} left unfinished by an earlier extract",
                    p.what
                ),
                e,
            )),
            wait::Outcome::TimedOut => Err(BackendError::Device {
                backend: NAME,
                message: format!(
                    "the device has still not finished {} left by an earlier extract that timed \
                     out, within another {}; this backend runs no new work until it does",
                    p.what,
                    describe_wait_limit(limit)
                ),
            }),
        }
    }

    /// Writes the lights and zeroed counters, runs the kernel and reads the two counters into
    /// `counts`: three submissions, each waited for within `limit`. Returns their (upload,
    /// compute, readback) times.
    ///
    /// On an error, `flat_l` or `counts` may have been moved into [`OpenClBackend::pending`]
    /// (left empty): their memory stays with a command that had not ended.
    fn run_once(
        &mut self,
        id: PreparedId,
        flat_l: &mut Vec<f32>,
        counts: &mut Vec<u32>,
        num_lights: usize,
        mode: Accuracy,
        limit: Duration,
    ) -> Result<(Duration, Duration, Duration), BackendError> {
        let mut events = Vec::with_capacity(1);
        let t = Instant::now();
        let p = self.scenes.get_mut(id)?;
        let (lights_buf, _) = p.lights.as_mut().expect("ensured by extract");
        let (counts_buf, _) = p.counts.as_mut().expect("ensured by extract");
        // SAFETY: non-blocking writes into buffers at least that large, from `ZEROS` (static)
        // and `flat_l`, which `wait_for` keeps alive until the writes have ended (moving it into
        // `pending` if it stops waiting before that).
        let enqueued = unsafe {
            self.queue
                .enqueue_write_buffer(lights_buf, CL_NON_BLOCKING, 0, flat_l, &[])
                .map_err(|e| device_error("writing lights", e))
                .and_then(|e| {
                    events.push(("writing the lights", e));
                    self.queue
                        .enqueue_write_buffer(counts_buf, CL_NON_BLOCKING, 0, &ZEROS, &[])
                        .map_err(|e| device_error("zeroing counters", e))
                })
                .map(|e| events.push(("zeroing the counters", e)))
        };
        self.wait_for(&mut events, enqueued, limit, || {
            vec![Box::new(std::mem::take(flat_l))]
        })?;
        let upload = t.elapsed();

        let t = Instant::now();
        let p = self.scenes.get(id)?;
        // SAFETY: the kernel uses device buffers only, which `p` keeps alive.
        let enqueued = unsafe {
            enqueue_kernel(
                &self.queue,
                &self.kernel,
                self.fixed_group,
                p,
                num_lights,
                mode,
            )
        }
        .map(|e| events.push(("the silhouette kernel", e)));
        self.wait_for(&mut events, enqueued, limit, Vec::new)?;
        let compute = t.elapsed();

        let t = Instant::now();
        let p = self.scenes.get(id)?;
        let (counts_buf, _) = p.counts.as_ref().expect("ensured by extract");
        // SAFETY: a non-blocking read, no larger than the buffer, into `counts`, which
        // `wait_for` keeps alive and untouched until the read has ended (moving it into
        // `pending` if it stops waiting before that).
        let enqueued = unsafe {
            self.queue
                .enqueue_read_buffer(counts_buf, CL_NON_BLOCKING, 0, counts, &[])
                .map_err(|e| device_error("reading counters", e))
        }
        .map(|e| events.push(("reading the counters", e)));
        self.wait_for(&mut events, enqueued, limit, || {
            vec![Box::new(std::mem::take(counts))]
        })?;
        Ok((upload, compute, t.elapsed()))
    }

    /// One kernel launch over the lights `batch` of `job.obj_lights` (rerun while the
    /// uncertain-record buffer grows): uploads their object-space lights, runs the kernel, reads
    /// back the silhouette list and uncertain records, and fills the batch's rows of `out`
    /// (already reset to the scene's edges and all lights), adding the times and the uncertain
    /// count to `stats`. Every wait is bounded by `job.limit`, as in [`OpenClBackend::run_once`].
    ///
    /// Returns [`Batch::TooManyUncertain`] instead when the batch has two or more lights and its
    /// uncertain records need more than the device's largest allocation.
    ///
    /// # Errors
    /// [`BackendError::Device`] when a command fails, a wait times out, or the output is
    /// malformed; [`BackendError::Limit`] when the uncertain records of a single light do not
    /// fit the device's largest allocation.
    pub(crate) fn extract_batch(
        &mut self,
        job: &Extraction<'_>,
        batch: Range<usize>,
        out: &mut Multiplicities,
        stats: &mut ExtractStats,
    ) -> Result<Batch, BackendError> {
        let &Extraction {
            id,
            obj_lights,
            mode,
            limit,
        } = job;
        let t = Instant::now();
        let num_lights = batch.len();
        let mut flat_l = flat_light_batch(obj_lights, batch.clone())?;
        let edges = self.ensure_buffers(id, flat_l.len(), num_lights, mode)?;
        stats.upload += t.elapsed();
        let Some(counts) = self.run_until_records_fit(job, &batch, &mut flat_l, stats)? else {
            return Ok(Batch::TooManyUncertain);
        };
        let t = Instant::now();
        let (raw_sil, raw_unc) = self.read_lists(id, &counts, edges * num_lights, limit)?;
        stats.readback += t.elapsed();
        let t = Instant::now();
        let output = KernelOutput {
            silhouettes: raw_sil
                .chunks_exact(2)
                .map(|c| (c[0] as u32, c[1]))
                .collect(),
            uncertain: UncertainRecord::read_all(&raw_unc),
            counts,
        };
        stats.uncertain += output.uncertain.len() as u64;
        let p = self.scenes.get(id)?;
        finish_batch(&p.index, obj_lights, batch, output, out, NAME)?;
        stats.host_resolve += t.elapsed();
        Ok(Batch::Done)
    }

    /// Makes the per-frame buffers of scene `id` large enough for a launch of `num_lights`
    /// lights (`light_floats` floats of lights) in `mode`: lights, counters, silhouette list,
    /// and uncertain records (exact mode starts with room for
    /// [`INITIAL_UNCERTAIN_CAPACITY`] records). Returns the scene's edge count.
    fn ensure_buffers(
        &mut self,
        id: PreparedId,
        light_floats: usize,
        num_lights: usize,
        mode: Accuracy,
    ) -> Result<usize, BackendError> {
        let max_records = self.max_uncertain_records();
        let ctx = &self.context;
        let p = self.scenes.get_mut(id)?;
        let edges = p.index.edge_count();
        ensure(ctx, &mut p.lights, light_floats, "the light buffer")?;
        ensure(ctx, &mut p.counts, 2, "the counters")?;
        ensure(
            ctx,
            &mut p.sil,
            2 * edges * num_lights,
            "the silhouette lists",
        )?;
        let initial = INITIAL_UNCERTAIN_CAPACITY.min(max_records);
        if mode == Accuracy::Exact && p.unc_records < initial {
            ensure(
                ctx,
                &mut p.unc,
                UncertainRecord::WORDS * initial,
                "the uncertain records",
            )?;
            p.unc_records = initial;
        } else if p.unc.is_none() {
            ensure(
                ctx,
                &mut p.unc,
                UncertainRecord::WORDS,
                "the uncertain records",
            )?;
            p.unc_records = 1;
        }
        Ok(edges)
    }

    /// Runs the launch of the lights `batch` until its uncertain records fit the buffer, growing
    /// the buffer between runs, adding the times to `stats`, and returns the two counters
    /// (uncertain records, silhouette entries). `None` when the batch has two or more lights
    /// and its records need more than the device's largest allocation (the caller splits it).
    ///
    /// # Errors
    /// As [`OpenClBackend::run_once`]; [`BackendError::Limit`] when the records of a single
    /// light do not fit the device's largest allocation.
    fn run_until_records_fit(
        &mut self,
        job: &Extraction<'_>,
        batch: &Range<usize>,
        flat_l: &mut Vec<f32>,
        stats: &mut ExtractStats,
    ) -> Result<Option<Vec<u32>>, BackendError> {
        let (id, num_lights) = (job.id, batch.len());
        let max_records = self.max_uncertain_records();
        let mut counts = vec![0u32; 2];
        loop {
            let (up, comp, read) =
                self.run_once(id, flat_l, &mut counts, num_lights, job.mode, job.limit)?;
            stats.upload += up;
            stats.compute += comp;
            stats.readback += read;
            let p = self.scenes.get(id)?;
            let needed = counts[0] as usize;
            // (The buffer never exceeds the largest allocation; the `min` matters only when
            // tests lower the pretended limit after the buffer grew.)
            if needed <= p.unc_records.min(max_records) {
                return Ok(Some(counts));
            }
            if needed > max_records {
                if num_lights > 1 {
                    return Ok(None);
                }
                return Err(BackendError::Limit {
                    backend: NAME,
                    message: format!(
                        "exact mode left {needed} (edge, OV, light) records of light {} \
                         uncertain; they need {} bytes, more than the device's largest \
                         allocation ({} bytes); split the scene",
                        batch.start,
                        (needed * UncertainRecord::WORDS * 4) as u64,
                        self.max_alloc
                    ),
                });
            }
            // More uncertain records than the buffer holds: grow it and run again.
            let records = needed.next_power_of_two().min(max_records);
            let ctx = &self.context;
            let p = self.scenes.get_mut(id)?;
            ensure(
                ctx,
                &mut p.unc,
                UncertainRecord::WORDS * records,
                "the uncertain records",
            )?;
            p.unc_records = records;
        }
    }

    /// Reads back the silhouette list and the uncertain records the `counts` name (at most
    /// `max_entries` list entries: one per (edge, light)), as raw words, with one bounded wait.
    fn read_lists(
        &mut self,
        id: PreparedId,
        counts: &[u32],
        max_entries: usize,
        limit: Duration,
    ) -> Result<(Vec<i32>, Vec<u32>), BackendError> {
        let p = self.scenes.get(id)?;
        // At most one entry per (edge, light): a larger count is a device fault, caught by
        // `finish_batch` when fewer entries than counted come back.
        let mut raw_sil = vec![0i32; 2 * (counts[1] as usize).min(max_entries)];
        let mut raw_unc = vec![0u32; UncertainRecord::WORDS * counts[0] as usize];
        let mut events = Vec::with_capacity(2);
        let (sil_buf, _) = p.sil.as_ref().expect("ensured");
        let (unc_buf, _) = p.unc.as_ref().expect("ensured");
        // SAFETY: non-blocking reads into slices that `wait_for` keeps alive and untouched until
        // the reads have ended (moving them into `pending` when it stops waiting before that);
        // the lengths lie inside the buffers.
        let enqueued = unsafe {
            (|| {
                if !raw_sil.is_empty() {
                    events.push((
                        "reading the silhouette list",
                        self.queue
                            .enqueue_read_buffer(sil_buf, CL_NON_BLOCKING, 0, &mut raw_sil, &[])
                            .map_err(|e| device_error("reading the silhouette list", e))?,
                    ));
                }
                if !raw_unc.is_empty() {
                    events.push((
                        "reading the uncertain records",
                        self.queue
                            .enqueue_read_buffer(unc_buf, CL_NON_BLOCKING, 0, &mut raw_unc, &[])
                            .map_err(|e| device_error("reading uncertain records", e))?,
                    ));
                }
                Ok(())
            })()
        };
        self.wait_for(&mut events, enqueued, limit, || {
            vec![
                Box::new(std::mem::take(&mut raw_sil)),
                Box::new(std::mem::take(&mut raw_unc)),
            ]
        })?;
        Ok((raw_sil, raw_unc))
    }
}

/// Sets the kernel's arguments for prepared scene `p` and enqueues it over (edges × lights).
///
/// # Safety
/// The kernel must be [`KERNEL_NAME`](crate::KERNEL_NAME) of [`KERNEL_SOURCE`](crate::KERNEL_SOURCE) (or a source with the same
/// signature), and `p`'s buffers must stay alive until the kernel has ended (dropping them is
/// fine in OpenCL: a released buffer lives on until the commands using it have finished).
unsafe fn enqueue_kernel(
    queue: &CommandQueue,
    k: &Kernel,
    fixed_group: bool,
    p: &Prepared,
    num_lights: usize,
    mode: Accuracy,
) -> Result<Event, BackendError> {
    let edges = p.index.edge_count();
    let set = |i: u32, r: Result<(), ClError>| {
        r.map_err(|e| device_error(&format!("setting kernel argument {i}"), e))
    };
    let (lights_buf, _) = p.lights.as_ref().expect("ensured by extract");
    let (counts_buf, _) = p.counts.as_ref().expect("ensured by extract");
    let (sil_buf, _) = p.sil.as_ref().expect("ensured by extract");
    let (unc_buf, _) = p.unc.as_ref().expect("ensured by extract");
    let (ne, nl, code, cap) = (
        edges as u32,
        num_lights as u32,
        mode_code(mode),
        p.unc_records as u32,
    );
    // SAFETY: argument types and order match `silhouette` in kernels/silhouette.cl.
    unsafe {
        set(0, k.set_arg(0, &p.pos.get()))?;
        set(1, k.set_arg(1, &p.edges.get()))?;
        set(2, k.set_arg(2, &p.ovs.get()))?;
        set(3, k.set_arg(3, &lights_buf.get()))?;
        set(4, k.set_arg(4, &ne))?;
        set(5, k.set_arg(5, &nl))?;
        set(6, k.set_arg(6, &code))?;
        set(7, k.set_arg(7, &counts_buf.get()))?;
        set(8, k.set_arg(8, &sil_buf.get()))?;
        set(9, k.set_arg(9, &unc_buf.get()))?;
        set(10, k.set_arg(10, &cap))?;
        let global = [edges.div_ceil(GROUP) * GROUP, num_lights];
        let local = [GROUP, 1];
        let local_ptr = if fixed_group {
            local.as_ptr()
        } else {
            ptr::null()
        };
        queue
            .enqueue_nd_range_kernel(k.get(), 2, ptr::null(), global.as_ptr(), local_ptr, &[])
            .map_err(|e| device_error("enqueueing the silhouette kernel", e))
    }
}
