//! Test shapes: [`uv_sphere_y`], the closed sphere the backends' tests, examples and benches
//! share, and the exact shapes of [`shadowvol_scenes::shapes`] that tests use, re-exported so
//! that a test finds every fixture here.
//!
//! ```
//! use shadowvol_test_support::shapes::{cuboid, tetrahedron, uv_sphere_y};
//!
//! assert_eq!(uv_sphere_y(4, 5, 1.0).triangles.len(), 2 * 3 * 5);
//! assert_eq!(tetrahedron(1.0).triangles.len(), 4);
//! assert_eq!(cuboid(glam::Vec3::ZERO, glam::Vec3::ONE).triangles.len(), 12);
//! ```

use glam::Vec3;
use shadowvol_mesh_topology::Mesh;

pub use shadowvol_scenes::shapes::{cuboid, plane_grid, tetrahedron, Rng};

/// A closed UV sphere of `radius` around the origin with its poles on the y axis, for tests and
/// benchmarks: `rings` latitude bands, `segments` longitudes, poles as fans of `segments`
/// triangles (vertex 0 = north pole at `+radius` y, last vertex = south pole), outward
/// (counter-clockwise seen from outside) winding. It has `2 + (rings - 1) * segments` vertices
/// and `2 * (rings - 1) * segments` triangles, every edge shared by exactly two of them.
///
/// Ring vertices are `radius * (sin θ cos φ, cos θ, sin θ sin φ)` with `θ = π r / rings`,
/// `φ = 2π s / segments`, evaluated in `f32` with the standard library's `sin`/`cos` (so the last
/// bits may differ between platforms; the conformance corpus uses the deterministic
/// [`shadowvol_scenes::shapes`] instead). That is fine where a test compares backends on the
/// same mesh built in the same process.
///
/// ```
/// use shadowvol_mesh_topology::EdgeTable;
/// use shadowvol_test_support::shapes::uv_sphere_y;
///
/// let sphere = uv_sphere_y(9, 7, 1.0);
/// assert_eq!(sphere.triangles.len(), 2 * 8 * 7);
/// let table = EdgeTable::build(&sphere).unwrap();
/// assert_eq!(table.stats.edges, table.stats.manifold_edges);
/// ```
///
/// # Panics
/// When `rings < 2` or `segments < 3` (no closed sphere).
#[must_use]
pub fn uv_sphere_y(rings: u32, segments: u32, radius: f32) -> Mesh {
    assert!(
        rings >= 2 && segments >= 3,
        "uv_sphere_y needs rings >= 2 and segments >= 3, got {rings} x {segments}"
    );
    let mut p = vec![Vec3::new(0.0, radius, 0.0)];
    for r in 1..rings {
        let th = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let ph = std::f32::consts::TAU * s as f32 / segments as f32;
            p.push(radius * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
        }
    }
    p.push(Vec3::new(0.0, -radius, 0.0));
    let south = (p.len() - 1) as u32;
    let ring = |r: u32, s: u32| 1 + (r - 1) * segments + (s % segments);
    let mut t = Vec::new();
    for s in 0..segments {
        t.push([0, ring(1, s + 1), ring(1, s)]);
        t.push([south, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (
                ring(r, s),
                ring(r, s + 1),
                ring(r + 1, s),
                ring(r + 1, s + 1),
            );
            t.push([a, b, d]);
            t.push([a, d, c]);
        }
    }
    Mesh {
        positions: p,
        triangles: t,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_sphere_y_is_closed_outward_and_on_the_sphere() {
        let m = uv_sphere_y(6, 9, 1.5);
        m.validate().unwrap();
        assert_eq!(m.positions.len(), 2 + 5 * 9);
        assert_eq!(m.triangles.len(), 2 * 5 * 9);
        assert_eq!(m.positions[0], Vec3::new(0.0, 1.5, 0.0));
        assert_eq!(
            m.positions[m.positions.len() - 1],
            Vec3::new(0.0, -1.5, 0.0)
        );
        for p in &m.positions {
            assert!((p.length() - 1.5).abs() < 1e-5, "{p}");
        }
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let outward = (b - a).cross(c - a).dot(a + b + c);
            assert!(outward > 0.0, "{t:?} winds inward");
        }
        let t = shadowvol_mesh_topology::EdgeTable::build(&m).unwrap();
        assert_eq!(t.stats.edges, t.stats.manifold_edges);
        assert_eq!(t.stats.degenerate_triangles, 0);
    }

    #[test]
    #[should_panic(expected = "rings >= 2")]
    fn uv_sphere_y_rejects_one_ring() {
        let _ = uv_sphere_y(1, 8, 1.0);
    }
}

/// Deterministic pseudo-random numbers for test shapes: a 64-bit linear congruential generator
/// (Knuth's MMIX constants), the same sequence on every machine.
#[derive(Debug, Clone)]
pub struct Lcg(pub u64);

impl Lcg {
    /// The next number in `[0, 1)`, from the state's top 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Distance in the plane from `p` to the nearest of `triangles` (0 inside one, either winding).
#[must_use]
pub fn distance_to_triangles(p: glam::DVec2, triangles: &[[glam::DVec2; 3]]) -> f64 {
    let segment = |a: glam::DVec2, b: glam::DVec2| {
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        (a + ab * t - p).length()
    };
    triangles
        .iter()
        .map(|s| {
            let side = |a: glam::DVec2, b: glam::DVec2| (b - a).perp_dot(p - a);
            let d = [side(s[0], s[1]), side(s[1], s[2]), side(s[2], s[0])];
            if d.iter().all(|&x| x >= 0.0) || d.iter().all(|&x| x <= 0.0) {
                0.0
            } else {
                (0..3)
                    .map(|k| segment(s[k], s[(k + 1) % 3]))
                    .fold(f64::INFINITY, f64::min)
            }
        })
        .fold(f64::INFINITY, f64::min)
}
