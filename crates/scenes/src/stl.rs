//! STL loading, ASCII and binary.
//!
//! An STL file is a triangle soup: every facet lists its three corners by position. The mesh
//! keeps that soup as it is: facet `t` becomes triangle `[3t, 3t + 1, 3t + 2]` over its own
//! three vertices, in file order. Welding (exact `f32` position, `-0 == +0`, as for every input)
//! then decides the topology when the edge table is built, so two facets share an edge exactly
//! when their corners have equal coordinates. Input vertex `k` is corner `k % 3` of facet
//! `k / 3`; the CLI's JSON names silhouette edges by these indices (each weld group by its
//! smallest one). Facet normals and the binary attribute bytes are ignored.
//!
//! Which kind a file is: a file of `84 + 50 n` bytes whose header declares `n` facets is binary,
//! even when its 80-byte header starts with `solid` (many exporters write that); otherwise a file
//! that starts with `solid` is ASCII; anything else is a binary file of the wrong length.
//!
//! ASCII grammar (keywords case-insensitive, any whitespace): `solid [name]`, then facets
//! `facet normal nx ny nz` / `outer loop` / three `vertex x y z` / `endloop` / `endfacet`, then
//! `endsolid [name]`; several solids may follow one another. Coordinates are read as `f32`
//! (round to nearest) and must be finite.
//!
//! This is a parser of our own rather than `stl_io`: errors must name the file and the line
//! (ASCII) or the facet and byte offset (binary), and `stl_io` reports neither, reads a binary
//! file whose header starts with `solid ` as ASCII (and fails), and accepts a binary file
//! longer than its facet count silently.
//!
//! ```
//! use shadowvol_scenes::stl::parse_stl;
//!
//! let text = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
//!             vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
//! let mesh = parse_stl(text.as_bytes(), "t.stl").unwrap();
//! assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
//!
//! let err = parse_stl(b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 x\n", "bad.stl");
//! assert_eq!(
//!     err.unwrap_err().to_string(),
//!     "bad.stl: line 4: vertex coordinate z: 'x' is not a number"
//! );
//! ```

use crate::SceneError;
use glam::Vec3;
use shadowvol_mesh_topology::{EdgeTable, Mesh, SoupWeld};
use std::io::{BufRead, Read, Seek, SeekFrom};
use std::path::Path;

/// Reads an STL file (ASCII or binary). See the [module documentation](self).
///
/// # Errors
/// [`SceneError::Io`] if the file cannot be read; [`SceneError::Stl`] naming the file and the
/// line (ASCII) or facet (binary) for malformed content.
pub fn load_stl(path: impl AsRef<Path>) -> Result<Mesh, SceneError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse_stl(&bytes, &path.display().to_string())
}

/// Parses STL bytes (ASCII or binary). `source_name` is used in messages.
///
/// # Errors
/// [`SceneError::Stl`] naming `source_name` and the line (ASCII) or facet and byte offset
/// (binary): a wrong file length, a malformed or missing keyword or number, a NaN or infinite
/// coordinate, too many facets for `u32` vertex indices.
pub fn parse_stl(bytes: &[u8], source_name: &str) -> Result<Mesh, SceneError> {
    let err = |location: String, message: String| SceneError::Stl {
        file: source_name.to_owned(),
        location,
        message,
    };
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]);
        if 84 + 50 * n as u64 == bytes.len() as u64 {
            return parse_binary(bytes, n as usize, &err);
        }
    }
    if starts_with_solid(bytes) {
        let mut positions = Vec::new();
        let io = |e: std::io::Error| err("text".to_owned(), e.to_string());
        parse_ascii(bytes, &err, &io, &mut |f| {
            positions.extend(f);
            Ok(())
        })?;
        return Ok(soup(positions));
    }
    if bytes.len() < 84 {
        return Err(err(
            "header".to_owned(),
            format!(
                "{} bytes: too short for a binary STL (84-byte header) and not ASCII STL (it \
                 does not start with \"solid\")",
                bytes.len()
            ),
        ));
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]);
    Err(err(
        "header".to_owned(),
        format!(
            "not ASCII STL (it does not start with \"solid\"), and as binary STL its header \
             declares {n} facets, 84 + 50 * {n} = {} bytes, but the file has {} bytes",
            84 + 50 * u64::from(n),
            bytes.len()
        ),
    ))
}

fn starts_with_solid(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    let rest = &bytes[start..];
    rest.len() >= 5
        && rest[..5].eq_ignore_ascii_case(b"solid")
        && rest.get(5).is_none_or(|b| b.is_ascii_whitespace())
}

fn check_size(facets: usize) -> Result<(), String> {
    if facets as u64 * 3 >= u64::from(u32::MAX) {
        return Err(format!(
            "{facets} facets: too many for u32 vertex indices (3 vertices per facet)"
        ));
    }
    Ok(())
}

