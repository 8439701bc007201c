//! glTF 2.0 loading (`.gltf` with external or embedded buffers, and `.glb`).
//!
//! What is read:
//!
//! * **Nodes** of the scene named by `scene`, else of the first scene, else every root node,
//!   visited depth first in order: a node, then its children in order. Each node with a mesh becomes one
//!   object of [`Scene::geometry`](crate::Scene::geometry) whose transform is the node's world
//!   transform, composed in `f32`
//!   (`parent * local`, glTF's `matrix` or `T * R * S`). This order is the vertex numbering of
//!   the CLI contract: depth-first node order, then primitive order, then accessor order.
//! * **Meshes**: all primitives of a mesh are concatenated, in order, into one mesh, welded into
//!   one edge table. Nodes
//!   that use the same mesh share one `Arc<EdgeTable>`. The walk reads the meshes; the tables
//!   are built after it, once the file's buffers are dropped, each mesh freed as its table is
//!   built (notes and objects keep the walk's order). Modes `TRIANGLES`, `TRIANGLE_STRIP` and
//!   `TRIANGLE_FAN` are read (strips and fans are turned into triangle lists); points and lines,
//!   and primitives without `POSITION`, are skipped with a note (see
//!   [`load_gltf_slice_with_notes`]), and a node whose mesh is left without triangles is skipped
//!   too. Non-indexed primitives use their vertices in order. Only `POSITION` and the indices
//!   (`UNSIGNED_BYTE`, `_SHORT`, `_INT`) are read. Skins and morph targets are not applied: a
//!   skinned or morphed mesh is read at its base `POSITION`s, under its node's transform.
//! * **Accessors**, to the spec: an accessor without `bufferView` is zero-filled; a sparse
//!   accessor's values replace those of its base (a view, or zeros).
//! * **`KHR_mesh_quantization`** (when in `extensionsUsed`): `POSITION` may also be `BYTE`,
//!   `UNSIGNED_BYTE`, `SHORT` or `UNSIGNED_SHORT`. Integers are read as their value; normalized
//!   ones are decoded by the spec's formulas in `f32`, correctly rounded: `c / 255`, `c / 65535`,
//!   `max(c / 127, -1)`, `max(c / 32767, -1)`. The node transform (where exporters put the
//!   dequantization scale and offset) is then applied in `f32` as for float positions: exact
//!   results are exact for these `f32` world positions, not for the real numbers a quantizer
//!   had in mind.
//! * **`EXT_meshopt_compression`**: compressed buffer views read by positions and indices are
//!   decoded with meshoptimizer (the `meshopt` crate; see [`crate::meshopt_view`]); a fallback
//!   buffer (no data) is never read. Decoding is lossless: a compressed file gives exactly the
//!   vertex data of the same file uncompressed (the index codec may rotate a triangle's
//!   corners, keeping its winding).
//! * **`KHR_draco_mesh_compression`**: a primitive that carries the extension is read from its
//!   Draco stream (required or only used: the stream replaces any fallback data of its
//!   accessors), decoded with `draco-oxide` (a pure-Rust port of Google's decoder, bitstream
//!   2.2, sequential and edgebreaker; the workspace carries it with three allocation bounds,
//!   `third_party/README.md`). Its `POSITION` is the Draco attribute that
//!   `attributes.POSITION` names, dequantized to `f32` by the decoder, bit for bit as Google's
//!   decoder does (tested on glTF Transform's encodings); the decoded faces, flattened, are the
//!   primitive's indices, assembled by its mode. The accessors must declare the decoded counts.
//!   The vertex numbering is the decoder's point order: Google's own where the stream holds
//!   positions only; where other attributes (normals, texture coordinates) split points at
//!   seams, the same points and triangles in another order.
//!   Exact results are exact for these `f32` positions, as for quantized ones. Before
//!   decoding, the stream header's counts are checked against the accessors and the memory
//!   available (the decoder sizes its tables from them). A stream that does not decode is an
//!   error naming the primitive; the decoder can panic on a corrupted stream, which is caught
//!   and reported as that error (see [`in_guarded_decoder`]).
//! * **Cameras**: the first node with a perspective camera (depth-first order) becomes the scene
//!   camera: eye at the node's origin, looking down its `-Z`, up its `+Y`. A `"target"` in the
//!   node's extras (written by [`crate::export_glb`]) sets the target point exactly.
//! * **Lights** (`KHR_lights_punctual`): a point light at the node's origin (`w = 1`); a
//!   directional light towards the node's `+Z` axis (the light shines down `-Z`; `w = 0`, the
//!   direction is the `f32` third column of the world matrix, not renormalised). A **spot** light
//!   is treated as a point light at its position: shadow volumes of a spot light are those of a
//!   point light, the cone only limits what is lit. Each light's colour, intensity (candela,
//!   lux for directional lights), `range` and cone angles become its [`crate::Emission`]
//!   (the spot's axis is the node's `-Z`, normalised).
//!
//! Parsing goes through the `gltf` crate's types without its validation, plus checks of our own:
//! the crate's serde types refuse files the spec calls valid (an integer written as `1.0`, an
//! animation channel target without `node`), and its validation refuses every required extension
//! it does not implement (`KHR_mesh_quantization`, `EXT_meshopt_compression`,
//! `KHR_draco_mesh_compression`) and primitives
//! without `POSITION`. So the JSON is first normalised (integral numbers become integers,
//! `animations`, which are not read, are dropped), then the crate's structural validation runs
//! with those findings left out, and required extensions are checked against what is read here
//! (material and texture extensions do not change geometry and are accepted).
//!
//! The `gltf` crate does not check what accessors contain, so this module validates it: every
//! accessor must be in its buffer view and buffer, have a count above 0 and the right type;
//! positions must be finite, indices in range, and index counts must make whole triangles. Every
//! error names the file and the node, mesh, primitive and accessor.

