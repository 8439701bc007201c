//! The CPU twin of `resident/extract.wgsl`: the triangle pass and the edge pass, statement for
//! statement, on a [`ResidentLayout`].
//!
//! The device appends side records in an unspecified order; [`side_records`] returns them sorted,
//! and tests compare sorted lists. As for the `wgpu` backend's twin, the only intended difference
//! from the device is floating-point contraction, which can change the `f32` modes in the last
//! bits but never the exact mode.

use super::layout::{ResidentLayout, NEGATIVE};
use shadowvol_robust_math::{sign_f32, Accuracy};
use shadowvol_wgpu_compute::exact_int::orient_int;
use shadowvol_wgpu_compute::twin::{exact_filter, ExactFilter};

/// The sign value of a triangle with a vertex exactly at the point light: it has no volume.
pub const TOUCH: i32 = 2;

/// Per-(light, object) technique codes of the pass: the edge's or triangle's object is skipped
/// (culled), its sides go to the z-pass list, or to the z-fail list (and it gets caps).
pub mod technique {
    /// Culled: no sign, no record.
    pub const CULLED: u32 = 0;
    /// Z-pass sides.
    pub const ZPASS: u32 = 1;
    /// Z-fail sides and caps.
    pub const ZFAIL: u32 = 2;
}

fn position(layout: &ResidentLayout, id: u32) -> [f32; 3] {
    layout.scene.position(id)
}

fn touches(p: [f32; 3], l: [f32; 4]) -> bool {
    l[3] != 0.0 && p[0] * l[3] == l[0] && p[1] * l[3] == l[1] && p[2] * l[3] == l[2]
}

/// Twin of WGSL `triangle_sign`: the sign of the canonical triangle `(p0, p1, p2)` in `mode`,
/// and whether exact mode needed the integer path (the filter could not certify it).
#[must_use]
pub fn triangle_sign(
    mode: Accuracy,
    filter: ExactFilter,
    p0: [f32; 3],
    p1: [f32; 3],
    p2: [f32; 3],
    l: [f32; 4],
) -> (i32, bool) {
    match mode {
        Accuracy::Exact => match exact_filter(filter, p0, p1, l, p2) {
            Some(s) => (i32::from(s), false),
            None => (i32::from(orient_int(p0, p1, l, p2)), true),
        },
        Accuracy::Robust => {
            let s0 = sign_f32(p0, p1, l, p2);
            let s1 = sign_f32(p1, p2, l, p0);
            let s2 = sign_f32(p2, p0, l, p1);
            (
                if s0 == s1 && s1 == s2 {
                    i32::from(s0)
                } else {
                    0
                },
                false,
            )
        }
        Accuracy::Ordered | Accuracy::Original => (i32::from(sign_f32(p0, p1, l, p2)), false),
    }
}

/// Twin of `resident_triangles`: `signs[light * tri_count + triangle]` (−1, 0, 1 or [`TOUCH`];
/// 0 for culled objects) and the number of (triangle, light) pairs decided by the integer path.
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
    let n = layout.tri_count();
    let objects = layout.object_count();
    let mut signs = vec![0i32; n * light_count];
    let mut integer = 0u64;
    for (t, tr) in layout.tris.iter().enumerate() {
        let (p0, p1, p2) = (
            position(layout, tr[0]),
            position(layout, tr[1]),
            position(layout, tr[2]),
        );
        let obj = tr[3] as usize;
        for li in 0..light_count {
            if techniques[li * objects + obj] == technique::CULLED {
                continue;
            }
            let l = lights[obj * light_count + li];
            signs[li * n + t] = if touches(p0, l) || touches(p1, l) || touches(p2, l) {
                TOUCH
            } else {
                let (s, int) = triangle_sign(mode, filter, p0, p1, p2, l);
                integer += u64::from(int);
                s
            };
        }
    }
    (signs, integer)
}

/// The side records of one light: global edge ids, [`NEGATIVE`] set when `m < 0`, each edge
/// `|m|` times; sorted.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LightRecords {
    /// Records of z-pass objects.
    pub zpass: Vec<u32>,
    /// Records of z-fail objects.
    pub zfail: Vec<u32>,
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
    let s = &layout.scene;
    let edges = s.edge_count();
    let objects = layout.object_count();
    let n = layout.tri_count();
    let mut mult = vec![0i32; edges * light_count];
    let mut out = vec![LightRecords::default(); light_count];
    for (e, rec) in s.edges[..edges].iter().enumerate() {
        let (ov_begin, ov_end) = (rec[2] as usize, s.edges[e + 1][2] as usize);
        let obj = rec[3] as usize;
        for li in 0..light_count {
            let tech = techniques[li * objects + obj];
            if tech == technique::CULLED {
                continue;
            }
            let row = li * n;
            let mut m = 0i32;
            if mode == Accuracy::Original {
                let l = lights[obj * light_count + li];
                let (a, b) = (position(layout, rec[0]), position(layout, rec[1]));
                for k in ov_begin..ov_end {
                    let t = (layout.ov_tris[k] & !NEGATIVE) as usize;
                    if signs[row + t] != TOUCH {
                        m += i32::from(sign_f32(a, b, l, position(layout, s.ovs[k])));
                    }
                }
            } else {
                for k in ov_begin..ov_end {
                    let ot = layout.ov_tris[k];
                    let sg = signs[row + (ot & !NEGATIVE) as usize];
                    if sg != TOUCH {
                        m += if ot & NEGATIVE != 0 { -sg } else { sg };
                    }
                }
            }
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
