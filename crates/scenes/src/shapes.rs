//! Small exact shapes: the building blocks of the `hard-*` presets ([`crate::hard`]) and of
//! tests and examples that need a closed box, a tetrahedron or a planar grid.
//!
//! Every shape is computed with `+ - * /` and `sqrt` only (IEEE correctly rounded), in `f64` and
//! rounded to `f32` once, so it is bit-identical on every platform: no `sin`/`cos` from the
//! system's math library, whose last bits may differ between machines. [`Rng`] is the
//! deterministic generator the presets' random soups use, with the same sequence everywhere.
//!
//! ```
//! use shadowvol_scenes::shapes::{cuboid, tetrahedron};
//! use glam::Vec3;
//!
//! let t = tetrahedron(1.0);
//! assert_eq!((t.positions.len(), t.triangles.len()), (4, 4));
//! let b = cuboid(Vec3::ZERO, Vec3::ONE);
//! assert_eq!((b.positions.len(), b.triangles.len()), (8, 12));
//! ```

use glam::{DVec3, Vec3};
use shadowvol_mesh_topology::Mesh;

/// `(sin x, cos x)` by Taylor series after reduction to `[-pi, pi]`; deterministic, accurate to
/// about 1e-15 (plenty: the shapes only need to be reproducible and reasonable).
pub(crate) fn sin_cos(x: f64) -> (f64, f64) {
    let tau = std::f64::consts::TAU;
    let mut r = x - (x / tau).round() * tau;
    if r > std::f64::consts::PI {
        r -= tau;
    }
    let (mut s, mut c) = (0.0, 0.0);
    let (mut ts, mut tc) = (r, 1.0);
    for k in 0..20 {
        s += ts;
        c += tc;
        let k = f64::from(k);
        ts *= -r * r / ((2.0 * k + 2.0) * (2.0 * k + 3.0));
        tc *= -r * r / ((2.0 * k + 1.0) * (2.0 * k + 2.0));
    }
    (s, c)
}

/// Rounds an `f64` point to `f32` once.
pub(crate) fn f32v(p: DVec3) -> Vec3 {
    p.as_vec3()
}

/// A deterministic generator (splitmix64) for the `hard-*` presets' soups and for randomised
/// tests: the same seed gives the same sequence on every platform.
///
/// ```
/// use shadowvol_scenes::shapes::Rng;
/// let mut a = Rng::new(7);
/// let x = a.unit();
/// assert!((-1.0..1.0).contains(&x));
/// assert_eq!(Rng::new(7).unit(), x);
/// ```
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator with the state `seed`.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A uniform integer in `0..n`.
    ///
    /// # Panics
    /// If `n` is 0.
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }

    /// A uniform `f32` in `[-1, 1)` with 24 random bits.
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    }
}

