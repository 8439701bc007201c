//! What an extraction puts on the device: the device buffers of a prepared scene (the shared
//! [`SceneLayout`](shadowvol_silhouette::gpu::SceneLayout) uploaded once, and the per-frame
//! buffers grown on demand), the kernel's light buffer, and how many lights fit one launch
//! within the device's largest allocation.

use crate::backend::OpenClBackend;
use crate::device::device_error;
use crate::NAME;
use opencl3::context::Context;
use opencl3::memory::{Buffer, CL_MEM_COPY_HOST_PTR, CL_MEM_READ_WRITE};
use opencl3::types::cl_mem_flags;
use shadowvol_silhouette::gpu::{SceneIndex, UncertainRecord};
use shadowvol_silhouette::{BackendError, PreparedBytes};
use std::ops::Range;
use std::ptr;

/// The lights `batch` of `object_lights` flattened for one kernel launch: 4 `f32` per (object,
/// light of the batch), index `object * batch.len() + (light - batch.start)`.
///
/// # Errors
/// [`BackendError::InvalidInput`] when `batch` is not a range of every object's lights.
pub fn flat_light_batch(
    object_lights: &[Vec<[f32; 4]>],
    batch: Range<usize>,
) -> Result<Vec<f32>, BackendError> {
    let mut flat = Vec::with_capacity(object_lights.len() * batch.len() * 4);
    for (i, per_object) in object_lights.iter().enumerate() {
        let lights = per_object.get(batch.clone()).ok_or_else(|| {
            BackendError::InvalidInput(format!(
                "light batch {batch:?} out of range: object {i} has {} lights",
                per_object.len()
            ))
        })?;
        flat.extend(lights.iter().flatten());
    }
    Ok(flat)
}

/// Device buffers of one prepared scene.
pub(crate) struct Prepared {
    /// Each object's transform, world from object.
    pub(crate) transforms: Vec<glam::Affine3A>,
    /// The objects in the uploaded layout's numbering, over the scene's edge tables: what the
    /// host's exact decisions read (the layout itself is dropped once uploaded).
    pub(crate) index: SceneIndex,
    /// Bytes of the three static buffers (positions, edge records, OVs; at least one element
    /// each).
    pub(crate) static_bytes: u64,
    pub(crate) pos: Buffer<f32>,
    pub(crate) edges: Buffer<u32>,
    pub(crate) ovs: Buffer<u32>,
    /// Per-frame buffers, grown on demand: (buffer, capacity in elements).
    pub(crate) lights: Option<(Buffer<f32>, usize)>,
    pub(crate) counts: Option<(Buffer<u32>, usize)>,
    pub(crate) sil: Option<(Buffer<i32>, usize)>,
    pub(crate) unc: Option<(Buffer<u32>, usize)>,
    pub(crate) unc_records: usize,
}

impl Prepared {
    /// What the scene holds beyond its edge tables: the index on the host, and the device
    /// buffers (the scene's, at least one element each, and the per-frame ones at their
    /// capacity).
    pub(crate) fn bytes(&self) -> PreparedBytes {
        fn cap<T>(b: &Option<(Buffer<T>, usize)>) -> u64 {
            b.as_ref()
                .map_or(0, |(_, n)| (n * std::mem::size_of::<T>()) as u64)
        }
        let device = self.static_bytes
            + cap(&self.lights)
            + cap(&self.counts)
            + cap(&self.sil)
            + cap(&self.unc);
        PreparedBytes {
            host: self.index.heap_bytes() + shadowvol_silhouette::vec_bytes(&self.transforms),
            device,
        }
    }
}

/// Creates a buffer holding a copy of `data` (at least one element: OpenCL has no empty buffers).
pub(crate) fn upload<T: Copy + Default>(
    context: &Context,
    flags: cl_mem_flags,
    data: &[T],
    what: &str,
) -> Result<Buffer<T>, BackendError> {
    let one = [T::default()];
    let data = if data.is_empty() { &one[..] } else { data };
    // SAFETY: `data` is valid for `data.len()` elements; COPY_HOST_PTR copies it before return.
    unsafe {
        Buffer::<T>::create(
            context,
            flags | CL_MEM_COPY_HOST_PTR,
            data.len(),
            data.as_ptr().cast_mut().cast(),
        )
    }
    .map_err(|e| device_error(&format!("uploading {what} ({} elements)", data.len()), e))
}

/// Makes sure `slot` holds a read-write buffer of at least `len` elements.
pub(crate) fn ensure<T>(
    context: &Context,
    slot: &mut Option<(Buffer<T>, usize)>,
    len: usize,
    what: &str,
) -> Result<(), BackendError> {
    let len = len.max(1);
    if slot.as_ref().is_some_and(|(_, cap)| *cap >= len) {
        return Ok(());
    }
    // SAFETY: no host pointer; the buffer is written by the device or by enqueued writes.
    let buf = unsafe { Buffer::<T>::create(context, CL_MEM_READ_WRITE, len, ptr::null_mut()) }
        .map_err(|e| device_error(&format!("allocating {what} ({len} elements)"), e))?;
    *slot = Some((buf, len));
    Ok(())
}

impl OpenClBackend {
    /// The most records the uncertain-record buffer (12 bytes each) may hold: the device's
    /// largest allocation, at least 1.
    pub(crate) fn max_uncertain_records(&self) -> usize {
        usize::try_from(self.max_alloc / (UncertainRecord::WORDS as u64 * 4))
            .unwrap_or(usize::MAX)
            .max(1)
    }

    /// Lights per kernel launch for a scene of `edges` edges (at least 1), `objects` objects
    /// and `ovs` opposite-vertex slots: as many as the silhouette list (8 bytes per edge and
    /// light) and the light buffer (16 bytes per object and light) allow within the device's
    /// largest allocation, with `light * edges + edge` and the uncertain-record counter (at most
    /// one per OV slot and light) within `u32`, and at most
    /// [`OpenClOptions::max_lights_per_batch`](crate::OpenClOptions::max_lights_per_batch).
    ///
    /// # Errors
    /// [`BackendError::Limit`] with the numbers when not even one light fits.
    pub(crate) fn lights_per_batch(
        &self,
        edges: usize,
        objects: usize,
        ovs: usize,
    ) -> Result<usize, BackendError> {
        let sil = 8 * edges as u64;
        let light = 16 * objects as u64;
        let index = u64::from(u32::MAX);
        let n = shadowvol_silhouette::gpu::lights_per_batch(
            &[
                (self.max_alloc, sil),
                (self.max_alloc, light),
                (index, edges as u64),
                (index, ovs as u64),
            ],
            self.max_lights_per_batch,
        );
        if n == 0 {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "one light alone does not fit a kernel launch: its silhouette list needs \
                     {sil} bytes for {edges} edges and its light buffer {light} bytes for \
                     {objects} objects, but the device's largest allocation is {} bytes; split \
                     the scene",
                    self.max_alloc
                ),
            });
        }
        Ok(n)
    }

    pub(crate) fn check_alloc(
        &self,
        what: &str,
        bytes: usize,
        hint: &str,
    ) -> Result<(), BackendError> {
        if bytes as u64 > self.max_alloc {
            return Err(BackendError::Limit {
                backend: NAME,
                message: format!(
                    "{what} needs {bytes} bytes, more than the device's largest allocation \
                     ({} bytes){hint}",
                    self.max_alloc
                ),
            });
        }
        Ok(())
    }
}
