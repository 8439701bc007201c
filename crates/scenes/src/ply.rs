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
//! The file is read a buffer at a time, each element into a small record of its own (16 bytes a
//! vertex, 32 a face, other elements dropped as they are read), not into the parser's generic
//! property maps.
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
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Header, Property, PropertyAccess, PropertyAccessResult};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use std::io::BufRead;
use std::path::Path;

/// Reads a PLY file, a buffer at a time. See the [module documentation](self).
///
/// # Errors
/// [`SceneError::Io`] if the file cannot be read; [`SceneError::Ply`] naming the file and the
/// line or element for malformed content.
pub fn load_ply(path: impl AsRef<Path>) -> Result<Mesh, SceneError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let reader = std::io::BufReader::with_capacity(1 << 20, file);
    PlyFile {
        name: &path.display().to_string(),
    }
    .read_mesh(reader)
}

/// Parses PLY bytes. `source_name` is used in messages.
///
/// # Errors
/// [`SceneError::Ply`] naming `source_name` and where: a malformed header or payload (from the
/// parser, with the line where it has one), no `vertex` element or no `x`/`y`/`z` property, a
/// NaN or infinite coordinate, a face with fewer than 3 corners or an index out of range, a mesh
/// too large for `u32` indices.
pub fn parse_ply(bytes: &[u8], source_name: &str) -> Result<Mesh, SceneError> {
    PlyFile { name: source_name }.read_mesh(bytes)
}

/// A vertex as the parser fills it: `x`, `y`, `z` (as `f32`) and which of them were given; the
/// other properties are dropped as they are read. 16 bytes.
#[derive(Clone, Copy, Default)]
struct PlyVertex {
    p: [f32; 3],
    given: u8,
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(k) = ["x", "y", "z"].iter().position(|&a| a == name) else {
            return PropertyAccessResult::Ignored;
        };
        match property.to_f32_lossy() {
            Some(v) => {
                self.p[k] = v;
                self.given |= 1 << k;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

/// A face as the parser fills it: its corners as vertex indices (inline for a triangle), or
/// why they are not (a negative or non-integer index); the other properties are dropped.
#[derive(Clone, Default)]
struct PlyFace {
    corners: Corners,
    /// The corners came from `vertex_indices` (which wins over `vertex_index`).
    from_indices: bool,
}

#[derive(Clone, Default)]
enum Corners {
    #[default]
    Missing,
    Three([u32; 3]),
    Other(Vec<u32>),
    Invalid(String),
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let indices = name == "vertex_indices";
        if !(indices || name == "vertex_index" && !self.from_indices) {
            return PropertyAccessResult::Ignored;
        }
        self.from_indices |= indices;
        let mut corners = Vec::new();
        self.corners = match list_indices(&property, &mut corners) {
            Err(m) => Corners::Invalid(m),
            Ok(()) => match corners[..] {
                [a, b, c] => Corners::Three([a, b, c]),
                _ => Corners::Other(corners),
            },
        };
        PropertyAccessResult::Set
    }
}

/// An element read and dropped (`edge`, `material`, ...).
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Skipped
    }
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

    /// The parser's error, with its line where it has one (without its prefix).
    fn parse_err(&self, e: &ply_rs_bw::parser::ParseError) -> SceneError {
        match e.line() {
            Some(l) => self.err(
                &format!("line {l}"),
                e.to_string()
                    .trim_start_matches(&format!("Line {l}: "))
                    .replace("\n\t", "; "),
            ),
            None => self.err("payload", e.to_string().replace("\n\t", "; ")),
        }
    }

