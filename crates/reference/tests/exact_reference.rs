//! The reference's exact occlusion on small scenes built to hit each degenerate case, checked
//! against an independent exact computation: rationals (big-integer fractions) that intersect the
//! line with the caster's plane (the parameter `t` of the crossing) and test the crossing point's
//! barycentric signs, instead of the orientation determinants the reference uses.

mod common;

use common::Frame;
use glam::{DVec3, Vec3};
use num_bigint::BigInt;
use shadowvol_mesh_topology::Mesh;
use shadowvol_reference::occlusion::{light_side, Caster, Crossing, ShadowRay};
use shadowvol_reference::{self as reference, PixelState};
use shadowvol_robust_math::Light;
use shadowvol_scenes::{Camera, Receiver, Scene, SceneLight};
use std::sync::Arc;

// ---------------------------------------------------------------------------------------------
// Exact rationals, just what the oracle needs.

#[derive(Clone, Debug)]
struct Q {
    n: BigInt,
    /// Always > 0.
    d: BigInt,
}

impl Q {
    /// The exact value of a finite `f64`, found by doubling until it is an integer (every
    /// finite `f64` is an integer over a power of two).
    fn from_f64(x: f64) -> Self {
        assert!(x.is_finite());
        let mut y = x;
        let mut d = BigInt::from(1);
        while y.fract() != 0.0 {
            y *= 2.0;
            d *= 2;
        }
        assert!(y.abs() < 1e30, "test values stay small: {x}");
        Self {
            n: BigInt::from(y as i128),
            d,
        }
    }
    fn int(k: i64) -> Self {
        Self {
            n: BigInt::from(k),
            d: BigInt::from(1),
        }
    }
    fn add(&self, o: &Self) -> Self {
        Self {
            n: &self.n * &o.d + &o.n * &self.d,
            d: &self.d * &o.d,
        }
    }
    fn sub(&self, o: &Self) -> Self {
        Self {
            n: &self.n * &o.d - &o.n * &self.d,
            d: &self.d * &o.d,
        }
    }
    fn mul(&self, o: &Self) -> Self {
        Self {
            n: &self.n * &o.n,
            d: &self.d * &o.d,
        }
    }
    /// `self / o`, `o ≠ 0`.
    fn div(&self, o: &Self) -> Self {
        let (mut n, mut d) = (&self.n * &o.d, &self.d * &o.n);
        if d < BigInt::from(0) {
            n = -n;
            d = -d;
        }
        Self { n, d }
    }
    fn signum(&self) -> i32 {
        match self.n.sign() {
            num_bigint::Sign::Plus => 1,
            num_bigint::Sign::Minus => -1,
            num_bigint::Sign::NoSign => 0,
        }
    }
}

type Q3 = [Q; 3];

fn q3(v: DVec3) -> Q3 {
    [Q::from_f64(v.x), Q::from_f64(v.y), Q::from_f64(v.z)]
}
fn sub3(a: &Q3, b: &Q3) -> Q3 {
    [a[0].sub(&b[0]), a[1].sub(&b[1]), a[2].sub(&b[2])]
}
fn add3(a: &Q3, b: &Q3) -> Q3 {
    [a[0].add(&b[0]), a[1].add(&b[1]), a[2].add(&b[2])]
}
fn scale3(a: &Q3, s: &Q) -> Q3 {
    [a[0].mul(s), a[1].mul(s), a[2].mul(s)]
}
fn dot3(a: &Q3, b: &Q3) -> Q {
    a[0].mul(&b[0]).add(&a[1].mul(&b[1])).add(&a[2].mul(&b[2]))
}
fn cross3(a: &Q3, b: &Q3) -> Q3 {
    [
        a[1].mul(&b[2]).sub(&a[2].mul(&b[1])),
        a[2].mul(&b[0]).sub(&a[0].mul(&b[2])),
        a[0].mul(&b[1]).sub(&a[1].mul(&b[0])),
    ]
}