fn parse_binary(
    bytes: &[u8],
    n: usize,
    err: &dyn Fn(String, String) -> SceneError,
) -> Result<Mesh, SceneError> {
    check_size(n).map_err(|m| err("header".to_owned(), m))?;
    let mut positions = Vec::with_capacity(3 * n);
    for (t, rec) in bytes[84..].chunks_exact(50).enumerate() {
        positions.extend(facet_corners(rec, t, err)?);
    }
    Ok(soup(positions))
}

/// The three corners of binary facet `t` (its 50-byte record `rec`).
fn facet_corners(
    rec: &[u8],
    t: usize,
    err: &dyn Fn(String, String) -> SceneError,
) -> Result<[Vec3; 3], SceneError> {
    let mut corners = [Vec3::ZERO; 3];
    for (c, corner) in corners.iter_mut().enumerate() {
        let mut p = [0.0f32; 3];
        for (axis, v) in p.iter_mut().enumerate() {
            let o = 12 + 12 * c + 4 * axis;
            *v = f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
            if !v.is_finite() {
                return Err(err(
                    format!("facet {t} (byte {})", 84 + 50 * t + o),
                    format!(
                        "vertex {c} coordinate {} is {v}, but positions must be finite",
                        ['x', 'y', 'z'][axis]
                    ),
                ));
            }
        }
        *corner = Vec3::from_array(p);
    }
    Ok(corners)
}

