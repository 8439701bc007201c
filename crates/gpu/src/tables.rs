//! The scene's edge tables on a device, packed into one storage buffer of `u32` words (binding
//! 1 of `shaders/silhouette.wgsl`'s group 0) with the word offset of each table in a small
//! uniform (binding 2): one storage binding instead of one per table, so that the kernels fit
//! `wgpu::Limits::default()` (8 storage buffers per stage). The tables are uploaded in bounded
//! chunks straight from the scene's edge tables. The `wgpu` backend and the renderer's
//! GPU-resident pass upload a scene this way.

use shadowvol_silhouette::gpu::{TableBuffer, TableLayout, TableWriter, FIRST_VERTEX};

/// A bind group entry for the whole of `buffer` at `binding`.
#[must_use]
pub fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// One table of the packed buffer: a [`TableBuffer`] (its words as [`TableBuffer::words`]
/// says), or the object of each global vertex (one word per vertex; the GPU-resident pass's).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// A table of [`TableBuffer`].
    Table(TableBuffer),
    /// Per global vertex, its object.
    VertexObjects,
}

impl Section {
    /// The sections in their order in the packed buffer (the fields of [`TableOffsets`]).
    pub const ORDER: [Section; 8] = [
        Section::Table(TableBuffer::Objects),
        Section::Table(TableBuffer::Positions),
        Section::Table(TableBuffer::Edges),
        Section::Table(TableBuffer::OvOffsets),
        Section::Table(TableBuffer::OvRefs),
        Section::Table(TableBuffer::Triangles),
        Section::Table(TableBuffer::OvVertices),
        Section::VertexObjects,
    ];

    /// Words per element.
    #[must_use]
    pub fn words(self) -> usize {
        match self {
            Section::Table(b) => b.words(),
            Section::VertexObjects => 1,
        }
    }

    /// Its name in messages.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Section::Table(b) => b.label(),
            Section::VertexObjects => "vertex objects",
        }
    }
}

/// The optional sections a packed buffer holds besides [`TableBuffer::ALL`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Extras {
    /// [`TableBuffer::OvVertices`] (the `wgpu` backend's `original` edge step on small scenes).
    pub ov_vertices: bool,
    /// [`Section::VertexObjects`] (the renderer's GPU-resident pass).
    pub vertex_objects: bool,
}

/// The word offset of each table in the packed buffer, in [`Section::ORDER`]: the uniform
/// `TableOffsets` of `shaders/silhouette.wgsl` (and `RTables` of `shaders/resident_draw.wgsl`),
/// field for field. An absent optional section has the offset of the end of the tables and no
/// word (it is never read).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TableOffsets {
    /// [`TableBuffer::Objects`].
    pub objects: u32,
    /// [`TableBuffer::Positions`] (`f32` bits).
    pub positions: u32,
    /// [`TableBuffer::Edges`].
    pub edges: u32,
    /// [`TableBuffer::OvOffsets`].
    pub ov_offsets: u32,
    /// [`TableBuffer::OvRefs`].
    pub ov_refs: u32,
    /// [`TableBuffer::Triangles`].
    pub tris: u32,
    /// [`TableBuffer::OvVertices`].
    pub ov_vertices: u32,
    /// [`Section::VertexObjects`].
    pub vertex_objects: u32,
}

impl TableOffsets {
    /// Bytes of the uniform.
    pub const BYTES: u64 = 32;

    /// The uniform's words, in [`Section::ORDER`].
    #[must_use]
    pub fn to_words(self) -> [u32; 8] {
        [
            self.objects,
            self.positions,
            self.edges,
            self.ov_offsets,
            self.ov_refs,
            self.tris,
            self.ov_vertices,
            self.vertex_objects,
        ]
    }

    fn from_words(w: [u32; 8]) -> Self {
        Self {
            objects: w[0],
            positions: w[1],
            edges: w[2],
            ov_offsets: w[3],
            ov_refs: w[4],
            tris: w[5],
            ov_vertices: w[6],
            vertex_objects: w[7],
        }
    }
}

/// Where each table of a scene goes in the packed buffer, and its size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TablePacking {
    /// The word offsets (the uniform).
    pub at: TableOffsets,
    /// Elements of each section in [`Section::ORDER`] (0 for an absent one).
    pub elements: [usize; 8],
    /// The optional sections it holds.
    pub extras: Extras,
    /// Words of the whole buffer.
    pub words: u64,
}