mod buffers;
mod document;
mod draco;
mod mesh;
mod nodes;
mod objects;

use crate::scene::{file_name, Effects, Scene};
use crate::SceneError;
use buffers::decode_meshopt_views;
pub use draco::in_guarded_decoder;
use nodes::{root_nodes, Loader};

use objects::add_objects;
use std::collections::HashSet;
use std::path::Path;

/// Loads a `.gltf` or `.glb` file as a [`Scene`] with its objects kept separate.
///
/// # Errors
/// [`SceneError::Io`] if the file cannot be read, [`SceneError::Gltf`] naming the file and the
/// node/mesh/primitive/accessor for anything malformed (see the module documentation).
pub fn load_gltf(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
    load_gltf_with_notes(path).map(|(s, _)| s)
}

/// As [`load_gltf`], and also returns the notes about what was skipped (see
/// [`load_gltf_slice_with_notes`]).
///
/// # Errors
/// As [`load_gltf`].
pub fn load_gltf_with_notes(path: impl AsRef<Path>) -> Result<(Scene, Vec<String>), SceneError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let base = path.parent().map(|p| {
        if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        }
    });
    let name = path.display().to_string();
    let is_glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if is_glb && !bytes.starts_with(b"glTF") {
        let head = &bytes[..bytes.len().min(4)];
        return Err(SceneError::Gltf {
            file: name,
            context: "document".to_owned(),
            message: format!(
                "not a binary glTF file: it starts with {:?}, a .glb starts with \"glTF\"",
                String::from_utf8_lossy(head)
            ),
        });
    }
    load_owned(bytes, &name, base).map(|(mut s, notes)| {
        s.name = file_name(path);
        (s, notes)
    })
}

