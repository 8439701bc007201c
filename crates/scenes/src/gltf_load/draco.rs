//! `KHR_draco_mesh_compression`: a primitive's positions and triangles decoded from its Draco
//! stream with `draco-oxide` (a pure-Rust port of Google's Draco decoder, bitstream 2.2; the
//! workspace carries it with allocation bounds, `third_party/README.md`). Its header counts are
//! checked first, and its panics are caught.

use super::buffers::memory_shortfall;
use super::nodes::Loader;
use crate::SceneError;
use draco_oxide_core::attribute::ComponentDataType;
use draco_oxide_core::bit_coder::Reader;
use draco_oxide_core::codec::header::EncoderMethod;
use draco_oxide_core::types::{NdVector, PointIdx, Vector};
use glam::Vec3;
use std::cell::Cell;

thread_local! {
    static GUARDED: Cell<bool> = const { Cell::new(false) };
}

/// Whether this thread is running a third-party decoder whose panics the loader catches and
/// reports as [`SceneError::Gltf`] (the Draco decoder, on a corrupted stream). A panic hook can
/// stay silent while this is true: the panic becomes an error that the caller sees. The
/// `shadowvol` CLI's hook does so.
#[must_use]
pub fn in_guarded_decoder() -> bool {
    GUARDED.with(Cell::get)
}

/// What a Draco mesh stream's header declares, read before decoding: the decoder sizes its
/// tables from these counts without checking them against the stream or the memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Declared {
    faces: u64,
    /// Sequential: the point count; edgebreaker: the encoded vertices (at most the points,
    /// which attribute seams can split further).
    vertices: u64,
    /// Sequential: `vertices` is the point count itself.
    exact_points: bool,
    /// Edgebreaker: symbols and split symbols, each at most one per face.
    symbols: u64,
    split_symbols: u64,
}

/// Bytes the decoder needs per declared face and per point, with room to spare: corner tables,
/// the vertex maps and the attribute buffers.
const BYTES_PER_FACE: u64 = 96;
const BYTES_PER_POINT: u64 = 64;

/// Reads the header, the metadata (skipped) and the connectivity counts of a Draco mesh stream.
/// `Err` is a message for a stream whose header does not parse (the decoder would refuse it too).
fn declared_counts(bytes: &[u8]) -> Result<Declared, String> {
    let mut r = Reader::new(bytes);
    let header = draco_oxide_decoder::header::decode_header(&mut r).map_err(|e| e.to_string())?;
    if header.metadata {
        skip_metadata(&mut r)?;
    }
    Ok(match header.encoder_method {
        EncoderMethod::Sequential => {
            let faces = varint(&mut r)?;
            let points = varint(&mut r)?;
            Declared {
                faces,
                vertices: points,
                exact_points: true,
                symbols: 0,
                split_symbols: 0,
            }
        }
        EncoderMethod::Edgebreaker => {
            let _traversal = byte(&mut r)?;
            let vertices = varint(&mut r)?;
            let faces = varint(&mut r)?;
            let _attribute_data = byte(&mut r)?;
            let symbols = varint(&mut r)?;
            let split_symbols = varint(&mut r)?;
            Declared {
                faces,
                vertices,
                exact_points: false,
                symbols,
                split_symbols,
            }
        }
    })
}

/// One byte of the stream.
fn byte(r: &mut Reader<'_>) -> Result<u8, String> {
    r.read_u8().map_err(|e| e.to_string())
}

/// A LEB128 varint: at most 10 bytes of 7 bits, since a longer one overflows `u64`.
fn varint(r: &mut Reader<'_>) -> Result<u64, String> {
    let mut value = 0u64;
    for i in 0..10 {
        let b = byte(r)?;
        value |= u64::from(b & 0x7F) << (7 * i);
        if b & 0x80 == 0 {
            return Ok(value);
        }
    }
    Err("a varint longer than 10 bytes".to_owned())
}

/// Skips `n` bytes.
fn skip(r: &mut Reader<'_>, n: u64) -> Result<(), String> {
    let n = usize::try_from(n).map_err(|_| "metadata runs past the stream".to_owned())?;
    r.read_bytes(n).map(|_| ()).map_err(|e| e.to_string())
}

/// Skips the metadata section: per-attribute blocks, then the geometry block.
fn skip_metadata(r: &mut Reader<'_>) -> Result<(), String> {
    for _ in 0..varint(r)? {
        varint(r)?;
        skip_metadata_block(r, 0)?;
    }
    skip_metadata_block(r, 0)
}

