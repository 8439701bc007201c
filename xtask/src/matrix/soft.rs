//! The soft-shadow measurements: per scene and light size, exact volumes at each
//! `--light-samples` and at the plan's choice, and PCSS at each map size, every render against
//! the reference (the visibility error over the penumbra) with `--frames` (the frame time) in one
//! call.
//!
//! A point light's radius is a fraction of the scene's caster box, which one small probe render
//! per scene reads (`scene_bounds`), with its lights. A scene that mixes directional and point
//! lights is rendered with its point lights alone (`--light`).

use super::cli::RenderReport;
use super::plan::{SoftPlan, SoftRadius, MAP_KEY, SOFT_VOLUMES_KEY};
use super::records::{Data, Key, Render};
use super::runner::{render_args, Matrix};

/// What draws one render's soft shadows.
#[derive(Debug, Clone, Copy)]
enum Technique {
    /// Exact volumes on the default pipeline with `--light-samples` (`None`: the plan's choice).
    Volumes(Option<u32>),
    /// PCSS maps of this many texels a side.
    Pcss(u32),
}

impl Technique {
    /// A short name for file names and the progress bar.
    fn label(self) -> String {
        match self {
            Self::Volumes(Some(n)) => format!("volumes-n{n}"),
            Self::Volumes(None) => "volumes-plan".to_owned(),
            Self::Pcss(size) => format!("pcss-{size}"),
        }
    }
}

/// The lights to render a scene with, from its own (homogeneous `[x, y, z, w]`): its point
/// lights when it mixes directional and point lights (one `--light-radius` cannot size both);
/// `None` to keep its own.
pub(crate) fn point_lights_of_a_mix(lights: &[[f32; 4]]) -> Option<Vec<[f32; 4]>> {
    let points: Vec<[f32; 4]> = lights.iter().filter(|l| l[3] != 0.0).copied().collect();
    (!points.is_empty() && points.len() < lights.len()).then_some(points)
}

/// The radius `r` gives lights of the kinds in `lights` in a scene whose caster box has diagonal
/// `diagonal`, and for point lights the fraction of the diagonal: radians when every light is
/// directional (`w = 0`), a fraction of the diagonal when none is; an error for a mix or a scene
/// without lights or box.
pub(crate) fn radius_for(
    r: SoftRadius,
    lights: &[[f32; 4]],
    diagonal: Option<f64>,
) -> Result<(f64, Option<f64>), String> {
    let directional = lights.iter().filter(|l| l[3] == 0.0).count();
    match (directional, lights.len()) {
        (_, 0) => Err("the scene has no light".to_owned()),
        (d, n) if d == n => Ok((r.radians, None)),
        (0, _) => match diagonal {
            Some(d) if d > 0.0 => Ok((r.fraction * d, Some(r.fraction))),
            _ => Err("the render JSON has no scene_bounds to size its point lights".to_owned()),
        },
        _ => Err(
            "its lights mix directional and point lights; one radius cannot size both".to_owned(),
        ),
    }
}

/// `--light=X,Y,Z,W` for each of `lights`.
fn light_flags(lights: &[[f32; 4]]) -> Vec<String> {
    lights
        .iter()
        .map(|[x, y, z, w]| format!("--light={x},{y},{z},{w}"))
        .collect()
}

impl Matrix {
    /// The soft-shadow table's renders (experiment `soft`).
    pub(super) fn soft_table(&mut self, plan: &SoftPlan) {
        let mut techniques: Vec<Technique> = plan
            .samples
            .iter()
            .map(|&n| Technique::Volumes(Some(n)))
            .collect();
        if plan.plan_choice {
            techniques.push(Technique::Volumes(None));
        }
        techniques.extend(plan.pcss_sizes.iter().map(|&s| Technique::Pcss(s)));
        for &(scene, flags) in &plan.scenes {
            self.progress.step(&format!("soft: {scene} probe"));
            let mut flags: Vec<String> = flags.iter().map(|f| (*f).to_owned()).collect();
            let radii: Result<Vec<(f64, Option<f64>)>, String> = self
                .soft_probe(scene, &flags)
                .and_then(|(mut lights, diagonal)| {
                    if let Some(points) = point_lights_of_a_mix(&lights) {
                        flags.extend(light_flags(&points));
                        lights = points;
                    }
                    plan.radii
                        .iter()
                        .map(|&r| radius_for(r, &lights, diagonal))
                        .collect::<Result<_, _>>()
                        .map_err(|e| format!("soft: {scene}: {e}"))
                });
            let radii = match radii {
                Ok(r) => r,
                Err(e) => {
                    for _ in 0..plan.radii.len() as u64 * plan.renders_per_radius() {
                        self.progress.step(&format!("soft: {scene} skipped"));
                    }
                    self.fail(format!("{e}; the scene's soft renders were skipped"));
                    continue;
                }
            };
            for (i, &(radius, fraction)) in radii.iter().enumerate() {
                for &t in &techniques {
                    self.soft_render(scene, &flags, plan.size, i, radius, fraction, t);
                }
            }
        }
    }

