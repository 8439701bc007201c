//! The matrix's records: one per measurement, as `results.json` and `results.csv` hold them.
//!
//! A measurement names only the fields the tables and plots read; the rest of what the CLI
//! printed stays in its flattened `extra` map, so that `results.json` and `results.csv` carry
//! every field the CLI gave, new ones included. Reading `results.json` back (`--replot`) gives
//! the same records.

use super::cli::{frame_ms, timing_columns, CliRecord, RenderReport};
use serde::{Deserialize, Deserializer, Serialize};
use serde_json::{Map, Value};
use std::collections::BTreeMap;

/// One `bench` measurement: silhouette time of one (scene, backend, mode, light count).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Bench {
    /// Lights extracted in one call.
    pub lights: Option<u64>,
    /// Triangles of the scene.
    pub triangles: Option<u64>,
    /// Median silhouette time over the timed frames, ms.
    pub median_ms: Option<f64>,
    /// 10th percentile, ms.
    pub p10_ms: Option<f64>,
    /// 90th percentile, ms.
    pub p90_ms: Option<f64>,
    /// The run's floor, ms (the matrix sets it to the report's `floor_ms`).
    pub floor_ms: Option<f64>,
    /// Every other field the CLI printed, and the `detail_*` columns.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// One `accuracy` measurement: what one mode gets wrong on one (scene, backend), against
/// `exact`. (Not named after the command: `Accuracy` names the mode everywhere else.)
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ModeErrors {
    /// Lights of the scene.
    pub lights: Option<u64>,
    /// Vertices where the silhouette chain does not close, over all lights.
    pub open_vertices: Option<u64>,
    /// Edges whose multiplicity differs from `exact`'s, over all lights.
    pub sign_diff_vs_exact: Option<u64>,
    /// Evaluations decided on the host (exact mode).
    pub uncertain: Option<u64>,
    /// Every other field the CLI printed.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// One `baselines` measurement: one of the seeds' algorithms, or ours, on one scene.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Baseline {
    /// Triangles of the scene.
    pub triangles: Option<u64>,
    /// Median time, ms (`null` when the algorithm failed).
    pub median_ms: Option<f64>,
    /// 10th percentile, ms.
    pub p10_ms: Option<f64>,
    /// 90th percentile, ms.
    pub p90_ms: Option<f64>,
    /// Edges with `m != 0`, over all lights.
    pub silhouette_edges: Option<u64>,
    /// Whether the edge set equals the `cpu` backend's `exact` one.
    pub agrees_with_exact: Option<bool>,
    /// Why the algorithm failed.
    pub error: Option<String>,
    /// Every other field the CLI printed, and the `detail_*` columns.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// One `render` of the matrix, as recorded.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Render {
    /// Image size, `WxH`.
    pub size: String,
    /// See [`RenderReport`].
    pub artifact_pixels: Option<u64>,
    /// See [`RenderReport`].
    pub shadow_pixels: Option<u64>,
    /// See [`RenderReport`].
    pub reference_shadow_pixels: Option<u64>,
    /// See [`RenderReport`].
    pub covered_pixels: Option<u64>,
    /// See [`RenderReport`].
    pub adapter: Option<String>,
    /// [`frame_ms`] of the report's timings.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_ms: Option<f64>,
    /// `gpu` or `host`, when the report said.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pipeline: Option<String>,
    /// Median of the `--frames` frames (light orbit, re-extracting every frame), ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames_median_ms: Option<f64>,
    /// 10th percentile of those frames, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames_p10_ms: Option<f64>,
    /// 90th percentile of those frames, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames_p90_ms: Option<f64>,
    /// Bytes brought to the host during those frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_readback_bytes: Option<u64>,
    /// Pixels where render and reference differ within a pixel of a reference boundary.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub boundary_pixels: Option<u64>,
    /// Covered pixels the reference could not decide.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub undecidable_pixels: Option<u64>,
    /// Side of the directional and spot maps, texels (the map pipeline's renders).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_size: Option<u64>,
    /// `hard` or `pcf` (the map pipeline's renders).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_filter: Option<String>,
    /// `default` (Bevy's per light type) or the `--map-bias` given (the map pipeline's renders).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_bias: Option<String>,
    /// GPU time of the map passes, ms (median of the `--frames` frames).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_shadow_maps_ms: Option<f64>,
    /// `--light-radius` (the soft-shadow table): world units for point and spot lights,
    /// radians for directional ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_radius: Option<f64>,
    /// For point and spot lights, `light_radius` over the diagonal of the scene's caster box.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_radius_fraction: Option<f64>,
    /// `--light-samples` as asked: a count, or `plan` for the plan's choice (volumes only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_samples_setting: Option<String>,
    /// See [`SoftFields::light_samples_used`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_samples_used: Option<u64>,
    /// See [`SoftFields::light_penumbra_px`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_penumbra_px: Option<f64>,
    /// See [`SoftFields::penumbra_pixels`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub penumbra_pixels: Option<u64>,
    /// See [`SoftFields::visibility_mean`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visibility_mean: Option<f64>,
    /// See [`SoftFields::visibility_p99`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visibility_p99: Option<f64>,
    /// See [`SoftFields::visibility_max`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visibility_max: Option<f64>,
    /// See [`SoftFields::lit_umbra_mismatches`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lit_umbra_mismatches: Option<u64>,
    /// See [`SoftFields::sample_artifact_pixels`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample_artifact_pixels: Option<u64>,
    /// Where the image was written.
    pub png: String,
    /// The report's timings as `timing_<stage>` columns.
    #[serde(flatten)]
    pub timing: Map<String, Value>,
}

