//! glTF 2.0 loading (`.gltf` with external or embedded buffers, and `.glb`).
//!
//! What is read:
//!
//! * **Nodes** of the scene named by `scene`, else of the first scene, else every root node,
//!   visited depth first in order: a node, then its children in order. Each node with a mesh becomes one
//!   [`Object`] whose transform is the node's world transform, composed in `f32`
//!   (`parent * local`, glTF's `matrix` or `T * R * S`). This order is the vertex numbering of
//!   the CLI contract: depth-first node order, then primitive order, then accessor order.
//! * **Meshes**: all primitives of a mesh are concatenated, in order, into one [`Mesh`]. Nodes
//!   that use the same mesh share one `Arc<Mesh>`. Modes `TRIANGLES`, `TRIANGLE_STRIP` and
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
//! * **`KHR_draco_mesh_compression`** is not supported (there is no maintained Rust decoder): a
//!   file that requires it is refused with an error saying so; a file that only uses it reads
//!   the uncompressed fallback accessors.
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
//! it does not implement (`KHR_mesh_quantization`, `EXT_meshopt_compression`) and primitives
//! without `POSITION`. So the JSON is first normalised (integral numbers become integers,
//! `animations`, which are not read, are dropped), then the crate's structural validation runs
//! with those findings left out, and required extensions are checked against what is read here
//! (material and texture extensions do not change geometry and are accepted).
//!
//! The `gltf` crate does not check what accessors contain, so this module validates it: every
//! accessor must be in its buffer view and buffer, have a count above 0 and the right type;
//! positions must be finite, indices in range, and index counts must make whole triangles. Every
//! error names the file and the node, mesh, primitive and accessor.

use crate::scene::{file_name, Camera, Effects, Object, Scene};
use crate::SceneError;
use glam::{Affine3A, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use shadowvol_mesh_topology::Mesh;
use shadowvol_robust_math::Light;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

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
    load_gltf_slice_with_notes(&bytes, &name, base).map(|(mut s, notes)| {
        s.name = file_name(path);
        (s, notes)
    })
}

/// Loads a `.gltf` or `.glb` file flattened into one world-space mesh: node transforms applied
/// in `f32`, vertices numbered in depth-first node order, then primitive order, then accessor
/// order (the CLI contract). Same as `load_gltf(path)?.baked_mesh()`.
///
/// # Errors
/// As [`load_gltf`], plus [`SceneError::Mesh`] if the merged mesh is too large.
pub fn load_gltf_mesh(path: impl AsRef<Path>) -> Result<Mesh, SceneError> {
    load_gltf(path)?.baked_mesh()
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
    let err = |context: &str, message: String| SceneError::Gltf {
        file: source_name.to_owned(),
        context: context.to_owned(),
        message,
    };
    let mut early_notes = Vec::new();
    let mut bytes = bytes;
    let (json, blob) = if bytes.starts_with(b"glTF") {
        if bytes.len() >= 12 {
            let declared = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize;
            if declared >= 12 && declared < bytes.len() {
                // Data after the end of the GLB stream: the spec allows it (the Khronos
                // validator warns, GLB_EXTRA_DATA); the stream ends where the header says.
                early_notes.push(format!(
                    "{source_name}: {} bytes after the end of the GLB stream (its header \
                     declares {declared}) are ignored",
                    bytes.len() - declared
                ));
                bytes = &bytes[..declared];
            }
            if declared != bytes.len() {
                return Err(err(
                    "document",
                    format!(
                        "GLB header declares {declared} bytes but the file has {} (truncated or \
                         corrupted)",
                        bytes.len()
                    ),
                ));
            }
        }
        let glb = gltf::Glb::from_slice(bytes).map_err(|e| err("document", e.to_string()))?;
        (
            glb.json.into_owned(),
            glb.bin.map(std::borrow::Cow::into_owned),
        )
    } else {
        (bytes.to_vec(), None)
    };
    let mut value: serde_json::Value = serde_json::from_slice(&json)
        .map_err(|e| err("document", format!("not valid JSON: {e}")))?;
    normalize_json(&mut value);
    early_notes.extend(unknown_enum_values(&mut value, source_name));
    let ext = Extensions::read(&value);
    let json = serde_json::to_vec(&value).map_err(|e| err("document", e.to_string()))?;
    let root = gltf::json::Root::from_slice(&json).map_err(|e| err("document", e.to_string()))?;
    let document = gltf::Document::from_json_without_validation(root);
    validate(&document).map_err(|m| err("document", m))?;
    check_required_extensions(&document).map_err(|m| err("document", m))?;
    // `import_buffers` unwraps the percent-decoding of relative URIs (it panics when the decoded
    // bytes are not UTF-8): check them first.
    for b in document.buffers() {
        if let gltf::buffer::Source::Uri(uri) = b.source() {
            if !uri.contains(':') && std::str::from_utf8(&percent_decode(uri)).is_err() {
                return Err(err(
                    "buffers",
                    format!(
                        "buffer {}: uri {uri:?} percent-decodes to bytes that are not UTF-8",
                        b.index()
                    ),
                ));
            }
        }
    }
    // Only the buffers that positions and indices read are loaded (others may be placeholders
    // without data, or URIs this loader cannot resolve, which is valid glTF). An
    // EXT_meshopt_compression fallback buffer has no data; its views are decoded instead.
    let needed = needed_buffers(&document, &ext);
    let mut blob = blob;
    let mut data: Vec<Option<Vec<u8>>> = Vec::with_capacity(document.buffers().len());
    for b in document.buffers() {
        let bin = matches!(b.source(), gltf::buffer::Source::Bin);
        if !needed.contains(&b.index()) || (ext.fallback.contains(&b.index()) && bin) {
            if bin && b.index() == 0 {
                // The GLB's BIN chunk belongs to buffer 0 only.
                blob = None;
            }
            data.push(None);
            continue;
        }
        if bin && blob.is_none() {
            // Valid glTF JSON (a buffer without `uri` names the GLB's binary chunk), but a
            // `.gltf` has no such chunk, so the positions or indices it should hold are missing.
            return Err(err(
                "buffers",
                format!(
                    "buffer {} has no uri and no GLB binary chunk holds it (a .gltf has none; in \
                     a .glb only buffer 0 uses it): the {} bytes its positions or indices are read \
                     from are not in the file",
                    b.index(),
                    b.length()
                ),
            ));
        }
        let d = gltf::buffer::Data::from_source_and_blob(b.source(), base, &mut blob)
            .map_err(|e| err("buffers", format!("buffer {}: {e}", b.index())))?;
        // Data shorter than byteLength is refused; data longer than it (beyond the up to 3
        // padding bytes a GLB BIN chunk may carry) is a lie about the length too. Views are then
        // checked against the declared length only.
        if d.0.len() < b.length() || d.0.len() > b.length() + 3 {
            return Err(err(
                "buffers",
                format!(
                    "buffer {}: its data holds {} bytes but byteLength declares {} (a data URI, \
                     file or GLB chunk must match byteLength)",
                    b.index(),
                    d.0.len(),
                    b.length()
                ),
            ));
        }
        let mut d = d.0;
        d.truncate(b.length());
        data.push(Some(d));
    }
    let buffers: Vec<Option<&[u8]>> = data.iter().map(Option::as_deref).collect();
    let decoded = decode_meshopt_views(&document, &ext, &buffers).map_err(|(c, m)| err(&c, m))?;

    let roots: Vec<gltf::Node> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(s) => s.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            for n in document.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };

    let mut loader = Loader {
        source_name,
        buffers: &buffers,
        decoded: &decoded,
        meshes: HashMap::new(),
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
    // Depth-first, pre-order, with an explicit stack (deep hierarchies must not overflow).
    let mut stack: Vec<(gltf::Node, Affine3A)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, Affine3A::IDENTITY))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        let world = loader.visit(&node, parent)?;
        let children: Vec<gltf::Node> = node.children().collect();
        for c in children.into_iter().rev() {
            stack.push((c, world));
        }
    }
    Ok((loader.scene, loader.notes))
}