/// The oracle: does the open segment from `o` to the light (for `w = 0`, the open ray towards
/// it) cross the closed triangle? The crossing point is `o + t·dir` with
/// `t = n·(a − o) / n·dir`; it must lie strictly between the ends (`0 < t < 1`, or `t > 0` for a
/// directional light) and inside the closed triangle (three barycentric signs `≥ 0`).
fn oracle_blocks(o: DVec3, tri: [Vec3; 3], l: [f32; 4]) -> bool {
    let o = q3(o);
    let [a, b, c] = tri.map(|p| q3(p.as_dvec3()));
    let n = cross3(&sub3(&b, &a), &sub3(&c, &a));
    if n.iter().all(|x| x.signum() == 0) {
        return false;
    }
    let xyz = [
        Q::from_f64(f64::from(l[0])),
        Q::from_f64(f64::from(l[1])),
        Q::from_f64(f64::from(l[2])),
    ];
    let w = Q::from_f64(f64::from(l[3]));
    let dir = if w.signum() == 0 {
        xyz
    } else {
        let p = [xyz[0].div(&w), xyz[1].div(&w), xyz[2].div(&w)];
        sub3(&p, &o)
    };
    let den = dot3(&n, &dir);
    if den.signum() == 0 {
        return false;
    }
    let t = dot3(&n, &sub3(&a, &o)).div(&den);
    if t.signum() <= 0 {
        return false;
    }
    if w.signum() != 0 && t.sub(&Q::int(1)).signum() >= 0 {
        return false;
    }
    let x = add3(&o, &scale3(&dir, &t));
    [(&a, &b), (&b, &c), (&c, &a)]
        .iter()
        .all(|(u, v)| dot3(&n, &cross3(&sub3(v, u), &sub3(&x, u))).signum() >= 0)
}

// ---------------------------------------------------------------------------------------------
// The cases.

