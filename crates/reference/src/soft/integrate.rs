//! Edges, their cancellation and the integration of the covered area (slabs, closed form).

use super::frame::{HLine, Pt};
use super::{Integration, Visibility, FAST_PATH_EDGES, U};

/// A directed edge `p → q` of multiplicity `m` (negative: `q → p`), with `p`'s key below `q`'s.
#[derive(Debug, Clone, Copy)]
pub(super) struct Edge {
    p: Pt,
    q: Pt,
    m: i32,
    /// The edge's line, to bound the ends' distance from the exact line (`None`: `extra` is
    /// that bound).
    line: Option<HLine>,
    /// Added to the distance: the frame's own error.
    extra: f64,
}

impl Edge {
    /// A bound on the distance of both ends from the exact edge's line.
    fn deviation(&self) -> f64 {
        self.line
            .map_or(0.0, |l| l.dist(self.p).max(l.dist(self.q)))
            + self.extra
    }
}

/// Appends the ring's edges `i → i + 1` that `keep` keeps, each on line `lines[i]` (or with
/// the deviation `extra[i]` alone), reversed unless `ccw`.
pub(super) fn push_polygon(
    pts: &[Pt],
    keep: &[bool],
    lines: &[Option<HLine>],
    extra: &[f64],
    ccw: bool,
    out: &mut Vec<Edge>,
) {
    let n = pts.len();
    for i in 0..n {
        if !keep[i] {
            continue;
        }
        let (mut a, mut b) = (pts[i], pts[(i + 1) % n]);
        if !ccw {
            std::mem::swap(&mut a, &mut b);
        }
        if a.x == b.x && a.y == b.y {
            continue;
        }
        let (line, extra) = (lines[i], extra[i]);
        out.push(if a.key() < b.key() {
            Edge {
                p: a,
                q: b,
                m: 1,
                line,
                extra,
            }
        } else {
            Edge {
                p: b,
                q: a,
                m: -1,
                line,
                extra,
            }
        });
    }
}

