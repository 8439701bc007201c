//! PLY loading (ASCII, binary little-endian and binary big-endian), parsed with the `ply-rs-bw`
//! crate (a maintained fork of `ply-rs`).
//!
//! What is read:
//!
//! * the `vertex` element's `x`, `y`, `z` properties (any scalar type; `double` is rounded to
//!   the nearest `f32`, integers above 2^24 likewise), in file order: vertex `i` of the file is
//!   input vertex `i`. Every other vertex property (normals, colours, texture coordinates,
//!   confidence, ...) is ignored.
//! * the `face` element's `vertex_indices` (or `vertex_index`) list, of any integer type.
//!   A face with `n ≥ 3` corners becomes the fan `(c0, c1, c2), (c0, c2, c3), ...`, as for OBJ
//!   polygons; a face with fewer corners, a negative index or one past the last vertex is an
//!   error naming the face. Other face properties and other elements (`edge`, `material`, ...)
//!   are ignored.
//!
//! A file without a `face` element (a point cloud) has no triangles. Errors name the file and,
//! where the parser knows it, the line (ASCII and header); the checks made here name the element
//! and its index.
//!
//! ```
//! use shadowvol_scenes::ply::parse_ply;
//!
//! let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
//!             property float z\nproperty uchar red\nelement face 1\n\
//!             property list uchar int vertex_indices\nend_header\n\
//!             0 0 0 255\n1 0 0 255\n1 1 0 255\n0 1 0 255\n4 0 1 2 3\n";
//! let mesh = parse_ply(text.as_bytes(), "quad.ply").unwrap();
//! assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
//! ```

use crate::SceneError;
use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Ply, Property};
use shadowvol_mesh_topology::Mesh;
use std::path::Path;

/// Reads a PLY file. See the [module documentation](self).
///
/// # Errors
/// [`SceneError::Io`] if the file cannot be read; [`SceneError::Ply`] naming the file and the
/// line or element for malformed content.
pub fn load_ply(path: impl AsRef<Path>) -> Result<Mesh, SceneError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse_ply(&bytes, &path.display().to_string())
}

/// Parses PLY bytes. `source_name` is used in messages.
///
/// # Errors
/// [`SceneError::Ply`] naming `source_name` and where: a malformed header or payload (from the
/// parser, with the line where it has one), no `vertex` element or no `x`/`y`/`z` property, a
/// NaN or infinite coordinate, a face with fewer than 3 corners or an index out of range, a mesh
/// too large for `u32` indices.
pub fn parse_ply(bytes: &[u8], source_name: &str) -> Result<Mesh, SceneError> {
    let file = PlyFile { name: source_name };
    let ply = file.read(bytes)?;
    file.check_vertex_header(&ply)?;
    let positions = file.positions(&ply)?;
    let triangles = file.triangles(&ply, positions.len())?;
    Ok(Mesh {
        positions,
        triangles,
    })
}

/// The PLY file being parsed, by name, so that every stage of [`parse_ply`] names it alike.
struct PlyFile<'a> {
    name: &'a str,
}