/// Skips one metadata block: a list of name/value entries, then nested named blocks (at most
/// 1000 deep, as Google's decoder allows). A name is a u8 length and its bytes.
fn skip_metadata_block(r: &mut Reader<'_>, level: usize) -> Result<(), String> {
    if level > 1000 {
        return Err("metadata nested more than 1000 deep".to_owned());
    }
    for _ in 0..varint(r)? {
        let name = byte(r)?;
        skip(r, u64::from(name))?;
        let size = varint(r)?;
        skip(r, size)?;
    }
    for _ in 0..varint(r)? {
        let name = byte(r)?;
        skip(r, u64::from(name))?;
        skip_metadata_block(r, level + 1)?;
    }
    Ok(())
}

/// A decoded Draco mesh: the positions of the POSITION attribute, one per point, and the faces
/// as point indices (not yet checked against the point count).
struct Decoded {
    positions: Vec<Vec3>,
    faces: Vec<[usize; 3]>,
}

/// Why [`decode`] gave no mesh.
enum Failure {
    /// The decoder's own error.
    Decoder(String),
    /// No attribute has the id that `attributes.POSITION` names; the ids present.
    NoPosition(String),
    /// The attribute is not 3 components of F32: its component count and type.
    NotVec3F32(usize, String),
}

/// Decodes `bytes` and reads the attribute `position_id` and the faces. Called under
/// `catch_unwind`: the decoder, and the mesh it returns, may panic on a corrupted stream.
fn decode(bytes: &[u8], position_id: usize) -> Result<Decoded, Failure> {
    let mesh = draco_oxide_decoder::Decoder::new()
        .decode_mesh(bytes)
        .map_err(|e| Failure::Decoder(e.to_string()))?;
    let attr = mesh
        .attributes
        .iter()
        .find(|a| a.get_id().as_usize() == position_id)
        .ok_or_else(|| {
            Failure::NoPosition(
                mesh.attributes
                    .iter()
                    .map(|a| a.get_id().as_usize().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
            )
        })?;
    if attr.get_component_type() != ComponentDataType::F32 || attr.get_num_components() != 3 {
        return Err(Failure::NotVec3F32(
            attr.get_num_components(),
            format!("{:?}", attr.get_component_type()),
        ));
    }
    let n = attr.len();
    let mut positions = Vec::new();
    positions
        .try_reserve_exact(n)
        .map_err(|_| Failure::Decoder(format!("{n} decoded points: cannot allocate them")))?;
    for i in 0..n {
        let v: NdVector<3, f32> = attr.get(PointIdx::from(i));
        positions.push(Vec3::new(*v.get(0), *v.get(1), *v.get(2)));
    }
    let faces = mesh
        .get_faces()
        .iter()
        .map(|f| f.map(usize::from))
        .collect();
    Ok(Decoded { positions, faces })
}

impl Loader<'_> {
    /// Positions (one per decoded point) and the decoded faces flattened into an index list, of
    /// the primitive whose `KHR_draco_mesh_compression` object is `ext`. `label` names the
    /// primitive. Its `POSITION` accessor `pos_acc` (and `indices`, if any) must declare the
    /// decoded counts, as the extension requires.
    pub(super) fn read_draco(
        &self,
        label: &str,
        prim: &gltf::Primitive,
        pos_acc: &gltf::Accessor,
        ext: &serde_json::Value,
    ) -> Result<(Vec<Vec3>, Vec<u32>), SceneError> {
        let dlabel = format!("{label}, KHR_draco_mesh_compression");
        let err = |m: String| self.err(dlabel.clone(), m);
        let index = |v: Option<&serde_json::Value>, what: &str| {
            v.and_then(serde_json::Value::as_u64)
                .and_then(|x| usize::try_from(x).ok())
                .ok_or_else(|| {
                    err(match v {
                        None => format!("\"{what}\" is missing"),
                        Some(v) => format!("\"{what}\" must be a non-negative integer, found {v}"),
                    })
                })
        };
        let view_index = index(ext.get("bufferView"), "bufferView")?;
        let position_id = index(ext.pointer("/attributes/POSITION"), "attributes.POSITION")?;
        let view = self.document.views().nth(view_index).ok_or_else(|| {
            err(format!(
                "bufferView {view_index} does not exist (the file has {} buffer views)",
                self.document.views().len()
            ))
        })?;
        let bytes = self.view_bytes(&dlabel, &view)?;
        self.check_declared(&dlabel, prim, pos_acc.count() as u64, bytes, view_index)?;
        let cannot = |why: String| {
            err(format!(
                "the Draco stream in buffer view {view_index} ({} bytes) cannot be decoded: {why}",
                bytes.len()
            ))
        };
        // draco-oxide returns errors for the malformed streams it checks, but it can still panic
        // (an index out of bounds) on a corrupted one: the decoding and every read of its
        // result run under catch_unwind, and a panic is reported as an error.
        GUARDED.with(|g| g.set(true));
        let decoded = std::panic::catch_unwind(|| decode(bytes, position_id));
        GUARDED.with(|g| g.set(false));
        let Decoded { positions, faces } = match decoded {
            Ok(Ok(d)) => d,
            Ok(Err(Failure::Decoder(e))) => return Err(cannot(e)),
            Ok(Err(Failure::NoPosition(ids))) => {
                return Err(err(format!(
                    "attributes.POSITION names Draco attribute {position_id}, but the stream \
                     holds attributes [{ids}]"
                )))
            }
            Ok(Err(Failure::NotVec3F32(n, ty))) => {
                return Err(err(format!(
                    "Draco attribute {position_id} (POSITION) decodes to {n} components of \
                     {ty}; positions need 3 of F32"
                )))
            }
            Err(payload) => {
                let what = payload
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_owned())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic".to_owned());
                return Err(cannot(format!(
                    "the decoder failed on it ({what}); the stream is corrupted"
                )));
            }
        };
        let points = positions.len();
        if pos_acc.count() != points {
            return Err(err(format!(
                "the stream decodes {points} points, but the POSITION accessor {} declares count \
                 {}",
                pos_acc.index(),
                pos_acc.count()
            )));
        }
        for (i, p) in positions.iter().enumerate() {
            if let Some((axis, value)) = ['x', 'y', 'z']
                .into_iter()
                .zip(p.to_array())
                .find(|(_, c)| !c.is_finite())
            {
                return Err(err(format!(
                    "decoded point {i}: coordinate {axis} is {value}, but positions must be \
                     finite"
                )));
            }
        }
        if let Some(acc) = prim.indices() {
            if Some(acc.count()) != faces.len().checked_mul(3) {
                return Err(err(format!(
                    "the stream decodes {} triangles, but the indices accessor {} declares count \
                     {} (3 per triangle)",
                    faces.len(),
                    acc.index(),
                    acc.count()
                )));
            }
        }
        let mut indices = Vec::new();
        indices
            .try_reserve_exact(faces.len().saturating_mul(3))
            .map_err(|_| {
                err(format!(
                    "{} decoded triangles: cannot allocate them",
                    faces.len()
                ))
            })?;
        for (f, face) in faces.iter().enumerate() {
            for &c in face {
                if c >= points {
                    return Err(err(format!(
                        "decoded triangle {f} refers to point {c}, but the stream has {points}"
                    )));
                }
                indices.push(c as u32);
            }
        }
        Ok((positions, indices))
    }

    /// Refuses a stream whose header declares counts that disagree with the primitive's
    /// accessors (`points`: its POSITION count), or that no memory holds, before the decoder
    /// allocates for them.
    fn check_declared(
        &self,
        dlabel: &str,
        prim: &gltf::Primitive,
        points: u64,
        bytes: &[u8],
        view_index: usize,
    ) -> Result<(), SceneError> {
        let err = |m: String| self.err(dlabel.to_owned(), m);
        let d = declared_counts(bytes).map_err(|e| {
            err(format!(
                "the Draco stream in buffer view {view_index} ({} bytes) cannot be decoded: {e}",
                bytes.len()
            ))
        })?;
        let disagree = |what: String| {
            err(format!(
                "the Draco stream in buffer view {view_index} declares {what}: the stream is \
                 corrupted or the accessors are wrong"
            ))
        };
        if let Some(idx) = prim.indices() {
            if Some(idx.count() as u64) != d.faces.checked_mul(3) {
                return Err(disagree(format!(
                    "{} triangles, but the indices accessor {} declares count {} (3 per triangle)",
                    d.faces,
                    idx.index(),
                    idx.count()
                )));
            }
        }
        if (d.exact_points && d.vertices != points) || d.vertices > points {
            return Err(disagree(format!(
                "{} {}, but the POSITION accessor declares count {points}",
                d.vertices,
                if d.exact_points {
                    "points"
                } else {
                    "encoded vertices (at most one per point)"
                }
            )));
        }
        if d.symbols > d.faces || d.split_symbols > d.faces {
            return Err(disagree(format!(
                "{} symbols and {} split symbols for {} triangles (at most one each per triangle)",
                d.symbols, d.split_symbols, d.faces
            )));
        }
        let need = d
            .faces
            .saturating_mul(BYTES_PER_FACE)
            .saturating_add(points.saturating_mul(BYTES_PER_POINT));
        if let Some((available, source)) = memory_shortfall(need) {
            return Err(err(format!(
                "decoding {} triangles and {points} points needs about {need} bytes, more than \
                 the {available} bytes available ({source})",
                d.faces
            )));
        }
        Ok(())
    }
}
