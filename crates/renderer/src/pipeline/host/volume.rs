//! Shadow-volume geometry from multiplicities (sides) and per-triangle signs (caps).
//!
//! # Orientation
//! With `s(a, b, o)` the contribution of opposite vertex `o` to edge `(a, b)` (see
//! [`shadowvol_robust_math`]) and a triangle `T` with canonical vertex order `(p0, p1, p2)`
//! (ascending ids) and sign `σ_T = triangle_sign(mode, p0, p1, p2, L)`, one checks that
//! `s(a, b, o) · (a → b)` is `σ_T` times the directed boundary edge of `T` in canonical order.
//! So the silhouette chain `Σ m(a, b) · (a → b)` is the boundary of the cap chain `Σ σ_T · T`, and
//! `σ_T = sgn(n_T · (L.xyz − L.w p0))` with `n_T = (p1 − p0) × (p2 − p0)`: `σ_T · T` is `T`
//! turned to face the light. Each triangle so turned is the near cap of a semi-infinite prism
//! (its shadow); the sides of all prisms cancel on edges whose multiplicity is 0 and remain
//! `m` times on silhouette edges. The prisms are oriented outwards, so two-sided stencil
//! counting gives, at a point, the number of prisms containing it.
//!
//! For a directed silhouette edge `a → b` (m > 0) the outward side quad is
//! `(b, a, a∞, b∞)` (counter-clockwise seen from outside); for `m < 0` it is `(a, b, b∞, a∞)`.
//! `x∞ = (L.w · x − L.xyz, 0)`: the point at infinity away from the light. A directional light
//! has all `x∞` equal, so sides are triangles and there is no back cap. The back cap of `σ_T · T`
//! is the extruded triangle with reversed order.

use glam::Vec3;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::{ov_sign, triangle_sign, Accuracy};

/// A vertex of shadow-volume geometry: `(x, y, z, w)`, `w = 1` on the caster, `w = 0` at infinity.
pub type VolumeVertex = [f32; 4];

/// The point at infinity of `p` away from the light `l` (world space): the direction
/// `l.w · p − l.xyz`, scaled so that its largest component is ±1, with `w = 0`.
///
/// The direction is evaluated in `f64`, where the products of `f32` inputs are exact and the
/// difference is exact whenever it cancels, and only then rounded to `f32`. So a vertex a hair
/// (10⁻⁸) from a light still extrudes in the right direction, where `f32` would round the
/// difference to noise or to zero. `[0, 0, 0, 0]` when `p` is exactly at the light.
#[must_use]
#[inline]
pub fn extrude(p: Vec3, l: [f32; 4]) -> VolumeVertex {
    let w = f64::from(l[3]);
    let d = [
        f64::from(p.x) * w - f64::from(l[0]),
        f64::from(p.y) * w - f64::from(l[1]),
        f64::from(p.z) * w - f64::from(l[2]),
    ];
    let s = d[0].abs().max(d[1].abs()).max(d[2].abs());
    if s == 0.0 || !s.is_finite() {
        return [0.0; 4];
    }
    [(d[0] / s) as f32, (d[1] / s) as f32, (d[2] / s) as f32, 0.0]
}

#[inline]
fn fin(p: Vec3) -> VolumeVertex {
    [p.x, p.y, p.z, 1.0]
}

/// Appends the side triangles for one object and one light.
///
/// `edges` are the object's edges (`[a, b]`, `a < b`, compact ids into `world`), `m` their
/// multiplicities for this light, `world` the world-space (`f32`) positions, `light` the world
/// light. Emits `|m|` copies per edge (the stencil can only step by 1). Returns the number of
/// side quads (directional: side triangles) emitted.
///
/// # Panics
/// Panics if `m.len() != edges.len()` or an id is out of range of `world`.
pub fn build_sides(
    edges: &[[u32; 2]],
    m: &[i32],
    world: &[Vec3],
    light: [f32; 4],
    out: &mut Vec<VolumeVertex>,
) -> usize {
    assert_eq!(edges.len(), m.len(), "one multiplicity per edge");
    let directional = light[3] == 0.0;
    let mut quads = 0;
    for (&[a, b], &mult) in edges.iter().zip(m) {
        if mult == 0 {
            continue;
        }
        let (pa, pb) = (world[a as usize], world[b as usize]);
        // Outward order: for m > 0 walk b -> a on the caster, else a -> b.
        let (p, q) = if mult > 0 { (pb, pa) } else { (pa, pb) };
        let (pi, qi) = (extrude(p, light), extrude(q, light));
        for _ in 0..mult.unsigned_abs() {
            if directional {
                out.extend_from_slice(&[fin(p), fin(q), qi]);
            } else {
                out.extend_from_slice(&[fin(p), fin(q), qi, fin(p), qi, pi]);
            }
            quads += 1;
        }
    }
    quads
}