/// Rewrites what the glTF 2.0 schema allows but the `gltf` crate's serde types refuse:
///
/// * a number with an integral value written with a fraction or exponent (`1.0`, `3e2`) where
///   an integer is expected: JSON does not distinguish them and the spec's JSON Schema accepts
///   them, but `gltf-json` deserializes indices and counts as Rust integers. Every such number
///   (below 2^53, not `-0.0`) becomes an integer; `f32` fields read it to the same value.
/// * `animations`: shadowvol reads no animation, and `gltf-json` refuses channel targets without
///   a `node` (valid in glTF 2.0, used by `KHR_animation_pointer`), so they are dropped before
///   parsing.
/// * a scene without `nodes` (optional in the spec) gets an empty list.
fn normalize_json(value: &mut serde_json::Value) {
    use serde_json::Value;
    if let Value::Object(m) = value {
        m.remove("animations");
        // `scene.nodes` is optional in glTF 2.0, required by gltf-json.
        if let Some(Value::Array(scenes)) = m.get_mut("scenes") {
            for sc in scenes {
                if let Value::Object(o) = sc {
                    o.entry("nodes").or_insert_with(|| Value::Array(Vec::new()));
                }
            }
        }
    }
    let mut stack = vec![value];
    while let Some(v) = stack.pop() {
        match v {
            Value::Number(n) if !(n.is_i64() || n.is_u64()) => {
                if let Some(f) = n.as_f64() {
                    if f.fract() == 0.0
                        && f.abs() < 9_007_199_254_740_992.0
                        && !(f == 0.0 && f.is_sign_negative())
                    {
                        *v = Value::from(f as i64);
                    }
                }
            }
            Value::Array(a) => stack.extend(a.iter_mut()),
            Value::Object(m) => stack.extend(m.values_mut()),
            _ => {}
        }
    }
}