impl TablePacking {
    /// The packing of tables of `elements(section)` elements, with the optional sections of
    /// `extras`.
    #[must_use]
    pub fn of_elements(elements: impl Fn(Section) -> usize, extras: Extras) -> Self {
        let mut counts = [0; 8];
        let mut at = [0u32; 8];
        let mut words = 0u64;
        for (k, s) in Section::ORDER.into_iter().enumerate() {
            let present = match s {
                Section::Table(TableBuffer::OvVertices) => extras.ov_vertices,
                Section::VertexObjects => extras.vertex_objects,
                Section::Table(_) => true,
            };
            // Offsets past u32 are refused by `check`; saturate rather than wrap meanwhile.
            at[k] = u32::try_from(words).unwrap_or(u32::MAX);
            if present {
                counts[k] = elements(s);
                words += (counts[k] * s.words()) as u64;
            }
        }
        Self {
            at: TableOffsets::from_words(at),
            elements: counts,
            extras,
            words,
        }
    }

    /// The packing of the scene `writer` writes.
    #[must_use]
    pub fn new(writer: &TableWriter<'_>, extras: Extras) -> Self {
        Self::of_elements(
            |s| match s {
                Section::Table(b) => writer.elements(b),
                Section::VertexObjects => writer.elements(TableBuffer::Positions),
            },
            extras,
        )
    }

    /// The packing of a laid-out scene (with [`Section::VertexObjects`] when `vertex_objects`
    /// holds them; no OV vertex list).
    #[must_use]
    pub fn of_layout(layout: &TableLayout, vertex_objects: bool) -> Self {
        Self::of_elements(
            |s| match s {
                Section::Table(TableBuffer::Objects) => layout.objects.len(),
                Section::Table(TableBuffer::Positions) | Section::VertexObjects => {
                    layout.positions.len() / 3
                }
                Section::Table(TableBuffer::Edges) => layout.edges.len(),
                Section::Table(TableBuffer::OvOffsets) => layout.ov_offsets.len(),
                Section::Table(TableBuffer::OvRefs | TableBuffer::OvVertices) => {
                    layout.ov_refs.len()
                }
                Section::Table(TableBuffer::Triangles) => layout.tris.len(),
            },
            Extras {
                ov_vertices: false,
                vertex_objects,
            },
        )
    }

    /// Bytes of the packed buffer.
    #[must_use]
    pub fn bytes(&self) -> u64 {
        4 * self.words
    }

    /// `Err` naming the limit when the packed buffer exceeds `max_binding` bytes (the device's
    /// `max_storage_buffer_binding_size`, the smaller of it and `max_buffer_size` where the
    /// caller passes that) or its words cannot be indexed with `u32`; `who` names the kernels.
    ///
    /// # Errors
    /// The message, with the bytes of every table.
    pub fn check(&self, who: &str, max_binding: u64) -> Result<(), String> {
        let over_u32 = self.words > u64::from(u32::MAX);
        if self.bytes() <= max_binding && !over_u32 {
            return Ok(());
        }
        let tables = Section::ORDER
            .iter()
            .zip(self.elements)
            .filter(|&(_, n)| n > 0)
            .map(|(s, n)| format!("{} {}", s.label(), 4 * n * s.words()))
            .collect::<Vec<_>>()
            .join(", ");
        Err(if over_u32 {
            format!(
                "the scene's tables take {} words, but {who} index one binding with u32 words ({tables} bytes)",
                self.words
            )
        } else {
            format!(
                "the scene's tables, packed into one storage binding, take {} bytes ({tables}); the device binds at most {max_binding} (max_storage_buffer_binding_size)",
                self.bytes()
            )
        })
    }

    /// The whole packed buffer on the host, written from `writer` (what [`TableBuffers::upload`]
    /// writes in chunks).
    #[must_use]
    pub fn pack(&self, writer: &TableWriter<'_>) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.words as usize);
        for (k, s) in Section::ORDER.into_iter().enumerate() {
            write_section(writer, s, 0, self.elements[k], &mut out);
        }
        out
    }