struct Case {
    name: &'static str,
    casters: Vec<[Vec3; 3]>,
    light: [f32; 4],
    points: Vec<DVec3>,
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// An irregular grid of `f64` surface points on `z = z0` (values `f32` can't hold), plus the
/// given special points.
fn ground_points(off: f64, z0: f64, special: &[DVec3]) -> Vec<DVec3> {
    let mut p = Vec::new();
    for i in 0..23 {
        for j in 0..19 {
            let x = -3.0 + 6.0 * (f64::from(i) + 0.3711) / 23.0;
            let y = -3.0 + 6.0 * (f64::from(j) + 0.6173) / 19.0;
            p.push(DVec3::new(off + x, off + y, z0));
        }
    }
    p.extend_from_slice(special);
    p
}

/// Points on the lines from the light through each vertex and edge midpoint of `tri` (for a
/// point light: `o = L + k (q − L)`, `k = 2` beyond the caster, `k = 1/2` before it), computed
/// exactly in `f64` (dyadic scalars of `f32` differences).
fn through_features(tri: [Vec3; 3], l: [f32; 4]) -> Vec<DVec3> {
    let lp = DVec3::new(f64::from(l[0]), f64::from(l[1]), f64::from(l[2]));
    let t = tri.map(|p| p.as_dvec3());
    let feats = [
        t[0],
        t[1],
        t[2],
        (t[0] + t[1]) * 0.5,
        (t[1] + t[2]) * 0.5,
        (t[2] + t[0]) * 0.5,
        (t[0] + t[1] + t[2] * 2.0) * 0.25,
    ];
    let mut out = Vec::new();
    for q in feats {
        if l[3] == 0.0 {
            out.push(q - lp * 2.0);
            out.push(q + lp * 0.5);
        } else {
            assert_eq!(l[3], 1.0, "feature points for w = 1 only");
            out.push(lp + (q - lp) * 2.0);
            out.push(lp + (q - lp) * 0.5);
        }
    }
    out
}

/// Checks every (point, caster) pair against the oracle; returns (blocked, clear) point counts.
fn check(case: &Case, eye: DVec3) -> (usize, usize) {
    let prepared: Vec<(Caster, i8)> = case
        .casters
        .iter()
        .map(|t| (Caster::new(*t), light_side(*t, case.light)))
        .collect();
    let (mut blocked, mut clear) = (0, 0);
    for &o in &case.points {
        let ray = ShadowRay::new(o, case.light, eye);
        let mut any = false;
        for (k, (c, side)) in prepared.iter().enumerate() {
            let got = ray.crossing(c, *side);
            assert_ne!(
                got,
                Crossing::Undecidable,
                "{}: point {o} caster {k} undecidable",
                case.name
            );
            let want = oracle_blocks(o, case.casters[k], case.light);
            assert_eq!(
                got == Crossing::Blocks,
                want,
                "{}: point {o:?} caster {k} {:?}: reference {got:?}, oracle blocks = {want}",
                case.name,
                case.casters[k]
            );
            any |= want;
        }
        if any {
            blocked += 1;
        } else {
            clear += 1;
        }
    }
    (blocked, clear)
}

fn eye() -> DVec3 {
    DVec3::new(0.5, -7.0, 6.0)
}

/// A blocker that casts an ordinary shadow in every case, so that each case has blocked and
/// clear points.
fn plain_blocker(off: f32) -> [Vec3; 3] {
    [
        v(off - 1.0, off - 1.0, 0.5),
        v(off + 0.5, off - 1.0, 0.5),
        v(off - 1.0, off + 0.25, 0.625),
    ]
}

/// The light lies in the casters' planes: an axis-aligned wall, a tilted triangle, and (with
/// `w = 3`) a light whose point `xyz / w` has no binary representation.
fn light_on_plane(off: f32) -> Vec<Case> {
    let l = [off + 0.75, off + 0.5, 1.5, 1.0];
    // Wall x = off + 0.75 holds the light; tilted plane through (off+0.25, off, 1), spanned by
    // (1, 0, 1) and (0, 1, 1), holds L = (off+0.75, off+0.5, 2) ... built from dyadic steps.
    let base = v(off + 0.25, off, 1.0);
    let tilted = [base, base + v(1.0, 0.0, 1.0), base + v(0.0, 1.0, 1.0)];
    let l_tilted = base + v(0.5, 0.25, 0.75);
    let wall = [
        v(off + 0.75, off - 2.0, 0.25),
        v(off + 0.75, off + 2.0, 0.25),
        v(off + 0.75, off, 3.0),
    ];
    let third = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 3.0), v(0.0, 1.0, 0.0)]; // 3x − z = 0
    let l3 = [1.0, 1.0, 3.0, 3.0]; // the point (1/3, 1/3, 1), in the plane 3x − z = 0
    let mut cases = vec![
        Case {
            name: "light on a wall's plane",
            casters: vec![wall, plain_blocker(off)],
            light: l,
            points: ground_points(f64::from(off), 0.0, &through_features(wall, l)),
        },
        Case {
            name: "light on a tilted caster's plane",
            casters: vec![tilted, plain_blocker(off)],
            light: [l_tilted.x, l_tilted.y, l_tilted.z, 1.0],
            points: ground_points(f64::from(off), 0.0, &[]),
        },
    ];
    if off == 0.0 {
        cases.push(Case {
            name: "homogeneous light (w = 3) on a caster's plane",
            casters: vec![third, plain_blocker(0.0)],
            light: l3,
            points: ground_points(0.0, -0.25, &[]),
        });
    }
    cases
}

