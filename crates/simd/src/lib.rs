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
//! * **Layout**: for scenes of up to [`COPY_MAX_TRIANGLES`] triangles, a copy laid out for speed
//!   (16-byte position records, canonical triangles sorted by vertex id, per-edge columns for
//!   blocks of 8 two-OV (manifold) edges next to the general CSR path; about 56 bytes a
//!   triangle); beyond, the edge table itself, read in place (under one byte a triangle of its
//!   own, 1.5–3x the time). [`LayoutChoice`] and [`LAYOUT_ENV`] choose; `simd_layout` in
//!   [`BackendInfo::details`] says which ran.
//! * **Modes**: `original` per (edge, OV) with the exact operation order of
//!   [`shadowvol_robust_math::sign_f32`]; `ordered`, `robust` and `exact` once per canonical
//!   triangle (every (edge, OV) pair of a triangle has that triangle as its canonical form, so
//!   `ov_sign = sign(triangle) × parity`), then one pass over the edges. `exact` runs the
//!   certified `f32` filter of `orient_filter_f32` (same operations, constants, range checks)
//!   eight lanes at a time, then, only for the lanes it cannot certify, the certified `f64`
//!   filter of `orient_filter_f64` four lanes at a time, and decides the lanes neither certifies
//!   with the scalar `orient_exact`; those are counted in [`ExtractStats::uncertain`] (three
//!   (edge, OV) pairs per uncertain triangle evaluation).
//! * **A light's samples**: in `exact`, a call with at least four lights of one `w` (a light's
//!   samples, in one object's frame) classifies each triangle once against the lights' box
//!   ([`shadowvol_robust_math::LightBox`]: its certified filter on four `f64` lanes, the exact
//!   predicate at the box's corners for the lanes it leaves; the corner tests are not counted in
//!   `uncertain`), evaluates per light only the blocks with a triangle whose plane cuts the box,
//!   and computes an edge whose triangles are all shared once for every light, writing it only
//!   where it is not 0: a reused result is cleared by its compact lists
//!   ([`Multiplicities::zero_listed`]). An object where a sample of its triangles is mostly cut
//!   (lights spread around it) keeps the per-light pass. The other modes always evaluate per
//!   light: their `f32` signs near a plane are not the exact ones, so no box argument holds
//!   for them.
//!
//! Results are bit-identical to the `cpu` backend in every mode (all four evaluate the same IEEE
//! operations on the same inputs).
//!
//! ```
//! use shadowvol_silhouette::{extract_once, invariant, Accuracy};
//! use shadowvol_test_support::corpus;
//!
//! let case = &corpus::cases()[0];
//! let scene = case.scene().unwrap();
//! let mut simd = shadowvol_simd::create_backend().unwrap();
//! let (m, stats) = extract_once(simd.as_mut(), &scene, &case.lights, Accuracy::Exact).unwrap();
//! assert_eq!(invariant::open_vertices_scene(&scene, &m, 0), 0);
//! assert_eq!(stats.uncertain, 0);
//! ```

mod dispatch;
mod extract;
mod kernel;
mod lanes;
mod layout;

use extract::{run_extract, Prepared, Scratch};
pub use layout::{LayoutChoice, COPY_MAX_TRIANGLES};
use shadowvol_silhouette::{
    check_lights, Accuracy, BackendError, BackendInfo, ExtractStats, Light, Multiplicities,
    PreparedBytes, PreparedId, PreparedScenes, SilhouetteBackend, TopologyScene,
};
use std::time::Instant;

/// Environment variable that forces a [`SimdLevel`] in [`create_backend`]: `wide` or `avx2`.
pub const LEVEL_ENV: &str = "SHADOWVOL_SIMD_LEVEL";

/// Environment variable that forces a [`LayoutChoice`] in [`create_backend`]: `auto`, `copy` or
/// `in-place`.
pub const LAYOUT_ENV: &str = "SHADOWVOL_SIMD_LAYOUT";

/// The backend's registry name.
pub const NAME: &str = "simd";

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
/// with [`LayoutChoice::Auto`], unless [`LEVEL_ENV`] names a level or [`LAYOUT_ENV`] a layout.
///
/// # Errors
/// [`BackendError::Unavailable`] when [`LEVEL_ENV`] names an unknown level or one this CPU
/// lacks, or [`LAYOUT_ENV`] an unknown layout.
pub fn create_backend() -> Result<Box<dyn SilhouetteBackend>, BackendError> {
    let from_env = |var: &str| match std::env::var(var) {
        Ok(v) if !v.trim().is_empty() => Some(v),
        _ => None,
    };
    let unavailable = |var: &str, why: String| BackendError::Unavailable {
        backend: NAME,
        reason: format!("{var}: {why}"),
    };
    let level = match from_env(LEVEL_ENV) {
        Some(v) => v.parse().map_err(|why| unavailable(LEVEL_ENV, why))?,
        None => SimdLevel::detect(),
    };
    let layout = match from_env(LAYOUT_ENV) {
        Some(v) => v.parse().map_err(|why| unavailable(LAYOUT_ENV, why))?,
        None => LayoutChoice::Auto,
    };
    Ok(Box::new(
        SimdBackend::with_level(level, None)?.with_layout(layout),
    ))
}

/// The SIMD + threads backend. See the crate documentation.
#[derive(Debug)]
pub struct SimdBackend {
    level: SimdLevel,
    layout: LayoutChoice,
    /// The layout the last prepared scene got (`copy` or `in-place`).
    last_layout: Option<&'static str>,
    pool: Option<rayon::ThreadPool>,
    scenes: PreparedScenes<Prepared>,
    /// What an extraction keeps between calls (triangle signs, per-item silhouette lists, the
    /// lights in each object's frame).
    scratch: Scratch,
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
                backend: NAME,
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
                        backend: NAME,
                        reason: format!("cannot start {n} worker threads: {e}"),
                    })?,
            ),
        };
        Ok(Self {
            level,
            layout: LayoutChoice::Auto,
            last_layout: None,
            pool,
            scenes: PreparedScenes::new(NAME),
            scratch: Scratch::default(),
        })
    }

    /// The backend with `layout` for the scenes it prepares from now on.
    #[must_use]
    pub fn with_layout(mut self, layout: LayoutChoice) -> Self {
        self.layout = layout;
        self
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

impl SilhouetteBackend for SimdBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            name: NAME,
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
                (
                    "simd_layout".to_owned(),
                    self.last_layout.unwrap_or(self.layout.name()).to_owned(),
                ),
            ],
        }
    }

    fn prepare(&mut self, scene: &TopologyScene) -> Result<PreparedId, BackendError> {
        let prepared = Prepared::build(scene, self.layout)?;
        self.last_layout = Some(prepared.layout_name());
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
        let level = self.level;
        let scratch = &mut self.scratch;
        let uncertain = match &self.pool {
            Some(pool) => pool.install(|| run_extract(level, p, scratch, lights, mode, out)),
            None => run_extract(level, p, scratch, lights, mode, out),
        };
        Ok(ExtractStats {
            compute: start.elapsed(),
            uncertain,
            ..ExtractStats::default()
        })
    }

    fn prepared_bytes(&self, id: PreparedId) -> Result<PreparedBytes, BackendError> {
        Ok(PreparedBytes {
            host: self.scenes.get(id)?.heap_bytes(),
            device: 0,
        })
    }

    fn release(&mut self, id: PreparedId) {
        self.scenes.remove(id);
    }
}
