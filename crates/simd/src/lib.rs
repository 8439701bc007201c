//! The `simd` silhouette backend: 8-lane `f32` / 4-lane `f64` vectors on every core.
//!
//! * **Lanes**: the kernels are written once, generic over a lane type, and compiled twice: with
//!   the [`wide`] crate at the compile-time target level (SSE2 in a default x86-64 build), and,
//!   on x86-64, inside `#[target_feature(enable = "avx2")]` functions with 256-bit `std::arch`
//!   lanes. [`SimdLevel::detect`] picks AVX2 at run time when the CPU has it, so a plain
//!   `cargo build --release` uses AVX2 without `-C target-cpu`. The level used is reported in
//!   [`BackendInfo::details`] as `simd_level`. AVX-512 is not dispatched (see the README).
//! * **Threads**: [`rayon`], over a work list that covers every object of the prepared scene, so
//!   objects are batched with no per-object barrier; all lights are handled in the same pass
//!   (the geometry of a block is loaded once and evaluated for every light). `original` is one
//!   parallel pass over the edges of all objects; the per-triangle modes are two (all triangles,
//!   then all edges) with a single join between them.
//! * **Layout**: structure-of-arrays positions, canonical triangles sorted by vertex id, edges in
//!   the table's sorted order with a fast path for blocks of 8 two-OV (manifold) edges next to the
//!   general CSR path.
//! * **Modes**: `original` per (edge, OV) with the exact operation order of
//!   [`shadowvol_robust_math::sign_f32`]; `ordered`, `robust` and `exact` once per canonical
//!   triangle (every (edge, OV) pair of a triangle has that triangle as its canonical form, so
//!   `ov_sign = sign(triangle) × parity`), then one pass over the edges. `exact` runs the
//!   certified `f32` filter of `orient_filter_f32` (same operations, constants, range checks)
//!   eight lanes at a time, then, only for the lanes it cannot certify, the certified `f64`
//!   filter of `orient_filter_f64` four lanes at a time, and decides the lanes neither certifies
//!   with the scalar `orient_exact`; those are counted in [`ExtractStats::uncertain`] (three
//!   (edge, OV) pairs per uncertain triangle evaluation).
//!
//! Results are bit-identical to the `cpu` backend in every mode (all four evaluate the same IEEE
//! operations on the same inputs).
//!
//! ```
//! use shadowvol_silhouette::{corpus, extract_once, invariant, Accuracy};
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut simd = shadowvol_simd::create_backend().unwrap();
//! let (m, stats) = extract_once(simd.as_mut(), &scene, &case.lights, Accuracy::Exact).unwrap();
//! assert_eq!(invariant::open_vertices_scene(&scene, &m, 0), 0);
//! assert_eq!(stats.uncertain, 0);
//! ```

pub mod floor;
mod kernel;
mod lanes;
mod layout;

pub use floor::MemoryFloor;

use layout::{Layout, LANES};
use rayon::prelude::*;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_silhouette::{
    check_lights, object_lights, Accuracy, BackendError, BackendInfo, ExtractStats, Light,
    Multiplicities, PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;

/// Environment variable that forces a [`SimdLevel`] in [`create_backend`]: `wide` or `avx2`.
pub const LEVEL_ENV: &str = "SHADOWVOL_SIMD_LEVEL";

/// Blocks of 8 per work item (2048 triangles or edges): small enough to balance two to many
/// threads, large enough that scheduling costs nothing.
const BLOCKS_PER_ITEM: usize = 256;

/// The instruction-set level the kernels run at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SimdLevel {
    /// The `wide` crate at the compile-time target level (SSE2 in a default x86-64 build, or
    /// whatever `-C target-feature` / `-C target-cpu` enabled). Available everywhere.
    Wide,
    /// 256-bit AVX2 lanes (`std::arch`), selected at run time. x86-64 CPUs with AVX2 only.
    Avx2,
}

impl SimdLevel {
    /// The best level this CPU supports: [`SimdLevel::Avx2`] when detected, else
    /// [`SimdLevel::Wide`].
    #[must_use]
    pub fn detect() -> Self {
        if Self::Avx2.is_supported() {
            Self::Avx2
        } else {
            Self::Wide
        }
    }

    /// True when this CPU can run the level.
    #[must_use]
    pub fn is_supported(self) -> bool {
        match self {
            Self::Wide => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            Self::Avx2 => false,
        }
    }

    /// The name recorded with results: `avx2`, or `wide-<compile-time level>` (for example
    /// `wide-sse2`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx2 => "avx2",
            Self::Wide => wide_compile_level(),
        }
    }
}

