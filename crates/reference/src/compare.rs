//! The artifact metric: raster against reference per pixel and light, the counts, the shading
//! check and the disagreement image.

use crate::footprint::Footprints;
use crate::states::{
    faces_light, light_attenuation, light_vec, raster_states, raster_states_geometric,
    reference_states_with, surface_points, visible_only, Casters, PixelPoints, SurfacePoint,
};
use crate::{PixelState, Shot};
use rayon::prelude::*;

/// The comparison of a rendered frame with the reference.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Pixels whose state differs from the reference for some light, where the reference's state
    /// is the same over the pixel's 3×3 neighbourhood and no shadow boundary of that light
    /// crosses the pixel's footprint (the footprint rule, [`Comparison::footprint_boundary_pixels`]).
    pub artifact_pixels: usize,
    /// `artifact_pixels` with the geometric facing ([`crate::faces_light_geometric`]): lit means the
    /// light reaches a surface with `cos θ > 0`, however dimly, without the 1/255 visibility
    /// threshold. DESIGN.md's definition read literally; differences here that are not in
    /// `artifact_pixels` are invisible in the 8-bit image.
    pub geometric_artifact_pixels: usize,
    /// Pixels the footprint rule kept out of `artifact_pixels`: they differ for a light where
    /// the reference is the same over the 3×3 neighbourhood, but a shadow boundary of that light
    /// crosses the pixel's footprint, decided exactly: the footprint (the pixel's square seen on
    /// the plane of its triangle) holds both a region of positive area some caster shadows and
    /// one none does. They are counted in `boundary_pixels` (or in `undecidable_pixels` where the
    /// reference could not decide another light).
    pub footprint_boundary_pixels: usize,
    /// The same for `geometric_artifact_pixels`.
    pub geometric_footprint_boundary_pixels: usize,
    /// The pixels (`y · width + x`) counted in `footprint_boundary_pixels`, ascending.
    pub footprint_moved: Vec<usize>,
    /// Pixels whose state differs for some light (boundaries included), or where the reference
    /// is [`PixelState::Uncertain`].
    pub differing_pixels: usize,
    /// Covered pixels where the reference could not decide some light
    /// ([`PixelState::Uncertain`]; see [`crate::occlusion`] for the one case that remains) and
    /// that are not artifacts for another light.
    pub undecidable_pixels: usize,
    /// Pixels where raster and reference differ for some light but the reference's own state
    /// changes within the pixel's 3×3 neighbourhood (within one pixel of a reference shadow
    /// boundary) or a shadow boundary crosses the pixel's footprint
    /// ([`Comparison::footprint_boundary_pixels`]), that are neither artifacts nor undecidable:
    /// not counted as artifacts.
    pub boundary_pixels: usize,
    /// Covered pixels the raster shadows (stencil ≠ 0 on a surface facing the light) for some
    /// light.
    pub shadow_pixels: usize,
    /// The same count from the reference.
    pub reference_shadow_pixels: usize,
    /// Covered pixels.
    pub covered_pixels: usize,
    /// Per light: the pixels [`Comparison::artifact_pixels`] would count if the shot had that
    /// light alone (a pixel can count for several lights).
    pub artifact_pixels_per_light: Vec<usize>,
    /// Per pixel: 0 agree, 1 differs near a boundary or the reference is uncertain (not
    /// counted), 2 artifact: raster lit where
    /// the reference is shadowed, 3 artifact: raster shadowed where the reference is lit.
    pub classes: Vec<u8>,
}

impl Comparison {
    /// `artifact_pixels` as a fraction of all pixels.
    #[must_use]
    pub fn artifact_fraction(&self, total_pixels: usize) -> f64 {
        self.artifact_pixels as f64 / total_pixels.max(1) as f64
    }

    /// The share of covered pixels the metric checked: covered pixels that are neither
    /// [`Comparison::boundary_pixels`] nor [`Comparison::undecidable_pixels`] (1 when nothing is
    /// covered).
    #[must_use]
    pub fn checked_fraction(&self) -> f64 {
        if self.covered_pixels == 0 {
            return 1.0;
        }
        let left_out = self.boundary_pixels + self.undecidable_pixels;
        self.covered_pixels.saturating_sub(left_out) as f64 / self.covered_pixels as f64
    }
}

/// Counts the raster's shadowed pixels (stencil ≠ 0 on a surface facing the light, any light):
/// what a comparison counts as `shadow_pixels`, each pixel's point computed and dropped in
/// turn.
#[must_use]
pub fn shadow_pixels(shot: &Shot<'_>) -> usize {
    let at = PixelPoints::new(shot);
    (0..at.pixels())
        .into_par_iter()
        .filter(|&i| {
            at.point(shot, i).is_some_and(|sp| {
                (0..shot.scene.lights.len())
                    .any(|li| shot.stencil[li][i] != 0 && faces_light(shot, &sp, li))
            })
        })
        .count()
}

