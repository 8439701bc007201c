//! Sharing groups: the runs of a light's samples that the extraction decides together
//! ([`PassFrame::sample_groups`] split by technique and size), and what the kernels read of them:
//! a word per light after the technique codes, and per (group, object) the box of the group's
//! object-space lights after the lights.

use super::{PassFrame, SharingGroup, MAX_SHARING_GROUP};
use crate::plan::Technique;
use crate::RenderError;
use shadowvol_robust_math::{Accuracy, LightBox};

/// A shared sign the triangle pass left (`NOT_SHARED` in `shaders/resident_extract.wgsl`): each
/// light of the group decides that triangle on its own.
pub const NOT_SHARED: i32 = 4;

/// The word of a light outside every group (`NO_GROUP` in `shaders/resident_extract.wgsl`).
pub(super) const NO_GROUP: u32 = u32::MAX;

/// Groups are numbered in 16 bits.
const MAX_GROUPS: usize = 1 << 16;

/// The sharing groups of frame `f` over `objects` objects: each of its sample groups split into
/// runs of at most [`MAX_SHARING_GROUP`] lights whose techniques are the same for every object,
/// and at the boundaries of batches of `per_batch` lights; runs of one light are left out. None outside exact mode (the `f32` modes' signs near a plane
/// are not the exact ones a box decides).
///
/// # Errors
/// [`RenderError::InvalidInput`] when a sample group is empty, reaches past the lights, or
/// overlaps another.
pub(crate) fn sharing_groups(
    f: &PassFrame<'_>,
    objects: usize,
    per_batch: usize,
) -> Result<Vec<SharingGroup>, RenderError> {
    let n = f.lights.len();
    let mut taken = vec![false; n];
    for r in f.sample_groups {
        if r.start >= r.end || r.end > n {
            return Err(RenderError::InvalidInput(format!(
                "GPU pipeline frame: sample group {r:?} is empty or reaches past the {n} light(s)"
            )));
        }
        if taken[r.clone()].iter().any(|&t| t) {
            return Err(RenderError::InvalidInput(format!(
                "GPU pipeline frame: sample group {r:?} overlaps another"
            )));
        }
        taken[r.clone()].fill(true);
    }
    if f.mode != Accuracy::Exact {
        return Ok(Vec::new());
    }
    let row = |li: usize| &f.techniques[li * objects..(li + 1) * objects];
    let mut out = Vec::new();
    for r in f.sample_groups {
        let mut first = r.start;
        while first < r.end && out.len() < MAX_GROUPS {
            let mut end = first + 1;
            while end < r.end
                && end - first < MAX_SHARING_GROUP
                && end % per_batch.max(1) != 0
                && row(end) == row(first)
            {
                end += 1;
            }
            let culled = row(first).iter().all(|&t| t == Technique::Culled);
            if end - first > 1 && !culled {
                out.push(SharingGroup {
                    first,
                    count: end - first,
                });
            }
            first = end;
        }
    }
    Ok(out)
}

/// The word of a light outside every group whose objects are all culled: the edge pass skips it
/// (`ALL_CULLED` in `shaders/resident_extract.wgsl`).
pub(super) const ALL_CULLED: u32 = u32::MAX - 1;

/// One word per light of `n`: [`NO_GROUP`] ([`ALL_CULLED`] where `culled(light)`), or its group
/// (bits 0-15), the group's light count (bits 16-23) and the light's index in it (bits 24-31).
pub(super) fn group_words(
    groups: &[SharingGroup],
    n: usize,
    culled: impl Fn(usize) -> bool,
) -> Vec<u32> {
    let mut words: Vec<u32> = (0..n)
        .map(|li| if culled(li) { ALL_CULLED } else { NO_GROUP })
        .collect();
    for (g, grp) in groups.iter().enumerate() {
        for j in 0..grp.count {
            words[grp.first + j] = g as u32 | (grp.count as u32) << 16 | (j as u32) << 24;
        }
    }
    words
}

