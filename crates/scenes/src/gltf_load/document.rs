//! The glTF JSON before and after parsing: the JSON and binary chunk of a GLB, normalising what
//! the `gltf` crate's serde types refuse, reading the extensions in use, and the structural and
//! required-extension checks.

use super::Source;
use crate::SceneError;
use std::collections::HashMap;

impl Source<'_> {
    /// The JSON and BIN chunk of a GLB (trailing data cut with a note), or the JSON as is. The
    /// BIN chunk is `file` itself, cut to the chunk in place: the file is not held twice.
    pub(super) fn split_container(
        &self,
        mut file: Vec<u8>,
        notes: &mut Vec<String>,
    ) -> Result<(Vec<u8>, Option<Vec<u8>>), SceneError> {
        if !file.starts_with(b"glTF") {
            return Ok((file, None));
        }
        let mut bytes = &file[..];
        if bytes.len() >= 12 {
            let declared = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize;
            if declared >= 12 && declared < bytes.len() {
                // Data after the end of the GLB stream: the spec allows it (the Khronos
                // validator warns, GLB_EXTRA_DATA); the stream ends where the header says.
                notes.push(format!(
                    "{}: {} bytes after the end of the GLB stream (its header declares \
                     {declared}) are ignored",
                    self.name,
                    bytes.len() - declared
                ));
                bytes = &bytes[..declared];
            }
            if declared != bytes.len() {
                return Err(self.err(
                    "document",
                    format!(
                        "GLB header declares {declared} bytes but the file has {} (truncated or \
                         corrupted)",
                        bytes.len()
                    ),
                ));
            }
        }
        let glb = gltf::Glb::from_slice(bytes).map_err(|e| self.err("document", e.to_string()))?;
        let json = glb.json.into_owned();
        // Where the BIN chunk lies in the file (the parser borrows it from there).
        let bin = glb.bin.map(|b| {
            let at = b.as_ptr() as usize - file.as_ptr() as usize;
            at..at + b.len()
        });
        Ok((
            json,
            bin.map(|r| {
                file.truncate(r.end);
                file.drain(..r.start);
                file
            }),
        ))
    }

    /// The document, normalised, parsed and validated, and the extension data it drops.
    pub(super) fn read_document(
        &self,
        json: &[u8],
        notes: &mut Vec<String>,
    ) -> Result<(gltf::Document, Extensions), SceneError> {
        let err = |message: String| self.err("document", message);
        let mut value: serde_json::Value =
            serde_json::from_slice(json).map_err(|e| err(format!("not valid JSON: {e}")))?;
        normalize_json(&mut value);
        notes.extend(unknown_enum_values(&mut value, self.name));
        let ext = Extensions::read(&value);
        let json = serde_json::to_vec(&value).map_err(|e| err(e.to_string()))?;
        let root = gltf::json::Root::from_slice(&json).map_err(|e| err(e.to_string()))?;
        let document = gltf::Document::from_json_without_validation(root);
        validate(&document).map_err(err)?;
        check_required_extensions(&document).map_err(err)?;
        Ok((document, ext))
    }
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
pub(super) struct Extensions {
    /// Buffers marked `EXT_meshopt_compression.fallback`.
    pub(super) fallback: Vec<usize>,
    /// `EXT_meshopt_compression` objects of buffer views, by view index.
    pub(super) meshopt: HashMap<usize, serde_json::Value>,
    /// `KHR_draco_mesh_compression` objects of primitives, by (mesh, primitive) index.
    pub(super) draco: HashMap<(usize, usize), serde_json::Value>,
}

impl Extensions {
    pub(super) fn read(root: &serde_json::Value) -> Self {
        let ext =
            |v: &serde_json::Value| v.get("extensions")?.get("EXT_meshopt_compression").cloned();
        let list = |k: &str| {
            root.get(k)
                .and_then(|v| v.as_array())
                .cloned()
                .unwrap_or_default()
        };
        let mut draco = HashMap::new();
        for (m, mesh) in list("meshes").iter().enumerate() {
            let prims = mesh.get("primitives").and_then(|p| p.as_array());
            for (p, prim) in prims.into_iter().flatten().enumerate() {
                if let Some(e) = prim.pointer("/extensions/KHR_draco_mesh_compression") {
                    draco.insert((m, p), e.clone());
                }
            }
        }
        Self {
            draco,
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

/// Extensions that may be required: those read here, and those that only change appearance
/// (materials, textures), which shadow volumes do not depend on.
fn check_required_extensions(document: &gltf::Document) -> Result<(), String> {
    for (i, ext) in document.extensions_required().enumerate() {
        let ok = matches!(
            ext,
            "KHR_lights_punctual"
                | "KHR_mesh_quantization"
                | "EXT_meshopt_compression"
                | "KHR_draco_mesh_compression"
        ) || ext.starts_with("KHR_materials_")
            || ext.starts_with("KHR_texture_")
            || ext.starts_with("EXT_texture_")
            || ext == "MSFT_texture_dds";
        if ok {
            continue;
        }
        return Err(format!(
            "extensionsRequired[{i}]: extension {ext} is required but not supported \
             (supported: KHR_lights_punctual, KHR_mesh_quantization, EXT_meshopt_compression, \
             KHR_draco_mesh_compression, and material and texture extensions, which do not \
             change geometry)"
        ));
    }
    Ok(())
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
