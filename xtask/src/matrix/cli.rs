//! The JSON the CLI prints, as the matrix reads it: `backends`, `scenes`, `bench`, `accuracy`,
//! `baselines` and `render` (`--format json`; DESIGN.md, "CLI contract").
//!
//! The CLI's shapes are only ever extended, so no type here rejects unknown fields, and a field
//! that may be missing is an `Option` or has a default. The measurements of `bench`, `accuracy`
//! and `baselines` are the types of [`super::records`], flattened into a [`CliRecord`].

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// One row of `shadowvol backends --format json`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
pub struct BackendRow {
    /// Registry name (`cpu`, `simd`, `wgpu`, `opencl`, `vulkan`).
    pub name: String,
    /// Whether the backend started on this machine.
    #[serde(default)]
    pub available: bool,
    /// The device, in words, when it started.
    pub device: Option<String>,
    /// Why it did not start.
    pub reason: Option<String>,
}

/// One row of `shadowvol scenes --format json` (only the name is read).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
pub struct SceneRow {
    /// Preset name.
    pub name: String,
}

/// `shadowvol bench --format json`, with its measurements read as `T` (the matrix's
/// [`super::records::Bench`]).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default)]
pub struct BenchReport<T> {
    /// Time to stream the bytes the extraction must touch (the first light count's), in ms.
    pub floor_ms: Option<f64>,
    /// One record per (backend, mode, light count).
    pub records: Vec<CliRecord<T>>,
    /// How the binary was built.
    pub host: BenchHost,
}

/// The part of `bench`'s `host` object the matrix reads.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default)]
pub struct BenchHost {
    /// The CPU model, as the CLI reads it (`/proc/cpuinfo`'s `model name`).
    pub cpu: Option<String>,
    /// Target features enabled at compile time.
    pub compile_target_features: Vec<String>,
    /// Cargo profile of the binary.
    pub profile: Option<String>,
}

/// `{"records": [...]}`: the output of `shadowvol accuracy` and `shadowvol baselines`.
#[derive(Debug, Clone, Deserialize)]
pub struct RecordList<T> {
    /// The records, in the CLI's order.
    #[serde(default = "Vec::new")]
    pub records: Vec<CliRecord<T>>,
}

/// One record of `bench`, `accuracy` or `baselines`: the fields they share, then the
/// measurement `T` (flattened: all in one JSON object).
#[derive(Debug, Clone, Deserialize)]
pub struct CliRecord<T> {
    /// Scene name.
    pub scene: String,
    /// Backend name (for `baselines`, the algorithm).
    pub backend: String,
    /// Accuracy mode (`null` for the seeds' algorithms).
    pub mode: Option<String>,
    /// The backend's device, where the command names it.
    pub device: Option<String>,
    /// Backend-specific details (for example `simd_level`).
    #[serde(default)]
    pub details: Details,
    /// The measurement.
    #[serde(flatten)]
    pub data: T,
}

/// A backend's `details` object.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Details {
    /// The SIMD level the `simd` backend picked at run time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simd_level: Option<String>,
    /// Every other detail.
    #[serde(flatten)]
    pub other: Map<String, Value>,
}

impl Details {
    /// The details as `detail_<name>` columns.
    pub(super) fn into_columns(self) -> Map<String, Value> {
        let mut out = Map::new();
        if let Some(level) = self.simd_level {
            out.insert("detail_simd_level".into(), Value::String(level));
        }
        for (k, v) in self.other {
            out.insert(format!("detail_{k}"), v);
        }
        out
    }
}

/// `shadowvol render --format json`, read through the type the command writes it with.
pub use shadowvol_report::RenderReport;

/// A render's frame time, ms: `total_ms - prepare_ms` (the one-off upload of the edge tables is
/// not part of a frame).
#[must_use]
pub fn frame_ms(t: &shadowvol_report::Timings) -> f64 {
    t.total_ms - t.prepare_ms
}

/// A render's timings as `timing_<stage>` columns.
pub(super) fn timing_columns(t: &shadowvol_report::Timings) -> Map<String, Value> {
    let Ok(Value::Object(m)) = serde_json::to_value(t) else {
        return Map::new();
    };
    m.into_iter()
        .map(|(k, v)| (format!("timing_{k}"), v))
        .collect()
}
