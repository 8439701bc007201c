//! The scene's edge tables on a device: uploaded in bounded chunks straight from the tables,
//! one buffer per [`TableBuffer`], bound as `shaders/silhouette.wgsl`'s group 0. The `wgpu`
//! backend and the renderer's GPU-resident pass upload a scene this way.

use shadowvol_silhouette::gpu::{TableBuffer, TableWriter};

/// A bind group entry for the whole of `buffer` at `binding`.
#[must_use]
pub fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// Creates buffer `b` of the tables `writer` writes, with `usage` (and `COPY_DST`), and fills it
/// in chunks of 1 MiB written straight from the scene's edge tables; every 4 MiB it submits
/// and calls `wait` with the submission, which must wait for the device, so that the staging
/// memory of the copies stays bounded whatever the scene's size. The last chunk is waited for
/// too. An empty buffer is 16 zero bytes (a binding cannot be empty).
///
/// No host copy of the scene is made: this is how the `wgpu` backend and the renderer's
/// GPU-resident pass upload a scene.
///
/// # Errors
/// The first error of `wait`. The caller checks the buffer against the device's limits
/// ([`TableWriter::bytes`]) and catches validation errors in an error scope.
pub fn upload_table<E>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    writer: &TableWriter<'_>,
    b: TableBuffer,
    usage: wgpu::BufferUsages,
    wait: &mut impl FnMut(wgpu::SubmissionIndex) -> Result<(), E>,
) -> Result<wgpu::Buffer, E> {
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(b.label()),
        size: writer.bytes(b).max(16),
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let per_chunk = (UPLOAD_CHUNK_WORDS / b.words()).max(1);
    let mut words = Vec::with_capacity(per_chunk * b.words());
    let (mut first, mut staged) = (0, 0);
    while first < writer.elements(b) {
        let n = per_chunk.min(writer.elements(b) - first);
        words.clear();
        writer.write(b, first, n, &mut words);
        let offset = (first * b.words() * 4) as u64;
        queue.write_buffer(&buffer, offset, bytemuck::cast_slice(&words));
        first += n;
        staged += 1;
        if staged % CHUNKS_PER_WAIT == 0 {
            wait(queue.submit([]))?;
        }
    }
    // The last copies run at this submission; waiting frees their staging memory.
    wait(queue.submit([]))?;
    Ok(buffer)
}

/// Words (4 bytes) of one chunk of a static buffer's upload: 1 MiB.
const UPLOAD_CHUNK_WORDS: usize = 1 << 18;

/// Chunks staged between two waits for the device (4 MiB of staging memory at most).
const CHUNKS_PER_WAIT: usize = 4;

/// The scene's buffers as `shaders/silhouette.wgsl` binds them, one per [`TableBuffer`], uploaded
/// once per prepared scene by the `wgpu` backend and by the renderer's GPU-resident pass (cheap
/// to clone: wgpu buffers are shared handles).
#[derive(Debug, Clone)]
pub struct TableBuffers {
    /// [`TableBuffer::Positions`], binding 1.
    pub positions: wgpu::Buffer,
    /// [`TableBuffer::Edges`], binding 2.
    pub edges: wgpu::Buffer,
    /// [`TableBuffer::OvRefs`], binding 3.
    pub ov_refs: wgpu::Buffer,
    /// [`TableBuffer::Triangles`], binding 9.
    pub tris: wgpu::Buffer,
    /// [`TableBuffer::OvOffsets`], binding 10.
    pub ov_offsets: wgpu::Buffer,
    /// [`TableBuffer::Objects`], binding 12.
    pub objects: wgpu::Buffer,
    /// [`TableBuffer::OvVertices`], binding 13, where `has_ov_vertices`; else 16 bytes never
    /// read (the binding must exist).
    pub ov_vertices: wgpu::Buffer,
    /// Whether `ov_vertices` holds the OVs: `original`'s edge step may then be built with
    /// [`OV_VERTICES_CONSTANT`](crate::shaders::OV_VERTICES_CONSTANT).
    pub has_ov_vertices: bool,
}

impl TableBuffers {
    /// Uploads every [`TableBuffer`] of the scene `writer` writes, with [`upload_table`], and
    /// [`TableBuffer::OvVertices`] too when `with_ov_vertices`. `usage` is added to each
    /// buffer's.
    ///
    /// # Errors
    /// The first error of `wait` (see [`upload_table`]).
    pub fn upload<E>(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        writer: &TableWriter<'_>,
        usage: wgpu::BufferUsages,
        with_ov_vertices: bool,
        mut wait: impl FnMut(wgpu::SubmissionIndex) -> Result<(), E>,
    ) -> Result<Self, E> {
        let mut up = |b| upload_table(device, queue, writer, b, usage, &mut wait);
        Ok(Self {
            positions: up(TableBuffer::Positions)?,
            edges: up(TableBuffer::Edges)?,
            ov_refs: up(TableBuffer::OvRefs)?,
            tris: up(TableBuffer::Triangles)?,
            ov_offsets: up(TableBuffer::OvOffsets)?,
            objects: up(TableBuffer::Objects)?,
            ov_vertices: if with_ov_vertices {
                up(TableBuffer::OvVertices)?
            } else {
                Self::no_ov_vertices(device)
            },
            has_ov_vertices: with_ov_vertices,
        })
    }

    /// The placeholder bound at binding 13 when the scene has no OV vertex list.
    #[must_use]
    pub fn no_ov_vertices(device: &wgpu::Device) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("no opposite vertices"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    }

    /// Every buffer, for counting their bytes.
    #[must_use]
    pub fn all(&self) -> [&wgpu::Buffer; 7] {
        [
            &self.positions,
            &self.edges,
            &self.ov_refs,
            &self.tris,
            &self.ov_offsets,
            &self.objects,
            &self.ov_vertices,
        ]
    }

    /// Their entries in a bind group of `shaders/silhouette.wgsl`'s group 0 (bindings 1, 2, 3,
    /// 9, 10, 12 and 13).
    #[must_use]
    pub fn entries(&self) -> [wgpu::BindGroupEntry<'_>; 7] {
        [
            entry(1, &self.positions),
            entry(2, &self.edges),
            entry(3, &self.ov_refs),
            entry(9, &self.tris),
            entry(10, &self.ov_offsets),
            entry(12, &self.objects),
            entry(13, &self.ov_vertices),
        ]
    }
}