/// Sums the multiplicities of identical edges (same bits at both ends) and drops those that
/// cancel. Sorted by a hash of the ends (16-byte records), then exactly within equal hashes.
pub(super) fn cancel(edges: Vec<Edge>) -> Vec<Edge> {
    let full = |e: &Edge| (e.p.key(), e.q.key());
    let mut order: Vec<(u64, u32)> = edges
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let [a, b] = e.p.key();
            let [c, d] = e.q.key();
            let mut h = a.wrapping_mul(0x9E37_79B9_7F4A_7C15);
            for w in [b, c, d] {
                h = (h.rotate_left(23) ^ w).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            }
            (h, i as u32)
        })
        .collect();
    order.sort_unstable();
    let mut out: Vec<Edge> = Vec::with_capacity(edges.len() / 4 + 4);
    let mut i = 0;
    while i < order.len() {
        let mut j = i + 1;
        while j < order.len() && order[j].0 == order[i].0 {
            j += 1;
        }
        let group = &mut order[i..j];
        if group.len() > 1 {
            group.sort_unstable_by_key(|&(_, k)| full(&edges[k as usize]));
        }
        let mut k = 0;
        while k < group.len() {
            let mut e = edges[group[k].1 as usize];
            let mut l = k + 1;
            while l < group.len() && full(&edges[group[l].1 as usize]) == full(&e) {
                let f = &edges[group[l].1 as usize];
                e.m += f.m;
                e.extra = e.extra.max(f.extra);
                l += 1;
            }
            if e.m != 0 {
                out.push(e);
            }
            k = l;
        }
        i = j;
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Integration.

/// A non-vertical edge from left to right with its signed weight (`+m` when it runs towards
/// `+x`: counting from below, crossing it enters `m` polygons).
#[derive(Debug, Clone, Copy)]
pub(super) struct Seg {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    s: i32,
    /// Within its error of the disk.
    inner: bool,
}

impl Seg {
    fn y_at(&self, x: f64) -> f64 {
        if x == self.x0 {
            self.y0
        } else if x == self.x1 {
            self.y1
        } else {
            self.y0 + (x - self.x0) * ((self.y1 - self.y0) / (self.x1 - self.x0))
        }
    }
}

/// The parameters `t ∈ [0, 1]` where the segment `p + t (q − p)` meets the circle of radius
/// `r` about the origin, ascending (none, one or two).
pub(super) fn circle_params(p: [f64; 2], q: [f64; 2], r: f64) -> ([f64; 2], usize) {
    let d = [q[0] - p[0], q[1] - p[1]];
    let a = d[0] * d[0] + d[1] * d[1];
    let b = p[0] * d[0] + p[1] * d[1];
    let c = p[0] * p[0] + p[1] * p[1] - r * r;
    let disc = b * b - a * c;
    if a == 0.0 || disc < 0.0 {
        return ([0.0; 2], 0);
    }
    let s = disc.sqrt();
    let mut out = [0.0; 2];
    let mut n = 0;
    for t in [(-b - s) / a, (-b + s) / a] {
        if (0.0..=1.0).contains(&t) {
            out[n] = t;
            n += 1;
        }
    }
    (out, n)
}

/// The length of the segment's part within distance `r` of the origin.
pub(super) fn length_within(p: [f64; 2], q: [f64; 2], r: f64) -> f64 {
    let d = [q[0] - p[0], q[1] - p[1]];
    let len = d[0].hypot(d[1]);
    let a = d[0] * d[0] + d[1] * d[1];
    if a == 0.0 {
        return 0.0;
    }
    let b = p[0] * d[0] + p[1] * d[1];
    let c = p[0] * p[0] + p[1] * p[1] - r * r;
    let disc = b * b - a * c;
    if disc <= 0.0 {
        return 0.0;
    }
    let s = disc.sqrt();
    let (t0, t1) = (((-b - s) / a).max(0.0), ((-b + s) / a).min(1.0));
    (t1 - t0).max(0.0) * len
}

/// Neumaier's compensated sum.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    fn add(&mut self, x: f64) {
        let t = self.s + x;
        if self.s.abs() >= x.abs() {
            self.c += (self.s - t) + x;
        } else {
            self.c += (x - t) + self.s;
        }
        self.s = t;
    }
    fn value(&self) -> f64 {
        self.s + self.c
    }
}

/// The visibility of the disk of radius `r` from the edges left after cancellation.
pub(super) fn integrate(edges: &[Edge], r: f64, integration: Integration) -> Visibility {
    let disk_area = std::f64::consts::PI * r * r;
    let count = edges.len() as u32;
    // The edges that may reach the disk, and the error their displacement can make.
    let mut geom = 0.0;
    let mut inner = vec![false; edges.len()];
    for (i, e) in edges.iter().enumerate() {
        let d = e.deviation();
        let (p, q) = ([e.p.x, e.p.y], [e.q.x, e.q.y]);
        let within = length_within(p, q, r + d);
        if within > 0.0 || p[0].hypot(p[1]) <= r + d {
            inner[i] = true;
            geom += (within + 2.0 * d) * d * f64::from(e.m.unsigned_abs());
        }
    }
    let segs: Vec<Seg> = edges
        .iter()
        .zip(&inner)
        .filter(|(e, _)| e.p.x != e.q.x)
        .map(|(e, &inner)| {
            let (a, b, s) = if e.p.x < e.q.x {
                (e.p, e.q, e.m)
            } else {
                (e.q, e.p, -e.m)
            };
            Seg {
                x0: a.x,
                y0: a.y,
                x1: b.x,
                y1: b.y,
                s,
                inner,
            }
        })
        .filter(|s| s.x1 > -r && s.x0 < r)
        .collect();
    // An edge within its error of the disk but not in it is taken for a boundary: whether it
    // separates w = 0 from w > 0 is only asked where it is inside.
    let grazing = edges.iter().zip(&inner).any(|(e, &inner)| {
        let (p, q) = ([e.p.x, e.p.y], [e.q.x, e.q.y]);
        inner && length_within(p, q, r) == 0.0 && p[0].hypot(p[1]) >= r
    });
    let exact = |covered: bool| Visibility {
        value: if covered { 0.0 } else { 1.0 },
        bound: 0.0,
        casters: 0,
        edges: count,
    };
    if !inner.contains(&true) {
        // w is the same over the whole disk: its value at the centre.
        return exact(w_at(&segs, 0.0, 0.0) > 0);
    }
    // A vertical edge near the disk that separates w = 0 from w > 0 is a boundary.
    let vertical_boundary = edges.iter().zip(&inner).any(|(e, &inner)| {
        if !inner || e.p.x != e.q.x {
            return false;
        }
        // Just right of an edge running up with multiplicity m, w is m less than just left.
        let right = w_at(&segs, e.p.x, 0.5 * (e.p.y + e.q.y));
        let up = if e.p.y < e.q.y { e.m } else { -e.m };
        (right > 0) != (right + up > 0)
    });
    let (covered, err, boundary) = match (integration, convex_cycle(edges)) {
        (Integration::Auto, Some(ring)) => {
            let (a, abs) = polygon_disk_area_abs(&ring, r);
            (
                a,
                16.0 * U * abs + 4.0 * U * disk_area * ring.len() as f64,
                true,
            )
        }
        _ => slabs(edges, &inner, &segs, r),
    };
    if !boundary && !vertical_boundary && !grazing {
        // No edge that separates covered from uncovered comes near the disk.
        return exact(covered > 0.5 * disk_area);
    }
    let value = (1.0 - covered / disk_area).clamp(0.0, 1.0);
    Visibility {
        value,
        // Above 1 it says nothing (an edge whose line could not be bounded).
        bound: ((geom + err) / disk_area + 8.0 * U).min(1.0),
        casters: 0,
        edges: count,
    }
}

