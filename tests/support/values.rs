//! Independent references for the values of every accuracy mode, shared by the conformance suite
//! and the GPU crates' device tests (included with `#[path]`).
//!
//! Nothing here calls the predicates of `shadowvol-robust-math` or a backend:
//!
//! * `exact`: a loose `f64` filter written here (bound `1e-13` of the permanent, about a hundred
//!   times the proven one), and the big-integer oracle (`crates/robust-math/tests/oracle`) for
//!   every pair it does not decide;
//! * `original`, `ordered`, `robust`: the documented `f32` operation sequence written out here,
//!   with each mode's rule (canonical order by sorting, parity by counting inversions, robust's
//!   three rotations and its disagreement rule).
//!
//! Two rules compare a backend's `f32` modes with these references ([`Rule`]): bit for bit where
//! the device evaluates without contraction, and otherwise only on the pairs whose sign is
//! certified with a margin larger than the `f32` error bound, where every evaluation order must
//! give the exact sign. Exact mode is always compared bit for bit.
//!
//! The lights are brought into object space by `object_lights`, as the backends do: that
//! function has its own test against an independent inverse (`crates/silhouette/tests`).
#![allow(dead_code)]

#[path = "../../crates/robust-math/tests/oracle/mod.rs"]
mod oracle;

use shadowvol_silhouette::{object_lights, Accuracy, Light, Multiplicities, TopologyScene};

/// How a backend's `f32` modes are compared with the reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// Bit for bit: host backends, and devices known to evaluate without contraction (Mesa
    /// lavapipe/llvmpipe, PoCL).
    BitExact,
    /// Only edges whose every pair is certified with a margin: any device.
    Certified,
}

impl Rule {
    /// The rule for a device backend running on `device` (the backend's `info().device`). A host
    /// backend (the registry's `host`, such as `cpu` and `simd`) is always [`Rule::BitExact`].
    #[must_use]
    pub fn for_device(device: &str) -> Rule {
        let d = device.to_ascii_lowercase();
        if d.contains("llvmpipe")
            || d.contains("lavapipe")
            || d.contains("pocl")
            || d.contains("portable computing language")
        {
            Rule::BitExact
        } else {
            Rule::Certified
        }
    }

    /// A short name for test names and notes.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Rule::BitExact => "bit-exact",
            Rule::Certified => "certified",
        }
    }
}

/// The margin of [`certified`]: a pair counts as certified when `|det| > 2^-18 * perm` in `f64`,
/// twice the `f32` filter's bound `2^-19` (itself about four times `gamma_8`, for contraction and
/// reassociation on GPUs).
pub const CERTIFIED_MARGIN: f64 = 1.0 / 262_144.0;

/// The documented `f32` sequence of `sgn(((A - B) x V) . (O - A))`, `V = L.xyz - L.w * A`.
#[must_use]
pub fn sign_f32(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    let v = [l[0] - l[3] * a[0], l[1] - l[3] * a[1], l[2] - l[3] * a[2]];
    let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let n = [
        e[1] * v[2] - e[2] * v[1],
        e[2] * v[0] - e[0] * v[2],
        e[0] * v[1] - e[1] * v[0],
    ];
    let d = [o[0] - a[0], o[1] - a[1], o[2] - a[2]];
    let s = (n[0] * d[0] + n[1] * d[1]) + n[2] * d[2];
    if s > 0.0 {
        1
    } else if s < 0.0 {
        -1
    } else {
        0
    }
}

