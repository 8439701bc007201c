//! Wavefront OBJ loading: positions and faces only.
//!
//! This is a small line parser of our own rather than `tobj`: every error must name the file and
//! the line it comes from (a malformed number, a face with fewer than three corners, an index out
//! of range or beyond `u32`, a relative index that runs off the start, a NaN or infinite
//! coordinate), and `tobj` reports errors without line numbers and accepts some of these inputs
//! silently. Only what silhouette extraction needs is read:
//!
//! * `v x y z [w | r g b]`: a vertex; the first three numbers are the position, any further
//!   numbers (a rational weight or a vertex colour) must be numbers but are ignored;
//! * `f i j k ...`: a face; each corner is `v`, `v/vt`, `v//vn` or `v/vt/vn`, only `v` is used.
//!   Indices are 1-based; negative indices count back from the last vertex defined so far
//!   (`-1` is the latest). Polygons with more than three corners are triangulated as a fan
//!   `(c0, c1, c2), (c0, c2, c3), ...`. Positive indices may refer to vertices defined later in
//!   the file.
//! * Everything else (`vt`, `vn`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`, comments, unknown
//!   statements) is skipped. A line ending in `\` continues on the next line.
//!   [`parse_obj_with_notes`] also returns a note for the geometry that is skipped (lines `l`,
//!   points `p`, free-form `curv`, `curv2` and `surf`), since none of it can cast a shadow.
//!
//! Vertex numbers in messages are 0-based, as in the rest of shadowvol (the CLI's JSON names
//! vertices by 0-based input index); the OBJ (1-based) number is given next to it.
//!
//! ```
//! use shadowvol_scenes::obj::parse_obj;
//!
//! let mesh = parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "quad.obj").unwrap();
//! assert_eq!(mesh.positions.len(), 4);
//! assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
//!
//! let err = parse_obj("v 0 0 0\nv 1 0 0\nf 1 2\n", "bad.obj").unwrap_err();
//! assert_eq!(err.to_string(), "bad.obj:3: face has 2 corner(s), but at least 3 are needed");
//! ```

use glam::Vec3;
use shadowvol_mesh_topology::{Mesh, MeshError};
use std::path::{Path, PathBuf};

/// Errors from loading a mesh file.
///
/// Every variant names where the problem is: the file, and the line where there is one.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The path given.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The text is malformed at a line.
    #[error("{source_name}:{line}: {message}")]
    Parse {
        /// The file name (or another name for the text) used in messages.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong, naming the statement, the token and (for vertices) the vertex index.
        message: String,
    },
    /// The mesh, though well-formed text, is not a valid [`Mesh`] (for example too large for
    /// `u32` indexing).
    #[error("{source_name}: {error}")]
    Mesh {
        /// The file name used in messages.
        source_name: String,
        /// The mesh error.
        error: MeshError,
    },
}

/// Reads and parses an OBJ file. See the [module documentation](self) for what is read.
///
/// # Errors
/// [`LoadError::Io`] if the file cannot be read, [`LoadError::Parse`] naming `file:line` for
/// malformed content, [`LoadError::Mesh`] if the mesh is too large for `u32` indices.
pub fn load_obj(path: impl AsRef<Path>) -> Result<Mesh, LoadError> {
    load_obj_with_notes(path).map(|(mesh, _)| mesh)
}