impl std::str::FromStr for SimdLevel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "wide" => Ok(Self::Wide),
            "avx2" => Ok(Self::Avx2),
            other => Err(format!(
                "unknown SIMD level {other:?}; expected \"wide\" or \"avx2\""
            )),
        }
    }
}

/// The instruction set `wide` was compiled for (its `f32x8` implementation).
fn wide_compile_level() -> &'static str {
    if cfg!(target_feature = "avx512f") {
        "wide-avx512f"
    } else if cfg!(target_feature = "avx2") {
        "wide-avx2"
    } else if cfg!(target_feature = "avx") {
        "wide-avx"
    } else if cfg!(target_feature = "sse4.1") {
        "wide-sse4.1"
    } else if cfg!(target_feature = "sse2") {
        "wide-sse2"
    } else {
        "wide-scalar"
    }
}

/// Starts the `simd` backend at [`SimdLevel::detect`]'s level on rayon's global thread pool,
/// unless [`LEVEL_ENV`] names a level.
///
/// # Errors
/// [`BackendError::Unavailable`] when [`LEVEL_ENV`] names an unknown level or one this CPU
/// lacks.
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    let level = match std::env::var(LEVEL_ENV) {
        Ok(v) if !v.trim().is_empty() => v.parse().map_err(|why| BackendError::Unavailable {
            backend: "simd",
            reason: format!("{LEVEL_ENV}: {why}"),
        })?,
        _ => SimdLevel::detect(),
    };
    Ok(Box::new(SimdBackend::with_level(level, None)?))
}

/// One object of a prepared scene.
#[derive(Debug)]
struct PreparedObject {
    layout: Arc<Layout>,
    /// First global edge index.
    edge_base: usize,
    /// First slot of the object's triangles in the per-light sign arrays (multiple of 8).
    tri_base: usize,
}

/// A work item: a range of blocks of one object.
#[derive(Debug, Clone)]
struct Item {
    object: usize,
    blocks: Range<usize>,
}

#[derive(Debug)]
struct Prepared {
    scene: TopologyScene,
    objects: Vec<PreparedObject>,
    total_edges: usize,
    /// Total triangle slots (padded per object).
    total_tri_slots: usize,
    tri_items: Vec<Item>,
    edge_items: Vec<Item>,
}

/// The SIMD + threads backend. See the crate documentation.
#[derive(Debug)]
pub struct SimdBackend {
    level: SimdLevel,
    pool: Option<rayon::ThreadPool>,
    scenes: PreparedScenes<Prepared>,
    /// Scratch: triangle signs, one byte per triangle slot in each pack of up to four lights
    /// (see `kernel::PACK`).
    signs: Vec<i8>,
}

impl SimdBackend {
    /// Creates the backend at `level`, on a private pool of `threads` threads (`None`: rayon's
    /// global pool, one thread per core).
    ///
    /// # Errors
    /// [`BackendError::Unavailable`] when the CPU lacks `level`, or the thread pool cannot be
    /// created.
    pub fn with_level(level: SimdLevel, threads: Option<usize>) -> Result<Self, BackendError> {
        if !level.is_supported() {
            return Err(BackendError::Unavailable {
                backend: "simd",
                reason: format!("this CPU does not support SIMD level {}", level.name()),
            });
        }
        let pool = match threads {
            None => None,
            Some(n) => Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n.max(1))
                    .build()
                    .map_err(|e| BackendError::Unavailable {
                        backend: "simd",
                        reason: format!("cannot start {n} worker threads: {e}"),
                    })?,
            ),
        };
        Ok(Self {
            level,
            pool,
            scenes: PreparedScenes::new("simd"),
            signs: Vec::new(),
        })
    }

    /// The level the kernels run at.
    #[must_use]
    pub fn level(&self) -> SimdLevel {
        self.level
    }

    /// Number of worker threads.
    #[must_use]
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or_else(
            rayon::current_num_threads,
            rayon::ThreadPool::current_num_threads,
        )
    }
}

/// Splits `buf` (`parts` equal light slices of `len`) at the item `bounds` (ascending, from 0
/// to `len`): result\[item\]\[light\].
fn split_items<'a, T>(buf: &'a mut [T], len: usize, bounds: &[usize]) -> Vec<Vec<&'a mut [T]>> {
    let items = bounds.len() - 1;
    let mut res: Vec<Vec<&mut [T]>> = (0..items).map(|_| Vec::new()).collect();
    if len == 0 {
        return res;
    }
    for light in buf.chunks_mut(len) {
        let mut rest = light;
        for (i, w) in bounds.windows(2).enumerate() {
            let (head, tail) = rest.split_at_mut(w[1] - w[0]);
            res[i].push(head);
            rest = tail;
        }
    }
    res
}

