//! Nearest-hit ray casting for the exposure meter ([`crate::lighting::ExposureMeter`]).
//!
//! The renderer's own: the reference judges the renderer's images, so the two share no ray
//! code. Metering needs the first surface a camera ray meets; a bounding volume hierarchy
//! (median split, leaves of at most [`LEAF`] triangles) visited nearest box first makes that
//! cheap for scenes of millions of triangles.

use glam::DVec3;

/// Triangles a leaf holds at most.
const LEAF: usize = 4;

/// A box and what it holds: `count > 0` is a leaf of `count` triangles from `start` in
/// [`NearestHit::order`]; `count == 0` has children `start` and `start + 1`.
#[derive(Debug, Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    start: u32,
    count: u32,
}

/// Triangles in `f64`, arranged for nearest-hit queries.
#[derive(Debug, Clone, Default)]
pub(crate) struct NearestHit {
    tris: Vec<[DVec3; 3]>,
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl NearestHit {
    /// Arranges `tris`; a hit names a triangle by its index in `tris`.
    pub(crate) fn new(tris: Vec<[DVec3; 3]>) -> Self {
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let centre = |i: u32| {
            let t = &tris[i as usize];
            t[0] + t[1] + t[2]
        };
        let root = Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            start: 0,
            count: 0,
        };
        let (mut nodes, mut todo) = if tris.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            (vec![root], vec![(0usize, 0usize, tris.len())])
        };
        while let Some((at, begin, end)) = todo.pop() {
            let slice = &mut order[begin..end];
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for &i in slice.iter() {
                for p in tris[i as usize] {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                clo = clo.min(centre(i));
                chi = chi.max(centre(i));
            }
            // Grown so that the slab test's rounding never loses a triangle the ray touches.
            let grow = (lo.abs().max(hi.abs()) + DVec3::ONE) * 1e-9;
            nodes[at].lo = lo - grow;
            nodes[at].hi = hi + grow;
            let spread = chi - clo;
            let widest = spread.max_element();
            if slice.len() <= LEAF || widest.is_nan() || widest <= 0.0 {
                nodes[at].start = begin as u32;
                nodes[at].count = slice.len() as u32;
                continue;
            }
            let axis = spread.max_position();
            let half = slice.len() / 2;
            slice
                .select_nth_unstable_by(half, |&a, &b| centre(a)[axis].total_cmp(&centre(b)[axis]));
            let first = nodes.len();
            nodes.extend([nodes[at]; 2]);
            nodes[at].start = first as u32;
            nodes[at].count = 0;
            todo.push((first, begin, begin + half));
            todo.push((first + 1, begin + half, end));
        }
        Self { tris, order, nodes }
    }

    /// The triangle at `index` of the list given to [`NearestHit::new`].
    pub(crate) fn triangle(&self, index: usize) -> [DVec3; 3] {
        self.tris[index]
    }

    /// The nearest triangle that the ray `origin + t·dir`, `t > 0`, meets, and its `t`; of
    /// triangles met at the same `t`, the one listed first. `None` when it meets none.
    pub(crate) fn cast(&self, origin: DVec3, dir: DVec3) -> Option<(usize, f64)> {
        let inv = DVec3::ONE / dir;
        let mut best: Option<(usize, f64)> = None;
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        if let Some(t) = self.nodes.first().and_then(|n| enter(n, origin, inv)) {
            stack.push((0, t));
        }
        while let Some((at, t_enter)) = stack.pop() {
            if best.is_some_and(|(_, b)| t_enter > b) {
                continue;
            }
            let n = self.nodes[at as usize];
            if n.count > 0 {
                for &i in &self.order[n.start as usize..(n.start + n.count) as usize] {
                    let Some(t) = meet(&self.tris[i as usize], origin, dir) else {
                        continue;
                    };
                    let better = match best {
                        None => t > 0.0,
                        Some((bi, bt)) => t > 0.0 && (t < bt || (t == bt && (i as usize) < bi)),
                    };
                    if better {
                        best = Some((i as usize, t));
                    }
                }
                continue;
            }
            let kids =
                [n.start, n.start + 1].map(|k| (k, enter(&self.nodes[k as usize], origin, inv)));
            // The nearer child goes on the stack last, so it is visited first.
            let (near, far) = match (kids[0].1, kids[1].1) {
                (Some(a), Some(b)) if b < a => (kids[1], kids[0]),
                _ => (kids[0], kids[1]),
            };
            for (k, t) in [far, near] {
                if let Some(t) = t {
                    stack.push((k, t));
                }
            }
        }
        best
    }
}

/// Where the ray with inverse direction `inv` enters `n`'s box (`t ≥ 0`), if it meets it. An
/// axis the ray runs parallel to constrains only where it gives a number.
fn enter(n: &Node, origin: DVec3, inv: DVec3) -> Option<f64> {
    let a = (n.lo - origin) * inv;
    let b = (n.hi - origin) * inv;
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        let (lo, hi) = (a[k].min(b[k]), a[k].max(b[k]));
        if !lo.is_nan() {
            t0 = t0.max(lo);
        }
        if !hi.is_nan() {
            t1 = t1.min(hi);
        }
    }
    (t0 <= t1).then_some(t0)
}

/// Where the ray `o + t·d` meets triangle `tri`: `t` from the plane's equation, then the point
/// inside all three edges (their cross products with the point agree with the normal); `None`
/// for a miss or a ray parallel to the plane.
fn meet(tri: &[DVec3; 3], o: DVec3, d: DVec3) -> Option<f64> {
    let [a, b, c] = *tri;
    let n = (b - a).cross(c - a);
    let along = n.dot(d);
    if along == 0.0 || !along.is_finite() {
        return None;
    }
    let t = n.dot(a - o) / along;
    let p = o + t * d;
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(p - u).dot(n) >= 0.0);
    (inside && t.is_finite()).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle, tried one by one: the answer the hierarchy must give.
    fn brute(tris: &[[DVec3; 3]], o: DVec3, d: DVec3) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, t) in tris.iter().enumerate() {
            if let Some(t) = meet(t, o, d).filter(|&t| t > 0.0) {
                if best.is_none_or(|(_, b)| t < b) {
                    best = Some((i, t));
                }
            }
        }
        best
    }

    #[test]
    fn casts_find_what_trying_every_triangle_finds() {
        // Stacked layers of small triangles at scattered heights, some sharing edges, and rays
        // in every direction, axis-parallel ones included.
        let mut tris = Vec::new();
        for i in 0..24 {
            for j in 0..24 {
                let o = DVec3::new(f64::from(i), f64::from(j), f64::from((i * 7 + j * 3) % 5));
                tris.push([o, o + DVec3::X, o + DVec3::Y]);
                tris.push([o + DVec3::X, o + DVec3::X + DVec3::Y, o + DVec3::Y]);
            }
        }
        let hit = NearestHit::new(tris.clone());
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut hits = 0;
        for k in 0..600 {
            let o = DVec3::new(next() * 26.0 - 1.0, next() * 26.0 - 1.0, 8.0 * next() - 2.0);
            let d = match k % 4 {
                0 => DVec3::Z,
                1 => -DVec3::Z,
                _ => DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5),
            };
            let want = brute(&tris, o, d);
            assert_eq!(hit.cast(o, d), want, "ray {k}: {o} + t {d}");
            hits += usize::from(want.is_some());
        }
        assert!(hits > 100, "the rays meet the layers ({hits})");
    }

    #[test]
    fn an_empty_list_meets_nothing() {
        assert_eq!(
            NearestHit::new(Vec::new()).cast(DVec3::ZERO, DVec3::X),
            None
        );
    }
}