/// The light on the line of an edge two triangles share, and at a vertex of a fan.
fn light_on_edge_and_vertex(off: f32) -> Vec<Case> {
    let (a, b) = (v(off - 1.0, off, 1.0), v(off + 1.0, off, 1.0));
    let wing1 = [a, b, v(off, off + 1.0, 2.0)];
    let wing2 = [a, b, v(off, off - 1.0, 0.75)];
    let on_line = [off + 3.0, off, 1.0, 1.0];
    let apex = v(off + 0.5, off + 0.25, 2.0);
    let fan: Vec<[Vec3; 3]> = (0..6)
        .map(|k| {
            let s = k as f32 * 0.5 - 1.5;
            [
                apex,
                v(off + s, off - 1.0, 0.75),
                v(off + s + 0.5, off - 1.0, 0.75),
            ]
        })
        .collect();
    let at_vertex = [apex.x, apex.y, apex.z, 1.0];
    let mut fan_casters = fan.clone();
    fan_casters.push(plain_blocker(off));
    let mut special = Vec::new();
    for t in &fan {
        special.extend(
            through_features(*t, at_vertex)
                .into_iter()
                .filter(|p| p.z < 0.0),
        );
    }
    vec![
        Case {
            name: "light on an edge line",
            casters: vec![wing1, wing2, plain_blocker(off)],
            light: on_line,
            points: ground_points(f64::from(off), 0.0, &through_features(wing1, on_line)),
        },
        Case {
            name: "light at a vertex",
            casters: fan_casters,
            light: at_vertex,
            points: ground_points(f64::from(off), 0.0, &special),
        },
    ]
}

/// Blockers one `f32` step before and one step beyond a point light (the whole case, ground
/// included, moved by `off` on every axis).
fn hair_before_light(off: f32) -> Vec<Case> {
    let lz = off + 1.0;
    let below = f32::from_bits(lz.to_bits() - 1);
    let above = f32::from_bits(lz.to_bits() + 1);
    let (lx, ly) = (off + 0.25, off + 0.375);
    let l = [lx, ly, lz, 1.0];
    // Contains the light's (x, y): every shadow ray that reaches the light's height crosses it.
    let small = [
        v(off, off, below),
        v(off + 0.5, off, below),
        v(off + 0.25, off + 0.75, below),
    ];
    // Its first edge passes exactly under the light, so the crossing points fall on both sides
    // of it, within 10⁻⁷ of the edge.
    let edge_sheet = |z: f32| {
        [
            v(lx - 2.0, ly - 2.0, z),
            v(lx + 2.0, ly + 2.0, z),
            v(lx - 2.0, ly + 2.0, z),
        ]
    };
    let plain = [
        v(off - 1.0, off - 1.0, off + 0.5),
        v(off + 0.5, off - 1.0, off + 0.5),
        v(off - 1.0, off + 0.25, off + 0.625),
    ];
    let z0 = f64::from(off);
    vec![
        Case {
            name: "blocker a hair before the light",
            casters: vec![small],
            light: l,
            points: ground_points(z0, z0, &through_features(small, l)),
        },
        Case {
            name: "blocker a hair beyond the light",
            casters: vec![edge_sheet(above), plain],
            light: l,
            points: ground_points(z0, z0, &[]),
        },
        Case {
            name: "sheet a hair before the light, its edge under it",
            casters: vec![edge_sheet(below)],
            light: l,
            points: ground_points(z0, z0, &through_features(edge_sheet(below), l)),
        },
    ]
}

/// A directional light exactly parallel to a face, and one `f32` step off parallel.
fn directional_parallel(off: f32) -> Vec<Case> {
    let d = [1.0f32, 2.0, 4.0, 0.0];
    // Plane 2x − y = off + 0.5 (normal (2, −1, 0)) contains the direction (1, 2, 4).
    let parallel = [
        v(off + 0.25, off, 0.25),
        v(off + 0.75, off + 1.0, 0.5),
        v(off + 0.25, off, 1.5),
    ];
    // The same kind of face with its second vertex one `f32` step off (its first edge was
    // along the direction): no longer parallel, it casts a thin shadow.
    let x2 = off + 0.5;
    let nudged = [
        v(off - 1.0, off - 0.5, 0.75),
        v(f32::from_bits(x2.to_bits() + 1), off + 2.5, 0.75 + 6.0),
        v(off - 1.0, off - 0.5, 1.25),
    ];
    vec![
        Case {
            name: "directional light parallel to a face",
            casters: vec![parallel, plain_blocker(off)],
            light: d,
            points: ground_points(f64::from(off), 0.0, &through_features(parallel, d)),
        },
        Case {
            name: "directional light a step off parallel",
            casters: vec![nudged, plain_blocker(off)],
            light: d,
            points: ground_points(f64::from(off), 0.0, &through_features(nudged, d)),
        },
    ]
}