impl Render {
    /// The record of `report`, rendered at `size` into `png`.
    #[must_use]
    pub fn new(report: RenderReport, size: &str, png: String) -> Self {
        let count = |n: usize| n as u64;
        let frames = report.frames.as_ref();
        let map_size = report.map.map_size.map(u64::from);
        Self {
            size: size.to_owned(),
            artifact_pixels: report.artifact_pixels.map(count),
            shadow_pixels: Some(count(report.shadow_pixels)),
            reference_shadow_pixels: report.reference_shadow_pixels.map(count),
            covered_pixels: report.covered_pixels.map(count),
            adapter: Some(report.frame.adapter.clone()),
            frame_ms: Some(frame_ms(&report.frame.timings)),
            pipeline: Some(report.frame.pipeline.name().to_owned()),
            frames_median_ms: frames.map(|f| f.median_ms),
            frames_p10_ms: frames.map(|f| f.p10_ms),
            frames_p90_ms: frames.map(|f| f.p90_ms),
            frame_readback_bytes: frames.map(|_| report.frame_readback_bytes),
            boundary_pixels: report.boundary_pixels.map(count),
            undecidable_pixels: report.undecidable_pixels.map(count),
            map_size,
            map_filter: report.map.map_filter.map(|f| f.name().to_owned()),
            map_bias: None,
            light_radius: None,
            light_radius_fraction: None,
            light_samples_setting: None,
            light_samples_used: None,
            light_penumbra_px: None,
            penumbra_pixels: None,
            visibility_mean: None,
            visibility_p99: None,
            visibility_max: None,
            lit_umbra_mismatches: None,
            sample_artifact_pixels: None,
            gpu_shadow_maps_ms: report
                .frame
                .gpu_timings
                .map(|t| t.shadow_maps)
                .filter(|_| map_size.is_some()),
            png,
            timing: timing_columns(&report.frame.timings),
        }
    }
}