/// As [`load_obj`], and also returns the notes of [`parse_obj_with_notes`].
///
/// # Errors
/// As [`load_obj`].
pub fn load_obj_with_notes(path: impl AsRef<Path>) -> Result<(Mesh, Vec<String>), LoadError> {
    use std::io::BufRead;
    let path = path.as_ref();
    let io = |source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    };
    // Read a line at a time: the file's text is never held whole beside the mesh it becomes.
    let mut reader =
        std::io::BufReader::with_capacity(1 << 16, std::fs::File::open(path).map_err(io)?);
    let name = path.display().to_string();
    let mut parser = Parser::new(&name);
    let mut line = Vec::new();
    for line_no in 1.. {
        line.clear();
        if reader.read_until(b'\n', &mut line).map_err(io)? == 0 {
            break;
        }
        // As `str::lines`: the `\n`, and a `\r` before it, end the line.
        let end = line.strip_suffix(b"\n").unwrap_or(&line);
        let end = end.strip_suffix(b"\r").unwrap_or(end);
        // Invalid UTF-8 becomes U+FFFD; if it sits in a `v` or `f` statement, the number that
        // holds it is reported as malformed at its line, elsewhere (comments, names) it does no
        // harm. (A `\n` byte is never part of a multi-byte character.)
        parser.line(&String::from_utf8_lossy(end), line_no)?;
    }
    parser.finish()
}

/// Parses OBJ text. `source_name` is used in error messages (usually the file name).
///
/// # Errors
/// [`LoadError::Parse`] naming `source_name:line` for malformed content, [`LoadError::Mesh`] if
/// the mesh is too large for `u32` indices.
pub fn parse_obj(text: &str, source_name: &str) -> Result<Mesh, LoadError> {
    Parser::new(source_name).run(text).map(|(mesh, _)| mesh)
}

/// As [`parse_obj`], and also returns one note per kind of geometry statement that was skipped
/// (`l`, `p`, `curv`, `curv2`, `surf`), with its count and first line, for example
/// `"wire.obj: 2 line (l) statements skipped, the first at line 5: only faces (f) cast shadows"`.
///
/// ```
/// use shadowvol_scenes::obj::parse_obj_with_notes;
///
/// let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nl 1 2\nl 2 3\n";
/// let (mesh, notes) = parse_obj_with_notes(text, "wire.obj").unwrap();
/// assert_eq!(mesh.triangles.len(), 1);
/// assert_eq!(
///     notes,
///     ["wire.obj: 2 line (l) statements skipped, the first at line 5: only faces (f) cast shadows"]
/// );
/// ```
///
/// # Errors
/// As [`parse_obj`].
pub fn parse_obj_with_notes(
    text: &str,
    source_name: &str,
) -> Result<(Mesh, Vec<String>), LoadError> {
    Parser::new(source_name).run(text)
}

/// The geometry statements that are read but cannot cast a shadow: (keyword, what it is).
const SKIPPED_GEOMETRY: [(&str, &str); 5] = [
    ("l", "line"),
    ("p", "point"),
    ("curv", "curve"),
    ("curv2", "2D curve"),
    ("surf", "surface"),
];

/// A positive face index that referred past the vertices defined so far; checked at the end.
struct ForwardRef {
    line: usize,
    index: u64,
}

struct Parser<'a> {
    source_name: &'a str,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    forward: Vec<ForwardRef>,
    corners: Vec<u32>,
    /// Per entry of [`SKIPPED_GEOMETRY`]: how many statements, and the first one's line.
    skipped: [(usize, usize); SKIPPED_GEOMETRY.len()],
    /// A statement continued with a trailing backslash, so far, and its first line.
    pending: String,
    pending_line: usize,
}

impl<'a> Parser<'a> {
    fn new(source_name: &'a str) -> Self {
        Self {
            source_name,
            positions: Vec::new(),
            triangles: Vec::new(),
            forward: Vec::new(),
            corners: Vec::new(),
            skipped: [(0, 0); SKIPPED_GEOMETRY.len()],
            pending: String::new(),
            pending_line: 0,
        }
    }

    fn err(&self, line: usize, message: String) -> LoadError {
        LoadError::Parse {
            source_name: self.source_name.to_owned(),
            line,
            message,
        }
    }

    fn run(mut self, text: &str) -> Result<(Mesh, Vec<String>), LoadError> {
        for (i, raw) in text.lines().enumerate() {
            self.line(raw, i + 1)?;
        }
        self.finish()
    }