/// Values of enums the spec may extend, which gltf-json refuses although the glTF validator
/// only warns (VALUE_NOT_IN_LIST): an accessor `type` outside SCALAR..MAT4 that no position or
/// index reads becomes SCALAR (it is never read; one that is read stays, and is refused by
/// name), and a KHR_lights_punctual light of an unknown `type` is dropped with the nodes'
/// references to it (its light is unknown, so it lights nothing). Returns a note per change.
fn unknown_enum_values(value: &mut serde_json::Value, source_name: &str) -> Vec<String> {
    use serde_json::Value;
    const TYPES: [&str; 7] = ["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"];
    const LIGHTS: [&str; 3] = ["directional", "point", "spot"];
    let mut notes = Vec::new();
    let Value::Object(root) = value else {
        return notes;
    };
    // Accessors that positions and indices read (directly; sparse and view data follow them).
    let mut read = std::collections::HashSet::new();
    if let Some(Value::Array(meshes)) = root.get("meshes") {
        for m in meshes {
            for p in m
                .get("primitives")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                if let Some(i) = p.get("indices").and_then(Value::as_u64) {
                    read.insert(i);
                }
                if let Some(i) = p.pointer("/attributes/POSITION").and_then(Value::as_u64) {
                    read.insert(i);
                }
            }
        }
    }
    if let Some(Value::Array(accessors)) = root.get_mut("accessors") {
        for (i, a) in accessors.iter_mut().enumerate() {
            let Some(t) = a.get("type").and_then(Value::as_str).map(str::to_owned) else {
                continue;
            };
            if !TYPES.contains(&t.as_str()) && !read.contains(&(i as u64)) {
                a["type"] = Value::from("SCALAR");
                notes.push(format!(
                    "{source_name}: accessor {i} has the unknown type {t:?}; nothing reads it"
                ));
            }
        }
    }
    let unknown: Vec<usize> = root
        .get("extensions")
        .and_then(|e| e.pointer("/KHR_lights_punctual/lights"))
        .and_then(Value::as_array)
        .map(|lights| {
            lights
                .iter()
                .enumerate()
                .filter(|(_, l)| {
                    l.get("type")
                        .and_then(Value::as_str)
                        .is_some_and(|t| !LIGHTS.contains(&t))
                })
                .map(|(i, _)| i)
                .collect()
        })
        .unwrap_or_default();
    if unknown.is_empty() {
        return notes;
    }
    if let Some(Value::Array(lights)) = root
        .get_mut("extensions")
        .and_then(|e| e.pointer_mut("/KHR_lights_punctual/lights"))
    {
        for &i in unknown.iter().rev() {
            let t = lights[i]["type"].clone();
            lights.remove(i);
            notes.push(format!(
                "{source_name}: KHR_lights_punctual light {i} has the unknown type {t}; it is \
                 left out"
            ));
        }
    }
    // Node references: dropped for the removed lights, renumbered past them.
    if let Some(Value::Array(nodes)) = root.get_mut("nodes") {
        for n in nodes {
            let Some(ext) = n.get_mut("extensions").and_then(Value::as_object_mut) else {
                continue;
            };
            let Some(l) = ext
                .get("KHR_lights_punctual")
                .and_then(|k| k.get("light"))
                .and_then(Value::as_u64)
            else {
                continue;
            };
            let l = l as usize;
            if unknown.contains(&l) {
                ext.remove("KHR_lights_punctual");
            } else {
                let shift = unknown.iter().filter(|&&u| u < l).count();
                ext["KHR_lights_punctual"]["light"] = Value::from(l - shift);
            }
        }
    }
    notes
}

/// The extension data that the `gltf` crate's types do not keep (it is read from the JSON).
#[derive(Default)]
struct Extensions {
    /// Buffers marked `EXT_meshopt_compression.fallback`.
    fallback: Vec<usize>,
    /// `EXT_meshopt_compression` objects of buffer views, by view index.
    meshopt: HashMap<usize, serde_json::Value>,
}

impl Extensions {
    fn read(root: &serde_json::Value) -> Self {
        let ext =
            |v: &serde_json::Value| v.get("extensions")?.get("EXT_meshopt_compression").cloned();
        let list = |k: &str| {
            root.get(k)
                .and_then(|v| v.as_array())
                .cloned()
                .unwrap_or_default()
        };
        Self {
            fallback: list("buffers")
                .iter()
                .enumerate()
                .filter(|(_, b)| {
                    ext(b)
                        .is_some_and(|e| e.get("fallback") == Some(&serde_json::Value::Bool(true)))
                })
                .map(|(i, _)| i)
                .collect(),
            meshopt: list("bufferViews")
                .iter()
                .enumerate()
                .filter_map(|(i, v)| ext(v).map(|e| (i, e)))
                .collect(),
        }
    }
}

/// The buffers that positions and indices read: the buffers of their views (and sparse views),
/// or, for `EXT_meshopt_compression` views, the buffer of the compressed source.
fn needed_buffers(document: &gltf::Document, ext: &Extensions) -> std::collections::HashSet<usize> {
    let mut out = std::collections::HashSet::new();
    let mut add = |v: gltf::buffer::View| {
        match ext
            .meshopt
            .get(&v.index())
            .and_then(|e| e.get("buffer"))
            .and_then(|b| b.as_u64())
        {
            Some(src) => out.insert(src as usize),
            None => out.insert(v.buffer().index()),
        };
    };
    for mesh in document.meshes() {
        for prim in mesh.primitives() {
            for acc in [prim.get(&gltf::Semantic::Positions), prim.indices()]
                .into_iter()
                .flatten()
            {
                if let Some(v) = acc.view() {
                    add(v);
                }
                if let Some(s) = acc.sparse() {
                    add(s.indices().view());
                    add(s.values().view());
                }
            }
        }
    }
    out
}

