//! What the matrix measures: the scenes of each table and the light counts, image size and
//! render scenes of one run.

use super::args::{Only, Options};

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
/// Scenes of the volumes-against-maps table besides every `hard-*` preset.
pub(super) const MAP_SCENES_EXTRA: [&str; 3] = ["town", "bunnies-10-individual", "sphere-1m"];
/// The `--quick` subset of the volumes-against-maps table.
pub(super) const MAP_SCENES_QUICK: [&str; 3] = ["hard-light-on-edge-line", "town", "bunny"];
/// Image size of the volumes-against-maps table.
pub(super) const MAP_RENDER_SIZE: &str = "1280x720";
/// Map sizes of the volumes-against-maps table (texels a side).
pub(super) const MAP_SIZES: [u32; 5] = [512, 1024, 2048, 4096, 8192];
/// The `--quick` map sizes.
pub(super) const MAP_SIZES_QUICK: [u32; 2] = [512, 2048];
/// The biases (`DEPTH,SLOPE,NORMAL`) swept for the table's "tuned with hindsight" rows, besides
/// Bevy's defaults: around both of Bevy's defaults, smaller and larger, and one with a
/// slope-scaled part.
pub(super) const MAP_BIAS_SWEEP: [&str; 6] = [
    "0.005,0,0.3",
    "0.02,0,0.6",
    "0.08,0,1.8",
    "0.02,2,1.8",
    "0.3,0,1.8",
    "0.3,0,4",
];
/// The `--quick` sweep.
pub(super) const MAP_BIAS_SWEEP_QUICK: [&str; 2] = ["0.005,0,0.3", "0.3,0,4"];
/// The key `backend` of the map pipeline's rows.
pub(super) const MAP_KEY: &str = "map";

/// Scenes of the memory table: spheres of 10^5, 10^6 and 10^7 triangles.
pub(super) const MEMORY_SCENES: [&str; 3] = ["sphere-100k", "sphere-1m", "sphere-10m"];
/// The `--quick` memory scenes (the 10^7 one left out).
pub(super) const MEMORY_SCENES_QUICK: [&str; 2] = ["sphere-100k", "sphere-1m"];
/// The real-curvature scene at scale (full run only): `silhouette` on every backend and
/// `render` on the GPU pipeline.
pub(super) const MEMORY_BUNNY: &str = "bunny-10m";
/// The 10^8 scene (full run only): `silhouette` on the CPU backends only, each when the
/// machine has the memory its sphere-10m peak in the same run implies.
pub(super) const MEMORY_HUGE: &str = "sphere-100m";
/// The backends that run [`MEMORY_HUGE`].
pub(super) const MEMORY_HUGE_BACKENDS: [&str; 2] = ["cpu", "simd"];
/// The 10^7 scene whose peak per triangle, times [`MEMORY_HUGE`]'s triangles and this margin,
/// must be available before [`MEMORY_HUGE`] runs on a backend.
pub(super) const MEMORY_HUGE_FROM: (&str, f64) = ("sphere-10m", 1.25);
/// The `render` runs of the memory table: its key `backend` and the flags that pick the
/// pipeline.
pub(super) const MEMORY_RENDERS: [(&str, &[&str]); 3] = [
    ("render-gpu", &["--pipeline", "gpu"]),
    (
        "render-host-simd",
        &["--pipeline", "host", "--backend", "simd"],
    ),
    ("render-map", &["--shadows", "map"]),
];
/// Builds of the largest memory scene's edge table timed (`bench --build-runs`).
pub(super) const BUILD_RUNS: &str = "3";
/// Image size of the memory table's renders.
pub(super) const MEMORY_RENDER_SIZE: &str = "1280x720";

/// Scenes of the soft-shadow table, each with the flags that give it a receiver: the hard-*
/// presets have no ground (a backdrop receives their shadows), the bunny stands on a floor; town
/// has its own ground.
pub(super) const SOFT_SCENES: [(&str, &[&str]); 4] = [
    ("hard-tetrahedron", &["--backdrop"]),
    ("hard-book-3", &["--backdrop"]),
    ("bunny", &["--ground", "on"]),
    ("town", &[]),
];
/// The `--quick` scene of the soft-shadow table.
pub(super) const SOFT_SCENES_QUICK: [(&str, &[&str]); 1] = [("hard-tetrahedron", &["--backdrop"])];
/// The light sizes of the soft-shadow table, small to large: for point and spot lights a
/// fraction of the diagonal of the scene's caster box ([`shadowvol_report::SceneBounds`]), for
/// directional lights an angular radius in radians (0.0047: the sun).
pub(super) const SOFT_RADII: [SoftRadius; 3] = [
    SoftRadius {
        fraction: 0.01,
        radians: 0.0047,
    },
    SoftRadius {
        fraction: 0.03,
        radians: 0.02,
    },
    SoftRadius {
        fraction: 0.1,
        radians: 0.05,
    },
];
/// The `--quick` light size: the middle one.
pub(super) const SOFT_RADII_QUICK: [SoftRadius; 1] = [SOFT_RADII[1]];
/// `--light-samples` of the volumes' rows; the plan's choice (no flag) is a row of its own.
pub(super) const SOFT_SAMPLES: [u32; 4] = [1, 4, 16, 64];
/// The `--quick` sample counts (no plan's-choice row).
pub(super) const SOFT_SAMPLES_QUICK: [u32; 2] = [1, 16];
/// PCSS map sizes (`--map-size`, texels a side).
pub(super) const SOFT_PCSS_SIZES: [u32; 2] = [2048, 4096];
/// The `--quick` PCSS size.
pub(super) const SOFT_PCSS_SIZES_QUICK: [u32; 1] = [2048];
/// Image size of the soft-shadow table.
pub(super) const SOFT_RENDER_SIZE: &str = "960x540";
/// The `--quick` image size.
pub(super) const SOFT_RENDER_SIZE_QUICK: &str = "320x180";
/// The key `backend` of the soft-shadow table's volume rows (the default pipeline).
pub(super) const SOFT_VOLUMES_KEY: &str = "volumes";