/// Cap geometry of one object for one light, split by how the rasterizer must see it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Caps {
    /// Front-cap triangles with `σ = +1`, in canonical vertex order (draw with counter-clockwise
    /// front faces): exactly the pre-pass vertices, so depths match bit for bit.
    pub front_ccw: Vec<VolumeVertex>,
    /// Front-cap triangles with `σ = −1`, in canonical vertex order (draw with clockwise front
    /// faces, which turns them to face the light without reordering their vertices).
    pub front_cw: Vec<VolumeVertex>,
    /// Back-cap triangles at infinity, outward (draw counter-clockwise). Empty for directional
    /// lights.
    pub back: Vec<VolumeVertex>,
    /// Triangles with `σ = 0` (light in their plane, or robust disagreement): no prism.
    pub zero: usize,
}

/// Builds the caps of one object for one light.
///
/// `table` is the object's edge table (object space), `object_light` the object-space light
/// from [`shadowvol_silhouette::object_lights`] (the same `f32` input the silhouette backend
/// saw), `world` the world-space positions, `world_light` the world light. The sign of each
/// triangle is [`triangle_sign`] on its canonical order in `mode`, which is what the
/// multiplicities of `robust`, `ordered` and `exact` are made of, so caps and sides meet.
/// `back_cap` is ignored (treated as false) for directional lights. Triangles with
/// `skip[t] == true` (see [`touching_triangles`]) get no cap.
///
/// # Panics
/// Panics if `world.len() != table.positions.len()`.
#[must_use]
pub fn build_caps(
    table: &EdgeTable,
    object_light: [f32; 4],
    world: &[Vec3],
    world_light: [f32; 4],
    mode: Accuracy,
    back_cap: bool,
    skip: &[bool],
) -> Caps {
    assert_eq!(
        world.len(),
        table.positions.len(),
        "one world position per vertex"
    );
    let back_cap = back_cap && world_light[3] != 0.0;
    let mut caps = Caps::default();
    for (ti, t) in table.triangles.iter().enumerate() {
        if skip.get(ti).copied().unwrap_or(false) {
            caps.zero += 1;
            continue;
        }
        let c = canonical_triangle(*t);
        let p = |i: u32| table.positions[i as usize];
        let sigma = triangle_sign(mode, p(c[0]), p(c[1]), p(c[2]), object_light);
        let w = [
            world[c[0] as usize],
            world[c[1] as usize],
            world[c[2] as usize],
        ];
        let front = [fin(w[0]), fin(w[1]), fin(w[2])];
        let inf = [
            extrude(w[0], world_light),
            extrude(w[1], world_light),
            extrude(w[2], world_light),
        ];
        match sigma {
            1 => {
                caps.front_ccw.extend_from_slice(&front);
                if back_cap {
                    caps.back.extend_from_slice(&[inf[0], inf[2], inf[1]]);
                }
            }
            -1 => {
                caps.front_cw.extend_from_slice(&front);
                if back_cap {
                    caps.back.extend_from_slice(&inf);
                }
            }
            _ => caps.zero += 1,
        }
    }
    caps
}

/// The triangles that have a vertex exactly at a point light (object space: `p · w == L.xyz`
/// exactly, see [`at_light`]), as a per-triangle flag; empty when there are none (always for directional lights).
///
/// Such a triangle's shadow has no volume (every ray from the light through it lies in its
/// plane), but the extrusion of its vertex at the light is undefined (`(0, 0, 0, 0)`), and a
/// mode that gives it a non-zero sign (`ordered`, `original`) would draw a flat prism that
/// z-fail counting does not cancel. The renderer draws no part of it: no cap, and its
/// contributions are taken out of the multiplicities with [`remove_triangles`].
#[must_use]
pub fn touching_triangles(table: &EdgeTable, object_light: [f32; 4]) -> Vec<bool> {
    let w = object_light[3];
    if w == 0.0 {
        return Vec::new();
    }
    let at_light: Vec<bool> = table
        .positions
        .iter()
        .map(|p| at_light(*p, object_light))
        .collect();
    if !at_light.contains(&true) {
        return Vec::new();
    }
    table
        .triangles
        .iter()
        .map(|t| t.iter().any(|&v| at_light[v as usize]))
        .collect()
}

