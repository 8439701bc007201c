//! The mesh as loaded: `f32` positions and `u32` triangles, checked on construction.

use crate::MeshError;
use glam::Vec3;

/// A triangle mesh as loaded: `f32` positions and `u32` vertex-index triples.
///
/// Positions are in the object's own coordinate frame. The winding of triangles is kept but is
/// irrelevant to silhouette extraction, which works on unoriented, possibly non-manifold meshes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Creates a mesh and validates it with [`Mesh::validate`].
    ///
    /// # Errors
    /// Returns the first [`MeshError`] found: a non-finite coordinate, an index out of range, or a
    /// mesh too large for `u32` indexing.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        let mesh = Self {
            positions,
            triangles,
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Checks that every coordinate is finite, every index is in range, and the mesh fits `u32`
    /// indexing (vertices < 2^32 and 3 × triangles < 2^32).
    ///
    /// # Errors
    /// The first problem found, in vertex order then triangle order.
    pub fn validate(&self) -> Result<(), MeshError> {
        let limit = u64::from(u32::MAX);
        if self.positions.len() as u64 >= limit {
            return Err(MeshError::TooLarge {
                what: "vertices",
                count: self.positions.len() as u64,
                limit: limit - 1,
            });
        }
        if self.triangles.len() as u64 * 4 >= limit {
            return Err(MeshError::TooLarge {
                what: "opposite-vertex references (4 x triangles)",
                count: self.triangles.len() as u64 * 4,
                limit: limit - 1,
            });
        }
        for (vertex, p) in self.positions.iter().enumerate() {
            for (axis, value) in ['x', 'y', 'z'].into_iter().zip(p.to_array()) {
                if !value.is_finite() {
                    return Err(MeshError::NonFinitePosition {
                        vertex,
                        axis,
                        value,
                    });
                }
            }
        }
        let n = self.positions.len();
        for (triangle, t) in self.triangles.iter().enumerate() {
            for (corner, &index) in t.iter().enumerate() {
                if index as usize >= n {
                    return Err(MeshError::IndexOutOfRange {
                        triangle,
                        corner,
                        index,
                        vertices: n,
                    });
                }
            }
        }
        Ok(())
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Appends `other` to this mesh, offsetting its indices. Used to bake several objects into one.
    ///
    /// # Errors
    /// [`MeshError::TooLarge`] when the result would not fit `u32` indexing.
    pub fn append(&mut self, other: &Mesh) -> Result<(), MeshError> {
        let base = self.positions.len() as u64;
        if base + other.positions.len() as u64 >= u64::from(u32::MAX) {
            return Err(MeshError::TooLarge {
                what: "vertices",
                count: base + other.positions.len() as u64,
                limit: u64::from(u32::MAX) - 1,
            });
        }
        let base = base as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
        Ok(())
    }
}