fn count_shadowed(
    shot: &Shot<'_>,
    points: &[Option<SurfacePoint>],
    states: &[Vec<PixelState>],
) -> usize {
    (0..points.len())
        .filter(|&i| {
            let Some(sp) = points[i] else { return false };
            (0..shot.scene.lights.len())
                .any(|li| faces_light(shot, &sp, li) && states[li][i] == PixelState::Unlit)
        })
        .count()
}

/// One pixel's verdict over the lights.
#[derive(Debug, Clone, Copy, Default)]
struct Verdict {
    /// See [`Comparison::classes`].
    class: u8,
    /// The reference is [`PixelState::Uncertain`] for some light.
    uncertain: bool,
    /// The footprint rule kept some light's difference from being an artifact.
    moved: bool,
}

/// Per pixel, the worst class over the lights (see [`Comparison::classes`]). A difference where
/// the reference is the same over the 3×3 neighbourhood is an artifact unless `crosses(pixel,
/// light)` (the footprint rule) finds a shadow boundary of that light inside the pixel.
fn classify(
    raster: &[Vec<PixelState>],
    reference: &[Vec<PixelState>],
    w: usize,
    h: usize,
    crosses: &(dyn Fn(usize, usize) -> bool + Sync),
) -> Vec<Verdict> {
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let mut v = Verdict::default();
            for (li, (r, f)) in raster.iter().zip(reference).enumerate() {
                if f[i] == PixelState::Uncertain {
                    v.class = v.class.max(1);
                    v.uncertain = true;
                    continue;
                }
                if r[i] == f[i] {
                    continue;
                }
                let (x, y) = (i % w, i / w);
                let uniform = (y.saturating_sub(1)..=(y + 1).min(h - 1)).all(|ny| {
                    (x.saturating_sub(1)..=(x + 1).min(w - 1)).all(|nx| f[ny * w + nx] == f[i])
                });
                let class = if !uniform {
                    1
                } else if crosses(i, li) {
                    v.moved = true;
                    1
                } else if r[i] == PixelState::Lit {
                    2
                } else {
                    3
                };
                v.class = v.class.max(class);
            }
            v
        })
        .collect()
}

/// The counts of one classification.
struct Counts {
    artifact: usize,
    moved: usize,
}

fn counts(verdicts: &[Verdict]) -> Counts {
    Counts {
        artifact: verdicts.iter().filter(|v| v.class >= 2).count(),
        moved: verdicts.iter().filter(|v| v.moved && v.class == 1).count(),
    }
}

/// Renders the reference and compares, with the visible facing ([`faces_light`]) for
/// `artifact_pixels` and the geometric one for `geometric_artifact_pixels`; both apply the
/// footprint rule ([`Comparison::footprint_boundary_pixels`]).
#[must_use]
pub fn compare(shot: &Shot<'_>) -> Comparison {
    compare_with(shot, Rule::Footprint)
}

/// Which pixels [`compare_with`] keeps out of the artifact count besides those within one pixel
/// of a reference boundary (the 3×3 rule, always applied).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Rule {
    /// Also those whose footprint a shadow boundary crosses: [`compare`], the metric.
    Footprint,
    /// None: the 3×3 rule alone, the metric before the footprint rule (to measure what the
    /// rule moves; `footprint_boundary_pixels` is then 0).
    Neighbourhood,
}

/// [`compare`] with the footprint rule on or off ([`Rule`]).
#[must_use]
pub fn compare_with(shot: &Shot<'_>, rule: Rule) -> Comparison {
    let points = surface_points(shot);
    let (w, h) = (shot.width as usize, shot.height as usize);
    let casters = Casters::new(shot);
    let footprints = Footprints::new(shot, &casters);
    // Asked by both classifications (the facing differs, the shadows do not): once each.
    let lights = shot.scene.lights.len();
    let memo: Vec<std::sync::OnceLock<bool>> = if rule == Rule::Footprint {
        (0..w * h * lights)
            .map(|_| std::sync::OnceLock::new())
            .collect()
    } else {
        Vec::new()
    };
    let crosses = |i: usize, li: usize| {
        rule == Rule::Footprint
            && *memo[i * lights + li].get_or_init(|| {
                points[i]
                    .as_ref()
                    .is_some_and(|sp| footprints.crosses(i, sp, li))
            })
    };
    let raster_geometric = raster_states_geometric(shot, &points);
    let reference_geometric = reference_states_with(shot, &points, &casters);
    let geometric = counts(&classify(
        &raster_geometric,
        &reference_geometric,
        w,
        h,
        &crosses,
    ));
    let raster = raster_states(shot, &points);
    let reference = visible_only(shot, &points, reference_geometric);
    let verdicts = classify(&raster, &reference, w, h, &crosses);
    let visible = counts(&verdicts);
    let artifact_pixels_per_light = (0..lights)
        .map(|li| {
            let one = |i: usize, _: usize| crosses(i, li);
            let r = (&raster[li..=li], &reference[li..=li]);
            counts(&classify(r.0, r.1, w, h, &one)).artifact
        })
        .collect();
    Comparison {
        artifact_pixels_per_light,
        artifact_pixels: visible.artifact,
        geometric_artifact_pixels: geometric.artifact,
        footprint_boundary_pixels: visible.moved,
        geometric_footprint_boundary_pixels: geometric.moved,
        differing_pixels: verdicts.iter().filter(|v| v.class >= 1).count(),
        undecidable_pixels: verdicts
            .iter()
            .filter(|v| v.uncertain && v.class == 1)
            .count(),
        boundary_pixels: verdicts
            .iter()
            .filter(|v| !v.uncertain && v.class == 1)
            .count(),
        shadow_pixels: count_shadowed(shot, &points, &raster),
        reference_shadow_pixels: count_shadowed(shot, &points, &reference),
        covered_pixels: points.iter().filter(|p| p.is_some()).count(),
        footprint_moved: verdicts
            .iter()
            .enumerate()
            .filter(|(_, v)| v.moved && v.class == 1)
            .map(|(i, _)| i)
            .collect(),
        classes: verdicts.iter().map(|v| v.class).collect(),
    }
}