/// True when `p · l.w == l.xyz` exactly (in `f64`, where the products of `f32` values are
/// exact): the point light is at `p`, not only within an `f32` rounding of it.
#[must_use]
#[inline]
pub fn at_light(p: Vec3, l: [f32; 4]) -> bool {
    let w = f64::from(l[3]);
    f64::from(p.x) * w == f64::from(l[0])
        && f64::from(p.y) * w == f64::from(l[1])
        && f64::from(p.z) * w == f64::from(l[2])
}

/// Subtracts, from the multiplicities `m` of every global edge of `scene` (objects in order,
/// at [`shadowvol_silhouette::TopologyScene::edge_offsets`]) for one light, given in each
/// object's space (`object_lights[object]`), the contributions of the triangles touching that
/// point light ([`touching_triangles`], [`remove_triangles`]): what the renderer draws from a
/// backend's multiplicities.
///
/// # Panics
/// Panics if `object_lights` or `m` do not match the scene.
pub fn remove_touching(
    scene: &shadowvol_silhouette::TopologyScene,
    object_lights: &[[f32; 4]],
    mode: Accuracy,
    m: &mut [i32],
) {
    let offsets = scene.edge_offsets();
    for (oi, o) in scene.objects.iter().enumerate() {
        let touching = touching_triangles(&o.table, object_lights[oi]);
        if !touching.is_empty() {
            let row = &mut m[offsets[oi]..offsets[oi + 1]];
            remove_triangles(&o.table, object_lights[oi], mode, &touching, row);
        }
    }
}

/// Subtracts, from the multiplicities `m` of one object for one light, the contributions
/// `ov_sign(mode, a, b, o)` of the flagged triangles, so that sides and caps keep bounding the
/// same prisms.
///
/// # Panics
/// Panics if `m` or `flags` do not match the table.
pub fn remove_triangles(
    table: &EdgeTable,
    object_light: [f32; 4],
    mode: Accuracy,
    flags: &[bool],
    m: &mut [i32],
) {
    for (ti, t) in table.triangles.iter().enumerate() {
        if !flags[ti] {
            continue;
        }
        for i in 0..3 {
            let (u, v, o) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            let (a, b) = if u < v { (u, v) } else { (v, u) };
            let e = table
                .edge_index(a, b)
                .expect("a triangle's edge is in its table") as usize;
            m[e] -= i32::from(ov_sign(mode, &table.positions, a, b, o, object_light));
        }
    }
}

