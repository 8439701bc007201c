//! The measured memory floor: how long it takes to stream the bytes an extraction must touch.
//!
//! Any silhouette extraction reads every edge record (`a, b`: 8 bytes), every opposite vertex
//! (4 bytes), every position (12 bytes), and writes one `i32` per edge and light. [`MemoryFloor`]
//! holds buffers of exactly those sizes and times one pass that sums the inputs with 8-lane
//! `u32` vectors and writes the output, split over the same rayon threads as the backend. The
//! `shadowvol bench` command reports it as `floor_ms`, measured in the same run as the backends.

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
            .map(|o| o.table.edges.len() * 2 + o.table.ovs.len() + o.table.positions.len() * 3)
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
                out.fill(s);
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