    /// The whole packed buffer of a laid-out scene (`vertex_objects` as [`Self::of_layout`]
    /// was told).
    #[must_use]
    pub fn pack_layout(&self, layout: &TableLayout, vertex_objects: &[u32]) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.words as usize);
        out.extend(layout.objects.iter().flatten());
        out.extend(layout.positions.iter().map(|p| p.to_bits()));
        out.extend(layout.edges.iter().flatten());
        out.extend(&layout.ov_offsets);
        out.extend(&layout.ov_refs);
        out.extend(layout.tris.iter().flatten());
        if self.extras.ov_vertices {
            out.extend(layout.ov_refs.iter().map(|&r| layout.ref_vertex(r)));
        }
        if self.extras.vertex_objects {
            out.extend(vertex_objects);
        }
        debug_assert_eq!(out.len() as u64, self.words);
        out
    }
}

/// Appends elements `first..first + count` of section `s` of `writer`'s scene.
fn write_section(
    writer: &TableWriter<'_>,
    s: Section,
    first: usize,
    count: usize,
    out: &mut Vec<u32>,
) {
    match s {
        Section::Table(b) => writer.write(b, first, count, out),
        Section::VertexObjects => {
            let objects = writer.objects();
            let mut v = first;
            let end = first + count;
            while v < end {
                let oi = objects
                    .partition_point(|o| o[FIRST_VERTEX] as usize <= v)
                    .saturating_sub(1);
                let stop = end.min(objects[oi + 1][FIRST_VERTEX] as usize);
                out.extend(std::iter::repeat_n(oi as u32, stop - v));
                v = stop;
            }
        }
    }
}

/// The packed tables read as the kernels read them: the CPU twin of the accessors of
/// `shaders/silhouette.wgsl` (`position`, `load_edge`, `ov_ref`, `tri_vertex`, `object_base`,
/// `ov_vertex`) and of `shaders/resident_draw.wgsl` (`r_vertex_object`).
#[derive(Debug, Clone, Copy)]
pub struct PackedView<'a> {
    /// The packed words.
    pub words: &'a [u32],
    /// The offsets.
    pub at: TableOffsets,
}

impl PackedView<'_> {
    /// `position(id)`.
    #[must_use]
    pub fn position(&self, id: u32) -> [f32; 3] {
        let k = (self.at.positions + 3 * id) as usize;
        [0, 1, 2].map(|i| f32::from_bits(self.words[k + i]))
    }

    /// `load_edge(e)`: ends `(a, b)` and OV slots `[begin, end)`.
    #[must_use]
    pub fn edge(&self, e: u32) -> [u32; 4] {
        let k = (self.at.edges + 2 * e) as usize;
        let o = (self.at.ov_offsets + e) as usize;
        [
            self.words[k],
            self.words[k + 1],
            self.words[o],
            self.words[o + 1],
        ]
    }

    /// `ov_ref(k)`.
    #[must_use]
    pub fn ov_ref(&self, k: u32) -> u32 {
        self.words[(self.at.ov_refs + k) as usize]
    }

    /// `tri_vertex(t, r)`.
    #[must_use]
    pub fn tri_vertex(&self, t: u32, r: u32) -> u32 {
        self.words[(self.at.tris + 3 * t + r) as usize]
    }

    /// `object_base(obj, field)`.
    #[must_use]
    pub fn object_base(&self, obj: u32, field: u32) -> u32 {
        self.words[(self.at.objects + 4 * obj + field) as usize]
    }

    /// `ov_vertex(k)`.
    #[must_use]
    pub fn ov_vertex(&self, k: u32) -> u32 {
        self.words[(self.at.ov_vertices + k) as usize]
    }

    /// `r_vertex_object(v)`.
    #[must_use]
    pub fn vertex_object(&self, v: u32) -> u32 {
        self.words[(self.at.vertex_objects + v) as usize]
    }
}

