//! A bounding volume hierarchy over `f64` triangles for the shadow rays.
//!
//! Why our own BVH: the `bvh` crate (0.13) needs Rust 1.90 (the workspace's MSRV is 1.89) and
//! brings in nalgebra; a median-split BVH over `glam` types is a hundred lines and keeps the
//! traversal (padded boxes, so that rounding never drops a candidate) in our hands.

use glam::DVec3;

/// A bounding volume hierarchy over triangles (median split on the longest centroid axis,
/// leaves of at most 4 triangles).
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<[DVec3; 3]>,
    ids: Vec<u32>,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first index into `order`; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
}

const LEAF: usize = 4;
/// Relative padding of the BVH boxes (`2⁻⁴⁰`).
const BOX_PAD: f64 = 1.0 / 1_099_511_627_776.0;

impl Bvh {
    /// Builds the hierarchy; triangle ids are the indices into `tris`.
    #[must_use]
    pub fn build(tris: Vec<[DVec3; 3]>) -> Self {
        let ids = (0..tris.len() as u32).collect();
        Self::build_with_ids(tris, ids)
    }

    /// Builds the hierarchy with a caller's id per triangle (what `skip` refers to).
    ///
    /// # Panics
    /// Panics if `ids.len() != tris.len()`.
    #[must_use]
    pub fn build_with_ids(tris: Vec<[DVec3; 3]>, ids: Vec<u32>) -> Self {
        assert_eq!(tris.len(), ids.len(), "one id per triangle");
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let centroids: Vec<DVec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 1);
        nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first: 0,
            count: 0,
        });
        let mut stack = vec![(0usize, 0usize, tris.len())];
        while let Some((node, begin, end)) = stack.pop() {
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let (mut clo, mut chi) = (lo, hi);
            for &i in &order[begin..end] {
                for p in tris[i as usize] {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                clo = clo.min(centroids[i as usize]);
                chi = chi.max(centroids[i as usize]);
            }
            // Padded by 2⁻⁴⁰ of the box's magnitude, so that the rounding of the slab test can
            // never drop a triangle a shadow ray meets exactly (at a corner or along a face).
            let pad = lo.abs().max(hi.abs()) * BOX_PAD + DVec3::splat(f64::MIN_POSITIVE);
            nodes[node].lo = lo - pad;
            nodes[node].hi = hi + pad;
            let ext = chi - clo;
            if end - begin <= LEAF || ext.max_element() <= 0.0 {
                nodes[node].first = begin as u32;
                nodes[node].count = (end - begin) as u32;
                continue;
            }
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = begin + (end - begin) / 2;
            order[begin..end].select_nth_unstable_by(mid - begin, |&a, &b| {
                centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
            });
            let left = nodes.len();
            nodes.push(nodes[node]);
            nodes.push(nodes[node]);
            nodes[node].first = left as u32;
            nodes[node].count = 0;
            stack.push((left, begin, mid));
            stack.push((left + 1, mid, end));
        }
        Self {
            nodes,
            order,
            tris,
            ids,
        }
    }

    /// True when the segment `origin + t·dir`, `t ∈ (t_min, t_max)`, hits a triangle other than
    /// `skip`.
    #[must_use]
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64, skip: u32) -> bool {
        self.occluded_by(origin, dir, t_min, t_max, |id| id != skip)
    }

    /// True when the segment `origin + t·dir`, `t ∈ (t_min, t_max)`, hits a triangle whose id
    /// passes `accept`.
    #[must_use]
    pub fn occluded_by(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
        accept: impl Fn(u32) -> bool,
    ) -> bool {
        self.traverse(origin, dir, t_min, t_max, |i| {
            accept(self.ids[i])
                && intersect(&self.tris[i], origin, dir).is_some_and(|t| t > t_min && t < t_max)
        })
    }
}