fn all_cases(off: f32) -> Vec<Case> {
    let mut c = light_on_plane(off);
    c.extend(light_on_edge_and_vertex(off));
    c.extend(hair_before_light(off));
    c.extend(directional_parallel(off));
    c
}

fn run_cases(off: f32) {
    let eye = eye() + DVec3::splat(f64::from(off));
    for case in all_cases(off) {
        let (blocked, clear) = check(&case, eye);
        assert!(
            blocked > 0 && clear > 0,
            "{} (offset {off}): {blocked} blocked, {clear} clear; the case must show both",
            case.name
        );
    }
}

#[test]
fn degenerate_cases_match_the_rational_oracle() {
    run_cases(0.0);
}

#[test]
fn degenerate_cases_at_1e4_offsets_match_the_rational_oracle() {
    run_cases(1.0e4);
}

/// The casters whose plane holds the light never block, whatever the point.
#[test]
fn lights_in_a_casters_plane_never_block_it() {
    for off in [0.0f32, 1.0e4] {
        let eye = eye() + DVec3::splat(f64::from(off));
        for case in light_on_plane(off)
            .into_iter()
            .chain(light_on_edge_and_vertex(off))
        {
            for t in &case.casters {
                if light_side(*t, case.light) != 0 {
                    continue;
                }
                let c = Caster::new(*t);
                for &o in &case.points {
                    let ray = ShadowRay::new(o, case.light, eye);
                    assert_eq!(ray.crossing(&c, 0), Crossing::Clear, "{}", case.name);
                }
            }
        }
    }
    // And the edge-on casters of those cases are recognised as edge-on.
    let edge_on: usize = light_on_plane(0.0)
        .iter()
        .chain(&light_on_edge_and_vertex(0.0))
        .map(|c| {
            c.casters
                .iter()
                .filter(|t| light_side(**t, c.light) == 0)
                .count()
        })
        .sum();
    assert_eq!(
        edge_on,
        3 + 2 + 6,
        "wall, tilted, w = 3; two wings; six fan blades"
    );
}

// ---------------------------------------------------------------------------------------------
// The whole reference on a frame built by hand (no GPU needed): a ground triangle fills the view
// and the casters of the cases above hang over it.

