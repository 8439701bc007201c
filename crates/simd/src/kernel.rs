//! The kernels, generic over the lane [`Level`]. Each is `#[inline(always)]` so that it is
//! compiled inside the per-level entry points of [`crate::dispatch`] (one of them a
//! `#[target_feature(enable = "avx2")]` function), with every lane operation inlined.
//!
//! Three passes, each a [`Pass`](crate::dispatch::Pass) over one work item:
//!
//! * [`tri_pass`]: one sign per canonical triangle and light (`robust`, `ordered`, `exact`).
//!   Because the canonical triangle of every (edge, OV) pair is the triangle itself, its sign
//!   times the pair's permutation parity is exactly `ov_sign` of the reference, so each triangle
//!   is evaluated once instead of once per edge.
//! * [`edge_pass`]: `m(e) = Σ sign(t) · parity` over the triangles of each edge.
//! * [`original`]: `original` mode, per (edge, OV), sharing `V`, `A − B` and `N` between the two
//!   OVs of a manifold edge.
//!
//! Beside them: [`filter`] (the certified `f32` and `f64` filters of `exact` and its scalar
//! fallback) and [`signs`] (how the triangle pass stores its signs and the edge pass reads
//! them). This file holds what they share: the vertex gathers, the operations of
//! [`sign_f32`](shadowvol_robust_math::sign_f32) in lanes, and an edge pass's output.

pub(crate) mod edge_pass;
pub(crate) mod filter;
pub(crate) mod original;
pub(crate) mod shared;
pub(crate) mod signs;
pub(crate) mod tri_pass;

/// A xorshift32 generator: the deterministic inputs of the kernels' unit tests.
#[cfg(test)]
pub(crate) fn xorshift(mut x: u32) -> impl FnMut() -> u32 {
    move || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    }
}

use crate::lanes::{Arith, Level, F32V};
use crate::layout::{Geometry, LANES};

/// Gathers the positions of the 8 vertex ids `idx[..8]`.
///
/// # Safety
/// `idx.len() >= 8` and every id is a vertex of `lay` (guaranteed for the ids the layout hands
/// out: `Layout::build` checks them).
#[inline(always)]
unsafe fn gather<Lv: Level, G: Geometry>(lay: &G, idx: &[u32]) -> [Lv::F; 3] {
    // SAFETY: forwarded from the caller.
    unsafe { lay.gather::<Lv>(idx) }
}

/// A light `[x, y, z, w]` in lanes.
#[inline(always)]
fn splat4<F: F32V>(l: [f32; 4]) -> [F; 4] {
    [
        F::splat(l[0]),
        F::splat(l[1]),
        F::splat(l[2]),
        F::splat(l[3]),
    ]
}

/// `((A − B) × V)·(O − A)` with exactly the operations (and order) of `sign_f32`; its sign is
/// `sign_f32(A, B, L, O)` in every lane.
#[inline(always)]
fn plane<F: F32V>(a: &[F; 3], b: &[F; 3], l: &[F; 4], o: &[F; 3]) -> F {
    let e = sub3(a, b);
    let n = edge_normal(l, a, &e);
    off_plane(&n, a, o)
}

/// `N = (A − B) × V` with `V = L.xyz − L.w·A`, given `E = A − B`: the first operations of
/// `sign_f32`, in its order (shared by both OVs of an edge in `original`).
#[inline(always)]
fn edge_normal<F: F32V>(lv: &[F; 4], a: &[F; 3], e: &[F; 3]) -> [F; 3] {
    cross(&cross_products(e, &light_dir(lv, a)))
}

/// `N·(O − A)`: the last operations of `sign_f32`, in its order.
#[inline(always)]
fn off_plane<F: F32V>(n: &[F; 3], a: &[F; 3], o: &[F; 3]) -> F {
    dot3(n, &sub3(o, a))
}

/// `p − q` per coordinate.
#[inline(always)]
fn sub3<V: Arith>(p: &[V; 3], q: &[V; 3]) -> [V; 3] {
    [p[0] - q[0], p[1] - q[1], p[2] - q[2]]
}

/// `V = L.xyz − L.w·A` per coordinate (the multiplication first).
#[inline(always)]
fn light_dir<V: Arith>(l: &[V; 4], a: &[V; 3]) -> [V; 3] {
    [l[0] - l[3] * a[0], l[1] - l[3] * a[1], l[2] - l[3] * a[2]]
}

/// The six products of `E × V`, `[p1, q1, p2, q2, p3, q3]` with `E × V = [p1 − q1, p2 − q2,
/// p3 − q3]`: the filters bound their error with them, the plane tests take the differences.
#[inline(always)]
fn cross_products<V: Arith>(e: &[V; 3], v: &[V; 3]) -> [V; 6] {
    [
        e[1] * v[2],
        e[2] * v[1],
        e[2] * v[0],
        e[0] * v[2],
        e[0] * v[1],
        e[1] * v[0],
    ]
}

/// `[p1 − q1, p2 − q2, p3 − q3]` from the products of [`cross_products`].
#[inline(always)]
fn cross<V: Arith>(pq: &[V; 6]) -> [V; 3] {
    [pq[0] - pq[1], pq[2] - pq[3], pq[4] - pq[5]]
}

/// `(n.x·d.x + n.y·d.y) + n.z·d.z`: the dot product of `sign_f32` and of the filters, in their
/// order.
#[inline(always)]
fn dot3<V: Arith>(n: &[V; 3], d: &[V; 3]) -> V {
    (n[0] * d[0] + n[1] * d[1]) + n[2] * d[2]
}

/// Pushes `base + i` for the set bits `i` of `bits`.
#[inline(always)]
fn push_bits(sil: &mut Vec<u32>, mut bits: u32, base: usize) {
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        sil.push((base + i) as u32);
    }
}

/// Stores the first `dst.len()` (< 8: the padded last block of an object) lanes of `m` as
/// `i32` and returns their non-zero mask.
#[inline(always)]
fn store_part<F: F32V>(m: F, dst: &mut [i32]) -> u32 {
    let mut lanes = [0i32; LANES];
    let nz = m.store_i32_cached(&mut lanes);
    let n = dst.len().min(LANES);
    dst[..n].copy_from_slice(&lanes[..n]);
    nz & ((1u32 << n) - 1)
}

/// Where an edge pass ([`edge_pass`], [`original`]) writes the results of one work item.
pub(crate) struct EdgeOut<'a, 'r> {
    /// `rows[l]`: light `l`'s multiplicities of the item's edges, from its first edge on.
    pub rows: &'a mut [&'r mut [i32]],
    /// `sil[l]`: light `l`'s silhouette edges (`m != 0`) as global edge indices, ascending.
    pub sil: &'a mut [Vec<u32>],
    /// Global index of the object's first edge.
    pub edge_base: usize,
}
