//! The render report: what one frame ran and drew, in one serialisable shape.
//!
//! * [`FrameReport`] is what a frame reports: a pipeline fills its part while it records the
//!   frame (uncertain counts, readback, GPU times, its silhouette and side-building times), and
//!   the renderer the rest (the plan, the lights' gains, the exposure, the wall times).
//! * [`RenderReport`] is `shadowvol render --format json`: the frame's report, flattened, with
//!   what the command adds (the scene and image, the reference's counts, the `--frames` times,
//!   memory). Scripts (the matrix in xtask) read the command's JSON back through it; every field
//!   a later version added has a default, so older records still read.
//!
//! The JSON's fields are the fields of these types, named as they are here; `docs/DESIGN.md`
//! ("CLI contract") describes them once, and `shadowvol render --help` points there.
//!
//! ```
//! use shadowvol_report::RenderReport;
//!
//! let json = r#"{"artifact_pixels": 0, "shadow_pixels": 120, "plan": [], "mode": "exact",
//!                "pipeline": "gpu", "timings": {"total_ms": 2.5}}"#;
//! let r: RenderReport = serde_json::from_str(json)?;
//! assert_eq!((r.artifact_pixels, r.shadow_pixels), (Some(0), 120));
//! assert_eq!(r.frame.timings.total_ms, 2.5);
//! # Ok::<(), serde_json::Error>(())
//! ```

mod frame;
mod maps;
mod plan;
mod render;

pub use frame::{FrameReport, GpuTimings, Pipeline, SamplesChoice, Timings, UncertainUnit};
pub use maps::{MapBias, MapFilter, MapKind, MapSummary};
pub use plan::{PlanEntry, SilhouetteSource, Technique};
pub use render::{FrameStats, Ground, LightsSource, MapBiases, MapFields, RenderReport};
pub use render::{SceneBounds, Shadows, TableBytes, VisibilityError};
pub use shadowvol_robust_math::Accuracy;

/// Compiles the README's examples as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