/// Extensions that may be required: those read here, and those that only change appearance
/// (materials, textures), which shadow volumes do not depend on.
fn check_required_extensions(document: &gltf::Document) -> Result<(), String> {
    for (i, ext) in document.extensions_required().enumerate() {
        let ok = matches!(
            ext,
            "KHR_lights_punctual" | "KHR_mesh_quantization" | "EXT_meshopt_compression"
        ) || ext.starts_with("KHR_materials_")
            || ext.starts_with("KHR_texture_")
            || ext.starts_with("EXT_texture_")
            || ext == "MSFT_texture_dds";
        if ok {
            continue;
        }
        return Err(if ext == "KHR_draco_mesh_compression" {
            format!(
                "extensionsRequired[{i}]: extension KHR_draco_mesh_compression is required but \
                 not supported (there is no maintained Rust Draco decoder): re-export the file \
                 without Draco, for example with meshopt compression \
                 (`gltfpack -i in.glb -o out.glb -c`)"
            )
        } else {
            format!(
                "extensionsRequired[{i}]: extension {ext} is required but not supported \
                 (supported: KHR_lights_punctual, KHR_mesh_quantization, \
                 EXT_meshopt_compression, and material and texture extensions, which do not \
                 change geometry)"
            )
        });
    }
    Ok(())
}

/// Decodes the `EXT_meshopt_compression` views that positions and indices read (views of
/// other attributes are left alone). Errors are `(context, message)`.
fn decode_meshopt_views(
    document: &gltf::Document,
    ext: &Extensions,
    buffers: &[Option<&[u8]>],
) -> Result<HashMap<usize, Vec<u8>>, (String, String)> {
    let mut wanted = std::collections::HashSet::new();
    let mut want = |acc: gltf::Accessor| {
        if let Some(v) = acc.view() {
            wanted.insert(v.index());
        }
        if let Some(s) = acc.sparse() {
            wanted.insert(s.indices().view().index());
            wanted.insert(s.values().view().index());
        }
    };
    for mesh in document.meshes() {
        for prim in mesh.primitives() {
            if let Some(a) = prim.get(&gltf::Semantic::Positions) {
                want(a);
            }
            if let Some(a) = prim.indices() {
                want(a);
            }
        }
    }
    let mut out = HashMap::new();
    for view in document.views().filter(|v| wanted.contains(&v.index())) {
        let Some(e) = ext.meshopt.get(&view.index()) else {
            continue;
        };
        let ctx = format!("buffer view {}, EXT_meshopt_compression", view.index());
        let bad = |m: String| (ctx.clone(), m);
        let uint = |k: &str| -> Result<Option<usize>, (String, String)> {
            match e.get(k) {
                None => Ok(None),
                Some(v) => v
                    .as_u64()
                    .and_then(|x| usize::try_from(x).ok())
                    .map(Some)
                    .ok_or_else(|| {
                        bad(format!("\"{k}\" must be a non-negative integer, found {v}"))
                    }),
            }
        };
        let need = |k: &str| uint(k)?.ok_or_else(|| bad(format!("\"{k}\" is missing")));
        let name = |k: &str, default: Option<&str>| -> Result<String, (String, String)> {
            match e.get(k) {
                None => default
                    .map(str::to_owned)
                    .ok_or_else(|| bad(format!("\"{k}\" is missing"))),
                Some(serde_json::Value::String(s)) => Ok(s.clone()),
                Some(v) => Err(bad(format!("\"{k}\" must be a string, found {v}"))),
            }
        };
        let src_index = need("buffer")?;
        let offset = uint("byteOffset")?.unwrap_or(0);
        let length = need("byteLength")?;
        let stride = need("byteStride")?;
        let count = need("count")?;
        let mode_name = name("mode", None)?;
        let filter_name = name("filter", Some("NONE"))?;
        let mode = crate::meshopt_view::Mode::from_name(&mode_name)
            .ok_or_else(|| bad(format!("unknown mode {mode_name:?}")))?;
        let filter = crate::meshopt_view::Filter::from_name(&filter_name)
            .ok_or_else(|| bad(format!("unknown filter {filter_name:?}")))?;
        let src = match buffers.get(src_index) {
            Some(Some(b)) => *b,
            Some(None) => {
                return Err(bad(format!(
                    "source buffer {src_index} is a fallback buffer without data"
                )))
            }
            None => return Err(bad(format!("source buffer {src_index} does not exist"))),
        };
        let encoded = offset
            .checked_add(length)
            .filter(|&end| end <= src.len())
            .map(|end| &src[offset..end])
            .ok_or_else(|| {
                bad(format!(
                    "source range byteOffset {offset}, byteLength {length} runs past the end of \
                     buffer {src_index} ({} bytes)",
                    src.len()
                ))
            })?;
        if count.checked_mul(stride) != Some(view.length()) {
            return Err(bad(format!(
                "count {count} x byteStride {stride} does not equal the view's byteLength {}",
                view.length()
            )));
        }
        let bytes =
            crate::meshopt_view::decode(encoded, count, stride, mode, filter).map_err(bad)?;
        out.insert(view.index(), bytes);
    }
    Ok(out)
}

