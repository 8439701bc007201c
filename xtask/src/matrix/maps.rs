//! The volumes-against-maps measurements: every scene of the table rendered at 1280x720 against
//! the reference with the volumes (the GPU pipeline in each mode, the host pipeline in exact
//! mode) and with shadow maps (each size and filter with Bevy's bias, timed, then each bias of
//! the sweep, untimed: the bias changes no work).

use super::cli::RenderReport;
use super::plan::{Plan, FRAME_GPU_KEY, FRAME_HOST_BACKEND, MAP_KEY, MAP_RENDER_SIZE};
use super::records::{Data, Key, Render};
use super::runner::{render_args, Matrix};

/// One render of the table: what draws the shadows.
enum Technique<'a> {
    /// Volumes on the GPU pipeline in `mode`.
    GpuVolumes(&'a str),
    /// Exact volumes on the host pipeline.
    HostExact,
    /// Maps of `size` texels read with `filter` and `bias` (`None`: Bevy's).
    Map {
        size: u32,
        filter: &'static str,
        bias: Option<&'a str>,
    },
}

impl Matrix {
    /// The volumes-against-maps table's renders (experiments `maps` and `maps-sweep`).
    pub(super) fn maps_table(&mut self, plan: &Plan) {
        let modes = plan.modes.clone();
        for scene in plan.map_scenes.clone() {
            for m in &modes {
                self.map_render(&scene, &Technique::GpuVolumes(m), true);
            }
            self.map_render(&scene, &Technique::HostExact, true);
            for &size in &plan.map_sizes {
                for filter in ["hard", "pcf"] {
                    let t = Technique::Map {
                        size,
                        filter,
                        bias: None,
                    };
                    self.map_render(&scene, &t, true);
                    for bias in &plan.map_biases {
                        let t = Technique::Map {
                            size,
                            filter,
                            bias: Some(bias),
                        };
                        self.map_render(&scene, &t, false);
                    }
                }
            }
        }
    }

    /// One render of `scene` with `t` against the reference, with `--frames` when `timed`.
    fn map_render(&mut self, scene: &str, t: &Technique<'_>, timed: bool) {
        let (backend, mode, label) = match t {
            Technique::GpuVolumes(m) => (
                FRAME_GPU_KEY.to_owned(),
                Some(*m),
                format!("volumes-gpu-{m}"),
            ),
            Technique::HostExact => (
                FRAME_HOST_BACKEND.to_owned(),
                Some("exact"),
                "volumes-host-exact".to_owned(),
            ),
            Technique::Map { size, filter, bias } => (
                MAP_KEY.to_owned(),
                None,
                format!(
                    "map-{size}-{filter}-{}",
                    bias.unwrap_or("default").replace(',', "_")
                ),
            ),
        };
        let experiment = if timed { "maps" } else { "maps-sweep" };
        self.progress
            .step(&format!("{experiment}: {scene} {label}"));
        let png_s = self.render_png(&format!("maps-{scene}-{label}"));
        let frames = self.frames();
        let size_s;
        let mut args = render_args(scene, &png_s, MAP_RENDER_SIZE);
        args.push("--reference");
        if timed {
            args.extend(["--frames", &frames]);
        }
        // The hard-* presets have no ground: a backdrop receives their shadows.
        if scene.starts_with("hard-") {
            args.push("--backdrop");
        }
        match t {
            Technique::GpuVolumes(m) => args.extend(["--pipeline", "gpu", "--mode", m]),
            Technique::HostExact => args.extend([
                "--pipeline",
                "host",
                "--backend",
                FRAME_HOST_BACKEND,
                "--mode",
                "exact",
            ]),
            Technique::Map { size, filter, bias } => {
                size_s = size.to_string();
                args.extend([
                    "--shadows",
                    "map",
                    "--map-size",
                    &size_s,
                    "--map-filter",
                    filter,
                ]);
                if let Some(b) = bias {
                    args.extend(["--map-bias", b]);
                }
            }
        }
        match self.cli.json::<RenderReport>(&args) {
            Ok(report) => {
                let device = report.frame.adapter.clone();
                let mut render = Render::new(report, MAP_RENDER_SIZE, png_s);
                if let Technique::Map { bias, .. } = t {
                    render.map_bias = Some(bias.unwrap_or("default").to_owned());
                }
                let key = Key {
                    scene: scene.to_owned(),
                    backend,
                    mode: mode.map(str::to_owned),
                };
                self.push(experiment, key, device, Data::Render(render));
            }
            Err(e) => self.fail(format!("{experiment}: {e}")),
        }
    }
}