    /// The lights (`[x, y, z, w]`) and the caster box's diagonal of `scene` as rendered with
    /// `flags`, from a small render.
    fn soft_probe(
        &mut self,
        scene: &str,
        flags: &[String],
    ) -> Result<(Vec<[f32; 4]>, Option<f64>), String> {
        let png = self.render_png(&format!("soft-{scene}-probe"));
        let mut args = render_args(scene, &png, "64x36");
        args.extend(flags.iter().map(String::as_str));
        let report: RenderReport = self
            .cli
            .json(&args)
            .map_err(|e| format!("soft: {scene} probe: {e}"))?;
        Ok((report.lights, report.scene_bounds.map(|b| b.diagonal())))
    }

    /// One render of `scene` with lights of `radius` (size `index` of the plan; `fraction` of
    /// the scene's box for point lights) drawn by `t`, against the reference with `--frames`.
    #[allow(clippy::too_many_arguments)]
    fn soft_render(
        &mut self,
        scene: &str,
        flags: &[String],
        size: &str,
        index: usize,
        radius: f64,
        fraction: Option<f64>,
        t: Technique,
    ) {
        let label = t.label();
        self.progress
            .step(&format!("soft: {scene} r{index} {label}"));
        let png = self.render_png(&format!("soft-{scene}-r{index}-{label}"));
        let frames = self.frames();
        let radius_s = radius.to_string();
        let (n_s, map_s);
        let mut args = render_args(scene, &png, size);
        args.extend(flags.iter().map(String::as_str));
        args.extend([
            "--reference",
            "--frames",
            &frames,
            "--light-radius",
            &radius_s,
        ]);
        match t {
            Technique::Volumes(n) => {
                args.extend(["--mode", "exact"]);
                if let Some(n) = n {
                    n_s = n.to_string();
                    args.extend(["--light-samples", &n_s]);
                }
            }
            Technique::Pcss(s) => {
                map_s = s.to_string();
                args.extend([
                    "--shadows",
                    "map",
                    "--map-filter",
                    "pcss",
                    "--map-size",
                    &map_s,
                ]);
            }
        }
        let report = match self.cli.json::<RenderReport>(&args) {
            Ok(r) => r,
            Err(e) => return self.fail(format!("soft: {e}")),
        };
        let device = report.frame.adapter.clone();
        let soft = super::records::SoftFields::of(&report, radius);
        let mut render = Render::new(report, size, png);
        let missing = soft.missing.clone();
        render.set_soft(soft, fraction, t_samples(t));
        let (backend, mode) = match t {
            Technique::Volumes(_) => (SOFT_VOLUMES_KEY, Some("exact".to_owned())),
            Technique::Pcss(_) => (MAP_KEY, None),
        };
        let key = Key {
            scene: scene.to_owned(),
            backend: backend.to_owned(),
            mode,
        };
        self.push("soft", key, device, Data::Render(render));
        if let Some(why) = missing {
            self.fail(format!(
                "soft: {scene} r{index} {label}: no visibility error: {why} (the render's time is recorded)"
            ));
        }
    }
}

/// The `--light-samples` setting of `t` as recorded: the count, `plan`, or `None` for PCSS.
fn t_samples(t: Technique) -> Option<String> {
    match t {
        Technique::Volumes(Some(n)) => Some(n.to_string()),
        Technique::Volumes(None) => Some("plan".to_owned()),
        Technique::Pcss(_) => None,
    }
}