    /// Line `line_no` of the file (without its line break): a statement, or part of one
    /// continued with a trailing backslash.
    fn line(&mut self, raw: &str, line_no: usize) -> Result<(), LoadError> {
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        if let Some(head) = raw.strip_suffix('\\') {
            if self.pending.is_empty() {
                self.pending_line = line_no;
            }
            self.pending.push_str(head);
            self.pending.push(' ');
            return Ok(());
        }
        if self.pending.is_empty() {
            self.statement(raw, line_no)
        } else {
            self.pending.push_str(raw);
            let joined = std::mem::take(&mut self.pending);
            self.statement(&joined, self.pending_line)
        }
    }

    /// After the last line: the statement still continued, the forward references, the mesh.
    fn finish(mut self) -> Result<(Mesh, Vec<String>), LoadError> {
        if !self.pending.is_empty() {
            let joined = std::mem::take(&mut self.pending);
            self.statement(&joined, self.pending_line)?;
        }
        let n = self.positions.len() as u64;
        if let Some(f) = self.forward.iter().find(|f| f.index > n) {
            return Err(self.err(
                f.line,
                format!(
                    "face index {} is out of range: the file defines only {n} vertices",
                    f.index
                ),
            ));
        }
        let notes = SKIPPED_GEOMETRY
            .iter()
            .zip(self.skipped)
            .filter(|(_, (count, _))| *count > 0)
            .map(|((keyword, what), (count, first))| {
                let plural = if count == 1 { "" } else { "s" };
                format!(
                    "{}: {count} {what} ({keyword}) statement{plural} skipped, the first at line \
                     {first}: only faces (f) cast shadows",
                    self.source_name
                )
            })
            .collect();
        let mesh = Mesh::new(self.positions, self.triangles).map_err(|error| LoadError::Mesh {
            source_name: self.source_name.to_owned(),
            error,
        })?;
        Ok((mesh, notes))
    }

    fn statement(&mut self, line: &str, line_no: usize) -> Result<(), LoadError> {
        let content = line.split('#').next().unwrap_or("");
        let mut tokens = content.split_ascii_whitespace();
        match tokens.next() {
            Some("v") => self.vertex(tokens, line_no),
            Some("f") | Some("fo") => self.face(tokens, line_no),
            Some(keyword) => {
                if let Some(k) = SKIPPED_GEOMETRY.iter().position(|(kw, _)| *kw == keyword) {
                    let (count, first) = &mut self.skipped[k];
                    if *count == 0 {
                        *first = line_no;
                    }
                    *count += 1;
                }
                Ok(())
            }
            None => Ok(()),
        }
    }