impl Render {
    /// Adds the soft-shadow table's fields: `soft` from the report, the radius as a `fraction`
    /// of the scene's box (point lights) and the `--light-samples` setting (`None` for maps).
    pub fn set_soft(&mut self, soft: SoftFields, fraction: Option<f64>, setting: Option<String>) {
        self.light_radius = Some(soft.light_radius);
        self.light_radius_fraction = fraction;
        self.light_samples_setting = setting;
        self.light_samples_used = soft.light_samples_used;
        self.light_penumbra_px = soft.light_penumbra_px;
        self.penumbra_pixels = soft.penumbra_pixels;
        self.visibility_mean = soft.visibility_mean;
        self.visibility_p99 = soft.visibility_p99;
        self.visibility_max = soft.visibility_max;
        self.lit_umbra_mismatches = soft.lit_umbra_mismatches;
        self.sample_artifact_pixels = soft.sample_artifact_pixels;
    }
}

/// A render's soft-shadow figures over its lights with a size, from its report. A figure the
/// report lacks is `None`, never a guess; `missing` says why the visibility error is.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SoftFields {
    /// The radius asked for with `--light-radius`.
    pub light_radius: f64,
    /// The most points any light was sampled with (`light_samples`).
    pub light_samples_used: Option<u64>,
    /// The plan's bound on the widest penumbra on screen over the lights, px
    /// (`light_penumbra_px`).
    pub light_penumbra_px: Option<f64>,
    /// Penumbra pixels (true visibility in (0, 1)), summed over the lights.
    pub penumbra_pixels: Option<u64>,
    /// Mean `|visibility - true visibility|` over all those pixels: the lights' means weighted
    /// by their penumbra pixels (unweighted when no light has any).
    pub visibility_mean: Option<f64>,
    /// The largest of the lights' 99th percentiles (the pooled percentile is not in the JSON).
    pub visibility_p99: Option<f64>,
    /// The largest error of any light.
    pub visibility_max: Option<f64>,
    /// Fully lit or fully shadowed pixels whose visibility differs, summed over the lights.
    pub lit_umbra_mismatches: Option<u64>,
    /// Each sample's hard shadow against the reference, artifact pixels summed over the lights
    /// and samples (`sample_artifact_pixels`; `None` where the report has none, as for maps).
    pub sample_artifact_pixels: Option<u64>,
    /// Why the visibility error is `None`, in words.
    pub missing: Option<String>,
}

impl SoftFields {
    /// The figures of `report`, rendered with every light's radius set to `radius`.
    #[must_use]
    pub fn of(report: &RenderReport, radius: f64) -> Self {
        let f = &report.frame;
        let mut out = Self {
            light_radius: radius,
            light_samples_used: f.samples.iter().map(|c| u64::from(c.samples)).max(),
            light_penumbra_px: f
                .samples
                .iter()
                .map(|c| c.penumbra_px)
                .max_by(f64::total_cmp),
            sample_artifact_pixels: report
                .sample_artifact_pixels
                .as_ref()
                .map(|v| v.iter().flatten().map(|&n| n as u64).sum()),
            ..Self::default()
        };
        let Some(errors) = &report.visibility_error else {
            out.missing = Some("the render JSON has no visibility_error".to_owned());
            return out;
        };
        let lights = report.lights.len().max(errors.len());
        let mut sized = Vec::new();
        for i in 0..lights {
            let r = f.light_radii.get(i).map_or(radius, |&r| f64::from(r));
            if r <= 0.0 {
                continue;
            }
            match errors.get(i).and_then(Option::as_ref) {
                Some(e) => sized.push(e),
                None => {
                    out.missing = Some(format!(
                        "visibility_error is null for light {i} of radius {r}"
                    ));
                    return out;
                }
            }
        }
        if sized.is_empty() {
            out.missing = Some("no light has a radius".to_owned());
            return out;
        }
        let pixels: usize = sized.iter().map(|e| e.penumbra_pixels).sum();
        out.penumbra_pixels = Some(pixels as u64);
        out.visibility_mean = Some(if pixels > 0 {
            sized
                .iter()
                .map(|e| e.mean * e.penumbra_pixels as f64)
                .sum::<f64>()
                / pixels as f64
        } else {
            sized.iter().map(|e| e.mean).sum::<f64>() / sized.len() as f64
        });
        out.visibility_p99 = sized.iter().map(|e| e.p99).max_by(f64::total_cmp);
        out.visibility_max = sized.iter().map(|e| e.max).max_by(f64::total_cmp);
        out.lit_umbra_mismatches = Some(sized.iter().map(|e| e.lit_umbra_mismatches as u64).sum());
        out
    }
}

