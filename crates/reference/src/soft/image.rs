//! Per image: the reference for every pixel of a shot and the comparison with it.

use super::{Integration, SoftCasters, Visibility};
use crate::states::PixelPoints;
use crate::Shot;
use rayon::prelude::*;
use shadowvol_scenes::LightDisk;

/// The true visibility of one light's disk for every pixel of a shot.
#[derive(Debug, Clone)]
pub struct SoftReference {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major, top row first: `None` for background, else the visibility of the pixel's
    /// surface point (the hard reference's point: [`crate::surface_points`]).
    pub pixels: Vec<Option<Visibility>>,
}

impl SoftReference {
    /// The largest bound over the covered pixels (0 when none is covered).
    #[must_use]
    pub fn max_bound(&self) -> f64 {
        self.pixels
            .iter()
            .flatten()
            .map(|v| v.bound)
            .fold(0.0, f64::max)
    }
}

/// Checks that `disk` can be light `light`'s.
fn check_light(shot: &Shot<'_>, light: usize, disk: &LightDisk) {
    let l = shot.light(light);
    assert_eq!(
        l[3] == 0.0,
        disk.directional,
        "light {light} and its disk disagree on being directional"
    );
}

/// The true visibility of `disk` (light `light`'s, [`LightDisk::of`] with
/// [`shadowvol_scenes::Scene::light_aim`]) for every pixel with a surface: the share of the disk
/// that pixel's surface point sees past the shot's casters, with its bound ([`Visibility`]).
/// Builds the casters' BVH, then runs over the pixels in parallel (rayon).
///
/// # Panics
/// Panics if `light` is not a light of the shot's scene, or if `disk` is directional and the
/// light is not, or the reverse.
#[must_use]
pub fn visibility_reference(shot: &Shot<'_>, light: usize, disk: &LightDisk) -> SoftReference {
    visibility_reference_with(
        shot,
        &SoftCasters::new(shot),
        light,
        disk,
        Integration::Auto,
    )
}

/// [`visibility_reference`] with casters built once ([`SoftCasters::new`] of the same shot) and
/// a choice of integration.
///
/// # Panics
/// As [`visibility_reference`].
#[must_use]
pub fn visibility_reference_with(
    shot: &Shot<'_>,
    casters: &SoftCasters,
    light: usize,
    disk: &LightDisk,
    integration: Integration,
) -> SoftReference {
    check_light(shot, light, disk);
    let at = PixelPoints::new(shot);
    let pixels = (0..at.pixels())
        .into_par_iter()
        .map(|i| {
            at.point(shot, i)
                .map(|sp| casters.visibility(disk, sp.position, sp.triangle, integration))
        })
        .collect();
    SoftReference {
        width: shot.width,
        height: shot.height,
        pixels,
    }
}

/// A render's per-pixel visibility (`k / N` of its samples) against the true one.
///
/// Pixels are sorted by the reference into *lit* (exactly 1), *umbra* (exactly 0), *penumbra*
/// (strictly between, beyond the bound) and *undecided* (within the bound of 0 or 1 but not
/// exactly it). A lit or umbra pixel whose 3×3 neighbourhood holds a covered pixel of another
/// class is a *border* pixel: its render value may come from a sample's hard shadow boundary
/// within rounding of the surface point (the hard metric's 3×3 rule), so its mismatches are
/// counted apart.
#[derive(Debug, Clone, PartialEq)]
pub struct SoftComparison {
    /// Pixels with a surface.
    pub covered_pixels: usize,
    /// Covered pixels whose true visibility is strictly between 0 and 1, beyond the bound.
    pub penumbra_pixels: usize,
    /// Mean of `|render − true|` over the penumbra pixels (0 when there are none).
    pub penumbra_mean_error: f64,
    /// 99th percentile (nearest rank) of `|render − true|` over the penumbra pixels.
    pub penumbra_p99_error: f64,
    /// Largest `|render − true|` over the penumbra pixels.
    pub penumbra_max_error: f64,
    /// Covered pixels whose true visibility is exactly 1.
    pub lit_pixels: usize,
    /// Lit pixels, not on a border, where the render's visibility is not 1.
    pub lit_mismatched: usize,
    /// Covered pixels whose true visibility is exactly 0.
    pub umbra_pixels: usize,
    /// Umbra pixels, not on a border, where the render's visibility is not 0.
    pub umbra_mismatched: usize,
    /// Lit or umbra pixels on a border (a 3×3 neighbour of another class) where the render
    /// differs: not counted in `lit_mismatched` or `umbra_mismatched`.
    pub border_mismatched: usize,
    /// Covered pixels within the bound of 0 or 1 but not exactly there: left out.
    pub undecided_pixels: usize,
    /// The largest error bound of the reference over the penumbra pixels: the errors above are
    /// true to within it.
    pub reference_bound: f64,
}

