//! `shadowvol render --format json`: the frame's report with what the command adds.

use crate::frame::FrameReport;
use crate::maps::{MapBias, MapFilter};
use serde::{Deserialize, Serialize};

/// The JSON of `shadowvol render` (the CLI contract's `render` shape, extended): the frame's
/// [`FrameReport`], flattened, then the image, the reference's counts, the lights, the
/// `--frames` times, the map settings and memory. Fields a later version added default when
/// absent, so older records still read.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RenderReport {
    /// What the frame ran and drew.
    #[serde(flatten)]
    pub frame: FrameReport,
    /// The scene's name (a preset's, or the file's stem).
    #[serde(default)]
    pub scene: String,
    /// Image size `[width, height]`, pixels.
    #[serde(default)]
    pub size: [u32; 2],
    /// Where the image was written.
    #[serde(default)]
    pub out: String,
    /// Pixels the render shows in shadow of at least one light.
    #[serde(default)]
    pub shadow_pixels: usize,
    /// Pixels whose lit or shadowed state differs from the exact reference, away from its
    /// shadow boundaries (with `--reference`; `None` without).
    #[serde(default)]
    pub artifact_pixels: Option<usize>,
    /// Pixels covered by a surface (with `--reference`).
    #[serde(default)]
    pub covered_pixels: Option<usize>,
    /// Pixels the reference shadows (with `--reference`).
    #[serde(default)]
    pub reference_shadow_pixels: Option<usize>,
    /// `artifact_pixels` with lit meaning `cos θ > 0` (no 1/255 visibility threshold).
    #[serde(default)]
    pub geometric_artifact_pixels: Option<usize>,
    /// Covered pixels the reference could not decide (not counted as artifacts).
    #[serde(default)]
    pub undecidable_pixels: Option<usize>,
    /// Pixels where raster and reference differ at a reference shadow boundary: within one
    /// pixel of one, or where one crosses the pixel's footprint (not counted as artifacts).
    #[serde(default)]
    pub boundary_pixels: Option<usize>,
    /// Of `boundary_pixels`, those only the footprint rule kept out of `artifact_pixels` (the
    /// reference is the same over the 3×3 neighbourhood, but a shadow boundary crosses the
    /// pixel's footprint): `artifact_pixels + footprint_boundary_pixels` is the 3×3 rule's
    /// count.
    #[serde(default)]
    pub footprint_boundary_pixels: Option<usize>,
    /// The same for `geometric_artifact_pixels`.
    #[serde(default)]
    pub geometric_footprint_boundary_pixels: Option<usize>,
    /// The lights used, homogeneous `[x, y, z, w]`.
    #[serde(default)]
    pub lights: Vec<[f32; 4]>,
    /// Where they came from.
    #[serde(default)]
    pub lights_source: LightsSource,
    /// The receiver plane under the scene, if any.
    #[serde(default)]
    pub ground: Option<Ground>,
    /// Bytes brought to the host during the `--frames` frames, besides the final image.
    #[serde(default)]
    pub frame_readback_bytes: u64,
    /// The `--frames` frames' times, `None` without them.
    #[serde(default)]
    pub frames: Option<FrameStats>,
    /// `shadows` and the map settings.
    #[serde(flatten)]
    pub map: MapFields,
    /// The process's peak resident set (the kernel's high-water mark), `None` off Linux.
    #[serde(default)]
    pub peak_rss_bytes: Option<u64>,
    /// What the prepared scene held: its edge tables plus the pipeline's host layout and device
    /// buffers (the image attachments not included): [`TableBytes::total`].
    #[serde(default)]
    pub table_bytes: u64,
    /// `table_bytes` by part.
    #[serde(default)]
    pub table_bytes_parts: TableBytes,
    /// With `--reference`: per light, the artifact pixels of each of its samples' hard shadows
    /// (one entry for a light of one sample); `None` without `--reference`.
    #[serde(default)]
    pub sample_artifact_pixels: Option<Vec<Vec<usize>>>,
    /// With `--reference`: per light, its visibility's error against the true visibility over
    /// the penumbra (`None` for a point light, whose visibility is its hard shadow);
    /// `None` without `--reference`.
    #[serde(default)]
    pub visibility_error: Option<Vec<Option<VisibilityError>>>,
    /// The files `--visibility` wrote, one per light.
    #[serde(default)]
    pub visibility_files: Vec<String>,
    /// World-space bounds of the scene's casters (receivers, the ground and the backdrop not
    /// included): the size a light's radius compares with. `None` for a scene without vertices.
    #[serde(default)]
    pub scene_bounds: Option<SceneBounds>,
}