/// One light size of the soft-shadow table, by the kind of light it is given to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SoftRadius {
    /// Point and spot lights: the radius over the diagonal of the scene's caster box.
    pub fraction: f64,
    /// Directional lights: the angular radius, radians.
    pub radians: f64,
}

/// What the soft-shadow table measures.
#[derive(Debug, Clone)]
pub(super) struct SoftPlan {
    /// Scenes and the flags that give each a receiver.
    pub scenes: Vec<(&'static str, &'static [&'static str])>,
    /// Light sizes.
    pub radii: Vec<SoftRadius>,
    /// `--light-samples` of the volumes' rows.
    pub samples: Vec<u32>,
    /// Whether the plan's choice (no `--light-samples`) is a row.
    pub plan_choice: bool,
    /// PCSS map sizes.
    pub pcss_sizes: Vec<u32>,
    /// Image size, `WxH`.
    pub size: &'static str,
}

impl SoftPlan {
    /// The full table, or its short form with `quick`.
    pub fn new(quick: bool) -> Self {
        if quick {
            Self {
                scenes: SOFT_SCENES_QUICK.to_vec(),
                radii: SOFT_RADII_QUICK.to_vec(),
                samples: SOFT_SAMPLES_QUICK.to_vec(),
                plan_choice: false,
                pcss_sizes: SOFT_PCSS_SIZES_QUICK.to_vec(),
                size: SOFT_RENDER_SIZE_QUICK,
            }
        } else {
            Self {
                scenes: SOFT_SCENES.to_vec(),
                radii: SOFT_RADII.to_vec(),
                samples: SOFT_SAMPLES.to_vec(),
                plan_choice: true,
                pcss_sizes: SOFT_PCSS_SIZES.to_vec(),
                size: SOFT_RENDER_SIZE,
            }
        }
    }

    /// Renders per scene and light size.
    pub fn renders_per_radius(&self) -> u64 {
        (self.samples.len() + usize::from(self.plan_choice) + self.pcss_sizes.len()) as u64
    }

    /// Progress steps: per scene one probe (its lights and box), then every render.
    pub fn steps(&self) -> u64 {
        self.scenes.len() as u64 * (1 + self.radii.len() as u64 * self.renders_per_radius())
    }
}

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
    /// Scenes of the volumes-against-maps table.
    pub map_scenes: Vec<String>,
    /// Map sizes of that table.
    pub map_sizes: Vec<u32>,
    /// Biases swept for its tuned rows.
    pub map_biases: Vec<&'static str>,
    /// Scenes of the memory table.
    pub memory_scenes: Vec<&'static str>,
    /// Whether the memory table adds [`MEMORY_BUNNY`] and [`MEMORY_HUGE`] (full run).
    pub memory_large: bool,
    /// The soft-shadow table.
    pub soft: SoftPlan,
    /// The one table that runs (`--only`), if any.
    pub only: Option<Only>,
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
            map_scenes: if o.quick {
                MAP_SCENES_QUICK.iter().map(|s| (*s).to_owned()).collect()
            } else {
                scenes
                    .iter()
                    .filter(|s| s.starts_with("hard-"))
                    .cloned()
                    .chain(MAP_SCENES_EXTRA.iter().map(|s| (*s).to_owned()))
                    .collect()
            },
            map_sizes: if o.quick {
                MAP_SIZES_QUICK.to_vec()
            } else {
                MAP_SIZES.to_vec()
            },
            memory_scenes: if o.quick {
                MEMORY_SCENES_QUICK.to_vec()
            } else {
                MEMORY_SCENES.to_vec()
            },
            memory_large: !o.quick,
            soft: SoftPlan::new(o.quick),
            only: o.only,
            map_biases: if o.quick {
                MAP_BIAS_SWEEP_QUICK.to_vec()
            } else {
                MAP_BIAS_SWEEP.to_vec()
            },
        }
    }

    /// Progress steps; must follow `Matrix::run_plan`: one per bench call (all backends
    /// at once), render, accuracy call (per backend) and baselines call.
    pub fn steps(&self) -> u64 {
        match self.only {
            Some(Only::Maps) => return self.map_steps(),
            Some(Only::Memory) => return self.memory_steps(),
            Some(Only::Soft) => return self.soft.steps(),
            None => {}
        }
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
            + self.map_steps()
            + self.memory_steps()
            + self.soft.steps()
    }

    /// Progress steps of the memory table: per scene one `silhouette` per backend and one
    /// `render` per pipeline, the large scenes of a full run, and the build timing.
    pub fn memory_steps(&self) -> u64 {
        let large = if self.memory_large {
            self.backends.len() as u64 + 1 + MEMORY_HUGE_BACKENDS.len() as u64
        } else {
            0
        };
        self.memory_scenes.len() as u64 * (self.backends.len() + MEMORY_RENDERS.len()) as u64
            + large
            + 1
    }

    /// Progress steps of the volumes-against-maps table: per scene the GPU pipeline in each mode
    /// and the host pipeline in exact mode, then per map size and filter the default bias and
    /// each swept one.
    pub fn map_steps(&self) -> u64 {
        let per_map = 1 + self.map_biases.len() as u64;
        self.map_scenes.len() as u64
            * (self.modes.len() as u64 + 1 + 2 * self.map_sizes.len() as u64 * per_map)
    }
}