fn items_for(counts: &[usize]) -> Vec<Item> {
    let mut items = Vec::new();
    for (object, &n) in counts.iter().enumerate() {
        let blocks = n.div_ceil(LANES);
        let mut b = 0;
        while b < blocks {
            let e = (b + BLOCKS_PER_ITEM).min(blocks);
            items.push(Item {
                object,
                blocks: b..e,
            });
            b = e;
        }
    }
    items
}

/// Per-level entry points. The AVX2 ones are compiled with the feature enabled, so the generic
/// kernels and their lane operations are inlined into AVX2 code.
mod dispatch {
    use super::*;
    use crate::kernel;
    use crate::lanes::Wide;

    pub(super) fn tri_signs(
        level: SimdLevel,
        lay: &Layout,
        blocks: Range<usize>,
        lights: &[[f32; 4]],
        mode: Accuracy,
        out: &mut [&mut [i8]],
    ) -> u64 {
        match level {
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => {
                // SAFETY: a backend at level Avx2 is only constructed after
                // `is_x86_feature_detected!("avx2")` (see `SimdBackend::with_level`).
                unsafe { tri_signs_avx2(lay, blocks, lights, mode, out) }
            }
            _ => kernel::tri_signs::<Wide>(lay, blocks, lights, mode, out),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn tri_signs_avx2(
        lay: &Layout,
        blocks: Range<usize>,
        lights: &[[f32; 4]],
        mode: Accuracy,
        out: &mut [&mut [i8]],
    ) -> u64 {
        kernel::tri_signs::<crate::lanes::Avx2>(lay, blocks, lights, mode, out)
    }

    pub(super) fn edge_original(
        level: SimdLevel,
        lay: &Layout,
        blocks: Range<usize>,
        lights: &[[f32; 4]],
        out: &mut [&mut [i32]],
        sil: &mut [Vec<u32>],
        edge_base: usize,
    ) {
        match level {
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => {
                // SAFETY: as in `tri_signs`.
                unsafe { edge_original_avx2(lay, blocks, lights, out, sil, edge_base) }
            }
            _ => kernel::edge_original::<Wide>(lay, blocks, lights, out, sil, edge_base),
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn edge_sums(
        level: SimdLevel,
        lay: &Layout,
        blocks: Range<usize>,
        signs: &[i8],
        bases: &[usize],
        out: &mut [&mut [i32]],
        sil: &mut [Vec<u32>],
        edge_base: usize,
    ) {
        match level {
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => {
                // SAFETY: AVX2 as in `tri_signs`.
                unsafe { kernel::edge_sums_avx2(lay, blocks, signs, bases, out, sil, edge_base) }
            }
            _ => kernel::edge_sums(lay, blocks, signs, bases, out, sil, edge_base),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn edge_original_avx2(
        lay: &Layout,
        blocks: Range<usize>,
        lights: &[[f32; 4]],
        out: &mut [&mut [i32]],
        sil: &mut [Vec<u32>],
        edge_base: usize,
    ) {
        kernel::edge_original::<crate::lanes::Avx2>(lay, blocks, lights, out, sil, edge_base);
    }
}

impl Prepared {
    fn build(scene: &TopologyScene) -> Result<Self, BackendError> {
        // Objects sharing one table (instances) share one layout.
        let mut cache: HashMap<*const EdgeTable, Arc<Layout>> = HashMap::new();
        let mut objects = Vec::with_capacity(scene.objects.len());
        let (mut edge_base, mut tri_base) = (0usize, 0usize);
        for (i, o) in scene.objects.iter().enumerate() {
            let key = Arc::as_ptr(&o.table);
            let layout = match cache.get(&key) {
                Some(l) => Arc::clone(l),
                None => {
                    let l = Arc::new(Layout::build(&o.table).map_err(|e| BackendError::Limit {
                        backend: "simd",
                        message: format!("object {i} ({}): {}", o.name, e.0),
                    })?);
                    cache.insert(key, Arc::clone(&l));
                    l
                }
            };
            let (ne, nt) = (layout.edge_count, layout.t0.len());
            objects.push(PreparedObject {
                layout,
                edge_base,
                tri_base,
            });
            edge_base += ne;
            tri_base += nt;
        }
        let tri_counts: Vec<usize> = objects.iter().map(|o| o.layout.tri_count).collect();
        let edge_counts: Vec<usize> = objects.iter().map(|o| o.layout.edge_count).collect();
        Ok(Self {
            scene: scene.clone(),
            objects,
            total_edges: edge_base,
            total_tri_slots: tri_base,
            tri_items: items_for(&tri_counts),
            edge_items: items_for(&edge_counts),
        })
    }

    /// Global edge bounds of the edge items (0, ..., total_edges).
    fn edge_bounds(&self) -> Vec<usize> {
        let mut b = vec![0];
        for it in &self.edge_items {
            let o = &self.objects[it.object];
            b.push(o.edge_base + (it.blocks.end * LANES).min(o.layout.edge_count));
        }
        b
    }

    /// Triangle-slot bounds of the triangle items.
    fn tri_bounds(&self) -> Vec<usize> {
        let mut b = vec![0];
        for it in &self.tri_items {
            b.push(self.objects[it.object].tri_base + it.blocks.end * LANES);
        }
        b
    }
}

fn run_extract(
    level: SimdLevel,
    p: &Prepared,
    signs: &mut Vec<i8>,
    obj_lights: &[Vec<[f32; 4]>],
    mode: Accuracy,
    out: &mut Multiplicities,
) -> u64 {
    let nl = obj_lights.first().map_or(0, Vec::len);
    let ne = p.total_edges;
    if out.edge_count() != ne || out.light_count() != nl {
        out.reset(ne, nl);
    }
    let mut uncertain = 0u64;
    if mode != Accuracy::Original {
        // Phase 1: one sign per (canonical triangle, light).
        // One byte per triangle slot in each pack of up to `PACK` lights.
        let slots = p.total_tri_slots;
        let packs = nl.div_ceil(kernel::PACK);
        signs.clear();
        signs.resize(slots * packs, 0);
        let parts = split_items(signs, slots, &p.tri_bounds());
        uncertain = p
            .tri_items
            .par_iter()
            .zip(parts)
            .map(|(it, mut dst)| {
                let lay = &p.objects[it.object].layout;
                dispatch::tri_signs(
                    level,
                    lay,
                    it.blocks.clone(),
                    &obj_lights[it.object],
                    mode,
                    &mut dst,
                )
            })
            .sum();
    }
    // Phase 2: one pass over all edges of all objects.
    let signs: &[i8] = signs;
    let slots = p.total_tri_slots;
    let parts = split_items(out.all_values_mut(), ne, &p.edge_bounds());
    let lists: Vec<Vec<Vec<u32>>> = p
        .edge_items
        .par_iter()
        .zip(parts)
        .map(|(it, mut dst)| {
            let o = &p.objects[it.object];
            let mut sil = vec![Vec::new(); nl];
            if mode == Accuracy::Original {
                dispatch::edge_original(
                    level,
                    &o.layout,
                    it.blocks.clone(),
                    &obj_lights[it.object],
                    &mut dst,
                    &mut sil,
                    o.edge_base,
                );
            } else {
                let bases: Vec<usize> = (0..nl.div_ceil(kernel::PACK))
                    .map(|pack| pack * slots + o.tri_base)
                    .collect();
                dispatch::edge_sums(
                    level,
                    &o.layout,
                    it.blocks.clone(),
                    signs,
                    &bases,
                    &mut dst,
                    &mut sil,
                    o.edge_base,
                );
            }
            sil
        })
        .collect();
    for l in 0..nl {
        let total = lists.iter().map(|s| s[l].len()).sum();
        let mut all = Vec::with_capacity(total);
        for s in &lists {
            all.extend_from_slice(&s[l]);
        }
        out.set_silhouette(l, all);
    }
    uncertain * 3
}

impl SilhouetteBackend for SimdBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: "simd",
            device: format!(
                "host CPU, {} threads, {} lanes (8 x f32, 4 x f64)",
                self.threads(),
                self.level.name()
            ),
            modes: Accuracy::ALL.to_vec(),
            max_lights: None,
            details: vec![
                ("simd_level".to_owned(), self.level.name().to_owned()),
                ("threads".to_owned(), self.threads().to_string()),
                (
                    "wide_compile_level".to_owned(),
                    wide_compile_level().to_owned(),
                ),
            ],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        let prepared = Prepared::build(scene)?;
        Ok(self.scenes.insert(prepared))
    }

    fn extract(
        &mut self,
        id: PreparedId,
        lights: &[Light],
        mode: Accuracy,
        out: &mut Multiplicities,
    ) -> Result<ExtractStats, BackendError> {
        let p = self.scenes.get(id)?;
        check_lights(lights)?;
        let start = Instant::now();
        let obj_lights = object_lights(&p.scene, lights);
        let level = self.level;
        let signs = &mut self.signs;
        let uncertain = match &self.pool {
            Some(pool) => pool.install(|| run_extract(level, p, signs, &obj_lights, mode, out)),
            None => run_extract(level, p, signs, &obj_lights, mode, out),
        };
        Ok(ExtractStats {
            compute: start.elapsed(),
            uncertain,
            ..ExtractStats::default()
        })
    }

    fn release(&mut self, id: PreparedId) {
        self.scenes.remove(id);
    }
}