/// Per (group, object), group-major, two `[f32; 4]`: the centre of the box of the group's
/// object-space lights with their `w`, and its half-extent with 1 (0 where the box cannot be
/// shared on the device: mixed `w`, or outside the filter's range; [`LightBox::device_box`]).
/// `lights[object * n + light]` are the object-space lights of `n` lights.
pub(crate) fn group_boxes(
    groups: &[SharingGroup],
    lights: &[[f32; 4]],
    n: usize,
    objects: usize,
) -> Vec<[f32; 4]> {
    let mut out = Vec::with_capacity(2 * groups.len() * objects);
    for grp in groups {
        for o in 0..objects {
            let ls = &lights[o * n + grp.first..o * n + grp.first + grp.count];
            match LightBox::of(ls).and_then(|b| b.device_box()) {
                Some(b) => {
                    let (c, h) = (b.centre, b.half);
                    out.push([c[0], c[1], c[2], b.w]);
                    out.push([h[0], h[1], h[2], 1.0]);
                }
                None => out.extend([[0.0; 4]; 2]),
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;
    use shadowvol_scenes::SceneLight;
    use shadowvol_silhouette::Light;

    fn frame<'a>(
        lights: &'a [SceneLight],
        techniques: &'a [Technique],
        groups: &'a [std::ops::Range<usize>],
        camera: &'a Camera,
    ) -> PassFrame<'a> {
        PassFrame {
            camera,
            aspect: 1.0,
            lights,
            colors: &[],
            transforms: &[],
            albedo: &[],
            techniques,
            scissors: &[],
            ambient: 0.0,
            mode: Accuracy::Exact,
            count: false,
            sample_groups: groups,
        }
    }

    #[test]
    fn groups_split_where_techniques_differ_and_at_the_cap() {
        let camera = Camera::look_at(glam::Vec3::ONE, glam::Vec3::ZERO);
        let lights = vec![SceneLight::unit(Light::point(glam::Vec3::Y)); 150];
        // One object; lights 10 and 11 z-pass, the others z-fail; light 149 culled.
        let mut t = vec![Technique::ZFail; 150];
        t[10] = Technique::ZPass;
        t[11] = Technique::ZPass;
        t[149] = Technique::Culled;
        let groups = [0..70, 70..150];
        let g = sharing_groups(&frame(&lights, &t, &groups, &camera), 1, 1000).unwrap();
        let runs: Vec<(usize, usize)> = g.iter().map(|g| (g.first, g.count)).collect();
        assert_eq!(runs, [(0, 10), (10, 2), (12, 58), (70, 64), (134, 15)]);
        let w = group_words(&g, 150, |li| t[li] == Technique::Culled);
        assert_eq!(w[70], 3 | 64 << 16);
        assert_eq!(w[71], 3 | 64 << 16 | 1 << 24);
        assert_eq!((w[149], w[148]), (ALL_CULLED, 4 | 15 << 16 | 14 << 24));
        // Overlapping or out-of-range groups are refused; other modes share nothing.
        let bad = [0..4, 3..6];
        assert!(sharing_groups(&frame(&lights, &t, &bad, &camera), 1, 1000).is_err());
        let bad = [0..2, 140..151];
        assert!(sharing_groups(&frame(&lights, &t, &bad, &camera), 1, 1000).is_err());
        let mut f = frame(&lights, &t, &groups, &camera);
        f.mode = Accuracy::Ordered;
        assert!(sharing_groups(&f, 1, 1000).unwrap().is_empty());
        // Batches of 50 lights split the groups at 50, 100 and 150.
        let g = sharing_groups(&frame(&lights, &t, &groups, &camera), 1, 50).unwrap();
        let runs: Vec<(usize, usize)> = g.iter().map(|g| (g.first, g.count)).collect();
        assert_eq!(
            runs,
            [(0, 10), (10, 2), (12, 38), (50, 20), (70, 30), (100, 49)]
        );
    }
}