/// The same determinant and its permanent in `f64` (inputs converted exactly).
fn det_perm_f64(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> (f64, f64) {
    let f = |x: [f32; 3]| x.map(f64::from);
    let (a, b, o) = (f(a), f(b), f(o));
    let l = l.map(f64::from);
    let v = [l[0] - l[3] * a[0], l[1] - l[3] * a[1], l[2] - l[3] * a[2]];
    let e = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let d = [o[0] - a[0], o[1] - a[1], o[2] - a[2]];
    let mut det = 0.0;
    let mut perm = 0.0;
    for (i, j, k) in [(1, 2, 0), (2, 0, 1), (0, 1, 2)] {
        let (p, q) = (e[i] * v[j], e[j] * v[i]);
        det += (p - q) * d[k];
        perm += (p.abs() + q.abs()) * d[k].abs();
    }
    (det, perm)
}

/// The exact sign: the loose `f64` filter, else the big-integer oracle.
#[must_use]
pub fn sign_exact(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> i8 {
    let (det, perm) = det_perm_f64(a, b, l, o);
    if det.abs() > 1e-13 * perm {
        if det > 0.0 {
            1
        } else {
            -1
        }
    } else {
        oracle::sign_exact(a, b, l, o)
    }
}

/// Whether the oracle would be asked for this pair (the loose filter leaves it undecided).
#[must_use]
pub fn needs_oracle(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> bool {
    let (det, perm) = det_perm_f64(a, b, l, o);
    det.abs() <= 1e-13 * perm
}

/// Whether any `f32` evaluation order, with or without contraction, gives the exact sign of this
/// evaluation: `w` is 0 or 1 (so `w * A` is exact), no input is subnormal (a flushing device
/// changes those), every non-zero difference lies in `[2^-40, 2^40]` (no product leaves the
/// normal range) and `|det| > CERTIFIED_MARGIN * perm`.
#[must_use]
pub fn certified(a: [f32; 3], b: [f32; 3], l: [f32; 4], o: [f32; 3]) -> bool {
    if l[3] != 0.0 && l[3] != 1.0 {
        return false;
    }
    let all = a.iter().chain(&b).chain(&l).chain(&o);
    if all.clone().any(|x| x.is_subnormal()) {
        return false;
    }
    let in_range = |x: f32, y: f32| {
        let d = (f64::from(x) - f64::from(y)).abs();
        d == 0.0 || (2f64.powi(-40)..=2f64.powi(40)).contains(&d)
    };
    for i in 0..3 {
        if !in_range(a[i], b[i]) || !in_range(o[i], a[i]) || !in_range(l[i], l[3] * a[i]) {
            return false;
        }
    }
    let (det, perm) = det_perm_f64(a, b, l, o);
    det.abs() > CERTIFIED_MARGIN * perm
}

/// The canonical order of `(a, b, o)` (ids ascending) and the parity of the permutation that
/// sorts it, counted as inversions.
#[must_use]
pub fn canonical(a: u32, b: u32, o: u32) -> ([u32; 3], i8) {
    let t = [a, b, o];
    let mut inversions = 0;
    for i in 0..3 {
        for j in i + 1..3 {
            if t[i] > t[j] {
                inversions += 1;
            }
        }
    }
    let mut s = t;
    s.sort_unstable();
    (s, if inversions % 2 == 0 { 1 } else { -1 })
}

/// The evaluations `(A, B, O)` a mode performs for the pair `(a, b, o)`, as id triples.
fn evaluations(mode: Accuracy, a: u32, b: u32, o: u32) -> Vec<[u32; 3]> {
    let ([i0, i1, i2], _) = canonical(a, b, o);
    match mode {
        Accuracy::Original | Accuracy::Exact => vec![[a, b, o]],
        Accuracy::Ordered => vec![[i0, i1, i2]],
        Accuracy::Robust => vec![[i0, i1, i2], [i1, i2, i0], [i2, i0, i1]],
    }
}

/// The reference value of `s(a, b, o)` in `mode`.
#[must_use]
pub fn ov_sign(mode: Accuracy, p: &[[f32; 3]], a: u32, b: u32, o: u32, l: [f32; 4]) -> i8 {
    let at = |i: u32| p[i as usize];
    let ev = |[x, y, z]: [u32; 3]| sign_f32(at(x), at(y), l, at(z));
    let (_, parity) = canonical(a, b, o);
    match mode {
        Accuracy::Exact => sign_exact(at(a), at(b), l, at(o)),
        Accuracy::Original => ev([a, b, o]),
        Accuracy::Ordered => ev(evaluations(mode, a, b, o)[0]) * parity,
        Accuracy::Robust => {
            let s: Vec<i8> = evaluations(mode, a, b, o).into_iter().map(ev).collect();
            if s[0] == s[1] && s[1] == s[2] {
                s[0] * parity
            } else {
                0
            }
        }
    }
}

/// The reference of one (scene, lights, mode): for every light, every global edge, the
/// reference multiplicity and whether each of its pairs is certified in that mode.
pub struct Reference {
    /// `values[light][edge]`.
    pub values: Vec<Vec<i32>>,
    /// `certified[light][edge]`: every evaluation of every pair of the edge is certified, so its
    /// multiplicity equals exact's on any device.
    pub certified: Vec<Vec<bool>>,
    /// `exact[light][edge]`: the exact multiplicities.
    pub exact: Vec<Vec<i32>>,
    /// Pairs decided by the big-integer oracle (the loose filter left them undecided), and how
    /// many of them have a non-zero sign.
    pub oracle_pairs: (usize, usize),
}

/// Computes the [`Reference`] of `mode` on `scene` for `lights`.
#[must_use]
pub fn reference(scene: &TopologyScene, lights: &[Light], mode: Accuracy) -> Reference {
    let obj_lights = object_lights(scene.transforms(), lights);
    let mut r = Reference {
        values: Vec::new(),
        certified: Vec::new(),
        exact: Vec::new(),
        oracle_pairs: (0, 0),
    };
    for li in 0..lights.len() {
        let (mut vals, mut certs, mut exact) = (Vec::new(), Vec::new(), Vec::new());
        for (object, per_light) in scene.objects.iter().zip(&obj_lights) {
            let l = per_light[li];
            let t = &object.table;
            let p: Vec<[f32; 3]> = t.positions.iter().map(|v| v.to_array()).collect();
            for (e, &[a, b]) in t.edges.iter().enumerate() {
                let (mut m, mut mx, mut cert) = (0i32, 0i32, true);
                for o in t.ovs_of(e) {
                    let x = sign_exact(p[a as usize], p[b as usize], l, p[o as usize]);
                    if needs_oracle(p[a as usize], p[b as usize], l, p[o as usize]) {
                        r.oracle_pairs.0 += 1;
                        r.oracle_pairs.1 += usize::from(x != 0);
                    }
                    mx += i32::from(x);
                    m += i32::from(if mode == Accuracy::Exact {
                        x
                    } else {
                        ov_sign(mode, &p, a, b, o, l)
                    });
                    cert &= evaluations(mode, a, b, o)
                        .into_iter()
                        .all(|[x, y, z]| certified(p[x as usize], p[y as usize], l, p[z as usize]));
                }
                vals.push(m);
                exact.push(mx);
                certs.push(cert);
            }
        }
        r.values.push(vals);
        r.certified.push(certs);
        r.exact.push(exact);
    }
    r
}

/// Names a global edge by object and compact ids, for messages.
fn edge_label(scene: &TopologyScene, global: usize) -> String {
    let mut g = global;
    for o in &scene.objects {
        if g < o.table.edges.len() {
            let [a, b] = o.table.edges[g];
            return format!("{} edge #{g} ({a}, {b})", o.name);
        }
        g -= o.table.edges.len();
    }
    format!("edge #{global}")
}

/// Compares `got` with the reference under `rule` (exact mode: always bit for bit). Returns a
/// note on what was compared, or the first difference.
///
/// # Errors
/// The first edge whose multiplicity differs, and the number of differing edges.
pub fn check(
    scene: &TopologyScene,
    lights: &[Light],
    mode: Accuracy,
    rule: Rule,
    reference: &Reference,
    got: &Multiplicities,
) -> Result<String, String> {
    let rule = if mode == Accuracy::Exact {
        Rule::BitExact
    } else {
        rule
    };
    let (mut compared, mut differing, mut first) = (0usize, 0usize, None);
    for li in 0..lights.len() {
        let values = got.values(li);
        for (e, &g) in values.iter().enumerate() {
            let want = match rule {
                Rule::BitExact => reference.values[li][e],
                Rule::Certified if reference.certified[li][e] => reference.exact[li][e],
                Rule::Certified => continue,
            };
            compared += 1;
            if g != want {
                differing += 1;
                first.get_or_insert((li, e, g, want));
            }
        }
    }
    let what = match rule {
        Rule::BitExact if mode == Accuracy::Exact => "the big-integer oracle".to_owned(),
        Rule::BitExact => format!("the reference {mode} (bit-exact rule)"),
        Rule::Certified => "exact on the certified edges (certified rule)".to_owned(),
    };
    match first {
        None => Ok(format!(
            "{mode}: {compared} (edge, light) values equal {what}"
        )),
        Some((li, e, g, want)) => Err(format!(
            "{mode} differs from {what} on {differing} of {compared} (edge, light) values; \
             first: light {li} ({}), {}: m = {g}, reference m = {want}",
            lights[li],
            edge_label(scene, e)
        )),
    }
}

/// The pairs of `scene` that the crate's `f64` filter (`orient_filter_f64`, used by every backend
/// before its exact fallback) leaves undecided, counted by their exact sign: `[-1, 0, +1]`.
#[must_use]
pub fn fallback_signs(scene: &TopologyScene, lights: &[Light]) -> [usize; 3] {
    let obj_lights = object_lights(scene.transforms(), lights);
    let mut counts = [0; 3];
    for (obj, object) in scene.objects.iter().enumerate() {
        let t = &object.table;
        let p: Vec<[f32; 3]> = t.positions.iter().map(|v| v.to_array()).collect();
        for l in &obj_lights[obj] {
            for (e, &[a, b]) in t.edges.iter().enumerate() {
                for o in t.ovs_of(e) {
                    let (a, b, o) = (p[a as usize], p[b as usize], p[o as usize]);
                    if shadowvol_robust_math::orient_filter_f64(a, b, *l, o).is_none() {
                        counts[(oracle::sign_exact(a, b, *l, o) + 1) as usize] += 1;
                    }
                }
            }
        }
    }
    counts
}