/// `w` at `(x, y)` counted from below along the vertical line (edges through `x` half-open,
/// `[x0, x1)`; vertical edges are not counted: `w` just right of them).
pub(super) fn w_at(segs: &[Seg], x: f64, y: f64) -> i32 {
    segs.iter()
        .filter(|s| s.x0 <= x && x < s.x1 && s.y_at(x) < y)
        .map(|s| s.s)
        .sum()
}

/// The covered area of the disk by slabs, its integration error bound, and whether an edge
/// separates `w = 0` from `w > 0` inside the disk.
pub(super) fn slabs(edges: &[Edge], inner: &[bool], segs: &[Seg], r: f64) -> (f64, f64, bool) {
    let events = slab_events(edges, inner, r);
    let g = |x: f64| {
        let x = x.clamp(-r, r);
        0.5 * (x * (r * r - x * x).max(0.0).sqrt() + r * r * (x / r).clamp(-1.0, 1.0).asin())
    };
    let gx: Vec<f64> = events.iter().map(|&x| g(x)).collect();
    let mut total = Sum::default();
    let mut abs = 0.0;
    let mut arcs = 0usize;
    let mut boundary = false;
    // An edge that never comes near the disk lies wholly below or wholly above it over
    // |x| < r (the strip outside the disk has two parts): above, it changes nothing inside;
    // below, it only adds its weight to w at the circle's bottom while x is in [x0, x1).
    let near: Vec<&Seg> = segs.iter().filter(|s| s.inner).collect();
    let (starts, ends) = below_disk(segs, r);
    let (mut si, mut ei, mut base) = (0, 0, 0i32);
    // (y at the slab's middle, weight, integral over the slab, its magnitude, inside the disk)
    let mut active: Vec<(f64, i32, f64, f64, bool)> = Vec::new();
    for k in 0..events.len().saturating_sub(1) {
        let (x0, x1) = (events[k], events[k + 1]);
        if x1 <= x0 {
            continue;
        }
        let xm = 0.5 * (x0 + x1);
        let c = (r * r - xm * xm).max(0.0).sqrt();
        let gd = gx[k + 1] - gx[k];
        while si < starts.len() && starts[si].0 <= xm {
            base += starts[si].1;
            si += 1;
        }
        while ei < ends.len() && ends[ei].0 <= xm {
            base -= ends[ei].1;
            ei += 1;
        }
        active.clear();
        // The circle's bottom and top, with what lies below.
        active.push((f64::NEG_INFINITY, base, -gd, gd.abs(), false));
        active.push((f64::INFINITY, 0, gd, gd.abs(), false));
        for s in &near {
            if !(s.x0 <= xm && xm < s.x1) {
                continue;
            }
            let ym = s.y_at(xm);
            let (val, mag, inside) = if ym >= c {
                (gd, gd.abs(), false)
            } else if ym <= -c {
                (-gd, gd.abs(), false)
            } else {
                let (ya, yb) = (s.y_at(x0), s.y_at(x1));
                (
                    0.5 * (x1 - x0) * (ya + yb),
                    (x1 - x0) * (ya.abs() + yb.abs()),
                    true,
                )
            };
            active.push((ym, s.s, val, mag, inside));
        }
        active.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut w = 0i32;
        for (j, a) in active.iter().enumerate() {
            let below = w;
            w += a.1;
            boundary |= a.4 && ((below > 0) != (w > 0));
            if w > 0 {
                if let Some(b) = active.get(j + 1) {
                    total.add(b.2);
                    total.add(-a.2);
                    abs += a.3 + b.3;
                    arcs += 2;
                }
            }
        }
    }
    let disk_area = std::f64::consts::PI * r * r;
    (
        total.value(),
        16.0 * U * abs + 4.0 * U * disk_area * arcs as f64,
        boundary,
    )
}