/// An axis-aligned box in world units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SceneBounds {
    /// The smallest corner.
    pub min: [f32; 3],
    /// The largest corner.
    pub max: [f32; 3],
}

impl SceneBounds {
    /// The length of the box's diagonal.
    #[must_use]
    pub fn diagonal(&self) -> f64 {
        (0..3)
            .map(|i| f64::from(self.max[i] - self.min[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// A light's visibility (`k / N` of its samples) against the true visibility of its disk,
/// over the penumbra: the pixels whose true visibility is strictly between 0 and 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VisibilityError {
    /// Penumbra pixels.
    pub penumbra_pixels: usize,
    /// Mean of `|visibility − true visibility|` over them.
    pub mean: f64,
    /// Its 99th percentile.
    pub p99: f64,
    /// Its maximum.
    pub max: f64,
    /// Pixels the reference finds fully lit (true visibility 1) or fully shadowed (0), not on
    /// the border of another class, where the render's visibility differs.
    pub lit_umbra_mismatches: usize,
    /// The same on a border (a 3x3 neighbour of another class), where a sample's hard shadow
    /// boundary may pass within rounding of the pixel's point: not counted above.
    #[serde(default)]
    pub border_mismatches: usize,
    /// The reference's own bound on its error in the true visibility.
    pub reference_bound: f64,
}

/// Where the lights of a render came from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightsSource {
    /// The scene file or preset.
    #[default]
    File,
    /// `--light`.
    Flags,
    /// The default key light (the scene has none).
    Default,
}

/// The receiver plane `y = ground_y` under the scene and why it is there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ground {
    /// Its height, world units.
    pub y: f32,
    /// `scene` (the preset declares it), `auto` (nothing lay below the casters) or `flags`
    /// (`--ground on`).
    pub source: String,
}

/// Times of the `--frames` frames (the lights on a fixed orbit, so that every frame
/// re-extracts), milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FrameStats {
    /// Frames timed.
    pub count: usize,
    /// Median frame time.
    pub median_ms: f64,
    /// 10th percentile (nearest rank).
    pub p10_ms: f64,
    /// 90th percentile (nearest rank).
    pub p90_ms: f64,
}

impl FrameStats {
    /// Median, p10 and p90 (nearest rank) of `ms`, which it sorts; `None` when empty.
    #[must_use]
    pub fn of(ms: &mut [f64]) -> Option<Self> {
        if ms.is_empty() {
            return None;
        }
        ms.sort_by(f64::total_cmp);
        let at = |q: f64| ms[((ms.len() - 1) as f64 * q).round() as usize];
        Some(Self {
            count: ms.len(),
            median_ms: at(0.5),
            p10_ms: at(0.1),
            p90_ms: at(0.9),
        })
    }
}

/// What drew the shadows.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Shadows {
    /// Stencil shadow volumes (the GPU or host pipeline). The default of a record that names
    /// none: every render before the map pipeline drew volumes.
    #[default]
    Volumes,
    /// Shadow maps (the map pipeline).
    Map,
}

/// What drew the shadows, and for maps the settings in effect (`None` for volumes).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MapFields {
    /// `volumes` or `map`.
    pub shadows: Shadows,
    /// Side of directional and spot maps, texels.
    pub map_size: Option<u32>,
    /// Side of each cube face (point lights), texels.
    pub map_size_point: Option<u32>,
    /// `hard`, `pcf` or `pcss`.
    pub map_filter: Option<MapFilter>,
    /// The bias of directional and spot maps, and of cube maps.
    pub map_bias: Option<MapBiases>,
    /// Cascades of each directional light's map.
    pub map_cascades: Option<u32>,
}

