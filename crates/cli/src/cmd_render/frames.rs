//! `render --frames N`: the lights on a fixed orbit, each frame timed without readback.

use super::render_error;
use shadowvol::CliError;
use shadowvol_renderer::{Renderer, Scene};
use shadowvol_robust_math::Light;

pub(crate) use shadowvol_report::FrameStats;

/// Light `l` in orbit frame `k`: turned by `k` degrees about the vertical axis through
/// `centre` (a point light moves, a directional light turns).
fn orbit_light(l: Light, centre: glam::Vec3, k: u32) -> Light {
    let rot = glam::Quat::from_rotation_y((k as f32).to_radians());
    if l.is_directional() {
        Light::directional(rot * l.to_vec4().truncate())
    } else {
        Light::point(centre + rot * (l.to_vec4().truncate() - centre))
    }
}

/// What the `--frames` frames measured.
#[derive(Debug, Default)]
pub(super) struct Timed {
    pub(super) stats: Option<FrameStats>,
    pub(super) readback_bytes: u64,
    /// The median of each pass's GPU time, where timestamps were read.
    pub(super) gpu_timings: Option<shadowvol_renderer::GpuTimings>,
}

/// The median of each field over `all` (`None` when empty).
fn median_timings(
    all: &[shadowvol_renderer::GpuTimings],
) -> Option<shadowvol_renderer::GpuTimings> {
    if all.is_empty() {
        return None;
    }
    let med = |f: fn(&shadowvol_renderer::GpuTimings) -> f64| {
        let mut v: Vec<f64> = all.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    Some(shadowvol_renderer::GpuTimings {
        extract: med(|t| t.extract),
        sides: med(|t| t.sides),
        caps: med(|t| t.caps),
        stencil: med(|t| t.stencil),
        lighting: med(|t| t.lighting),
        shadow_maps: med(|t| t.shadow_maps),
    })
}

/// `--frames`: `n` frames with the lights of `scene` on the orbit, timed without reading
/// images back; the scene's lights are put back afterwards.
pub(super) fn timed_frames(
    renderer: &mut Renderer,
    scene: &mut Scene,
    n: u32,
) -> Result<Timed, CliError> {
    if n == 0 {
        return Ok(Timed::default());
    }
    let centre = scene
        .bounds()
        .map_or(glam::Vec3::ZERO, |(lo, hi)| (lo + hi) * 0.5);
    let lights = scene.lights.clone();
    let bar = indicatif::ProgressBar::new(u64::from(n));
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} frames",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut ms = Vec::with_capacity(n as usize);
    let mut bytes = 0u64;
    let mut gpu = Vec::new();
    let mut run = |scene: &mut Scene| -> Result<(), CliError> {
        for k in 1..=n {
            for (l, start) in scene.lights.iter_mut().zip(&lights) {
                l.light = orbit_light(start.light, centre, k);
            }
            let t = renderer.render_timed(scene).map_err(render_error)?;
            ms.push(t.total_ms);
            bytes += t.readback_bytes;
            gpu.extend(t.gpu_timings);
            bar.inc(1);
        }
        Ok(())
    };
    let result = run(scene);
    bar.finish_and_clear();
    scene.lights.clone_from(&lights);
    result?;
    Ok(Timed {
        stats: FrameStats::of(&mut ms),
        readback_bytes: bytes,
        gpu_timings: median_timings(&gpu),
    })
}