/// One memory measurement: one `silhouette` (on a backend) or `render` (on a pipeline) of one
/// scene, in its own process, with the figures of its JSON.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Memory {
    /// Triangles of the scene.
    pub triangles: Option<u64>,
    /// The process's peak resident set, bytes (`peak_rss_bytes`).
    pub peak_rss_bytes: Option<u64>,
    /// What the prepared scene held, bytes (`table_bytes`).
    pub table_bytes: Option<u64>,
    /// Its edge tables (`table_bytes_parts.topology`).
    pub topology_bytes: Option<u64>,
    /// The backend's or pipeline's host layout (`table_bytes_parts.host`).
    pub host_bytes: Option<u64>,
    /// Its device buffers (`table_bytes_parts.device`).
    pub device_bytes: Option<u64>,
    /// Wall time of the whole command, s.
    pub wall_s: Option<f64>,
    /// The edge-table build's median, ms (`bench --build-runs`: records of backend `build`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build_ms: Option<f64>,
    /// Reading the build's input bytes from memory, ms, in the same run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build_read_ms: Option<f64>,
    /// Threads the build and the read ran on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build_threads: Option<u64>,
    /// Every other field.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

impl Memory {
    /// `bytes` per triangle.
    #[must_use]
    pub fn per_triangle(&self, bytes: Option<u64>) -> Option<f64> {
        let t = self.triangles.filter(|&t| t > 0)?;
        Some(bytes? as f64 / t as f64)
    }
}

/// What one record measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
// A run holds a few thousand records: boxing the larger variant would save little and add a
// layer to every construction and match.
#[allow(clippy::large_enum_variant)]
pub enum Data {
    /// `bench`: tables 1-3, time against triangles and lights.
    Bench(Bench),
    /// `accuracy`: what each mode gets wrong.
    ModeErrors(ModeErrors),
    /// `render`: frame times and artifact counts.
    Render(Render),
    /// `baselines`: the Toy Wars table.
    Baseline(Baseline),
    /// `memory`: bytes per triangle.
    Memory(Memory),
}

impl Data {
    /// Which measurement the records of `experiment` hold.
    fn parse(experiment: &str, fields: Map<String, Value>) -> serde_json::Result<Self> {
        let v = Value::Object(fields);
        Ok(match experiment {
            "accuracy" => Self::ModeErrors(serde_json::from_value(v)?),
            "artifacts" | "table1-frame" | "frames" | "maps" | "maps-sweep" | "soft" => {
                Self::Render(serde_json::from_value(v)?)
            }
            "toywars" => Self::Baseline(serde_json::from_value(v)?),
            "memory" => Self::Memory(serde_json::from_value(v)?),
            _ => Self::Bench(serde_json::from_value(v)?),
        })
    }

    /// Adds `detail_*` columns that the measurement does not have yet.
    fn add_columns(&mut self, columns: Map<String, Value>) {
        let extra = match self {
            Self::Bench(b) => &mut b.extra,
            Self::Baseline(b) => &mut b.extra,
            Self::ModeErrors(a) => &mut a.extra,
            Self::Render(r) => &mut r.timing,
            Self::Memory(m) => &mut m.extra,
        };
        for (k, v) in columns {
            extra.entry(k).or_insert(v);
        }
    }
}