/// The `x` where the slabs are cut: the disk's ends, and inside it every end of an edge near
/// the disk, every crossing of such an edge with the circle and every crossing of two of them
/// inside the disk; sorted, without repeats.
fn slab_events(edges: &[Edge], inner: &[bool], r: f64) -> Vec<f64> {
    let inner: Vec<usize> = (0..edges.len()).filter(|&i| inner[i]).collect();
    let mut events = vec![-r, r];
    let inside = |x: f64| x > -r && x < r;
    for &i in &inner {
        let e = &edges[i];
        for x in [e.p.x, e.q.x] {
            if inside(x) {
                events.push(x);
            }
        }
        let (ts, n) = circle_params([e.p.x, e.p.y], [e.q.x, e.q.y], r);
        for &t in &ts[..n] {
            let x = e.p.x + t * (e.q.x - e.p.x);
            if inside(x) {
                events.push(x);
            }
        }
    }
    // Crossings of two edges inside the disk (ends shared by a chain are ends already).
    for (k, &i) in inner.iter().enumerate() {
        let e = &edges[i];
        let (ep, eq) = ([e.p.x, e.p.y], [e.q.x, e.q.y]);
        let d1 = [eq[0] - ep[0], eq[1] - ep[1]];
        for &j in &inner[k + 1..] {
            let f = &edges[j];
            let (fp, fq) = ([f.p.x, f.p.y], [f.q.x, f.q.y]);
            if ep == fp || ep == fq || eq == fp || eq == fq {
                continue;
            }
            let d2 = [fq[0] - fp[0], fq[1] - fp[1]];
            let den = d1[0] * d2[1] - d1[1] * d2[0];
            if den == 0.0 {
                continue;
            }
            let w = [fp[0] - ep[0], fp[1] - ep[1]];
            let t = (w[0] * d2[1] - w[1] * d2[0]) / den;
            let s = (w[0] * d1[1] - w[1] * d1[0]) / den;
            if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&s) {
                let x = ep[0] + t * d1[0];
                let y = ep[1] + t * d1[1];
                if inside(x) && x.hypot(y) <= r * (1.0 + 1e-9) {
                    events.push(x);
                }
            }
        }
    }
    events.sort_unstable_by(f64::total_cmp);
    events.dedup();
    events
}

/// Points `(x, weight)` where edges start or end, sorted by `x`.
type Steps = Vec<(f64, i32)>;