/// Reads an STL file straight into its edge table: the table [`EdgeTable::build`] makes of
/// [`load_stl`]'s soup (the same vertex names, the same triangles), at a lower peak. A binary
/// file is read a facet at a time and its corners welded as they come ([`SoupWeld`]), so
/// neither the file nor the soup (three positions a facet) is held; an ASCII file is read a line
/// at a time, its corners welded in the same way.
///
/// # Errors
/// As [`load_stl`]; [`SceneError::Mesh`] naming the file when its table cannot be built
/// (too large for `u32` ids or for the available memory, checked before the facets are read).
pub fn load_stl_table(path: impl AsRef<Path>) -> Result<EdgeTable, SceneError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let io = |source| SceneError::Io {
        path: name.clone(),
        source,
    };
    let mesh_err = |source| SceneError::Mesh {
        what: name.clone(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut reader = std::io::BufReader::with_capacity(1 << 20, file);
    let mut header = [0u8; 84];
    if len >= 84 {
        reader.read_exact(&mut header).map_err(io)?;
        let n = u32::from_le_bytes([header[80], header[81], header[82], header[83]]);
        if 84 + 50 * u64::from(n) == len {
            let err = |location: String, message: String| SceneError::Stl {
                file: name.clone(),
                location,
                message,
            };
            let n = n as usize;
            check_size(n).map_err(|m| err("header".to_owned(), m))?;
            EdgeTable::check_size(n as u64, 3 * n as u64).map_err(mesh_err)?;
            let mut weld = SoupWeld::new();
            let mut triangles = Vec::with_capacity(n);
            let mut rec = [0u8; 50];
            for t in 0..n {
                reader.read_exact(&mut rec).map_err(io)?;
                let corners = facet_corners(&rec, t, &err)?;
                triangles.push(corners.map(|p| weld.push(p)));
            }
            return EdgeTable::from_soup_weld(weld, triangles).map_err(mesh_err);
        }
    }
    reader.seek(SeekFrom::Start(0)).map_err(io)?;
    if !starts_with_solid(reader.fill_buf().map_err(io)?) {
        // Not STL: the whole-file reader's message says why.
        drop(reader);
        return EdgeTable::build_owned(load_stl(path)?).map_err(mesh_err);
    }
    let err = |location: String, message: String| SceneError::Stl {
        file: name.clone(),
        location,
        message,
    };
    let mut weld = SoupWeld::new();
    let mut triangles = Vec::new();
    parse_ascii(reader, &err, &io, &mut |f| {
        triangles.push(f.map(|p| weld.push(p)));
        // The facet count is not in the header: the memory is checked as the facets come, and
        // the file is read no further once it would not fit.
        let n = triangles.len() as u64;
        if n.is_power_of_two() && n >= 1 << 16 {
            EdgeTable::check_size(n, 3 * n).map_err(mesh_err)?;
        }
        Ok(())
    })?;
    EdgeTable::from_soup_weld(weld, triangles).map_err(mesh_err)
}

/// Triangle `t` over vertices `3t, 3t + 1, 3t + 2`.
fn soup(positions: Vec<Vec3>) -> Mesh {
    let triangles = (0..positions.len() as u32 / 3)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

/// Whitespace-separated tokens of a text read a line at a time, with their 1-based line
/// numbers (a line ends at `\n`).
struct Tokens<R> {
    reader: R,
    /// The current line, with its `\n`.
    buf: Vec<u8>,
    at: usize,
    /// The current line's number.
    line: usize,
}

impl<R: BufRead> Tokens<R> {
    fn new(reader: R) -> Self {
        Self {
            reader,
            buf: Vec::new(),
            at: 0,
            line: 1,
        }
    }

    /// The next token and its line, or `None` at the end of the text.
    fn next(&mut self) -> std::io::Result<Option<(&[u8], usize)>> {
        loop {
            while self.at < self.buf.len() && self.buf[self.at].is_ascii_whitespace() {
                self.at += 1;
            }
            if self.at < self.buf.len() {
                break;
            }
            if self.buf.last() == Some(&b'\n') {
                self.line += 1;
            }
            self.buf.clear();
            self.at = 0;
            if self.reader.read_until(b'\n', &mut self.buf)? == 0 {
                return Ok(None);
            }
        }
        let start = self.at;
        while self.at < self.buf.len() && !self.buf[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
        Ok(Some((&self.buf[start..self.at], self.line)))
    }

    /// Skips the rest of the current line (a solid's name).
    fn skip_line(&mut self) {
        self.at = self.buf.len();
    }
}

/// Parses an ASCII STL text, giving each facet's corners to `facet` in file order; an error from
/// `facet` ends the parse.
fn parse_ascii<R: BufRead>(
    reader: R,
    err: &dyn Fn(String, String) -> SceneError,
    io: &dyn Fn(std::io::Error) -> SceneError,
    facet: &mut dyn FnMut([Vec3; 3]) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let mut tok = Tokens::new(reader);
    let at = |line: usize| format!("line {line}");
    let show = |t: &[u8]| String::from_utf8_lossy(t).into_owned();
    let mut facets = 0usize;
    // One solid per turn; `solid` has been read when the loop body starts.
    let Some((first, _)) = tok.next().map_err(io)? else {
        return Err(err("line 1".to_owned(), "empty file".to_owned()));
    };
    debug_assert!(first.eq_ignore_ascii_case(b"solid"));
    tok.skip_line();
    'solids: loop {
        loop {
            let Some((word, line)) = tok.next().map_err(io)? else {
                return Err(err(
                    at(tok.line),
                    "end of file inside a solid: \"endsolid\" expected".to_owned(),
                ));
            };
            if word.eq_ignore_ascii_case(b"endsolid") {
                tok.skip_line();
                break;
            }
            if !word.eq_ignore_ascii_case(b"facet") {
                return Err(err(
                    at(line),
                    format!("expected \"facet\" or \"endsolid\", found '{}'", show(word)),
                ));
            }
            expect(&mut tok, b"normal", err, io)?;
            for _ in 0..3 {
                // Normals are ignored; exporters write "nan" for degenerate facets, so any token
                // is accepted.
                if tok.next().map_err(io)?.is_none() {
                    return Err(err(
                        at(tok.line),
                        "end of file in a facet normal: 3 numbers expected".to_owned(),
                    ));
                }
            }
            expect(&mut tok, b"outer", err, io)?;
            expect(&mut tok, b"loop", err, io)?;
            let mut corners = [Vec3::ZERO; 3];
            for corner in &mut corners {
                expect(&mut tok, b"vertex", err, io)?;
                let mut p = [0.0f32; 3];
                for (axis, v) in p.iter_mut().enumerate() {
                    let name = ['x', 'y', 'z'][axis];
                    let Some((t, line)) = tok.next().map_err(io)? else {
                        return Err(err(
                            at(tok.line),
                            format!("end of file: vertex coordinate {name} expected"),
                        ));
                    };
                    let parsed = std::str::from_utf8(t)
                        .ok()
                        .and_then(|s| s.parse::<f32>().ok());
                    *v = match parsed {
                        Some(x) if x.is_finite() => x,
                        Some(x) => {
                            return Err(err(
                                at(line),
                                format!(
                                    "vertex coordinate {name} is {x}, but positions must be \
                                     finite"
                                ),
                            ))
                        }
                        None => {
                            return Err(err(
                                at(line),
                                format!("vertex coordinate {name}: '{}' is not a number", show(t)),
                            ))
                        }
                    };
                }
                *corner = Vec3::from_array(p);
            }
            expect(&mut tok, b"endloop", err, io)?;
            expect(&mut tok, b"endfacet", err, io)?;
            facets += 1;
            check_size(facets).map_err(|m| err(at(tok.line), m))?;
            facet(corners)?;
        }
        match tok.next().map_err(io)? {
            None => break 'solids,
            Some((w, _)) if w.eq_ignore_ascii_case(b"solid") => tok.skip_line(),
            Some((w, line)) => {
                return Err(err(
                    at(line),
                    format!(
                        "expected \"solid\" or the end of the file after \"endsolid\", found '{}'",
                        show(w)
                    ),
                ))
            }
        }
    }
    Ok(())
}

fn expect<R: BufRead>(
    tok: &mut Tokens<R>,
    word: &[u8],
    err: &dyn Fn(String, String) -> SceneError,
    io: &dyn Fn(std::io::Error) -> SceneError,
) -> Result<(), SceneError> {
    let want = String::from_utf8_lossy(word);
    match tok.next().map_err(io)? {
        Some((w, _)) if w.eq_ignore_ascii_case(word) => Ok(()),
        Some((w, line)) => Err(err(
            format!("line {line}"),
            format!(
                "expected \"{want}\", found '{}'",
                String::from_utf8_lossy(w)
            ),
        )),
        None => Err(err(
            format!("line {}", tok.line),
            format!("end of file: \"{want}\" expected"),
        )),
    }
}