impl PlyFile<'_> {
    /// A [`SceneError::Ply`] of this file at `location`, so every stage names the file alike.
    fn err(&self, location: &str, message: String) -> SceneError {
        SceneError::Ply {
            file: self.name.to_owned(),
            location: location.to_owned(),
            message,
        }
    }

    /// The parser's header and payload; its errors keep their line, without its prefix.
    fn read(&self, bytes: &[u8]) -> Result<Ply<DefaultElement>, SceneError> {
        let mut reader = bytes;
        Parser::<DefaultElement>::new()
            .read_ply(&mut reader)
            .map_err(|e| match e.line() {
                Some(l) => self.err(
                    &format!("line {l}"),
                    e.to_string()
                        .trim_start_matches(&format!("Line {l}: "))
                        .replace("\n\t", "; "),
                ),
                None => self.err("payload", e.to_string().replace("\n\t", "; ")),
            })
    }

    /// Checks the header's `vertex` element for scalar `x`, `y`, `z`, before any vertex.
    fn check_vertex_header(&self, ply: &Ply<DefaultElement>) -> Result<(), SceneError> {
        let Some(vdef) = ply.header.elements.get("vertex") else {
            return Err(self.err(
                "header",
                "no \"vertex\" element (a mesh needs vertex positions)".to_owned(),
            ));
        };
        for axis in ["x", "y", "z"] {
            match vdef.properties.get(axis).map(|p| &p.data_type) {
                Some(ply_rs_bw::ply::PropertyType::Scalar(_)) => {}
                Some(_) => {
                    return Err(self.err(
                        "header",
                        format!("vertex property \"{axis}\" is a list, a scalar is needed"),
                    ))
                }
                None => {
                    return Err(self.err(
                        "header",
                        format!("the vertex element has no \"{axis}\" property"),
                    ))
                }
            }
        }
        Ok(())
    }

    /// The vertex positions in file order: every coordinate present and finite.
    fn positions(&self, ply: &Ply<DefaultElement>) -> Result<Vec<Vec3>, SceneError> {
        let vertices = ply.payload.get("vertex").map_or(&[][..], Vec::as_slice);
        if vertices.len() as u64 >= u64::from(u32::MAX) {
            return Err(self.err(
                "header",
                format!("{} vertices: too many for u32 indices", vertices.len()),
            ));
        }
        let mut positions = Vec::with_capacity(vertices.len());
        for (i, v) in vertices.iter().enumerate() {
            let mut p = [0.0f32; 3];
            for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
                let value = v.get(axis).and_then(Property::to_f32_lossy);
                p[k] = match value {
                    Some(x) if x.is_finite() => x,
                    Some(x) => {
                        return Err(self.err(
                            &format!("element vertex {i}"),
                            format!("coordinate {axis} is {x}, but positions must be finite"),
                        ))
                    }
                    None => {
                        return Err(self.err(
                            &format!("element vertex {i}"),
                            format!("coordinate {axis} is missing"),
                        ))
                    }
                };
            }
            positions.push(Vec3::from_array(p));
        }
        Ok(positions)
    }

    /// The faces as triangle fans over `n` vertices; none without a `face` element.
    fn triangles(&self, ply: &Ply<DefaultElement>, n: usize) -> Result<Vec<[u32; 3]>, SceneError> {
        let mut triangles = Vec::new();
        let Some(fdef) = ply.header.elements.get("face") else {
            return Ok(triangles);
        };
        let key = ["vertex_indices", "vertex_index"]
            .into_iter()
            .find(|k| fdef.properties.contains_key(*k))
            .ok_or_else(|| {
                self.err(
                    "header",
                    "the face element has no \"vertex_indices\" (or \"vertex_index\") list"
                        .to_owned(),
                )
            })?;
        let mut corners: Vec<u32> = Vec::new();
        for (f, face) in ply.payload.get("face").into_iter().flatten().enumerate() {
            let loc = || format!("element face {f}");
            corners.clear();
            let list = face
                .get(key)
                .ok_or_else(|| self.err(&loc(), format!("property \"{key}\" is missing")))?;
            list_indices(list, &mut corners).map_err(|m| self.err(&loc(), m))?;
            self.check_face(f, &corners, n)?;
            for k in 1..corners.len() - 1 {
                triangles.push([corners[0], corners[k], corners[k + 1]]);
            }
            if triangles.len() as u64 * 3 >= u64::from(u32::MAX) {
                return Err(self.err(&loc(), "too many triangles for u32 indexing".to_owned()));
            }
        }
        Ok(triangles)
    }

    /// Checks face `f`'s corners: every index below `n`, and at least 3 of them.
    fn check_face(&self, f: usize, corners: &[u32], n: usize) -> Result<(), SceneError> {
        let loc = || format!("element face {f}");
        if let Some((c, &i)) = corners.iter().enumerate().find(|(_, &i)| i as usize >= n) {
            return Err(self.err(
                &loc(),
                format!("corner {c}: vertex index {i} is out of range (the file has {n} vertices)"),
            ));
        }
        if corners.len() < 3 {
            return Err(self.err(
                &loc(),
                format!(
                    "face has {} corner(s), but at least 3 are needed",
                    corners.len()
                ),
            ));
        }
        Ok(())
    }
}

/// The list's values as vertex indices; an error for a negative or non-integer value.
fn list_indices(p: &Property, out: &mut Vec<u32>) -> Result<(), String> {
    fn signed<T: Copy + Into<i64>>(v: &[T], out: &mut Vec<u32>) -> Result<(), String> {
        for (c, &x) in v.iter().enumerate() {
            let x: i64 = x.into();
            let i = u32::try_from(x)
                .map_err(|_| format!("corner {c}: vertex index {x} is negative"))?;
            out.push(i);
        }
        Ok(())
    }
    match p {
        Property::ListChar(v) => signed(v, out),
        Property::ListShort(v) => signed(v, out),
        Property::ListInt(v) => signed(v, out),
        Property::ListUChar(v) => signed(v, out),
        Property::ListUShort(v) => signed(v, out),
        Property::ListUInt(v) => {
            out.extend_from_slice(v);
            Ok(())
        }
        Property::ListFloat(_) | Property::ListDouble(_) => {
            Err("vertex indices are floating-point numbers, integers are needed".to_owned())
        }
        _ => Err("vertex indices are not a list".to_owned()),
    }
}