/// Writes section `s` of the tables `writer` writes into `buffer` from word `base`, in chunks
/// of 1 MiB; every 4 MiB it submits and calls `wait` with the submission, which must wait for
/// the device, so that the staging memory of the copies stays bounded whatever the scene's
/// size.
fn upload_section<E>(
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    (writer, s, elements, base): (&TableWriter<'_>, Section, usize, u64),
    staged: &mut usize,
    wait: &mut impl FnMut(wgpu::SubmissionIndex) -> Result<(), E>,
) -> Result<(), E> {
    let per_chunk = (UPLOAD_CHUNK_WORDS / s.words()).max(1);
    let mut words = Vec::with_capacity(per_chunk * s.words());
    let mut first = 0;
    while first < elements {
        let n = per_chunk.min(elements - first);
        words.clear();
        write_section(writer, s, first, n, &mut words);
        let offset = 4 * (base + (first * s.words()) as u64);
        queue.write_buffer(buffer, offset, bytemuck::cast_slice(&words));
        first += n;
        *staged += 1;
        if staged.is_multiple_of(CHUNKS_PER_WAIT) {
            wait(queue.submit([]))?;
        }
    }
    Ok(())
}

/// Words (4 bytes) of one chunk of the upload: 1 MiB.
const UPLOAD_CHUNK_WORDS: usize = 1 << 18;

/// Chunks staged between two waits for the device (4 MiB of staging memory at most).
const CHUNKS_PER_WAIT: usize = 4;

/// The scene's tables as `shaders/silhouette.wgsl` binds them: the packed buffer (binding 1)
/// and its offsets (binding 2), uploaded once per prepared scene by the `wgpu` backend and by
/// the renderer's GPU-resident pass (cheap to clone: wgpu buffers are shared handles).
#[derive(Debug, Clone)]
pub struct TableBuffers {
    /// Every table, packed ([`TablePacking`]); binding 1. At least 16 bytes.
    pub tables: wgpu::Buffer,
    /// The [`TableOffsets`] uniform; binding 2.
    pub offsets: wgpu::Buffer,
    /// Where each table is.
    pub packing: TablePacking,
}

impl TableBuffers {
    /// Uploads every [`TableBuffer`] of the scene `writer` writes and the sections of `extras`,
    /// packed, in chunks of 1 MiB written straight from the scene's edge tables (no host copy
    /// of the scene); every 4 MiB it submits and calls `wait` with the submission, which must
    /// wait for the device, so that the staging memory stays bounded. `usage` is added to the
    /// packed buffer's (`STORAGE | COPY_DST`).
    ///
    /// # Errors
    /// The first error of `wait`. The caller checks the packing against the device's limits
    /// ([`TablePacking::check`]) and catches validation errors in an error scope.
    pub fn upload<E>(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        writer: &TableWriter<'_>,
        usage: wgpu::BufferUsages,
        extras: Extras,
        mut wait: impl FnMut(wgpu::SubmissionIndex) -> Result<(), E>,
    ) -> Result<Self, E> {
        let packing = TablePacking::new(writer, extras);
        let tables = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene tables"),
            size: packing.bytes().max(16),
            usage: usage | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut staged = 0;
        let offsets = packing.at.to_words();
        for (k, s) in Section::ORDER.into_iter().enumerate() {
            let job = (writer, s, packing.elements[k], u64::from(offsets[k]));
            upload_section(queue, &tables, job, &mut staged, &mut wait)?;
        }
        // The last copies run at this submission; waiting frees their staging memory.
        wait(queue.submit([]))?;
        Ok(Self {
            tables,
            offsets: Self::offsets_uniform(device, packing.at),
            packing,
        })
    }

    /// The buffers of packed `words` (from [`TablePacking::pack_layout`]) laid out as
    /// `packing`.
    #[must_use]
    pub fn from_words(device: &wgpu::Device, words: &[u32], packing: TablePacking) -> Self {
        use wgpu::util::DeviceExt;
        let padded = [0u32; 4];
        let words = if words.is_empty() { &padded[..] } else { words };
        let tables = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene tables"),
            contents: bytemuck::cast_slice(words),
            usage: wgpu::BufferUsages::STORAGE,
        });
        Self {
            tables,
            offsets: Self::offsets_uniform(device, packing.at),
            packing,
        }
    }

    fn offsets_uniform(device: &wgpu::Device, at: TableOffsets) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene table offsets"),
            contents: bytemuck::cast_slice(&at.to_words()),
            usage: wgpu::BufferUsages::UNIFORM,
        })
    }

    /// Whether the packed buffer holds the OV vertex list: `original`'s edge step may then be
    /// built with [`OV_VERTICES_CONSTANT`](crate::shaders::OV_VERTICES_CONSTANT).
    #[must_use]
    pub fn has_ov_vertices(&self) -> bool {
        self.packing.extras.ov_vertices
    }

    /// Every buffer, for counting their bytes.
    #[must_use]
    pub fn all(&self) -> [&wgpu::Buffer; 2] {
        [&self.tables, &self.offsets]
    }

    /// Their entries in a bind group of `shaders/silhouette.wgsl`'s group 0 (bindings 1 and
    /// 2).
    #[must_use]
    pub fn entries(&self) -> [wgpu::BindGroupEntry<'_>; 2] {
        [entry(1, &self.tables), entry(2, &self.offsets)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowvol_mesh_topology::EdgeTable;
    use shadowvol_silhouette::gpu::{FIRST_EDGE, FIRST_TRIANGLE};
    use shadowvol_silhouette::TopologyScene;
    use shadowvol_test_support::shapes;

    /// Two spheres with an empty object between them.
    fn two_objects() -> TopologyScene {
        let sphere = |n, m, r| EdgeTable::build(&shapes::uv_sphere_y(n, m, r)).unwrap();
        let mut scene = TopologyScene::single(sphere(7, 5, 1.0));
        let mut empty = scene.objects[0].clone();
        empty.table = EdgeTable::build(&Default::default()).unwrap().into();
        scene.objects.push(empty);
        let mut other = scene.objects[0].clone();
        other.table = sphere(4, 3, 2.0).into();
        scene.objects.push(other);
        scene
    }

    /// The packed buffer read through the kernels' accessors gives back every table, written
    /// from the scene's tables or from its layout alike.
    #[test]
    fn packed_tables_read_back_as_the_layout() {
        let scene = two_objects();
        let writer = TableWriter::new(&scene, "test").unwrap();
        let layout = TableLayout::build(&scene, "test").unwrap();
        let extras = Extras {
            ov_vertices: true,
            vertex_objects: true,
        };
        let packing = TablePacking::new(&writer, extras);
        let words = packing.pack(&writer);
        assert_eq!(words.len() as u64, packing.words);
        let vertex_objects: Vec<u32> = (0..layout.positions.len() as u32 / 3)
            .map(|v| {
                layout
                    .objects
                    .partition_point(|o| o[FIRST_VERTEX] <= v)
                    .saturating_sub(1) as u32
            })
            .collect();
        let v = PackedView {
            words: &words,
            at: packing.at,
        };
        for id in 0..vertex_objects.len() as u32 {
            assert_eq!(
                v.position(id).map(f32::to_bits),
                layout.position(id).map(f32::to_bits)
            );
            assert_eq!(v.vertex_object(id), vertex_objects[id as usize]);
        }
        for e in 0..layout.edge_count() {
            let [a, b, begin, end] = v.edge(e as u32);
            assert_eq!([a, b], layout.edges[e]);
            assert_eq!(begin as usize..end as usize, layout.ov_slots(e));
        }
        for (k, &r) in layout.ov_refs.iter().enumerate() {
            assert_eq!(v.ov_ref(k as u32), r);
            assert_eq!(v.ov_vertex(k as u32), layout.ref_vertex(r));
        }
        for (t, tri) in layout.tris.iter().enumerate() {
            assert_eq!([0, 1, 2].map(|r| v.tri_vertex(t as u32, r)), *tri);
        }
        for (o, base) in layout.objects.iter().enumerate() {
            for f in [FIRST_EDGE, FIRST_TRIANGLE, FIRST_VERTEX] {
                assert_eq!(v.object_base(o as u32, f as u32), base[f]);
            }
        }
        let with_layout = TablePacking::of_layout(&layout, true);
        let mut no_ov = packing;
        no_ov.extras.ov_vertices = false;
        let no_ov = TablePacking::of_elements(
            |s| match s {
                Section::Table(b) => writer.elements(b),
                Section::VertexObjects => writer.elements(TableBuffer::Positions),
            },
            no_ov.extras,
        );
        assert_eq!(with_layout, no_ov);
        assert_eq!(
            with_layout.pack_layout(&layout, &vertex_objects),
            no_ov.pack(&writer)
        );
    }

    /// A packing beyond a binding is refused with a message naming the limit.
    #[test]
    fn a_packing_beyond_one_binding_names_the_limit() {
        let scene = two_objects();
        let writer = TableWriter::new(&scene, "test").unwrap();
        let packing = TablePacking::new(&writer, Extras::default());
        assert_eq!(packing.check("the kernels", packing.bytes()), Ok(()));
        let e = packing
            .check("the kernels", packing.bytes() - 1)
            .unwrap_err();
        assert!(e.contains("max_storage_buffer_binding_size"), "{e}");
        assert!(e.contains(&packing.bytes().to_string()), "{e}");
    }
}