    fn vertex<'t>(
        &mut self,
        tokens: impl Iterator<Item = &'t str>,
        line_no: usize,
    ) -> Result<(), LoadError> {
        let index = self.positions.len();
        if index as u64 >= u64::from(u32::MAX) {
            return Err(self.err(
                line_no,
                format!("too many vertices: vertex {index} cannot be indexed with u32"),
            ));
        }
        let mut xyz = [0f32; 3];
        let mut count = 0;
        for tok in tokens {
            let value: f32 = tok.parse().map_err(|_| {
                self.err(
                    line_no,
                    format!(
                        "vertex {index} (OBJ #{}): malformed number {tok:?}",
                        index + 1
                    ),
                )
            })?;
            if count < 3 {
                xyz[count] = value;
            }
            count += 1;
        }
        if count < 3 {
            return Err(self.err(
                line_no,
                format!(
                    "vertex {index} (OBJ #{}): expected 3 coordinates x y z, found {count}",
                    index + 1
                ),
            ));
        }
        for (axis, value) in ['x', 'y', 'z'].into_iter().zip(xyz) {
            if !value.is_finite() {
                return Err(self.err(
                    line_no,
                    format!(
                        "vertex {index} (OBJ #{}): coordinate {axis} is {value}, but positions must be finite",
                        index + 1
                    ),
                ));
            }
        }
        self.positions.push(Vec3::from_array(xyz));
        Ok(())
    }

    fn face<'t>(
        &mut self,
        tokens: impl Iterator<Item = &'t str>,
        line_no: usize,
    ) -> Result<(), LoadError> {
        let mut corners = std::mem::take(&mut self.corners);
        corners.clear();
        for tok in tokens {
            let v = tok.split('/').next().unwrap_or("");
            corners.push(self.index(v, tok, line_no)?);
        }
        if corners.len() < 3 {
            return Err(self.err(
                line_no,
                format!(
                    "face has {} corner(s), but at least 3 are needed",
                    corners.len()
                ),
            ));
        }
        let limit = u64::from(u32::MAX) / 3;
        let new_triangles = (corners.len() - 2) as u64;
        if self.triangles.len() as u64 + new_triangles >= limit {
            return Err(self.err(
                line_no,
                format!("too many triangles: more than {limit} cannot be indexed with u32"),
            ));
        }
        for k in 1..corners.len() - 1 {
            self.triangles
                .push([corners[0], corners[k], corners[k + 1]]);
        }
        self.corners = corners;
        Ok(())
    }

    /// Resolves one corner's vertex index to a 0-based `u32`.
    fn index(&mut self, v: &str, tok: &str, line_no: usize) -> Result<u32, LoadError> {
        let defined = self.positions.len() as u64;
        let digits = v.strip_prefix(['-', '+']).unwrap_or(v);
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return Err(self.err(
                line_no,
                format!("malformed face index {tok:?}: expected an integer vertex index"),
            ));
        }
        let negative = v.starts_with('-');
        // Digits only, so the only possible parse failure is overflow.
        let magnitude = digits.parse::<u64>().ok();
        let Some(magnitude) = magnitude.filter(|&m| m <= u64::from(u32::MAX)) else {
            return Err(self.err(
                line_no,
                format!(
                    "face index {v} is beyond the u32 range (at most {} vertices can be indexed)",
                    u32::MAX
                ),
            ));
        };
        if magnitude == 0 {
            return Err(self.err(
                line_no,
                "face index 0 is invalid: OBJ indices start at 1 (negative indices count back from the last vertex)"
                    .to_owned(),
            ));
        }
        if negative {
            if magnitude > defined {
                return Err(self.err(
                    line_no,
                    format!(
                        "relative face index {v} runs off the start: only {defined} vertices are defined before this line"
                    ),
                ));
            }
            Ok((defined - magnitude) as u32)
        } else {
            if magnitude >= u64::from(u32::MAX) {
                return Err(self.err(
                    line_no,
                    format!(
                        "face index {v} is beyond the u32 range (at most {} vertices can be indexed)",
                        u32::MAX - 1
                    ),
                ));
            }
            if magnitude > defined {
                self.forward.push(ForwardRef {
                    line: line_no,
                    index: magnitude,
                });
            }
            Ok((magnitude - 1) as u32)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Mesh, LoadError> {
        parse_obj(text, "t.obj")
    }

    fn message(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

    #[test]
    fn reads_vertices_faces_and_corner_forms() {
        let m = parse(&format!(
            "# comment\no obj\n{TRI}vt 0 0\nvn 0 0 1\nf 1/1 2//1 3/1/1 # trailing\n"
        ))
        .unwrap();
        assert_eq!(m.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn skipped_geometry_is_noted_with_count_and_first_line() {
        let text = format!(
            "{TRI}vt 0 0\nusemtl m\np 1\nf 1 2 3\nl 1 2\nl 2 3 \\\n 1\ncurv 0 1 1 2\nl 3 1\n"
        );
        let (mesh, notes) = parse_obj_with_notes(&text, "t.obj").unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(
            notes,
            [
                "t.obj: 3 line (l) statements skipped, the first at line 8: only faces (f) cast \
                 shadows",
                "t.obj: 1 point (p) statement skipped, the first at line 6: only faces (f) cast \
                 shadows",
                "t.obj: 1 curve (curv) statement skipped, the first at line 11: only faces (f) \
                 cast shadows",
            ]
        );
        // Texture coordinates, materials and unknown statements are not geometry: no note.
        let (_, notes) = parse_obj_with_notes(
            &format!("{TRI}vt 0 0\nvn 0 0 1\ns 1\nxyz 1\nf 1 2 3\n"),
            "t.obj",
        )
        .unwrap();
        assert!(notes.is_empty(), "{notes:?}");
    }

    #[test]
    fn fans_polygons_and_resolves_negative_indices() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf -5 -4 -3 -2 -1\n").unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn accepts_forward_references_crlf_and_continuations() {
        let m = parse("f 1 2 \\\r\n 3\r\nv 0 0 0\r\nv 1 0 0 1\r\nv 0 1 0 0.5 0.5 0.5\r\n").unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.positions.len(), 3);
    }

    #[test]
    fn malformed_number_names_line_and_vertex() {
        assert_eq!(
            message("v 0 0 0\nv 1 0x 0\n"),
            "t.obj:2: vertex 1 (OBJ #2): malformed number \"0x\""
        );
    }

    #[test]
    fn non_finite_coordinates_are_rejected() {
        assert_eq!(
            message("v 0 0 0\nv 0 nan 0\n"),
            "t.obj:2: vertex 1 (OBJ #2): coordinate y is NaN, but positions must be finite"
        );
        assert_eq!(
            message("v inf 0 0\n"),
            "t.obj:1: vertex 0 (OBJ #1): coordinate x is inf, but positions must be finite"
        );
        // Overflows f32 when parsed.
        assert!(message("v 0 0 1e39\n").contains("coordinate z is inf"));
    }

    #[test]
    fn short_vertices_and_faces_are_rejected() {
        assert!(message("v 1 2\n").contains("expected 3 coordinates x y z, found 2"));
        assert_eq!(
            message(&format!("{TRI}f 1 2\n")),
            "t.obj:4: face has 2 corner(s), but at least 3 are needed"
        );
    }

    #[test]
    fn bad_indices_are_rejected_with_line() {
        assert!(message(&format!("{TRI}f 1 2 4\n"))
            .starts_with("t.obj:4: face index 4 is out of range"));
        assert!(message(&format!("{TRI}f 1 2 0\n")).contains("t.obj:4: face index 0 is invalid"));
        assert!(message(&format!("{TRI}f 1 2 -4\n"))
            .contains("t.obj:4: relative face index -4 runs off the start: only 3 vertices"));
        assert!(message(&format!("{TRI}f 1 2 x\n")).contains("t.obj:4: malformed face index \"x\""));
        assert!(message(&format!("{TRI}f 1 2 3.5\n")).contains("malformed face index \"3.5\""));
        assert!(message(&format!("{TRI}f 1 2 //3\n")).contains("malformed face index"));
        assert!(message(&format!("{TRI}f 1 2 4294967296\n"))
            .contains("t.obj:4: face index 4294967296 is beyond the u32 range"));
        assert!(message(&format!("{TRI}f 1 2 99999999999999999999999\n"))
            .contains("beyond the u32 range"));
        assert!(message(&format!("{TRI}f 1 2 -99999999999999999999999\n"))
            .contains("beyond the u32 range"));
    }

    #[test]
    fn unreadable_file_names_the_path() {
        let err = load_obj("/definitely/not/here.obj").unwrap_err();
        assert!(matches!(err, LoadError::Io { .. }));
        assert!(err
            .to_string()
            .starts_with("cannot read /definitely/not/here.obj: "));
    }

    /// Triangles as coordinate triples, so that two loaders that number vertices differently
    /// can be compared.
    fn corner_positions(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[[f32; 3]; 3]> {
        triangles
            .iter()
            .map(|t| t.map(|i| positions[i as usize]))
            .collect()
    }

    /// The file loader reads a line at a time; it must see what the text parser sees: CRLF and
    /// LF endings, a statement continued over lines, invalid UTF-8 in a comment, no line break
    /// at the end, and an error on the right line.
    #[test]
    fn the_streaming_loader_reads_a_file_as_the_text_parser_reads_it() {
        let dir = std::env::temp_dir().join(format!("shadowvol-obj-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = |name: &str, bytes: &[u8]| {
            let path = dir.join(name);
            std::fs::write(&path, bytes).unwrap();
            path
        };
        let good: &[u8] = b"# \xff\xfe not UTF-8\r\nv 0 0 0\r\nv 1 0 \\\n 0\nv 0 1 0\n\
            v 0 0 1\r\r\nf 1 2 3\nf 1 3 4\nl 1 2\nf 1 4 2";
        let path = file("good.obj", good);
        let text = String::from_utf8_lossy(good);
        let name = path.display().to_string();
        let (want, want_notes) = parse_obj_with_notes(&text, &name).unwrap();
        let (got, notes) = load_obj_with_notes(&path).unwrap();
        assert_eq!(got.positions, want.positions);
        assert_eq!(got.triangles, want.triangles);
        assert_eq!(got.triangles.len(), 3);
        assert_eq!(notes, want_notes);
        // An error on line 4 after a continued line 2: the same message either way.
        let bad: &[u8] = b"v 0 0 0\r\nv 1 0 \\\n0\nv 0 1 1.5.2\n";
        let path = file("bad.obj", bad);
        let name = path.display().to_string();
        let want = parse_obj(&String::from_utf8_lossy(bad), &name)
            .unwrap_err()
            .to_string();
        let got = load_obj(&path).unwrap_err().to_string();
        assert_eq!(got, want);
        assert!(got.contains(":4:"), "{got}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Differential check on valid input against an independent parser (`tobj`, with fan
    /// triangulation): same triangles with the same corner coordinates, in the same order.
    #[test]
    fn agrees_with_tobj_on_valid_files() {
        let texts = [
            TRI.to_owned() + "f 1 2 3\n",
            "# quad, pentagon, slashes, negative indices\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
             vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\nv 0.5 2 0.25\nf -5 -4 -3 -2 -1\n\
             f 1//1 3//1 5//1\n"
                .to_owned(),
            "v 1e4 1e-4 -0\nv 10000.001 0 0\nv 1e4 1 3.5e-38\nv -1 -2 -3\nf 1 2 3\nf 2 3 4\n"
                .to_owned(),
        ];
        for text in &texts {
            let ours = parse(text).unwrap();
            let ours_pos: Vec<[f32; 3]> = ours.positions.iter().map(|p| p.to_array()).collect();
            let (models, _) = tobj::load_obj_buf(
                &mut text.as_bytes(),
                &tobj::LoadOptions {
                    triangulate: true,
                    ..tobj::LoadOptions::default()
                },
                |_| Err(tobj::LoadError::OpenFileFailed),
            )
            .unwrap();
            let mut theirs = Vec::new();
            for m in &models {
                let pos: Vec<[f32; 3]> = m
                    .mesh
                    .positions
                    .chunks(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect();
                let tris: Vec<[u32; 3]> = m
                    .mesh
                    .indices
                    .chunks(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect();
                theirs.extend(corner_positions(&pos, &tris));
            }
            assert_eq!(
                corner_positions(&ours_pos, &ours.triangles),
                theirs,
                "{text}"
            );
        }
    }

    #[test]
    fn empty_text_is_an_empty_mesh() {
        let m = parse("").unwrap();
        assert!(m.positions.is_empty() && m.triangles.is_empty());
    }
}