/// Where and how the matrix ran; `results.json`'s `host`, and columns of every record (`null`
/// where unknown).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct HostInfo {
    /// `uname -n`.
    pub host: Option<String>,
    /// `uname -sr`.
    pub os: Option<String>,
    /// CPU model.
    pub cpu: Option<String>,
    /// Logical cores.
    pub cores: Option<u64>,
    /// `rustc -V`.
    pub rustc: Option<String>,
    /// Git revision, `-dirty` with uncommitted changes.
    pub git_rev: Option<String>,
    /// `RUSTFLAGS` of the build.
    pub rustflags: Option<String>,
    /// Cargo profile of the CLI.
    pub profile: Option<String>,
    /// SIMD level the `simd` backend picks at run time.
    pub simd_level: Option<String>,
    /// Compile-time target features, joined with `+`.
    pub compile_target_features: Option<String>,
    /// The build, in words.
    pub flags: Option<String>,
}

/// The scene, backend and mode a record is about.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Key {
    /// Scene name.
    pub scene: String,
    /// Backend (or seed algorithm) name.
    pub backend: String,
    /// Accuracy mode (`null` for the seeds' algorithms).
    pub mode: Option<String>,
}

/// One record of `results.json` and one row of `results.csv`.
///
/// Serialised through a `serde_json::Value` (a sorted map), where a field of `data` wins over a
/// host field of the same name.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Record {
    /// Where it ran.
    #[serde(flatten)]
    pub host: HostInfo,
    /// Which table or plot it is for (`table1`, `lights`, `accuracy`, `artifacts`, ...).
    pub experiment: String,
    /// The experiment whose measurement this copies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reused_from: Option<String>,
    /// Scene, backend, mode.
    #[serde(flatten)]
    pub key: Key,
    /// The backend's device, in words.
    pub device: String,
    /// The measurement.
    #[serde(flatten)]
    pub data: Data,
}

impl Record {
    /// A record of `experiment` from one CLI record: its details become `detail_*` columns,
    /// and `device` is used where the CLI names none.
    #[must_use]
    pub fn from_cli<T>(
        experiment: &str,
        rec: CliRecord<T>,
        wrap: fn(T) -> Data,
        device: &str,
        host: &HostInfo,
    ) -> Self {
        let mut data = wrap(rec.data);
        data.add_columns(rec.details.into_columns());
        Self {
            host: host.clone(),
            experiment: experiment.to_owned(),
            reused_from: None,
            key: Key {
                scene: rec.scene,
                backend: rec.backend,
                mode: rec.mode,
            },
            device: rec.device.unwrap_or_else(|| device.to_owned()),
            data,
        }
    }

    /// Whether the record is of `experiment`, `scene` (any with `None`), `backend` and `mode`.
    #[must_use]
    pub fn is(&self, experiment: &str, scene: Option<&str>, backend: &str, mode: &str) -> bool {
        self.experiment == experiment
            && scene.is_none_or(|s| self.key.scene == s)
            && self.key.backend == backend
            && self.mode() == Some(mode)
    }

    /// The accuracy mode.
    #[must_use]
    pub fn mode(&self) -> Option<&str> {
        self.key.mode.as_deref()
    }

    /// The `bench` measurement, if that is what this is.
    #[must_use]
    pub fn bench(&self) -> Option<&Bench> {
        match &self.data {
            Data::Bench(b) => Some(b),
            _ => None,
        }
    }

    /// The `accuracy` measurement (what a mode gets wrong), if that is what this is.
    #[must_use]
    pub fn mode_errors(&self) -> Option<&ModeErrors> {
        match &self.data {
            Data::ModeErrors(a) => Some(a),
            _ => None,
        }
    }

    /// The `render` measurement, if that is what this is.
    #[must_use]
    pub fn render(&self) -> Option<&Render> {
        match &self.data {
            Data::Render(r) => Some(r),
            _ => None,
        }
    }