struct Loader<'a> {
    source_name: &'a str,
    /// Buffer data by index; `None` for an `EXT_meshopt_compression` fallback buffer.
    buffers: &'a [Option<&'a [u8]>],
    /// Decoded `EXT_meshopt_compression` views by view index.
    decoded: &'a HashMap<usize, Vec<u8>>,
    meshes: HashMap<usize, Arc<Mesh>>,
    visited: Vec<bool>,
    /// `KHR_mesh_quantization` is in `extensionsUsed`: integer positions are allowed.
    quantization: bool,
    notes: Vec<String>,
    scene: Scene,
}

fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) => format!("node {} '{n}'", node.index()),
        None => format!("node {}", node.index()),
    }
}

impl Loader<'_> {
    fn err(&self, context: String, message: impl Into<String>) -> SceneError {
        SceneError::Gltf {
            file: self.source_name.to_owned(),
            context,
            message: message.into(),
        }
    }

    /// Handles one node; returns its world transform.
    fn visit(&mut self, node: &gltf::Node, parent: Affine3A) -> Result<Affine3A, SceneError> {
        let label = node_label(node);
        if std::mem::replace(&mut self.visited[node.index()], true) {
            return Err(self.err(
                label,
                "is reached twice from the scene (the node hierarchy must be a forest: no \
                 cycles, no node with two parents)",
            ));
        }
        let m = Mat4::from_cols_array_2d(&node.transform().matrix());
        if !m.is_finite() {
            return Err(self.err(label, "transform has a NaN or infinite entry"));
        }
        let row3 = m.row(3);
        if row3 != glam::Vec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(self.err(
                label,
                format!("matrix is not affine: its last row is {row3}, expected (0, 0, 0, 1)"),
            ));
        }
        let local = Affine3A::from_mat4(m);
        let world = parent * local;
        if !world.is_finite() {
            return Err(self.err(label, "world transform overflows f32"));
        }

        if let Some(mesh) = node.mesh() {
            let det = world.matrix3.determinant();
            if !det.is_normal() {
                return Err(self.err(
                    label,
                    format!(
                        "world transform of the mesh is singular or degenerate (determinant \
                         {det:e}): a zero scale flattens the object, and lights cannot be \
                         brought into its frame"
                    ),
                ));
            }
            let shared = match self.meshes.get(&mesh.index()) {
                Some(m) => Arc::clone(m),
                None => {
                    let m = Arc::new(self.read_mesh(&label, &mesh)?);
                    self.meshes.insert(mesh.index(), Arc::clone(&m));
                    m
                }
            };
            let name = node
                .name()
                .or(mesh.name())
                .map_or_else(|| format!("node{}", node.index()), str::to_owned);
            if shared.triangles.is_empty() {
                self.notes.push(format!(
                    "{}: {label}: mesh {} has no triangles, the node is skipped",
                    self.source_name,
                    mesh.index()
                ));
            } else {
                self.scene.objects.push(Object {
                    name,
                    mesh: shared,
                    transform: world,
                });
            }
        }

        if let Some(light) = node.light() {
            let l = match light.kind() {
                gltf::khr_lights_punctual::Kind::Directional => {
                    let z = world.matrix3.z_axis;
                    Light::new(z.x, z.y, z.z, 0.0)
                }
                gltf::khr_lights_punctual::Kind::Point
                | gltf::khr_lights_punctual::Kind::Spot { .. } => {
                    let t = world.translation;
                    Light::new(t.x, t.y, t.z, 1.0)
                }
            }
            .map_err(|e| {
                self.err(
                    format!("{label}, light {}", light.index()),
                    format!("invalid light: {e}"),
                )
            })?;
            let emission = crate::emission::from_gltf(&light, &world)
                .map_err(|m| self.err(format!("{label}, light {}", light.index()), m))?;
            self.scene.lights.push(l);
            self.scene.emission.push(emission);
        }

        if let (Some(cam), None) = (node.camera(), self.scene.camera) {
            if let gltf::camera::Projection::Perspective(p) = cam.projection() {
                let eye = Vec3::from(world.translation);
                let forward = -Vec3::from(world.matrix3.z_axis);
                let up = Vec3::from(world.matrix3.y_axis);
                let target = extras_vec3(node.extras(), "target")
                    .unwrap_or(eye + forward.normalize_or(Vec3::NEG_Z));
                let camera = Camera {
                    eye,
                    target,
                    up: up.normalize_or(Vec3::Y),
                    fov_y: p.yfov(),
                    near: p.znear(),
                };
                let ok = camera.eye.is_finite()
                    && camera.target.is_finite()
                    && camera.fov_y.is_finite()
                    && camera.fov_y > 0.0
                    && camera.near.is_finite()
                    && camera.near > 0.0
                    && camera.target != camera.eye;
                if !ok {
                    return Err(self.err(
                        format!("{label}, camera {}", cam.index()),
                        "camera is degenerate (needs finite eye and target apart, yfov > 0, \
                         znear > 0)",
                    ));
                }
                self.scene.camera = Some(camera);
            }
        }
        Ok(world)
    }

    fn read_mesh(&mut self, node_label: &str, mesh: &gltf::Mesh) -> Result<Mesh, SceneError> {
        let mut out = Mesh::default();
        let mesh_label = match mesh.name() {
            Some(n) => format!("{node_label}, mesh {} '{n}'", mesh.index()),
            None => format!("{node_label}, mesh {}", mesh.index()),
        };
        for prim in mesh.primitives() {
            let label = format!("{mesh_label}, primitive {}", prim.index());
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.notes.push(format!(
                    "{}: {label}: mode {mode:?} is not a triangle mode, the primitive is skipped \
                     (shadow volumes need TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN)",
                    self.source_name
                ));
                continue;
            }
            let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
                self.notes.push(format!(
                    "{}: {label}: no POSITION attribute, the primitive is skipped",
                    self.source_name
                ));
                continue;
            };
            let positions = self.read_positions(&label, &pos_acc)?;
            let n = positions.len();
            let indices: Vec<u32> = match prim.indices() {
                Some(acc) => self.read_indices(&label, &acc, n)?,
                None => (0..n as u32).collect(),
            };
            let idx_label = prim.indices().map_or_else(
                || format!("{label} (non-indexed)"),
                |a| format!("{label}, accessor {} (indices)", a.index()),
            );
            let tris = assemble(mode, &indices).map_err(|m| self.err(idx_label, m))?;
            let base = out.positions.len() as u64;
            if base + n as u64 >= u64::from(u32::MAX) {
                return Err(self.err(label, "too many vertices for u32 indexing"));
            }
            let base = base as u32;
            out.positions.extend_from_slice(&positions);
            out.triangles
                .extend(tris.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        }
        out.validate()
            .map_err(|e| self.err(mesh_label, e.to_string()))?;
        Ok(out)
    }

    /// Positions as `f32`: `FLOAT`, or with `KHR_mesh_quantization` `BYTE`, `UNSIGNED_BYTE`,
    /// `SHORT`, `UNSIGNED_SHORT`, normalized or not (see the module documentation).
    fn read_positions(&self, label: &str, acc: &gltf::Accessor) -> Result<Vec<Vec3>, SceneError> {
        let alabel = format!("{label}, accessor {} (POSITION)", acc.index());
        let ty = acc.data_type();
        let allowed = ty == DataType::F32 || (self.quantization && ty != DataType::U32);
        if acc.dimensions() != Dimensions::Vec3 || !allowed {
            return Err(self.err(
                alabel,
                format!(
                    "POSITION must be VEC3 of FLOAT (or, with KHR_mesh_quantization in \
                     extensionsUsed, of BYTE, UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT), found \
                     {:?} of {:?}",
                    acc.dimensions(),
                    ty
                ),
            ));
        }
        let normalized = acc.normalized();
        if normalized && ty == DataType::F32 {
            return Err(self.err(alabel, "a FLOAT accessor cannot be normalized"));
        }
        let bytes = self.accessor_bytes(&alabel, acc)?;
        let size = acc.size() / 3;
        let component = |c: &[u8]| -> f32 {
            match (ty, normalized) {
                (DataType::F32, _) => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                (DataType::I8, false) => f32::from(c[0] as i8),
                (DataType::U8, false) => f32::from(c[0]),
                (DataType::I16, false) => f32::from(i16::from_le_bytes([c[0], c[1]])),
                (DataType::U16, false) => f32::from(u16::from_le_bytes([c[0], c[1]])),
                (DataType::I8, true) => (f32::from(c[0] as i8) / 127.0).max(-1.0),
                (DataType::U8, true) => f32::from(c[0]) / 255.0,
                (DataType::I16, true) => {
                    (f32::from(i16::from_le_bytes([c[0], c[1]])) / 32767.0).max(-1.0)
                }
                (DataType::U16, true) => f32::from(u16::from_le_bytes([c[0], c[1]])) / 65535.0,
                (DataType::U32, _) => f32::NAN,
            }
        };
        let mut out = Vec::with_capacity(acc.count());
        for (i, c) in bytes.chunks_exact(3 * size).enumerate() {
            let v = [
                component(&c[..size]),
                component(&c[size..2 * size]),
                component(&c[2 * size..]),
            ];
            for (axis, value) in ['x', 'y', 'z'].into_iter().zip(v) {
                if !value.is_finite() {
                    return Err(self.err(
                        alabel,
                        format!(
                            "element {i}: coordinate {axis} is {value}, but positions must be \
                             finite"
                        ),
                    ));
                }
            }
            out.push(Vec3::from_array(v));
        }
        Ok(out)
    }

    fn read_indices(
        &self,
        label: &str,
        acc: &gltf::Accessor,
        vertices: usize,
    ) -> Result<Vec<u32>, SceneError> {
        let alabel = format!("{label}, accessor {} (indices)", acc.index());
        if acc.dimensions() != Dimensions::Scalar
            || !matches!(
                acc.data_type(),
                DataType::U8 | DataType::U16 | DataType::U32
            )
        {
            return Err(self.err(
                alabel,
                format!(
                    "indices must be SCALAR of UNSIGNED_BYTE/SHORT/INT, found {:?} of {:?}",
                    acc.dimensions(),
                    acc.data_type()
                ),
            ));
        }
        let bytes = self.accessor_bytes(&alabel, acc)?;
        let values: Vec<u32> = match acc.data_type() {
            DataType::U8 => bytes.iter().map(|&b| u32::from(b)).collect(),
            DataType::U16 => bytes
                .chunks_exact(2)
                .map(|c| u32::from(u16::from_le_bytes([c[0], c[1]])))
                .collect(),
            _ => bytes
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        };
        if let Some((i, &v)) = values
            .iter()
            .enumerate()
            .find(|(_, &v)| v as usize >= vertices)
        {
            return Err(self.err(
                alabel,
                format!(
                    "element {i}: vertex index {v} is out of range (the primitive has {vertices} \
                     vertices)"
                ),
            ));
        }
        Ok(values)
    }

    /// The accessor's elements, tightly packed (`count * size` bytes), with bounds checks and
    /// sparse substitution.
    fn accessor_bytes(&self, alabel: &str, acc: &gltf::Accessor) -> Result<Vec<u8>, SceneError> {
        let count = acc.count();
        let size = acc.size();
        if count == 0 {
            return Err(self.err(alabel.to_owned(), "count is 0 (at least 1 element needed)"));
        }
        let total = count
            .checked_mul(size)
            .ok_or_else(|| self.err(alabel.to_owned(), format!("count {count} overflows")))?;
        // A view-less accessor is zeros of any declared count: its size is not bounded by the
        // file, so it is checked against the memory budget before it is allocated.
        if acc.view().is_none() && total as u64 > shadowvol_mesh_topology::MEMORY_CHECK_THRESHOLD {
            if let Some((available, source)) = shadowvol_mesh_topology::available_memory() {
                if total as u64 > available {
                    return Err(self.err(
                        alabel.to_owned(),
                        format!(
                            "{count} elements without a bufferView need {total} bytes, more than \
                             the {available} bytes available ({source})"
                        ),
                    ));
                }
            }
        }
        let mut out = match acc.view() {
            None => {
                let mut v = Vec::new();
                v.try_reserve_exact(total).map_err(|_| {
                    self.err(
                        alabel.to_owned(),
                        format!(
                            "{count} elements without a bufferView: cannot allocate {total} bytes"
                        ),
                    )
                })?;
                v.resize(total, 0u8);
                v
            }
            Some(view) => {
                let stride = view.stride().unwrap_or(size);
                if stride < size {
                    return Err(self.err(
                        alabel.to_owned(),
                        format!(
                            "buffer view {} has byteStride {stride}, smaller than the element \
                             size {size}",
                            view.index()
                        ),
                    ));
                }
                let data = self.view_bytes(alabel, &view)?;
                let needed = acc
                    .offset()
                    .checked_add((count - 1).saturating_mul(stride))
                    .and_then(|x| x.checked_add(size));
                match needed {
                    Some(needed) if needed <= data.len() => {}
                    _ => {
                        return Err(self.err(
                            alabel.to_owned(),
                            format!(
                                "{count} elements of {size} bytes (stride {stride}, byteOffset \
                                 {}) run past the end of buffer view {} ({} bytes)",
                                acc.offset(),
                                view.index(),
                                data.len()
                            ),
                        ))
                    }
                }
                let mut v = Vec::with_capacity(total);
                for i in 0..count {
                    let s = acc.offset() + i * stride;
                    v.extend_from_slice(&data[s..s + size]);
                }
                v
            }
        };
        if let Some(sparse) = acc.sparse() {
            let n = sparse.count();
            let idx = sparse.indices();
            let isize = match idx.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let slabel = format!("{alabel}, sparse");
            let idata = self.view_bytes(&slabel, &idx.view())?;
            let vdata = self.view_bytes(&slabel, &sparse.values().view())?;
            let ioff = idx.offset();
            let voff = sparse.values().offset();
            let ifits = n
                .checked_mul(isize)
                .and_then(|x| x.checked_add(ioff))
                .is_some_and(|e| e <= idata.len());
            let vfits = n
                .checked_mul(size)
                .and_then(|x| x.checked_add(voff))
                .is_some_and(|e| e <= vdata.len());
            if !ifits || !vfits {
                return Err(self.err(
                    slabel,
                    format!("{n} sparse indices or values run past the end of their buffer views"),
                ));
            }
            for k in 0..n {
                let c = &idata[ioff + k * isize..ioff + (k + 1) * isize];
                let target = match isize {
                    1 => usize::from(c[0]),
                    2 => usize::from(u16::from_le_bytes([c[0], c[1]])),
                    _ => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize,
                };
                if target >= count {
                    return Err(self.err(
                        slabel,
                        format!(
                            "sparse index {k} targets element {target}, but the accessor has \
                             {count}"
                        ),
                    ));
                }
                out[target * size..(target + 1) * size]
                    .copy_from_slice(&vdata[voff + k * size..voff + (k + 1) * size]);
            }
        }
        Ok(out)
    }

    fn view_bytes(&self, alabel: &str, view: &gltf::buffer::View) -> Result<&[u8], SceneError> {
        if let Some(d) = self.decoded.get(&view.index()) {
            return Ok(d);
        }
        let buf = match self.buffers.get(view.buffer().index()) {
            Some(Some(b)) => *b,
            Some(None) => {
                return Err(self.err(
                    alabel.to_owned(),
                    format!(
                        "buffer view {} is in buffer {}, an EXT_meshopt_compression fallback \
                         without data, but the view is not compressed",
                        view.index(),
                        view.buffer().index()
                    ),
                ))
            }
            None => {
                return Err(self.err(
                    alabel.to_owned(),
                    format!("buffer {} is missing", view.buffer().index()),
                ))
            }
        };
        let end = view.offset().checked_add(view.length());
        match end {
            Some(end) if end <= buf.len() => Ok(&buf[view.offset()..end]),
            _ => Err(self.err(
                alabel.to_owned(),
                format!(
                    "buffer view {} (byteOffset {}, byteLength {}) runs past the end of buffer {} \
                     ({} bytes)",
                    view.index(),
                    view.offset(),
                    view.length(),
                    view.buffer().index(),
                    buf.len()
                ),
            )),
        }
    }
}