    /// Reads the header, then each element in file order: vertices and faces into their own
    /// small records, every other element dropped as it is read.
    fn read_mesh(&self, input: impl BufRead) -> Result<Mesh, SceneError> {
        let mut reader = Reader::new(input);
        let header = Parser::<Skipped>::new()
            .read_header(&mut reader)
            .map_err(|e| self.parse_err(&e))?;
        self.check_vertex_header(&header)?;
        let face_key = self.face_key(&header)?;
        // The table these counts need (a face is at least one triangle), refused before a
        // record is read when it cannot fit.
        let count = |name: &str| header.elements.get(name).map_or(0, |e| e.count as u64);
        EdgeTable::check_size(count("face"), count("vertex")).map_err(|source| {
            SceneError::Mesh {
                what: self.name.to_owned(),
                source,
            }
        })?;
        let (mut vertices, mut faces) = (Vec::new(), Vec::new());
        for def in header.elements.values() {
            let read = match def.name.as_str() {
                "vertex" => self
                    .payload::<PlyVertex>(&mut reader, def, &header)
                    .map(|v| vertices = v),
                "face" if face_key.is_some() => self
                    .payload::<PlyFace>(&mut reader, def, &header)
                    .map(|f| faces = f),
                _ => self.payload::<Skipped>(&mut reader, def, &header).map(drop),
            };
            read?;
        }
        let positions = self.positions(vertices)?;
        let triangles = self.triangles(faces, face_key.unwrap_or_default(), positions.len())?;
        Ok(Mesh {
            positions,
            triangles,
        })
    }

    /// One element's records.
    fn payload<E: PropertyAccess>(
        &self,
        reader: &mut Reader<impl BufRead>,
        def: &ElementDef,
        header: &Header,
    ) -> Result<Vec<E>, SceneError> {
        Parser::<E>::new()
            .read_payload_for_element(reader, def, header)
            .map_err(|e| self.parse_err(&e))
    }

    /// Checks the header's `vertex` element for scalar `x`, `y`, `z`, before any vertex.
    fn check_vertex_header(&self, header: &Header) -> Result<(), SceneError> {
        let Some(vdef) = header.elements.get("vertex") else {
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
        if vdef.count as u64 >= u64::from(u32::MAX) {
            return Err(self.err(
                "header",
                format!("{} vertices: too many for u32 indices", vdef.count),
            ));
        }
        Ok(())
    }

    /// The face element's corner list (`vertex_indices`, else `vertex_index`); `None` without a
    /// `face` element.
    fn face_key(&self, header: &Header) -> Result<Option<&'static str>, SceneError> {
        let Some(fdef) = header.elements.get("face") else {
            return Ok(None);
        };
        ["vertex_indices", "vertex_index"]
            .into_iter()
            .find(|k| fdef.properties.contains_key(*k))
            .map(Some)
            .ok_or_else(|| {
                self.err(
                    "header",
                    "the face element has no \"vertex_indices\" (or \"vertex_index\") list"
                        .to_owned(),
                )
            })
    }

    /// The vertex positions in file order: every coordinate present and finite.
    fn positions(&self, vertices: Vec<PlyVertex>) -> Result<Vec<Vec3>, SceneError> {
        let mut positions = Vec::with_capacity(vertices.len());
        for (i, v) in vertices.into_iter().enumerate() {
            for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
                let x = v.p[k];
                if v.given & (1 << k) == 0 {
                    return Err(self.err(
                        &format!("element vertex {i}"),
                        format!("coordinate {axis} is missing"),
                    ));
                }
                if !x.is_finite() {
                    return Err(self.err(
                        &format!("element vertex {i}"),
                        format!("coordinate {axis} is {x}, but positions must be finite"),
                    ));
                }
            }
            positions.push(Vec3::from_array(v.p));
        }
        Ok(positions)
    }

    /// The faces as triangle fans over `n` vertices.
    fn triangles(
        &self,
        faces: Vec<PlyFace>,
        key: &str,
        n: usize,
    ) -> Result<Vec<[u32; 3]>, SceneError> {
        let mut triangles = Vec::with_capacity(faces.len());
        for (f, face) in faces.into_iter().enumerate() {
            let loc = || format!("element face {f}");
            let corners: &[u32] = match &face.corners {
                Corners::Missing => {
                    return Err(self.err(&loc(), format!("property \"{key}\" is missing")))
                }
                Corners::Invalid(m) => return Err(self.err(&loc(), m.clone())),
                Corners::Three(c) => c,
                Corners::Other(c) => c,
            };
            self.check_face(f, corners, n)?;
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
