//! What one frame reports, whichever pipeline drew it.

use crate::maps::{MapKind, MapSummary};
use crate::plan::PlanEntry;
use serde::{Deserialize, Serialize};
use shadowvol_robust_math::Accuracy;

/// Which pipeline drew a frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pipeline {
    /// The host pipeline: a silhouette backend's multiplicities come back to the host, which
    /// builds sides and caps and uploads them (any backend). The default of a record that
    /// names none: every render before the GPU pipeline was the host's.
    #[default]
    Host,
    /// The GPU pipeline: extraction, sides and caps on the renderer's device; nothing is read
    /// back during a frame, and no backend runs.
    Gpu,
    /// The map pipeline: shadow maps instead of volumes, on the renderer's device.
    Map,
}

impl Pipeline {
    /// `"host"`, `"gpu"` or `"map"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Pipeline::Host => "host",
            Pipeline::Gpu => "gpu",
            Pipeline::Map => "map",
        }
    }
}

/// What exact mode's uncertain count counts, which differs by pipeline.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum UncertainUnit {
    /// (edge, opposite vertex, light) triples of the backend's extractions (host pipeline),
    /// decided by the backend's exact fallback on the host.
    #[default]
    EdgeOppositeVertexLight,
    /// (triangle, light) pairs, decided on the device with exact integer arithmetic (GPU
    /// pipeline).
    TriangleLight,
}

/// Wall times of one frame, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Timings {
    /// The silhouette backend's `extract` calls; `None` when no backend ran (GPU pipeline:
    /// extraction is part of the device's work, see [`FrameReport::gpu_timings`]).
    pub silhouette_ms: Option<f64>,
    /// Building side quads and caps on the host; `None` when they are built on the device.
    pub side_building_ms: Option<f64>,
    /// Recording, submitting and waiting for the passes, and reading the image back.
    pub raster_ms: f64,
    /// Preparing the scene for the pipeline this frame (edge tables laid out and uploaded, the
    /// backend's `prepare`); 0 when nothing changed.
    pub prepare_ms: f64,
    /// The whole frame.
    pub total_ms: f64,
    /// The exact reference's judgement of the frame, where one ran (`render --reference`);
    /// `None` otherwise.
    pub reference_ms: Option<f64>,
}

/// GPU times of one frame's passes, milliseconds, from timestamp queries.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GpuTimings {
    /// The extraction compute pass (reset, triangle pass, edge pass).
    pub extract: f64,
    /// The side passes of every light.
    pub sides: f64,
    /// The cap passes of every light.
    pub caps: f64,
    /// Sides and caps: the whole stencil passes.
    pub stencil: f64,
    /// The depth pre-pass and every light's lit pass.
    pub lighting: f64,
    /// The shadow-map pipeline's map passes (0 for the volume pipelines).
    pub shadow_maps: f64,
}

/// One frame's report: the same shape for every pipeline. The pipeline fills the fields it
/// knows while it records the frame ([`FrameReport::uncertain`], [`FrameReport::host_resolved`],
/// [`FrameReport::readback_bytes`], [`FrameReport::gpu_timings`], [`FrameReport::scene_parts`],
/// [`FrameReport::surface_vertices`], the silhouette and side-building times, the plan's
/// counts); the renderer fills the rest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameReport {
    /// The pipeline that drew the frame.
    #[serde(default)]
    pub pipeline: Pipeline,
    /// The silhouette backend that ran (its registry name), `None` when none did (the GPU
    /// and map pipelines run none).
    #[serde(default)]
    pub backend: Option<String>,
    /// The device, in words (adapter name, backend, driver).
    #[serde(default)]
    pub adapter: String,
    /// The accuracy mode of silhouettes and caps.
    pub mode: Accuracy,
    /// The plan, light-major: per (light, surface) the technique, why, and what was drawn.
    #[serde(default)]
    pub plan: Vec<PlanEntry>,
    /// Per light: the colour times gain its lit pass multiplies by `albedo × attenuation ×
    /// cos θ` (linear RGB).
    #[serde(default)]
    pub light_colors: Vec<[f32; 3]>,
    /// Output per lux used for the lights with an emission (`None` without any).
    #[serde(default)]
    pub exposure: Option<f32>,
    /// Exact mode: evaluations the certified filter could not decide, counted in
    /// [`FrameReport::uncertain_unit`].
    #[serde(default)]
    pub uncertain: u64,
    /// What [`FrameReport::uncertain`] counts.
    #[serde(default)]
    pub uncertain_unit: UncertainUnit,
    /// Of the uncertain evaluations, the ones decided on the host (all of them in the host
    /// pipeline, none in the GPU pipeline).
    #[serde(default)]
    pub host_resolved: u64,
    /// Bytes brought to the host during the frame besides the image, the ids, the stencil and
    /// the plan's counts: the multiplicities (4 bytes per edge and light and extraction) in the
    /// host pipeline, 0 in the GPU pipeline.
    #[serde(default)]
    pub readback_bytes: u64,
    /// Pixels the per-light scissor kept out of the stencil and lit passes, summed over lights.
    #[serde(default)]
    pub scissor_pixels_saved: usize,
    /// True when the volumes were drawn with depth clamp.
    #[serde(default)]
    pub depth_clamp: bool,
    /// Wall times.
    #[serde(default)]
    pub timings: Timings,
    /// The GPU time of each pass from timestamp queries, where the pipeline and device have
    /// them; JSON `gpu_timings_ms`.
    #[serde(default, rename = "gpu_timings_ms")]
    pub gpu_timings: Option<GpuTimings>,
    /// Parts the GPU pipeline uploaded the scene in: 1, or more for a scene beyond one storage
    /// binding of the device. With more than one, each plan entry's `silhouette_edges` and
    /// `side_quads` add up the parts', the edges where the parts meet included (their volumes
    /// cancel in the stencil).
    #[serde(default)]
    pub scene_parts: usize,
    /// Where the GPU pipeline read the surface vertices, `"buffer"` or `"pulled"`; `None` for
    /// the other pipelines.
    #[serde(default)]
    pub surface_vertices: Option<String>,
    /// Per light, its shadow map (map pipeline; `None`: nothing casts); empty for the volume
    /// pipelines.
    #[serde(default)]
    pub shadow_maps: Vec<Option<MapSummary>>,
    /// Per light: its radius (world units; radians for a directional light; 0: a point light).
    #[serde(default)]
    pub light_radii: Vec<f32>,
    /// Per light: the points sampling it (1: a hard shadow), JSON `light_samples`, with the
    /// reason in `light_samples_reason`.
    #[serde(default, with = "samples_fields", flatten)]
    pub samples: Vec<SamplesChoice>,
}

