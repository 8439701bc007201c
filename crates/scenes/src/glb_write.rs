//! Writing a [`Scene`] as binary glTF 2.0 (`.glb`), so other tools can open it.
//!
//! Layout: one buffer (the GLB `BIN` chunk); per distinct edge table (`Arc::ptr_eq`) one glTF mesh
//! of its welded positions and kept triangles
//! with one `TRIANGLES` primitive (`POSITION` as `VEC3`/`FLOAT` with `min`/`max`, indices as
//! `UNSIGNED_INT`); per object one node referencing that mesh with its transform as a column-major
//! `matrix` (omitted for the identity). Every `f32` is written through `f64`, so the JSON numbers
//! read back to the same bits. Lights go to `KHR_lights_punctual`: a point light is a node
//! translated to its position; a directional light is a node whose matrix has the light vector
//! (towards the light) as its `Z` column, so the light shines down `-Z` as glTF says, and the
//! loader reads the vector back bit for bit. The camera is a perspective camera on a node with a
//! look-at matrix and the exact target in its extras.

use crate::scene::{points_bounds, Scene};
use crate::SceneError;
use glam::{Affine3A, Vec3};
use serde_json::{json, Value};
use shadowvol_mesh_topology::EdgeTable;
use std::collections::HashMap;
use std::path::Path;

/// Writes `scene` as a `.glb` file.
///
/// Lights go through `KHR_lights_punctual`. glTF has no homogeneous lights: a directional light
/// (`w = 0`) and a point light with `w = 1` are written bit for bit, and a point light with any
/// other `w` is written at `xyz / w` (rounded once in `f32`), so it loads back with `w = 1`.
///
/// # Errors
/// [`SceneError::Export`] if the scene cannot be encoded (over 4 GiB) and
/// [`SceneError::Io`] if the file cannot be written.
pub fn export_glb(scene: &Scene, path: impl AsRef<Path>) -> Result<(), SceneError> {
    let path = path.as_ref();
    let bytes = to_glb(scene)?;
    std::fs::write(path, bytes).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })
}

fn f(x: f32) -> Value {
    json!(f64::from(x))
}

fn v3(v: Vec3) -> Value {
    json!([f64::from(v.x), f64::from(v.y), f64::from(v.z)])
}

/// The scene's lights as `KHR_lights_punctual` lights, each placed by a node appended to
/// `nodes`; a light with a size keeps its radius in its `extras`.
fn light_nodes(scene: &Scene, nodes: &mut Vec<Value>) -> Vec<Value> {
    let mut lights = Vec::new();
    for (i, l) in scene.lights.iter().enumerate() {
        let [x, y, z, w] = l.light.to_array();
        let name = format!("light{i}");
        if w == 0.0 {
            let d = Vec3::new(x, y, z);
            let n = d.normalize_or(Vec3::Z);
            let helper = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
            let xa = helper.cross(n).normalize();
            let ya = n.cross(xa).normalize();
            let t = Affine3A::from_cols(xa.into(), ya.into(), d.into(), glam::Vec3A::ZERO);
            lights.push(
                json!({"name": name, "type": "directional", "color": [1.0, 1.0, 1.0],
            "intensity": 3.0}),
            );
            nodes.push(json!({"name": name, "matrix": matrix(&t),
            "extensions": {"KHR_lights_punctual": {"light": i}}}));
        } else {
            let p = Vec3::new(x, y, z) / w;
            lights.push(
                json!({"name": name, "type": "point", "color": [1.0, 1.0, 1.0],
            "intensity": 100.0}),
            );
            nodes.push(json!({"name": name, "translation": v3(p),
            "extensions": {"KHR_lights_punctual": {"light": i}}}));
        }
        if l.radius > 0.0 {
            // KHR_lights_punctual has no size; the loader reads it back from here.
            if let Some(last) = lights.last_mut() {
                last["extras"] = json!({"radius": l.radius});
            }
        }
    }
    lights
}

fn matrix(t: &Affine3A) -> Value {
    let m = glam::Mat4::from(*t).to_cols_array();
    Value::Array(m.iter().map(|&x| f(x)).collect())
}

