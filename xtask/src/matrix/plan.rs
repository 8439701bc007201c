//! What the matrix measures: the scenes of each table and the light counts, image size and
//! render scenes of one run.

use super::args::Options;

/// Scene of Table 1 and of the accuracy table's time ratios.
pub(super) const T1_SCENE: &str = "sphere-1m";
/// Scenes of Table 2 (individual against baked objects).
pub(super) const T2_SCENES: [&str; 4] = [
    "bunnies-10-individual",
    "bunnies-10-baked",
    "spheres-10-individual",
    "spheres-10-baked",
];
/// Scenes of Table 3 (triangles and objects).
pub(super) const T3_SCENES: [&str; 4] = [
    "sphere-1m",
    "sphere-100k",
    "spheres-100x10k",
    "spheres-100x1k",
];
/// Scenes for time against triangles (10^3 .. 10^6).
pub(super) const TRI_SCENES: [&str; 4] = ["sphere-1k", "sphere-10k", "sphere-100k", "sphere-1m"];
/// Scene for time against lights.
pub(super) const LIGHT_SCENE: &str = "sphere-100k";
/// Scenes rendered against the ray-traced reference for artifact counts: every `hard-*` preset
/// that `shadowvol scenes` lists (the corpus grows; the matrix follows it), then these.
pub(super) const RENDER_SCENES_EXTRA: [&str; 1] = ["town"];
/// Scenes of the frame table: the host pipeline (`simd`) against the GPU pipeline, `--frames`
/// on the light orbit, exact mode.
pub(super) const FRAME_SCENES: [&str; 3] = ["sphere-1m", "spheres-100x1k", "town"];
/// The backend of the frame table's host rows.
pub(super) const FRAME_HOST_BACKEND: &str = "simd";
/// The key `backend` of the frame table's GPU-pipeline rows.
pub(super) const FRAME_GPU_KEY: &str = "gpu-pipeline";
/// Scenes of the Toy Wars table (closed manifold meshes, which the seeds' algorithms need).
pub(super) const TOYWARS_SCENES: [&str; 2] = ["bunny", "bunny-subdivided"];

/// The measurements of one run.
pub(super) struct Plan {
    /// Backends to measure, in table order.
    pub backends: Vec<String>,
    /// Accuracy modes to measure.
    pub modes: Vec<String>,
    /// Light counts of the time-against-lights series.
    pub light_counts: Vec<u32>,
    /// Scenes rendered against the reference.
    pub render_scenes: Vec<String>,
    /// Image size of every render, `WxH`.
    pub render_size: &'static str,
    /// Scenes of the Toy Wars table.
    pub toywars_scenes: Vec<&'static str>,
    /// Scenes of the frame table (empty when `simd` is not measured).
    pub frame_scenes: Vec<&'static str>,
}

impl Plan {
    /// The plan of `o` on the available `backends`, with the CLI's preset `scenes`.
    pub fn new(o: &Options, backends: &[String], scenes: &[String]) -> Self {
        Self {
            backends: backends.to_vec(),
            modes: o.modes.clone(),
            light_counts: if o.quick {
                vec![1, 2, 4, 8]
            } else {
                (1..=8).collect()
            },
            render_scenes: scenes
                .iter()
                .filter(|s| s.starts_with("hard-"))
                .cloned()
                .chain(RENDER_SCENES_EXTRA.iter().map(|s| (*s).to_owned()))
                .collect(),
            render_size: if o.quick { "160x120" } else { "320x240" },
            toywars_scenes: TOYWARS_SCENES.to_vec(),
            frame_scenes: if backends.iter().any(|b| b == FRAME_HOST_BACKEND) {
                FRAME_SCENES.to_vec()
            } else {
                Vec::new()
            },
        }
    }

    /// Progress steps; must follow `Matrix::run_plan`: one per bench call (all backends
    /// at once), render, accuracy call (per backend) and baselines call.
    pub fn steps(&self) -> u64 {
        let b = self.backends.len() as u64;
        let m = self.modes.len() as u64;
        let tri = TRI_SCENES.iter().filter(|s| **s != T1_SCENE).count() as u64;
        let t3 = T3_SCENES
            .iter()
            .filter(|s| **s != T1_SCENE && !TRI_SCENES.contains(s))
            .count() as u64;
        let lights = self
            .light_counts
            .iter()
            .filter(|&&n| !(n == 1 && TRI_SCENES.contains(&LIGHT_SCENE)))
            .count() as u64;
        1 + b * m
            + T2_SCENES.len() as u64
            + tri
            + t3
            + lights
            + b
            + self.render_scenes.len() as u64 * b * m
            + self.toywars_scenes.len() as u64
            + 2 * self.frame_scenes.len() as u64
    }
}