/// `%XX` escapes decoded to bytes (anything else kept as is), as the gltf crate decodes relative
/// URIs.
fn percent_decode(uri: &str) -> Vec<u8> {
    let b = uri.as_bytes();
    let hex = |c: u8| (c as char).to_digit(16);
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    out
}

/// The `gltf` crate's structural validation (every index refers to something that exists, enums
/// are known, required fields are present), except that a missing `min`/`max` on `POSITION`
/// accessors is accepted (many exporters omit them and this loader does not use them), and that
/// `extensionsRequired` is checked by [`check_required_extensions`] instead (the crate refuses
/// every extension it does not implement, including those read here).
fn validate(document: &gltf::Document) -> Result<(), String> {
    use gltf::json::validation::{Error, Validate};
    let root = document.as_json();
    // gltf-json's validation indexes the POSITION accessor without a bounds check (it panics on
    // a dangling index): check that reference first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(a) = prim.attributes.get(&pos) {
                if a.value() >= root.accessors.len() {
                    return Err(format!(
                        "invalid glTF: meshes[{m}].primitives[{p}].attributes[\"POSITION\"]: \
                         accessor {} does not exist (the file has {} accessors)",
                        a.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let p = path().to_string();
        let min_max = p.ends_with(".min") || p.ends_with(".max");
        let required = p.starts_with("extensionsRequired") && matches!(error, Error::Unsupported);
        // A primitive without POSITION is valid glTF; it is skipped with a note.
        let position = p.ends_with("attributes[\"POSITION\"]");
        // An accessor without bufferView is zero-filled; a texture without source is valid (an
        // extension provides the image) and textures are not read.
        let optional = (p.starts_with("accessors[") && p.ends_with("].bufferView"))
            || (p.starts_with("textures[") && p.ends_with("].source"));
        if !((min_max || position || optional) && matches!(error, Error::Missing)) && !required {
            errors.push(format!("{p}: {error}"));
        }
    });
    if errors.is_empty() {
        Ok(())
    } else {
        Err(format!("invalid glTF: {}", errors.join("; ")))
    }
}

/// Turns an index list of a triangle mode into triangles.
fn assemble(mode: Mode, idx: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    match mode {
        Mode::Triangles => {
            if !idx.len().is_multiple_of(3) {
                return Err(format!(
                    "{} indices do not make whole triangles (TRIANGLES needs a multiple of 3)",
                    idx.len()
                ));
            }
            Ok(idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
        }
        Mode::TriangleStrip | Mode::TriangleFan => {
            if idx.len() < 3 {
                return Err(format!(
                    "{} indices make no triangle ({mode:?} needs at least 3)",
                    idx.len()
                ));
            }
            Ok((0..idx.len() - 2)
                .map(|i| match mode {
                    Mode::TriangleFan => [idx[0], idx[i + 1], idx[i + 2]],
                    _ if i % 2 == 0 => [idx[i], idx[i + 1], idx[i + 2]],
                    _ => [idx[i + 1], idx[i], idx[i + 2]],
                })
                .collect())
        }
        _ => Err(format!("mode {mode:?} is not a triangle mode")),
    }
}

/// Reads `extras[key]` as a finite `[x, y, z]`.
fn extras_vec3(extras: &gltf::json::Extras, key: &str) -> Option<Vec3> {
    let raw = extras.as_ref()?;
    let v: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    let a = v.get(key)?.as_array()?;
    if a.len() != 3 {
        return None;
    }
    let f = |i: usize| a[i].as_f64().map(|x| x as f32);
    let p = Vec3::new(f(0)?, f(1)?, f(2)?);
    p.is_finite().then_some(p)
}