/// Encodes `scene` as GLB bytes (see the module documentation for the layout).
///
/// # Errors
/// [`SceneError::Export`] if the binary chunk would exceed the 4 GiB limit of GLB.
pub fn to_glb(scene: &Scene) -> Result<Vec<u8>, SceneError> {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut meshes = Vec::new();
    let mut mesh_ids: HashMap<*const EdgeTable, usize> = HashMap::new();
    let mut nodes = Vec::new();

    for o in &scene.geometry.objects {
        let key = std::sync::Arc::as_ptr(&o.table);
        let mesh_id = if let Some(&id) = mesh_ids.get(&key) {
            id
        } else {
            let m = &*o.table;
            if m.positions.is_empty() || m.triangles.is_empty() {
                return Err(SceneError::Export {
                    message: format!(
                        "object '{}' has an empty mesh; glTF accessors need at least one element",
                        o.name
                    ),
                });
            }
            let pos_view = views.len();
            let offset = bin.len();
            bin.extend_from_slice(bytemuck::cast_slice(&m.positions));
            views.push(json!({"buffer": 0, "byteOffset": offset,
                "byteLength": bin.len() - offset, "target": 34962}));
            let idx_view = views.len();
            let offset = bin.len();
            bin.extend_from_slice(bytemuck::cast_slice(&m.triangles));
            views.push(json!({"buffer": 0, "byteOffset": offset,
                "byteLength": bin.len() - offset, "target": 34963}));
            let (lo, hi) = points_bounds(&m.positions).unwrap_or((Vec3::ZERO, Vec3::ZERO));
            let pos_acc = accessors.len();
            accessors.push(json!({"bufferView": pos_view, "componentType": 5126,
                "count": m.positions.len(), "type": "VEC3", "min": v3(lo), "max": v3(hi)}));
            let idx_acc = accessors.len();
            accessors.push(json!({"bufferView": idx_view, "componentType": 5125,
                "count": m.triangles.len() * 3, "type": "SCALAR"}));
            let id = meshes.len();
            meshes.push(json!({"name": o.name, "primitives": [
                {"attributes": {"POSITION": pos_acc}, "indices": idx_acc, "mode": 4}]}));
            mesh_ids.insert(key, id);
            id
        };
        let mut node = json!({"name": o.name, "mesh": mesh_id});
        if o.world_from_object != Affine3A::IDENTITY {
            node["matrix"] = matrix(&o.world_from_object);
        }
        nodes.push(node);
    }

    let lights = light_nodes(scene, &mut nodes);

    let mut cameras = Vec::new();
    if let Some(c) = scene.camera {
        let back = (c.eye - c.target).normalize_or(Vec3::Z);
        let xa = c.up.cross(back).normalize_or(Vec3::X);
        let ya = back.cross(xa).normalize_or(Vec3::Y);
        let t = Affine3A::from_cols(xa.into(), ya.into(), back.into(), c.eye.into());
        cameras.push(json!({"name": "camera", "type": "perspective",
            "perspective": {"yfov": f(c.fov_y), "znear": f(c.near)}}));
        nodes.push(json!({"name": "camera", "camera": 0, "matrix": matrix(&t),
            "extras": {"target": v3(c.target)}}));
    }

    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "shadowvol-scenes"},
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
    });
    if !meshes.is_empty() {
        doc["meshes"] = Value::Array(meshes);
        doc["accessors"] = Value::Array(accessors);
        doc["bufferViews"] = Value::Array(views);
        doc["buffers"] = json!([{"byteLength": bin.len()}]);
    }
    if !cameras.is_empty() {
        doc["cameras"] = Value::Array(cameras);
    }
    if !lights.is_empty() {
        doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        doc["extensions"] = json!({"KHR_lights_punctual": {"lights": lights}});
    }
    let json_bytes = serde_json::to_vec(&doc).map_err(|e| SceneError::Export {
        message: format!("JSON encoding failed: {e}"),
    })?;
    glb_container(&json_bytes, (!bin.is_empty()).then_some(&bin))
}

/// Frames a glTF JSON document and an optional binary chunk as a GLB 2.0 container: the
/// 12-byte header, the `JSON` chunk padded with spaces and the `BIN` chunk (when `bin` is
/// `Some`, even if empty) padded with zeros, each to 4 bytes. The JSON is not checked.
///
/// # Errors
/// [`SceneError::Export`] if the container would exceed the 4 GiB a GLB header can declare.
pub fn glb_container(json: &[u8], bin: Option<&[u8]>) -> Result<Vec<u8>, SceneError> {
    let pad = |n: usize| n.next_multiple_of(4);
    let total = 12 + 8 + pad(json.len()) + bin.map_or(0, |b| 8 + pad(b.len()));
    let too_big = || SceneError::Export {
        message: format!("the GLB needs {total} bytes, but GLB is limited to 4 GiB"),
    };
    let total32 = u32::try_from(total).map_err(|_| too_big())?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(&0x4654_6C67u32.to_le_bytes()); // "glTF"
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(pad(json.len()) as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes()); // "JSON"
    out.extend_from_slice(json);
    out.resize(out.len() + pad(json.len()) - json.len(), b' ');
    if let Some(bin) = bin {
        out.extend_from_slice(&(pad(bin.len()) as u32).to_le_bytes());
        out.extend_from_slice(&0x004E_4942u32.to_le_bytes()); // "BIN\0"
        out.extend_from_slice(bin);
        out.resize(out.len() + pad(bin.len()) - bin.len(), 0);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::glb_container;

    #[test]
    fn the_container_pads_both_chunks_and_parses_back() {
        let json = br#"{"asset":{"version":"2.0"}}"#; // 27 bytes
        let out = glb_container(json, Some(&[1, 2, 3, 4, 5])).unwrap();
        let word = |i: usize| u32::from_le_bytes(out[i..i + 4].try_into().unwrap()) as usize;
        assert_eq!(&out[..4], b"glTF");
        assert_eq!(word(8), out.len());
        assert_eq!(word(12), 28, "JSON padded to 4 with spaces");
        assert_eq!(&out[20 + 27..20 + 28], b" ");
        assert_eq!(word(48), 8, "BIN padded to 4 with zeros");
        assert_eq!(&out[56..64], &[1, 2, 3, 4, 5, 0, 0, 0]);
        let glb = gltf::Glb::from_slice(&out).unwrap();
        assert_eq!(glb.bin.as_deref(), Some(&[1u8, 2, 3, 4, 5, 0, 0, 0][..]));
        let bare = glb_container(json, None).unwrap();
        assert_eq!(bare.len(), 20 + 28);
        assert!(gltf::Glb::from_slice(&bare).unwrap().bin.is_none());
    }
}
