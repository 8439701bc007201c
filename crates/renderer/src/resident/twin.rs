//! The CPU twin of `shaders/resident_extract.wgsl`, for tests: the triangle pass and the edge
//! pass, statement for statement, on a [`ResidentLayout`], with the `wgpu` backend's twins of
//! the functions they share (`triangle_sign`, `edge_multiplicity` of
//! [`shadowvol_gpu::twin`]). The pass never calls it.
//!
//! The device appends side records in an unspecified order; [`side_records`] returns them sorted,
//! and tests compare sorted lists. As for the `wgpu` backend's twin, the only intended difference
//! from the device is floating-point contraction, which can change the `f32` modes in the last
//! bits but never the exact mode.

use super::layout::{ResidentLayout, NEGATIVE};
use super::{technique, LightRecords, SharingGroup, NOT_SHARED};
use shadowvol_gpu::shaders::TOUCH;
use shadowvol_gpu::twin;
use shadowvol_robust_math::Accuracy;
use shadowvol_robust_math::{box_sign_f32, DeviceBox};
use shadowvol_silhouette::gpu::ExactFilter;

fn position(layout: &ResidentLayout, id: u32) -> [f32; 3] {
    layout.tables.position(id)
}

fn touches(p: [f32; 3], l: [f32; 4]) -> bool {
    l[3] != 0.0 && crate::volume::at_light(glam::Vec3::from_array(p), l)
}

/// Twin of `resident_triangles` followed, in exact mode, by `resident_pending` (which decides
/// with the integer path the pairs the triangle pass's filter marked pending):
/// `signs[light * tri_count + triangle]` (−1, 0, 1 or [`TOUCH`]; 0 for culled objects) and the
/// number of (triangle, light) pairs decided by the integer path.
///
/// `lights[object * light_count + light]` are the object-space lights, `techniques[light *
/// object_count + object]` the [`technique`] codes.
///
/// # Panics
/// Panics if `lights` or `techniques` are shorter than the layout's objects × `light_count`.
#[must_use]
pub fn triangle_signs(
    layout: &ResidentLayout,
    lights: &[[f32; 4]],
    light_count: usize,
    techniques: &[u32],
    mode: Accuracy,
    filter: ExactFilter,
) -> (Vec<i32>, u64) {
    let (signs, _, integer) =
        triangle_signs_shared(layout, lights, light_count, techniques, (mode, filter), &[]);
    (signs, integer)
}

/// [`triangle_signs`] with sharing groups (exact mode; [`super::SharingGroup`], as
/// [`super::ResidentScene::sharing_groups`] gives them): also returns the groups' shared signs
/// `[group * tri_count + triangle]` (−1, 1 or [`NOT_SHARED`]), from the `f32` box filter
/// ([`box_sign_f32`], the twin of `box_sign`) on each group's box. A light of a group takes the
/// shared sign where there is one; the per-light signs are the same either way, since a certified
/// sign is every light's exact sign.
///
/// # Panics
/// As [`triangle_signs`].
#[must_use]
pub fn triangle_signs_shared(
    layout: &ResidentLayout,
    lights: &[[f32; 4]],
    light_count: usize,
    techniques: &[u32],
    (mode, filter): (Accuracy, ExactFilter),
    groups: &[SharingGroup],
) -> (Vec<i32>, Vec<i32>, u64) {
    let n = layout.tri_count();
    let objects = layout.object_count();
    let mut signs = vec![0i32; n * light_count];
    let mut shared = vec![NOT_SHARED; n * groups.len()];
    let boxes = super::groups::group_boxes(groups, lights, light_count, objects);
    let mut integer = 0u64;
    for (t, tr) in layout.tables.tris.iter().enumerate() {
        let (p0, p1, p2) = (
            position(layout, tr[0]),
            position(layout, tr[1]),
            position(layout, tr[2]),
        );
        let obj = layout.tables.tri_object(t);
        let group_of = |li: usize| {
            groups
                .iter()
                .position(|g| (g.first..g.first + g.count).contains(&li))
        };
        for li in 0..light_count {
            let tech = techniques[li * objects + obj];
            let group = group_of(li);
            if let Some(g) = group.filter(|&g| groups[g].first == li) {
                let k = 2 * (g * objects + obj);
                let (cw, hv) = (boxes[k], boxes[k + 1]);
                let bx = DeviceBox {
                    centre: [cw[0], cw[1], cw[2]],
                    half: [hv[0], hv[1], hv[2]],
                    w: cw[3],
                };
                let s = (mode == Accuracy::Exact && tech != technique::CULLED && hv[3] == 1.0)
                    .then(|| box_sign_f32(p0, p1, p2, &bx))
                    .flatten();
                shared[g * n + t] = s.map_or(NOT_SHARED, i32::from);
            }
            if tech == technique::CULLED {
                continue;
            }
            let l = lights[obj * light_count + li];
            let s = group.map_or(NOT_SHARED, |g| shared[g * n + t]);
            signs[li * n + t] = if s != NOT_SHARED {
                s
            } else if touches(p0, l) || touches(p1, l) || touches(p2, l) {
                TOUCH
            } else {
                let (s, int) = twin::triangle_sign(mode, filter, true, [p0, p1, p2], l);
                integer += u64::from(int);
                i32::from(s.expect("with device_exact every triangle is decided"))
            };
        }
    }
    (signs, shared, integer)
}

/// Twin of `resident_edges`: the multiplicities `m[light * edge_count + edge]` and each light's
/// side records, from the triangle signs of [`triangle_signs`].
///
/// # Panics
/// Panics if the inputs are shorter than the layout needs.
#[must_use]
pub fn side_records(
    layout: &ResidentLayout,
    signs: &[i32],
    lights: &[[f32; 4]],
    light_count: usize,
    techniques: &[u32],
    mode: Accuracy,
) -> (Vec<i32>, Vec<LightRecords>) {
    let s = &layout.tables;
    let edges = s.edge_count();
    let objects = layout.object_count();
    let x = twin::EdgeInputs {
        layout: s,
        signs,
        lights,
        light_count,
        touch_signs: true,
    };
    let mut mult = vec![0i32; edges * light_count];
    let mut out = vec![LightRecords::default(); light_count];
    for e in 0..edges {
        let obj = s.edge_object(e);
        for li in 0..light_count {
            let tech = techniques[li * objects + obj];
            if tech == technique::CULLED {
                continue;
            }
            let m = twin::edge_multiplicity(&x, e, li, mode);
            mult[li * edges + e] = m;
            let r = e as u32 | if m < 0 { NEGATIVE } else { 0 };
            let list = if tech == technique::ZFAIL {
                &mut out[li].zfail
            } else {
                &mut out[li].zpass
            };
            list.extend(std::iter::repeat_n(r, m.unsigned_abs() as usize));
        }
    }
    for r in &mut out {
        r.zpass.sort_unstable();
        r.zfail.sort_unstable();
    }
    (mult, out)
}