/// The frame of `case` by hand: its casters as one object, the ground as a receiver (surface 1,
/// so every pixel's id is `[2, 0]`), one unit light, and the raster's per-pixel data.
fn frame_for(case: &Case, size: u32) -> Frame {
    let ground = [v(-40.0, -40.0, 0.0), v(40.0, -40.0, 0.0), v(0.0, 60.0, 0.0)];
    let camera = Camera {
        eye: Vec3::new(0.5, -5.0, 7.0),
        target: Vec3::new(0.0, 0.0, 0.0),
        up: Vec3::Z,
        fov_y: 60f32.to_radians(),
        near: 0.01,
    };
    let soup = |tris: &[[Vec3; 3]]| Mesh {
        positions: tris.iter().flatten().copied().collect(),
        triangles: (0..tris.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect(),
    };
    let mut scene = Scene::single("casters", &soup(&case.casters)).unwrap();
    scene.receivers.push(Receiver {
        name: "ground".into(),
        table: Arc::new(shadowvol_mesh_topology::EdgeTable::build(&soup(&[ground])).unwrap()),
        albedo: [1.0; 3],
    });
    scene.lights.push(SceneLight::unit(
        Light::new(case.light[0], case.light[1], case.light[2], case.light[3]).unwrap(),
    ));
    scene.effects.ambient = 0.0;
    let n = (size * size) as usize;
    Frame {
        scene,
        camera,
        size,
        rgba: vec![0; n * 4],
        ids: vec![[2, 0]; n],
        stencil: vec![vec![0; n]],
        colors: vec![[1.0; 3]],
    }
}

#[test]
fn reference_states_match_the_oracle_per_pixel() {
    let mut both = 0;
    for case in all_cases(0.0) {
        let frame = frame_for(&case, 48);
        let shot = frame.shot();
        let points = reference::surface_points(&shot);
        let states = reference::reference_states_geometric(&shot, &points);
        let (mut lit, mut unlit) = (0, 0);
        for (i, p) in points.iter().enumerate() {
            let sp = p.expect("the ground covers the view");
            let state = states[0][i];
            assert_ne!(state, PixelState::Uncertain, "{}: pixel {i}", case.name);
            if !reference::faces_light_geometric(&shot, &sp, 0) {
                assert_eq!(state, PixelState::Unlit);
                continue;
            }
            let blocked = case
                .casters
                .iter()
                .any(|t| oracle_blocks(sp.position, *t, case.light));
            let want = if blocked {
                PixelState::Unlit
            } else {
                PixelState::Lit
            };
            assert_eq!(state, want, "{}: pixel {i} at {}", case.name, sp.position);
            if blocked {
                unlit += 1;
            } else {
                lit += 1;
            }
        }
        // (The small blocker a hair before the light covers the light's whole view cone.)
        both += usize::from(lit > 0 && unlit > 0);
        check_counts(&case, frame.clone(), &states[0]);
    }
    assert!(both >= 9, "only {both} cases show lit and shadowed pixels");
}

/// With a raster that equals the reference (stencil 1 exactly where the reference is shadowed),
/// nothing is an artifact, a boundary or undecidable; one raster pixel flipped inside a uniform
/// region is one artifact, one flipped next to a reference boundary is one boundary pixel.
fn check_counts(case: &Case, mut frame: Frame, states: &[PixelState]) {
    let w = frame.size as usize;
    frame.stencil[0] = states
        .iter()
        .map(|&s| u8::from(s != PixelState::Lit))
        .collect();
    let cmp = reference::compare(&frame.shot());
    assert_eq!(
        (
            cmp.artifact_pixels,
            cmp.boundary_pixels,
            cmp.undecidable_pixels
        ),
        (0, 0, 0),
        "{}",
        case.name
    );
    assert!((cmp.checked_fraction() - 1.0).abs() < 1e-12);
    let uniform = |i: usize| {
        let (x, y) = (i % w, i / w);
        x > 0 && y > 0 && x + 1 < w && y + 1 < w && {
            (y - 1..=y + 1).all(|ny| (x - 1..=x + 1).all(|nx| states[ny * w + nx] == states[i]))
        }
    };
    let lit_inside = (0..states.len()).find(|&i| states[i] == PixelState::Lit && uniform(i));
    let at_edge = (0..states.len()).find(|&i| {
        states[i] == PixelState::Lit && !uniform(i) && {
            let (x, y) = (i % w, i / w);
            x > 0 && y > 0 && x + 1 < w && y + 1 < w
        }
    });
    if let (Some(a), Some(b)) = (lit_inside, at_edge) {
        let mut f = frame.clone();
        f.stencil[0][a] = 1;
        f.stencil[0][b] = 1;
        let cmp = reference::compare(&f.shot());
        assert_eq!(
            (
                cmp.artifact_pixels,
                cmp.boundary_pixels,
                cmp.undecidable_pixels
            ),
            (1, 1, 0),
            "{}: pixels {a} (inside) and {b} (at a boundary) flipped",
            case.name
        );
        let covered = cmp.covered_pixels as f64;
        assert!((cmp.checked_fraction() - (covered - 1.0) / covered).abs() < 1e-12);
    }
}