/// How many points sample one light, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SamplesChoice {
    /// Points sampling the light (1: its centre, a hard shadow).
    pub samples: u32,
    /// The plan's upper bound of the light's widest penumbra on screen, in pixels (0 for a
    /// point light).
    pub penumbra_px: f64,
    /// Why, in words (the plan's estimate, or `--light-samples`).
    pub reason: String,
}

/// [`FrameReport::samples`] as three parallel JSON arrays: `light_samples`,
/// `light_samples_reason` and `light_penumbra_px`.
mod samples_fields {
    use super::SamplesChoice;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    #[derive(Serialize, Deserialize, Default)]
    struct Fields {
        #[serde(default)]
        light_samples: Vec<u32>,
        #[serde(default)]
        light_samples_reason: Vec<String>,
        #[serde(default)]
        light_penumbra_px: Vec<f64>,
    }

    pub fn serialize<S: Serializer>(v: &[SamplesChoice], s: S) -> Result<S::Ok, S::Error> {
        Fields {
            light_samples: v.iter().map(|c| c.samples).collect(),
            light_samples_reason: v.iter().map(|c| c.reason.clone()).collect(),
            light_penumbra_px: v.iter().map(|c| c.penumbra_px).collect(),
        }
        .serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<SamplesChoice>, D::Error> {
        let f = Fields::deserialize(d)?;
        Ok(f.light_samples
            .iter()
            .enumerate()
            .map(|(i, &samples)| SamplesChoice {
                samples,
                reason: f.light_samples_reason.get(i).cloned().unwrap_or_default(),
                penumbra_px: f.light_penumbra_px.get(i).copied().unwrap_or(0.0),
            })
            .collect())
    }
}

impl FrameReport {
    /// An empty report of a frame of `pipeline` in `mode`: no plan, counts 0.
    #[must_use]
    pub fn new(pipeline: Pipeline, mode: Accuracy) -> Self {
        Self {
            pipeline,
            backend: None,
            adapter: String::new(),
            mode,
            plan: Vec::new(),
            light_colors: Vec::new(),
            exposure: None,
            uncertain: 0,
            uncertain_unit: UncertainUnit::default(),
            host_resolved: 0,
            readback_bytes: 0,
            scissor_pixels_saved: 0,
            depth_clamp: false,
            timings: Timings::default(),
            gpu_timings: None,
            scene_parts: 1,
            surface_vertices: None,
            shadow_maps: Vec::new(),
            light_radii: Vec::new(),
            samples: Vec::new(),
        }
    }

    /// The plan as text, one line per (light, surface), after a line naming the pipeline, the
    /// backend, the mode and the device; for the map pipeline, one line per light's map.
    #[must_use]
    pub fn explain(&self) -> String {
        let mut s = format!(
            "{} pipeline; backend {}; mode {}; adapter {}; depth clamp {}; infinite far plane\n",
            self.pipeline.name(),
            self.backend.as_deref().unwrap_or("none"),
            self.mode,
            self.adapter,
            if self.depth_clamp { "on" } else { "off" }
        );
        if self.pipeline == Pipeline::Map {
            for (li, m) in self.shadow_maps.iter().enumerate() {
                s.push_str(&match m {
                    Some(m) => format!(
                        "light {li}: {:?} map {}x{}{}, texel {:.3e} {}, near {:.3e}, bias depth {} slope {} normal {} (offset {:.3e})\n",
                        m.kind,
                        m.size,
                        m.size,
                        match (m.kind, m.cascades) {
                            (MapKind::Cube, _) => " x 6 faces".to_owned(),
                            (_, 1) => String::new(),
                            (_, n) => format!(" x {n} cascades"),
                        },
                        m.texel,
                        if m.kind == MapKind::Directional { "world units" } else { "per unit of distance" },
                        m.near,
                        m.bias.depth,
                        m.bias.slope,
                        m.bias.normal,
                        m.normal_offset,
                    ),
                    None => format!("light {li}: no map (nothing casts a shadow)\n"),
                });
            }
            return s;
        }
        for (li, c) in self.samples.iter().enumerate() {
            if c.samples > 1 || self.light_radii.get(li).is_some_and(|&r| r > 0.0) {
                s.push_str(&format!(
                    "light {li}: radius {}, {} sample{}: {}\n",
                    self.light_radii.get(li).copied().unwrap_or(0.0),
                    c.samples,
                    if c.samples == 1 { "" } else { "s" },
                    c.reason
                ));
            }
        }
        for e in &self.plan {
            s.push_str(&e.to_string());
            s.push('\n');
        }
        s
    }
}