/// A triangle's vertex ids sorted ascending (the canonical order of the sign convention).
#[must_use]
#[inline]
pub fn canonical_triangle(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowvol_mesh_topology::Mesh;

    /// Every edge's multiplicity under `light` in `mode`: the sum of its (edge, OV) signs.
    fn naive_multiplicities(table: &EdgeTable, mode: Accuracy, light: [f32; 4]) -> Vec<i32> {
        table
            .edges
            .iter()
            .enumerate()
            .map(|(e, &[a, b])| {
                table
                    .ovs_of(e)
                    .map(|o| i32::from(ov_sign(mode, &table.positions, a, b, o, light)))
                    .sum()
            })
            .collect()
    }

    /// The side quad of a single triangle's edge must have its outward normal pointing away
    /// from the triangle's interior (checked with the prism of one triangle under a light).
    #[test]
    fn side_orientation_is_outward() {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        let table = EdgeTable::build(&mesh).unwrap();
        let light = [0.2, 0.2, 5.0, 1.0];
        let m = naive_multiplicities(&table, Accuracy::Exact, light);
        let mut out = Vec::new();
        let n = build_sides(&table.edges, &m, &table.positions, light, &mut out);
        assert_eq!(n, 3);
        let centroid = Vec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0);
        assert_eq!(out.len(), 18);
        for quad in out.chunks(6) {
            // Quad (p, q, q_inf, p, q_inf, p_inf): replace q_inf by a finite point along it.
            let v = |i: usize| Vec3::new(quad[i][0], quad[i][1], quad[i][2]);
            assert_eq!((quad[0][3], quad[1][3], quad[2][3]), (1.0, 1.0, 0.0));
            let (p, q) = (v(0), v(1));
            let q_far = q + v(2) * 0.5;
            let normal = (q - p).cross(q_far - p);
            // The prism (the triangle's shadow) lies on the inner side of every side face.
            assert!(
                normal.dot(centroid - p) < 0.0,
                "side normal {normal} points inwards"
            );
        }
    }

    #[test]
    fn touching_triangles_leave_no_light_vertex_in_sides() {
        // A tetrahedron with the light exactly at vertex 3, every mode.
        let mesh = Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.1, 0.2, 1.0)],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
        .unwrap();
        let table = EdgeTable::build(&mesh).unwrap();
        let l = [0.1, 0.2, 1.0, 1.0];
        let flags = touching_triangles(&table, l);
        assert_eq!(flags.iter().filter(|&&f| f).count(), 3);
        for mode in Accuracy::ALL {
            let mut m = naive_multiplicities(&table, mode, l);
            remove_triangles(&table, l, mode, &flags, &mut m);
            let mut out = Vec::new();
            build_sides(&table.edges, &m, &table.positions, l, &mut out);
            assert!(
                out.iter().all(|v| v != &[0.0; 4]),
                "{mode}: a side vertex at the light"
            );
            // What is left is the base triangle's own boundary (or nothing).
            let caps = build_caps(&table, l, &table.positions, l, mode, true, &flags);
            assert_eq!(
                caps.zero,
                3 + usize::from(caps.front_ccw.len() + caps.front_cw.len() == 0)
            );
        }
    }

    /// `x·2^149` as an integer (every finite `f32` is a multiple of `2^-149`).
    fn scaled(x: f32) -> num_bigint::BigInt {
        let bits = x.to_bits();
        let (exp, frac) = ((bits >> 23) & 0xff, bits & 0x7f_ffff);
        let (m, e) = if exp == 0 {
            (frac, 0)
        } else {
            (frac | 0x80_0000, exp - 1)
        };
        let v = num_bigint::BigInt::from(m) << e;
        if bits >> 31 == 1 {
            -v
        } else {
            v
        }
    }

    #[test]
    fn extrusion_is_directed_a_hair_from_the_light() {
        use num_traits::{Signed, ToPrimitive, Zero};
        // Lights (fl(w·P), w) at vertices P: w·P − L.xyz is 10⁻⁸ or less, which f32 rounds to
        // noise. The reference is the exact integer w·P − L.xyz (scaled by 2^298).
        for (p, w) in [
            (Vec3::new(0.3, -0.45, 1.35), 1.1f32),
            (Vec3::new(2.5, -1.133_975_8, 1.0), 1.3),
            (Vec3::new(-7.25, 0.001, 3.1), 0.75),
        ] {
            let l = [p.x * w, p.y * w, p.z * w, w];
            let d: Vec<num_bigint::BigInt> = (0..3)
                .map(|i| scaled(p[i]) * scaled(w) - (scaled(l[i]) << 149))
                .collect();
            assert!(d.iter().any(|x| !x.is_zero()), "{p} {w}: not a hair off");
            let dmax = d.iter().map(|x| x.abs()).max().unwrap();
            let got = extrude(p, l);
            assert_eq!(got[3], 0.0);
            for i in 0..3 {
                // Ratio to the largest component, as f64 from the exact integers.
                let want = (&d[i] * num_bigint::BigInt::from(1u64 << 53) / &dmax)
                    .to_f64()
                    .unwrap()
                    / (1u64 << 53) as f64;
                let scale = got[0].abs().max(got[1].abs()).max(got[2].abs());
                let have = f64::from(got[i]) / f64::from(scale);
                assert!(
                    (have - want).abs() <= 1e-6,
                    "{p} w {w}: component {i} is {have}, exact {want} ({got:?})"
                );
            }
            assert!(
                !at_light(p, l),
                "{p} {w}: w·P is not exact, L.xyz is not at P"
            );
        }
        // Exactly at the light: every product exact.
        let p = Vec3::new(0.5, 0.25, 2.0);
        assert!(at_light(p, [1.0, 0.5, 4.0, 2.0]));
        assert_eq!(extrude(p, [1.0, 0.5, 4.0, 2.0]), [0.0; 4]);
    }

    #[test]
    fn caps_split_by_sign_and_skip_back_cap_for_directional() {
        let mesh = Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
        .unwrap();
        let table = EdgeTable::build(&mesh).unwrap();
        let l = [2.0, 3.0, 5.0, 1.0];
        let caps = build_caps(&table, l, &table.positions, l, Accuracy::Exact, true, &[]);
        assert_eq!(
            (caps.front_ccw.len() + caps.front_cw.len()) / 3 + caps.zero,
            4
        );
        assert_eq!(caps.back.len(), caps.front_ccw.len() + caps.front_cw.len());
        let d = [1.0, 2.0, 3.0, 0.0];
        let caps = build_caps(&table, d, &table.positions, d, Accuracy::Exact, true, &[]);
        assert!(caps.back.is_empty());
    }
}