/// Where the edges that never come near the disk but lie below it start and end (`x`,
/// weight), each list sorted by `x`.
fn below_disk(segs: &[Seg], r: f64) -> (Steps, Steps) {
    let mut starts: Steps = Vec::new();
    let mut ends: Steps = Vec::new();
    for s in segs.iter().filter(|s| !s.inner) {
        if s.y_at(0.5 * (s.x0.max(-r) + s.x1.min(r))) < 0.0 {
            starts.push((s.x0, s.s));
            ends.push((s.x1, s.s));
        }
    }
    starts.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    ends.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    (starts, ends)
}

/// The edges as one convex counter-clockwise cycle of multiplicity 1, if they are one.
pub(super) fn convex_cycle(edges: &[Edge]) -> Option<Vec<[f64; 2]>> {
    let n = edges.len();
    if !(3..=FAST_PATH_EDGES).contains(&n) || edges.iter().any(|e| e.m.abs() != 1) {
        return None;
    }
    let directed: Vec<(Pt, Pt)> = edges
        .iter()
        .map(|e| if e.m > 0 { (e.p, e.q) } else { (e.q, e.p) })
        .collect();
    let mut ring = Vec::with_capacity(n);
    let mut used = vec![false; n];
    let mut cur = 0;
    for _ in 0..n {
        if used[cur] {
            return None;
        }
        used[cur] = true;
        ring.push([directed[cur].0.x, directed[cur].0.y]);
        let to = directed[cur].1.key();
        let mut next = None;
        for (j, d) in directed.iter().enumerate() {
            if d.0.key() == to {
                if next.is_some() {
                    return None;
                }
                next = Some(j);
            }
        }
        cur = next?;
    }
    if cur != 0 || used.iter().any(|u| !u) {
        return None;
    }
    let mut turning = 0.0;
    for i in 0..n {
        let (a, b, c) = (ring[i], ring[(i + 1) % n], ring[(i + 2) % n]);
        let (d1, d2) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
        let cross = d1[0] * d2[1] - d1[1] * d2[0];
        let dot = d1[0] * d2[0] + d1[1] * d2[1];
        if cross < 0.0 {
            return None;
        }
        turning += cross.atan2(dot);
    }
    ((turning - std::f64::consts::TAU).abs() < 1e-6).then_some(ring)
}

/// The signed area of a polygon clipped by the disk of radius `r` about the origin: positive
/// for a counter-clockwise ring, in the units of the coordinates squared. Exact up to floating
/// point for any simple polygon (the sum over its edges of the signed area of the triangle
/// `(origin, a, b)` within the disk: a triangle where the edge is inside, a circular sector
/// where it is outside); the closed form for a convex occluder clipped by a light's disk.
#[must_use]
pub fn polygon_disk_area(ring: &[[f64; 2]], r: f64) -> f64 {
    polygon_disk_area_abs(ring, r).0
}

/// [`polygon_disk_area`] and the sum of its terms' magnitudes (for the error bound).
pub(super) fn polygon_disk_area_abs(ring: &[[f64; 2]], r: f64) -> (f64, f64) {
    let n = ring.len();
    let mut total = Sum::default();
    let mut abs = 0.0;
    let sector = |p: [f64; 2], q: [f64; 2]| {
        let cross = p[0] * q[1] - p[1] * q[0];
        let dot = p[0] * q[0] + p[1] * q[1];
        0.5 * r * r * cross.atan2(dot)
    };
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        let (ts, k) = circle_params(a, b, r);
        let inside_a = a[0] * a[0] + a[1] * a[1] <= r * r;
        let at = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
        // Pieces of the edge between its ends and its crossings, each inside or outside.
        let mut cuts = vec![0.0];
        cuts.extend_from_slice(&ts[..k]);
        cuts.push(1.0);
        let mut inside = inside_a;
        for w in cuts.windows(2) {
            let (p, q) = (at(w[0]), at(w[1]));
            let mid = at(0.5 * (w[0] + w[1]));
            if k > 0 {
                inside = mid[0] * mid[0] + mid[1] * mid[1] <= r * r;
            }
            let term = if inside {
                0.5 * (p[0] * q[1] - p[1] * q[0])
            } else if p == q {
                0.0
            } else {
                sector(p, q)
            };
            total.add(term);
            abs += term.abs();
        }
    }
    (total.value(), abs)
}