/// Compares a render's visibility for light `light` with [`visibility_reference`].
/// `visibility` is row-major, top row first, one value per pixel (background pixels are
/// ignored).
///
/// # Panics
/// As [`visibility_reference`], and if `visibility` does not have one value per pixel.
#[must_use]
pub fn compare_visibility(
    shot: &Shot<'_>,
    light: usize,
    disk: &LightDisk,
    visibility: &[f32],
) -> SoftComparison {
    compare_with_reference(&visibility_reference(shot, light, disk), visibility)
}

/// [`compare_visibility`] against a reference already computed.
///
/// # Panics
/// Panics if `visibility` does not have one value per pixel of `reference`.
#[must_use]
pub fn compare_with_reference(reference: &SoftReference, visibility: &[f32]) -> SoftComparison {
    let (w, h) = (reference.width as usize, reference.height as usize);
    assert_eq!(visibility.len(), w * h, "one visibility per pixel");
    #[derive(Clone, Copy, PartialEq, Eq)]
    enum Class {
        None,
        Lit,
        Umbra,
        Penumbra,
        Undecided,
    }
    let class: Vec<Class> = reference
        .pixels
        .iter()
        .map(|p| match p {
            None => Class::None,
            Some(v) if v.is_lit() => Class::Lit,
            Some(v) if v.is_umbra() => Class::Umbra,
            Some(v) if v.is_penumbra() => Class::Penumbra,
            Some(_) => Class::Undecided,
        })
        .collect();
    let mut out = SoftComparison {
        covered_pixels: 0,
        penumbra_pixels: 0,
        penumbra_mean_error: 0.0,
        penumbra_p99_error: 0.0,
        penumbra_max_error: 0.0,
        lit_pixels: 0,
        lit_mismatched: 0,
        umbra_pixels: 0,
        umbra_mismatched: 0,
        border_mismatched: 0,
        undecided_pixels: 0,
        reference_bound: 0.0,
    };
    let mut errors = Vec::new();
    for i in 0..w * h {
        let Some(v) = reference.pixels[i] else {
            continue;
        };
        out.covered_pixels += 1;
        let render = f64::from(visibility[i]);
        match class[i] {
            Class::Penumbra => {
                out.penumbra_pixels += 1;
                errors.push((render - v.value).abs());
                out.reference_bound = out.reference_bound.max(v.bound);
            }
            Class::Undecided => out.undecided_pixels += 1,
            Class::Lit | Class::Umbra => {
                let lit = class[i] == Class::Lit;
                if lit {
                    out.lit_pixels += 1;
                } else {
                    out.umbra_pixels += 1;
                }
                if render == v.value {
                    continue;
                }
                let (x, y) = (i % w, i / w);
                let border = (y.saturating_sub(1)..=(y + 1).min(h - 1)).any(|ny| {
                    (x.saturating_sub(1)..=(x + 1).min(w - 1)).any(|nx| {
                        let c = class[ny * w + nx];
                        c != Class::None && c != class[i]
                    })
                });
                if border {
                    out.border_mismatched += 1;
                } else if lit {
                    out.lit_mismatched += 1;
                } else {
                    out.umbra_mismatched += 1;
                }
            }
            Class::None => {}
        }
    }
    if !errors.is_empty() {
        errors.sort_unstable_by(f64::total_cmp);
        let n = errors.len();
        out.penumbra_mean_error = errors.iter().sum::<f64>() / n as f64;
        out.penumbra_max_error = errors[n - 1];
        out.penumbra_p99_error = errors[(n * 99).div_ceil(100).max(1) - 1];
    }
    out
}
