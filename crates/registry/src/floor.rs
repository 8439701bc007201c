//! The measured memory floor: how long it takes to stream the bytes an extraction must touch.
//!
//! Any silhouette extraction reads every edge record (`a, b`: 8 bytes), every opposite vertex
//! (4 bytes), every position (12 bytes), and writes one `i32` per edge and light. [`MemoryFloor`]
//! holds buffers of exactly those sizes and times one pass that sums the inputs with 8-lane
//! `u32` vectors and writes the output, split over rayon's global pool (the threads the `simd`
//! backend runs on). The output is written with streaming (non-temporal) stores on x86-64, as
//! the `simd` backend's one-light kernels write theirs, so that neither side pays for reading the
//! output's cache lines before writing them.
//!
//! This is the one floor: `shadowvol bench` reports it as `floor_ms`, measured in the same run as
//! the backends, and the criterion benches (`benches/`) and `cargo xtask matrix` (through
//! `shadowvol bench`) use it too.
//!
//! ```
//! use shadowvol_registry::MemoryFloor;
//! use shadowvol_mesh_topology::{EdgeTable, Mesh};
//! use shadowvol_silhouette::TopologyScene;
//! use glam::Vec3;
//!
//! let tetrahedron = Mesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! )?;
//! let scene = TopologyScene::single(EdgeTable::build(&tetrahedron)?);
//! let mut floor = MemoryFloor::new(&scene, 2);
//! // 6 edges (8 bytes), 12 opposite vertices (4 bytes), 4 positions (12 bytes) read; 6 edges x 2
//! // lights x 4 bytes written.
//! assert_eq!(floor.bytes_read(), 6 * 8 + 12 * 4 + 4 * 12);
//! assert_eq!(floor.bytes_written(), 6 * 2 * 4);
//! let _pass = floor.run_once();
//! # Ok::<(), shadowvol_mesh_topology::MeshError>(())
//! ```

use rayon::prelude::*;
use shadowvol_silhouette::TopologyScene;
use std::time::{Duration, Instant};

/// Words (u32) per parallel task.
const TASK_WORDS: usize = 1 << 15;

/// Buffers sized like one extraction's minimum traffic. See the module documentation.
#[derive(Debug)]
pub struct MemoryFloor {
    input: Vec<u32>,
    output: Vec<u32>,
}

impl MemoryFloor {
    /// Buffers for `scene` with `lights` lights: reads `edges·8 + ovs·4 + vertices·12` bytes
    /// (every object counted, as a backend reads each object's table), writes
    /// `edges·lights·4` bytes.
    #[must_use]
    pub fn new(scene: &TopologyScene, lights: usize) -> Self {
        let words_in: usize = scene
            .objects
            .iter()
            .map(|o| o.table.edges.len() * 2 + o.table.ov_refs.len() + o.table.positions.len() * 3)
            .sum();
        let words_out = scene.total_edges() * lights;
        // Non-constant contents, so nothing can be folded away.
        let input = (0..words_in as u32)
            .map(|i| i.wrapping_mul(2_654_435_761))
            .collect();
        Self {
            input,
            output: vec![0; words_out],
        }
    }

    /// Buffers that read `bytes` (rounded up to whole `u32` words) and write nothing: the floor
    /// of any pass over that much input, such as building an edge table from a mesh.
    #[must_use]
    pub fn read_only(bytes: usize) -> Self {
        Self {
            input: (0..bytes.div_ceil(4) as u32)
                .map(|i| i.wrapping_mul(2_654_435_761))
                .collect(),
            output: Vec::new(),
        }
    }

    /// Bytes read per pass.
    #[must_use]
    pub fn bytes_read(&self) -> usize {
        self.input.len() * 4
    }

    /// Bytes written per pass.
    #[must_use]
    pub fn bytes_written(&self) -> usize {
        self.output.len() * 4
    }

    /// Runs one pass (read everything, write everything, in parallel on the current rayon
    /// pool) and returns its wall time.
    pub fn run_once(&mut self) -> Duration {
        let start = Instant::now();
        let tasks = self
            .input
            .len()
            .div_ceil(TASK_WORDS)
            .max(self.output.len().div_ceil(TASK_WORDS))
            .max(1);
        let in_chunk = self.input.len().div_ceil(tasks).max(8);
        let out_chunk = self.output.len().div_ceil(tasks).max(8);
        let input = &self.input;
        let sum: u32 = self
            .output
            .par_chunks_mut(out_chunk)
            .enumerate()
            .map(|(t, out)| {
                let lo = (t * in_chunk).min(input.len());
                let hi = ((t + 1) * in_chunk).min(input.len());
                let s = sum_words(&input[lo..hi]);
                fill_streaming(out, s);
                s
            })
            .reduce(|| 0, u32::wrapping_add);
        // Input words beyond the output's task count (when there is no output) are read too.
        let covered = self.output.len().div_ceil(out_chunk.max(1)) * in_chunk;
        let rest = if covered < input.len() {
            input[covered..]
                .par_chunks(in_chunk)
                .map(sum_words)
                .reduce(|| 0, u32::wrapping_add)
        } else {
            0
        };
        std::hint::black_box(sum.wrapping_add(rest));
        start.elapsed()
    }
}

/// `out.fill(value)`, with 16-byte streaming stores where the target has them (SSE2, part of
/// every x86-64 CPU), followed by a store fence.
fn fill_streaming(out: &mut [u32], value: u32) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128i, _mm_set1_epi32, _mm_sfence, _mm_stream_si128};
        let head = out.as_ptr().align_offset(16).min(out.len());
        let (first, rest) = out.split_at_mut(head);
        first.fill(value);
        let mut quads = rest.chunks_exact_mut(4);
        // SAFETY: SSE2 is part of x86-64; each chunk is 4 u32 = 16 bytes at a 16-byte aligned
        // address (`rest` starts aligned and chunks are 16 bytes); the fence orders the
        // streaming stores before the caller's later accesses.
        unsafe {
            let v = _mm_set1_epi32(value as i32);
            for q in &mut quads {
                _mm_stream_si128(q.as_mut_ptr().cast::<__m128i>(), v);
            }
            _mm_sfence();
        }
        quads.into_remainder().fill(value);
    }
    #[cfg(not(target_arch = "x86_64"))]
    out.fill(value);
}

fn sum_words(words: &[u32]) -> u32 {
    let mut acc = [wide::u32x8::ZERO; 4];
    let mut chunks = words.chunks_exact(32);
    for c in &mut chunks {
        for (k, a) in acc.iter_mut().enumerate() {
            let v: [u32; 8] = c[k * 8..k * 8 + 8].try_into().unwrap_or([0; 8]);
            *a += wide::u32x8::new(v);
        }
    }
    let mut s = (acc[0] + acc[1] + acc[2] + acc[3])
        .to_array()
        .iter()
        .fold(0u32, |x, &y| x.wrapping_add(y));
    for &w in chunks.remainder() {
        s = s.wrapping_add(w);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::fill_streaming;

    #[test]
    fn streaming_fill_writes_every_word_at_any_offset_and_length() {
        let mut buf = vec![7u32; 300];
        for start in 0..5 {
            for len in [0, 1, 3, 4, 5, 17, 64, 255] {
                buf.fill(7);
                fill_streaming(&mut buf[start..start + len], 0xDEAD_BEEF);
                for (i, &w) in buf.iter().enumerate() {
                    let inside = (start..start + len).contains(&i);
                    assert_eq!(w, if inside { 0xDEAD_BEEF } else { 7 }, "{start} {len} {i}");
                }
            }
        }
    }
}