/// The biases in effect per map kind.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MapBiases {
    /// Directional and spot maps.
    pub directional: MapBias,
    /// Cube maps (point lights).
    pub point: MapBias,
}

/// The bytes a prepared scene holds, by part; [`TableBytes::total`] is the JSON's
/// `table_bytes`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct TableBytes {
    /// The scene's edge tables (`EdgeTable::heap_bytes`, each shared table once).
    pub topology: u64,
    /// The backend's or pipeline's own host layout of the scene.
    pub host: u64,
    /// Device buffers the backend or pipeline keeps for the scene.
    pub device: u64,
}

impl TableBytes {
    /// `topology + host + device`.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.topology + self.host + self.device
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Accuracy, Pipeline};

    #[test]
    fn a_report_reads_back_as_written() {
        let mut r = RenderReport {
            frame: FrameReport::new(Pipeline::Gpu, Accuracy::Exact),
            scene: "hard-book-3".to_owned(),
            size: [64, 48],
            out: "book.png".to_owned(),
            shadow_pixels: 12,
            artifact_pixels: Some(0),
            covered_pixels: Some(3000),
            reference_shadow_pixels: Some(12),
            geometric_artifact_pixels: Some(0),
            undecidable_pixels: Some(0),
            boundary_pixels: Some(3),
            footprint_boundary_pixels: Some(1),
            geometric_footprint_boundary_pixels: Some(1),
            lights: vec![[1.0, 2.0, 3.0, 1.0]],
            lights_source: LightsSource::Flags,
            ground: Some(Ground {
                y: -1.0,
                source: "auto".to_owned(),
            }),
            frame_readback_bytes: 0,
            frames: FrameStats::of(&mut [3.0, 1.0, 2.0]),
            map: MapFields::default(),
            peak_rss_bytes: Some(1 << 20),
            table_bytes: 96,
            table_bytes_parts: TableBytes {
                topology: 64,
                host: 0,
                device: 32,
            },
            sample_artifact_pixels: Some(vec![vec![0, 0]]),
            visibility_error: Some(vec![Some(VisibilityError {
                penumbra_pixels: 10,
                mean: 0.01,
                p99: 0.03,
                max: 0.04,
                lit_umbra_mismatches: 0,
                border_mismatches: 2,
                reference_bound: 1e-9,
            })]),
            visibility_files: vec!["v.png".to_owned()],
            scene_bounds: Some(SceneBounds {
                min: [-1.0, 0.0, -1.0],
                max: [1.0, 2.0, 1.0],
            }),
        };
        r.frame.timings.total_ms = 4.5;
        r.frame.gpu_timings = Some(crate::GpuTimings {
            extract: 1.0,
            ..crate::GpuTimings::default()
        });
        let json = serde_json::to_value(&r).unwrap();
        // The contract's names, flat at the top level.
        for key in [
            "artifact_pixels",
            "shadow_pixels",
            "plan",
            "timings",
            "pipeline",
        ] {
            assert!(json.get(key).is_some(), "{key} in {json}");
        }
        assert_eq!(json["gpu_timings_ms"]["extract"], 1.0);
        assert_eq!(json["frames"]["median_ms"], 2.0);
        assert_eq!(json["shadows"], "volumes");
        assert_eq!(json["scene_bounds"]["max"][1], 2.0);
        assert!((r.scene_bounds.unwrap().diagonal() - 12f64.sqrt()).abs() < 1e-12);
        let back: RenderReport = serde_json::from_value(json).unwrap();
        assert_eq!(back, r);
    }

    #[test]
    fn an_old_record_without_the_later_fields_reads() {
        let r: RenderReport = serde_json::from_str(
            r#"{"artifact_pixels": 5, "shadow_pixels": 9, "plan": [], "mode": "robust",
                "timings": {"silhouette_ms": 1.0, "raster_ms": 2.0, "total_ms": 3.0}}"#,
        )
        .unwrap();
        assert_eq!(r.frame.pipeline, crate::Pipeline::Host);
        assert_eq!(r.map.shadows, Shadows::Volumes);
        assert_eq!(r.frame.timings.silhouette_ms, Some(1.0));
        assert_eq!(r.artifact_pixels, Some(5));
        assert_eq!(r.frames, None);
    }
}