/// Loads a `.gltf` or `.glb` file flattened into one world-space mesh: node transforms applied
/// in `f32`, vertices numbered in depth-first node order, then primitive order, then accessor
/// order (the CLI contract), welded into one edge table. Same as
/// `load_gltf(path)?.baked_table()`.
///
/// # Errors
/// As [`load_gltf`], plus [`SceneError::Mesh`] if the merged mesh is too large.
pub fn load_gltf_mesh(
    path: impl AsRef<Path>,
) -> Result<std::sync::Arc<shadowvol_mesh_topology::EdgeTable>, SceneError> {
    load_gltf(path)?.baked_table()
}

/// Loads glTF from bytes (JSON text or GLB). `source_name` is used in messages; `base` is the
/// directory that relative buffer URIs are resolved against (`None`: only embedded buffers).
///
/// # Errors
/// [`SceneError::Gltf`] naming `source_name` and the element at fault.
pub fn load_gltf_slice(
    bytes: &[u8],
    source_name: &str,
    base: Option<&Path>,
) -> Result<Scene, SceneError> {
    load_gltf_slice_with_notes(bytes, source_name, base).map(|(s, _)| s)
}

/// As [`load_gltf_slice`], and also returns the notes about what was skipped: primitives that
/// are not triangles (points, lines) or have no `POSITION`, and nodes whose mesh is left without
/// triangles. Each note names the file and the node, mesh and primitive.
///
/// # Errors
/// As [`load_gltf_slice`].
pub fn load_gltf_slice_with_notes(
    bytes: &[u8],
    source_name: &str,
    base: Option<&Path>,
) -> Result<(Scene, Vec<String>), SceneError> {
    load_owned(bytes.to_vec(), source_name, base)
}

/// [`load_gltf_slice_with_notes`] of a file's bytes, which become its BIN chunk in place.
fn load_owned(
    bytes: Vec<u8>,
    source_name: &str,
    base: Option<&Path>,
) -> Result<(Scene, Vec<String>), SceneError> {
    let source = Source {
        name: source_name,
        base,
    };
    let mut early_notes = Vec::new();
    let (json, blob) = source.split_container(bytes, &mut early_notes)?;
    let (document, ext) = source.read_document(&json, &mut early_notes)?;
    source.check_buffer_uris(&document)?;
    let data = source.load_buffers(&document, &ext, blob)?;
    let buffers: Vec<Option<&[u8]>> = data.iter().map(Option::as_deref).collect();
    let decoded =
        decode_meshopt_views(&document, &ext, &buffers).map_err(|(c, m)| source.err(&c, m))?;
    let mut loader = Loader {
        source_name,
        document: &document,
        draco: &ext.draco,
        buffers: &buffers,
        decoded: &decoded,
        read_meshes: HashSet::new(),
        pending: Vec::new(),
        visited: vec![false; document.nodes().len()],
        quantization: document
            .extensions_used()
            .any(|e| e == "KHR_mesh_quantization"),
        notes: early_notes,
        scene: Scene {
            name: source_name.to_owned(),
            effects: Effects::default(),
            ..Scene::default()
        },
    };
    loader.walk(root_nodes(&document))?;
    let Loader {
        pending,
        mut notes,
        mut scene,
        ..
    } = loader;
    // The meshes are read: the file's bytes and decoded views go before the tables are built.
    drop(decoded);
    drop(buffers);
    drop(data);
    add_objects(source_name, pending, &mut scene, &mut notes)?;
    Ok((scene, notes))
}

/// The file being loaded: its name in messages and the base directory of relative URIs.
#[derive(Debug, Clone, Copy)]
struct Source<'a> {
    name: &'a str,
    base: Option<&'a Path>,
}

impl Source<'_> {
    /// A [`SceneError::Gltf`] of this file at `context` (`document`, `buffers`, ...).
    fn err(&self, context: &str, message: String) -> SceneError {
        SceneError::Gltf {
            file: self.name.to_owned(),
            context: context.to_owned(),
            message,
        }
    }
}