/// The closed tetrahedron `0, scale·X, scale·Y, scale·Z` with outward winding: the smallest
/// closed mesh (4 vertices, 6 edges, 4 triangles), exact in `f32` for power-of-two scales.
///
/// ```
/// let t = shadowvol_scenes::shapes::tetrahedron(2.0);
/// assert_eq!((t.positions.len(), t.triangles.len()), (4, 4));
/// ```
#[must_use]
pub fn tetrahedron(scale: f32) -> Mesh {
    Mesh {
        positions: vec![
            Vec3::ZERO,
            Vec3::X * scale,
            Vec3::Y * scale,
            Vec3::Z * scale,
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    }
}

/// A UV sphere with its poles on the z axis: `rings` latitude bands (>= 2), `segments`
/// longitudes (>= 3), single pole vertices (0 = north at +z, 1 = south at -z).
pub(crate) fn uv_sphere(center: DVec3, radius: f64, rings: u32, segments: u32) -> Mesh {
    let mut positions = vec![
        f32v(center + DVec3::Z * radius),
        f32v(center - DVec3::Z * radius),
    ];
    for r in 1..rings {
        let (st, ct) = sin_cos(std::f64::consts::PI * f64::from(r) / f64::from(rings));
        for s in 0..segments {
            let (sp, cp) = sin_cos(std::f64::consts::TAU * f64::from(s) / f64::from(segments));
            positions.push(f32v(center + radius * DVec3::new(st * cp, st * sp, ct)));
        }
    }
    let ring = |r: u32, s: u32| 2 + (r - 1) * segments + s % segments;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(1, s), ring(1, s + 1)]);
        triangles.push([1, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (
                ring(r, s),
                ring(r, s + 1),
                ring(r + 1, s + 1),
                ring(r + 1, s),
            );
            triangles.push([a, d, c]);
            triangles.push([a, c, b]);
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// A closed axis-aligned box `[lo, hi]` with 8 shared vertices and 12 triangles, wound outward.
///
/// Vertex `i` takes `hi` on the axes whose bit (1 = x, 2 = y, 4 = z) is set in `i`, `lo` on
/// the others. No validation: `lo` and `hi` are expected finite.
#[must_use]
pub fn cuboid(lo: Vec3, hi: Vec3) -> Mesh {
    let positions = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let triangles = vec![
        [0, 2, 3],
        [0, 3, 1], // z = lo
        [4, 5, 7],
        [4, 7, 6], // z = hi
        [0, 1, 5],
        [0, 5, 4], // y = lo
        [2, 6, 7],
        [2, 7, 3], // y = hi
        [0, 4, 6],
        [0, 6, 2], // x = lo
        [1, 3, 7],
        [1, 7, 5], // x = hi
    ];
    Mesh {
        positions,
        triangles,
    }
}

/// The same box with every face's 4 corners emitted separately (24 vertices, as a flat-shaded
/// export does); zero coordinates of odd faces are written as `-0.0`. Welding restores the
/// closed 8-vertex box.
pub(crate) fn cuboid_unwelded(lo: Vec3, hi: Vec3) -> Mesh {
    let closed = cuboid(lo, hi);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (f, pair) in closed.triangles.chunks(2).enumerate() {
        // Corners of the face in first-seen order.
        let mut corners: Vec<u32> = Vec::new();
        for t in pair {
            for &v in t {
                if !corners.contains(&v) {
                    corners.push(v);
                }
            }
        }
        let base = positions.len() as u32;
        for &v in &corners {
            let p = closed.positions[v as usize];
            let neg0 = |x: f32| if x == 0.0 && f % 2 == 1 { -0.0 } else { x };
            positions.push(Vec3::new(neg0(p.x), neg0(p.y), neg0(p.z)));
        }
        for t in pair {
            triangles.push(t.map(|v| base + corners.iter().position(|&c| c == v).unwrap() as u32));
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// A `nu x nv`-quad grid on the plane `origin + i * du + j * dv`, each point computed in `f64`
/// and rounded to `f32` (so a tilted plane is only nearly coplanar after rounding), plus an
/// optional out-of-plane bump `h(i, j) * normal`. Vertex `(i, j)` is `j * (nu + 1) + i`; quads
/// alternate their diagonal, so both directions occur.
///
/// `du` and `dv` must not be parallel: the normal, and with it every point, would be NaN.
#[must_use]
pub fn plane_grid(
    origin: DVec3,
    du: DVec3,
    dv: DVec3,
    nu: u32,
    nv: u32,
    bump: impl Fn(u32, u32) -> f64,
) -> Mesh {
    let n = du.cross(dv).normalize();
    let mut positions = Vec::new();
    for j in 0..=nv {
        for i in 0..=nu {
            let p = origin + f64::from(i) * du + f64::from(j) * dv + bump(i, j) * n;
            positions.push(f32v(p));
        }
    }
    let id = |i: u32, j: u32| j * (nu + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            // Alternate the diagonal so both diagonal directions occur.
            if (i + j) % 2 == 0 {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                triangles.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                triangles.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// A fan of `n` triangles around `center` in the plane spanned by `u`, `v` (rounded to `f32`).
pub(crate) fn plane_fan(center: DVec3, u: DVec3, v: DVec3, radius: f64, n: u32) -> Mesh {
    let mut positions = vec![f32v(center)];
    for k in 0..n {
        let (s, c) = sin_cos(std::f64::consts::TAU * f64::from(k) / f64::from(n));
        positions.push(f32v(center + radius * (c * u + s * v)));
    }
    let triangles = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    Mesh {
        positions,
        triangles,
    }
}

/// A non-manifold "book": `pages` triangles sharing the spine `(a, b)`, page `k` having its
/// free vertex at `pages_at[k]`. Vertex ids: 0 = a, 1 = b, 2.. = pages.
pub(crate) fn book(a: Vec3, b: Vec3, pages_at: &[Vec3]) -> Mesh {
    let mut positions = vec![a, b];
    positions.extend_from_slice(pages_at);
    let triangles = (0..pages_at.len() as u32)
        .map(|k| {
            if k % 2 == 0 {
                [0, 1, 2 + k]
            } else {
                [1, 0, 2 + k]
            }
        })
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

/// Appends `other` to `mesh` (offsetting indices).
pub(crate) fn merge(mut mesh: Mesh, other: &Mesh) -> Mesh {
    let base = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&other.positions);
    mesh.triangles
        .extend(other.triangles.iter().map(|t| t.map(|v| v + base)));
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_is_accurate() {
        for k in -40..40 {
            let x = f64::from(k) * 0.37;
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() < 1e-12, "{x}");
            assert!((c - x.cos()).abs() < 1e-12, "{x}");
        }
    }

    #[test]
    fn uv_sphere_is_closed() {
        let m = uv_sphere(DVec3::ZERO, 1.0, 6, 8);
        let t = shadowvol_mesh_topology::EdgeTable::build(&m).unwrap();
        assert_eq!(t.stats.edges, t.stats.manifold_edges);
        assert_eq!(t.stats.degenerate_triangles, 0);
        assert_eq!(m.triangles.len(), 2 * 8 * 5);
    }

    #[test]
    fn unwelded_cuboid_welds_to_closed_box() {
        let m = cuboid_unwelded(Vec3::ZERO, Vec3::ONE);
        assert_eq!(m.positions.len(), 24);
        let t = shadowvol_mesh_topology::EdgeTable::build(&m).unwrap();
        assert_eq!(t.stats.welded_vertices, 8);
        assert_eq!(t.stats.edges, 18);
        assert_eq!(t.stats.manifold_edges, 18);
    }
}