    /// The `memory` measurement, if that is what this is.
    #[must_use]
    pub fn memory(&self) -> Option<&Memory> {
        match &self.data {
            Data::Memory(m) => Some(m),
            _ => None,
        }
    }

    /// The `baselines` measurement, if that is what this is.
    #[must_use]
    pub fn baseline(&self) -> Option<&Baseline> {
        match &self.data {
            Data::Baseline(b) => Some(b),
            _ => None,
        }
    }

    /// The record as one JSON object (host fields first, so the record's own win).
    ///
    /// # Errors
    /// When serde_json cannot represent a value (never for these types).
    pub fn to_value(&self) -> serde_json::Result<Value> {
        serde_json::to_value(self)
    }
}

impl<'de> Deserialize<'de> for Record {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        /// A record as stored: the named parts, then the measurement's own fields.
        #[derive(Deserialize)]
        struct Stored {
            #[serde(flatten)]
            host: HostInfo,
            experiment: String,
            reused_from: Option<String>,
            scene: String,
            backend: String,
            mode: Option<String>,
            #[serde(default)]
            device: String,
            #[serde(flatten)]
            rest: Map<String, Value>,
        }
        let s = Stored::deserialize(d)?;
        let data = Data::parse(&s.experiment, s.rest).map_err(serde::de::Error::custom)?;
        Ok(Self {
            host: s.host,
            experiment: s.experiment,
            reused_from: s.reused_from,
            key: Key {
                scene: s.scene,
                backend: s.backend,
                mode: s.mode,
            },
            device: s.device,
            data,
        })
    }
}

/// A backend that did not start.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Unavailable {
    /// Backend name.
    pub name: String,
    /// Why, in the CLI's words.
    pub reason: String,
}

/// `results.json`: one matrix run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Results {
    /// Where it ran.
    pub host: HostInfo,
    /// The command line.
    #[serde(default = "default_command")]
    pub command: String,
    /// Untimed frames per measurement (missing in old files: 1 with `quick`, else 3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warmup: Option<u32>,
    /// `--quick`.
    pub quick: bool,
    /// Timed frames per measurement.
    pub frames: u32,
    /// Wall time of the run, s.
    pub elapsed_s: f64,
    /// The backends measured, in table order.
    pub backends: Vec<String>,
    /// Backend name to device.
    pub devices: BTreeMap<String, String>,
    /// Backends that did not start.
    pub unavailable: Vec<Unavailable>,
    /// Measurements that failed, in words.
    pub failures: Vec<String>,
    /// Measurements left out on purpose, in words (why, and what it would have needed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skips: Vec<String>,
    /// Every measurement.
    pub records: Vec<Record>,
}

fn default_command() -> String {
    "cargo xtask matrix".to_owned()
}

impl Results {
    /// Warm-up frames per measurement.
    #[must_use]
    pub fn warmup(&self) -> u32 {
        self.warmup.unwrap_or(if self.quick { 1 } else { 3 })
    }

    /// The first `bench` record of `experiment` on `scene`, `backend`, `mode` with `lights`
    /// lights (any with `None`).
    #[must_use]
    pub fn bench(
        &self,
        experiment: &str,
        scene: &str,
        backend: &str,
        mode: &str,
        lights: Option<u64>,
    ) -> Option<&Bench> {
        self.records
            .iter()
            .filter(|r| r.is(experiment, Some(scene), backend, mode))
            .filter_map(Record::bench)
            .find(|b| lights.is_none_or(|n| b.lights == Some(n)))
    }

    /// Median silhouette ms of the one-light `bench` record of `experiment`.
    #[must_use]
    pub fn ms(&self, experiment: &str, scene: &str, backend: &str, mode: &str) -> Option<f64> {
        self.bench(experiment, scene, backend, mode, Some(1))
            .and_then(|b| b.median_ms)
    }
}
