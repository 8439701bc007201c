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
use ply_rs_bw::ply::{DefaultElement, Property};
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
    let err = |location: &str, message: String| SceneError::Ply {
        file: source_name.to_owned(),
        location: location.to_owned(),
        message,
    };
    let mut reader = bytes;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut reader)
        .map_err(|e| match e.line() {
            Some(l) => err(
                &format!("line {l}"),
                e.to_string()
                    .trim_start_matches(&format!("Line {l}: "))
                    .replace("\n\t", "; "),
            ),
            None => err("payload", e.to_string().replace("\n\t", "; ")),
        })?;
    let Some(vdef) = ply.header.elements.get("vertex") else {
        return Err(err(
            "header",
            "no \"vertex\" element (a mesh needs vertex positions)".to_owned(),
        ));
    };
    for axis in ["x", "y", "z"] {
        match vdef.properties.get(axis).map(|p| &p.data_type) {
            Some(ply_rs_bw::ply::PropertyType::Scalar(_)) => {}
            Some(_) => {
                return Err(err(
                    "header",
                    format!("vertex property \"{axis}\" is a list, a scalar is needed"),
                ))
            }
            None => {
                return Err(err(
                    "header",
                    format!("the vertex element has no \"{axis}\" property"),
                ))
            }
        }
    }
    let vertices = ply.payload.get("vertex").map_or(&[][..], Vec::as_slice);
    if vertices.len() as u64 >= u64::from(u32::MAX) {
        return Err(err(
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
                    return Err(err(
                        &format!("element vertex {i}"),
                        format!("coordinate {axis} is {x}, but positions must be finite"),
                    ))
                }
                None => {
                    return Err(err(
                        &format!("element vertex {i}"),
                        format!("coordinate {axis} is missing"),
                    ))
                }
            };
        }
        positions.push(Vec3::from_array(p));
    }
    let mut triangles = Vec::new();
    if let Some(fdef) = ply.header.elements.get("face") {
        let key = ["vertex_indices", "vertex_index"]
            .into_iter()
            .find(|k| fdef.properties.contains_key(*k))
            .ok_or_else(|| {
                err(
                    "header",
                    "the face element has no \"vertex_indices\" (or \"vertex_index\") list"
                        .to_owned(),
                )
            })?;
        let n = positions.len();
        let mut corners: Vec<u32> = Vec::new();
        for (f, face) in ply.payload.get("face").into_iter().flatten().enumerate() {
            let loc = || format!("element face {f}");
            corners.clear();
            let list = face
                .get(key)
                .ok_or_else(|| err(&loc(), format!("property \"{key}\" is missing")))?;
            list_indices(list, &mut corners).map_err(|m| err(&loc(), m))?;
            if let Some((c, &i)) = corners.iter().enumerate().find(|(_, &i)| i as usize >= n) {
                return Err(err(
                    &loc(),
                    format!(
                        "corner {c}: vertex index {i} is out of range (the file has {n} vertices)"
                    ),
                ));
            }
            if corners.len() < 3 {
                return Err(err(
                    &loc(),
                    format!(
                        "face has {} corner(s), but at least 3 are needed",
                        corners.len()
                    ),
                ));
            }
            for k in 1..corners.len() - 1 {
                triangles.push([corners[0], corners[k], corners[k + 1]]);
            }
            if triangles.len() as u64 * 3 >= u64::from(u32::MAX) {
                return Err(err(
                    &loc(),
                    "too many triangles for u32 indexing".to_owned(),
                ));
            }
        }
    }
    Ok(Mesh {
        positions,
        triangles,
    })
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