impl Bvh {
    /// The nearest triangle the ray `origin + t·dir`, `t > 0`, hits: its position in the list
    /// given to [`Bvh::build_with_ids`] and `t`; `None` when it hits nothing.
    #[must_use]
    pub fn closest_hit(&self, origin: DVec3, dir: DVec3) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        self.traverse(origin, dir, 0.0, f64::INFINITY, |i| {
            if let Some(t) = intersect(&self.tris[i], origin, dir) {
                if t > 0.0 && best.is_none_or(|(_, b)| t < b) {
                    best = Some((i, t));
                }
            }
            false
        });
        best
    }

    /// The triangle at position `index` of the list given to [`Bvh::build_with_ids`].
    #[must_use]
    pub fn triangle(&self, index: usize) -> [DVec3; 3] {
        self.tris[index]
    }

    /// Calls `visit(index)` for every triangle whose (padded) box the segment
    /// `origin + t·dir`, `t ∈ [0, t_max]`, meets, until it returns true; `index` is the position
    /// of the triangle in the list given to [`Bvh::build_with_ids`]. Returns whether some call
    /// returned true.
    pub fn visit(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
        visit: impl FnMut(usize) -> bool,
    ) -> bool {
        self.traverse(origin, dir, 0.0, t_max, visit)
    }

    /// Calls `visit(index)` for every triangle whose (padded) box `overlaps(lo, hi)` accepts,
    /// descending only into nodes whose boxes it accepts, until `visit` returns true; `index` is
    /// the position of the triangle in the list given to [`Bvh::build_with_ids`]. Returns
    /// whether some call returned true. `overlaps` must accept every box that holds a triangle
    /// the caller wants (a conservative test).
    pub fn visit_boxes(
        &self,
        overlaps: impl Fn(DVec3, DVec3) -> bool,
        mut visit: impl FnMut(usize) -> bool,
    ) -> bool {
        if self.tris.is_empty() {
            return false;
        }
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = self.nodes[stack[sp] as usize];
            if !overlaps(n.lo, n.hi) {
                continue;
            }
            if n.count > 0 {
                for &i in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    if visit(i as usize) {
                        return true;
                    }
                }
            } else if sp + 2 <= stack.len() {
                stack[sp] = n.first;
                stack[sp + 1] = n.first + 1;
                sp += 2;
            }
        }
        false
    }

    /// Calls `visit(index)` for the triangles whose (padded) box meets the segment
    /// `t ∈ [t_min, t_max]`, until it returns true; returns whether some call did.
    fn traverse(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
        visit: impl FnMut(usize) -> bool,
    ) -> bool {
        let inv = DVec3::ONE / dir;
        self.visit_boxes(|lo, hi| slab(lo, hi, origin, inv, t_min, t_max), visit)
    }
}

fn slab(lo: DVec3, hi: DVec3, o: DVec3, inv: DVec3, t_min: f64, t_max: f64) -> bool {
    let t1 = (lo - o) * inv;
    let t2 = (hi - o) * inv;
    // NaN (0 * inf) on an axis the ray is parallel to and touching: treat as overlapping.
    let tn = t1.min(t2);
    let tf = t1.max(t2);
    let mut near = t_min;
    let mut far = t_max;
    for k in 0..3 {
        if !tn[k].is_nan() {
            near = near.max(tn[k]);
        }
        if !tf[k].is_nan() {
            far = far.min(tf[k]);
        }
    }
    near <= far * (1.0 + 1e-12) + 1e-300
}

/// Möller–Trumbore in `f64`; `None` for a miss or a ray in the triangle's plane.
fn intersect(t: &[DVec3; 3], o: DVec3, d: DVec3) -> Option<f64> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bvh_matches_brute_force() {
        // A grid of small triangles; rays from below to above.
        let mut tris = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let o = DVec3::new(f64::from(i), f64::from(j), f64::from((i * 7 + j * 3) % 5));
                tris.push([o, o + DVec3::X * 0.8, o + DVec3::Y * 0.8]);
            }
        }
        let bvh = Bvh::build(tris.clone());
        for k in 0..200 {
            let o = DVec3::new(
                f64::from(k % 20) + 0.1 + f64::from(k % 7) * 0.05,
                f64::from(k / 10) * 0.5,
                -1.0,
            );
            let d = DVec3::new(0.01 * f64::from(k % 3), 0.02, 10.0);
            let brute = tris
                .iter()
                .any(|t| intersect(t, o, d).is_some_and(|t| t > 0.0 && t < 1.0));
            assert_eq!(bvh.occluded(o, d, 0.0, 1.0, u32::MAX), brute, "ray {k}");
            let nearest = tris
                .iter()
                .enumerate()
                .filter_map(|(i, t)| intersect(t, o, d).filter(|&t| t > 0.0).map(|t| (i, t)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            assert_eq!(bvh.closest_hit(o, d), nearest, "ray {k}");
        }
    }
}