/// How well the image's colours match the lighting model where raster and reference agree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ShadingCheck {
    /// Pixels compared: covered, and every light's state the same in raster and reference.
    pub compared: usize,
    /// Of those, pixels with a channel more than the tolerance away from the prediction.
    pub mismatched: usize,
    /// The largest channel difference seen, in 8-bit steps.
    pub max_error: u8,
}

/// Predicts every compared pixel's colour from the lighting model in `f64` (the pre-pass's
/// `albedo × ambient`, plus per light whose state is lit `albedo × colour × attenuation ×
/// cos θ`, [`light_attenuation`]) and compares it with the 8-bit image, channel by channel, to
/// within `tolerance` steps. Pixels where raster and reference disagree (`cmp.classes != 0`) are
/// left out: the artifact metric counts them.
///
/// # Panics
/// Panics if `cmp` was not computed from `shot`.
#[must_use]
pub fn shading_check(shot: &Shot<'_>, cmp: &Comparison, tolerance: u8) -> ShadingCheck {
    let points = surface_points(shot);
    let raster = raster_states(shot, &points);
    let mut out = ShadingCheck::default();
    for (i, sp) in points.iter().enumerate() {
        let Some(sp) = sp else { continue };
        if cmp.classes[i] != 0 {
            continue;
        }
        let Some(albedo) = shot.albedo(shot.ids[i][0] as usize - 1) else {
            continue;
        };
        let mut c = albedo.map(|a| f64::from(a) * f64::from(shot.ambient()));
        for (li, light) in shot.scene.lights.iter().enumerate() {
            if raster[li][i] != PixelState::Lit {
                continue;
            }
            let v = light_vec(light.light.to_array(), sp.position);
            let cos = sp.normal.dot(v) / (sp.normal.length() * v.length());
            if cos > 0.0 {
                let k = cos * light_attenuation(shot, sp, li);
                for (ch, value) in c.iter_mut().enumerate() {
                    *value += f64::from(albedo[ch]) * f64::from(shot.light_colors[li][ch]) * k;
                }
            }
        }
        out.compared += 1;
        let px = &shot.rgba[i * 4..i * 4 + 3];
        let err = (0..3)
            .map(|ch| {
                let want = (c[ch].clamp(0.0, 1.0) * 255.0).round() as i32;
                (want - i32::from(px[ch])).unsigned_abs()
            })
            .max()
            .unwrap_or(0);
        out.max_error = out.max_error.max(err.min(255) as u8);
        if err > u32::from(tolerance) {
            out.mismatched += 1;
        }
    }
    out
}

/// The disagreement as an image: the frame dimmed to grey, artifacts where the raster is lit
/// but the reference is shadowed in red, artifacts where the raster is shadowed but the reference
/// is lit in blue, boundary-only differences in yellow.
///
/// # Panics
/// Panics if `cmp` was not computed from `shot`.
#[must_use]
pub fn diff_image(shot: &Shot<'_>, cmp: &Comparison) -> image::RgbaImage {
    let mut img = shot.image();
    for (i, px) in img.pixels_mut().enumerate() {
        let g = ((u16::from(px[0]) + u16::from(px[1]) + u16::from(px[2])) / 6) as u8;
        *px = match cmp.classes[i] {
            0 => image::Rgba([g, g, g, 255]),
            1 => image::Rgba([230, 200, 40, 255]),
            2 => image::Rgba([255, 30, 30, 255]),
            _ => image::Rgba([40, 90, 255, 255]),
        };
    }
    img
}

/// Writes [`diff_image`] as a PNG.
///
/// # Errors
/// [`image::ImageError`] when the file cannot be written.
pub fn save_diff(
    shot: &Shot<'_>,
    cmp: &Comparison,
    path: impl AsRef<std::path::Path>,
) -> Result<(), image::ImageError> {
    diff_image(shot, cmp).save_with_format(path, image::ImageFormat::Png)
}
