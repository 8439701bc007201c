//! glTF 2.0 features that the spec calls valid and exporters write: quantized positions
//! (KHR_mesh_quantization), meshopt-compressed views, sparse accessors over a base view,
//! integers written as floats, animations without node targets, skipped non-triangle
//! primitives, several scenes, non-indexed primitives; and the refusals (unknown required
//! extensions, quantized positions without the extension). Draco has tests/draco.rs.

mod common;
use common::glb;

use glam::Vec3;
use serde_json::json;
use shadowvol_scenes::{load_gltf_slice, load_gltf_slice_with_notes};

fn err(doc: &serde_json::Value, bin: &[u8]) -> String {
    load_gltf_slice(&glb(doc, bin), "t.glb", None)
        .unwrap_err()
        .to_string()
}

/// One triangle whose positions are `components` of `component_type` (3 per vertex, each vertex
/// padded to 4-byte alignment), indices 0, 1, 2 as u8.
fn quantized_doc(
    component_type: u32,
    normalized: bool,
    size: usize,
    ext: bool,
) -> serde_json::Value {
    let stride = (3 * size).next_multiple_of(4);
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "scale": [2.0, 2.0, 2.0], "translation": [0.5, 0.0, 0.0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": 3 * stride}],
        "bufferViews": [{"buffer": 0, "byteLength": 3 * stride, "byteStride": stride}],
        "accessors": [{"bufferView": 0, "componentType": component_type, "type": "VEC3",
                       "count": 3, "normalized": normalized}],
    });
    if ext {
        doc["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    }
    doc
}

fn quantized_bin(raw: &[[i64; 3]; 3], size: usize) -> Vec<u8> {
    let stride = (3 * size).next_multiple_of(4);
    let mut out = vec![0u8; 3 * stride];
    for (v, p) in raw.iter().enumerate() {
        for (c, &x) in p.iter().enumerate() {
            let o = v * stride + c * size;
            out[o..o + size].copy_from_slice(&x.to_le_bytes()[..size]);
        }
    }
    out
}

#[test]
fn quantized_positions_decode_by_the_spec_then_take_the_node_transform_in_f32() {
    // (componentType, byte size, normalized, raw values, decoding in f32)
    type Case = (u32, usize, bool, [[i64; 3]; 3], fn(i64) -> f32);
    let cases: [Case; 8] = [
        (
            5120,
            1,
            false,
            [[-128, 0, 127], [1, -1, 5], [7, 9, -3]],
            |c| c as f32,
        ),
        (5121, 1, false, [[0, 255, 3], [1, 2, 250], [9, 8, 7]], |c| {
            c as f32
        }),
        (
            5122,
            2,
            false,
            [[-32768, 32767, 0], [1, -5, 9], [300, 0, -2]],
            |c| c as f32,
        ),
        (
            5123,
            2,
            false,
            [[0, 65535, 1], [2, 3, 40000], [5, 7, 11]],
            |c| c as f32,
        ),
        (
            5120,
            1,
            true,
            [[-128, -127, 127], [1, 64, -5], [7, 9, -3]],
            |c| (c as f32 / 127.0).max(-1.0),
        ),
        (5121, 1, true, [[0, 255, 3], [1, 2, 250], [9, 8, 7]], |c| {
            c as f32 / 255.0
        }),
        (
            5122,
            2,
            true,
            [[-32768, 32767, 0], [1, -5, 9], [300, 0, -2]],
            |c| (c as f32 / 32767.0).max(-1.0),
        ),
        (
            5123,
            2,
            true,
            [[0, 65535, 1], [2, 3, 40000], [5, 7, 11]],
            |c| c as f32 / 65535.0,
        ),
    ];
    for (ty, size, normalized, raw, decode) in cases {
        let doc = quantized_doc(ty, normalized, size, true);
        let scene = load_gltf_slice(&glb(&doc, &quantized_bin(&raw, size)), "q.glb", None)
            .unwrap_or_else(|e| panic!("{ty} {normalized}: {e}"));
        let mesh = scene.baked_table().unwrap();
        let expected: Vec<Vec3> = raw
            .iter()
            .map(|p| {
                let local = Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]));
                local * 2.0 + Vec3::new(0.5, 0.0, 0.0)
            })
            .collect();
        assert_eq!(
            mesh.positions, expected,
            "componentType {ty}, normalized {normalized}"
        );
        assert_eq!(
            mesh.triangles,
            [[0, 1, 2]],
            "non-indexed: vertices in order"
        );
    }
    // Without the extension, integer positions are invalid glTF.
    let doc = quantized_doc(5123, false, 2, false);
    let m = err(&doc, &quantized_bin(&[[0, 1, 2], [3, 4, 5], [6, 7, 9]], 2));
    assert!(
        m.contains("accessor 0 (POSITION)") && m.contains("KHR_mesh_quantization"),
        "{m}"
    );
}

/// Positions of a unit quad and its two triangles, as f32 and u16 bytes.
fn quad() -> (Vec<u8>, Vec<u8>) {
    let p: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let i: [u16; 6] = [0, 1, 2, 0, 2, 3];
    (
        bytemuck::cast_slice(&p).to_vec(),
        bytemuck::cast_slice(&i).to_vec(),
    )
}

/// A document over [`quad`]'s buffer (positions as accessor 0, indices as accessor 1) with
/// these `nodes` and `meshes`.
fn quad_doc(nodes: serde_json::Value, meshes: serde_json::Value) -> serde_json::Value {
    json!({
        "asset": {"version": "2.0"},
        "nodes": nodes,
        "meshes": meshes,
        "buffers": [{"byteLength": 60}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 4},
            {"bufferView": 1, "componentType": 5123, "type": "SCALAR", "count": 6}
        ],
    })
}

#[test]
fn meshopt_compressed_views_decode_to_the_uncompressed_data_and_fallbacks_are_not_read() {
    let (pos, idx) = quad();
    let verts: Vec<[u8; 12]> = pos
        .chunks_exact(12)
        .map(|c| c.try_into().unwrap())
        .collect();
    let vbuf = meshopt::encode_vertex_buffer(&verts).unwrap();
    let ibuf = meshopt::encode_index_buffer(&[0, 1, 2, 0, 2, 3], 4).unwrap();
    let mut bin = vbuf.clone();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let ioff = bin.len();
    bin.extend_from_slice(&ibuf);
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression"],
        "extensionsRequired": ["EXT_meshopt_compression"],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [
            {"byteLength": bin.len()},
            {"byteLength": 60, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ],
        "bufferViews": [
            {"buffer": 1, "byteOffset": 0, "byteLength": 48, "byteStride": 12,
             "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": 0,
                 "byteLength": vbuf.len(), "byteStride": 12, "mode": "ATTRIBUTES", "count": 4}}},
            {"buffer": 1, "byteOffset": 48, "byteLength": 12,
             "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": ioff,
                 "byteLength": ibuf.len(), "byteStride": 2, "mode": "TRIANGLES", "count": 6}}}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 4},
            {"bufferView": 1, "componentType": 5123, "type": "SCALAR", "count": 6}
        ],
    });
    let mesh = load_gltf_slice(&glb(&doc, &bin), "c.glb", None)
        .unwrap()
        .baked_table()
        .unwrap();
    let expected: Vec<Vec3> = bytemuck::cast_slice::<u8, [f32; 3]>(&pos)
        .iter()
        .map(|&p| Vec3::from_array(p))
        .collect();
    assert_eq!(mesh.positions, expected);
    assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(idx.len(), 12);

    // A corrupted stream, a wrong count, a view of the fallback that is not compressed.
    let mut bad = bin.clone();
    bad[0] ^= 0xff;
    let m = err(&doc, &bad);
    assert!(
        m.contains("buffer view 0, EXT_meshopt_compression") && m.contains("does not decode"),
        "{m}"
    );
    let mut d = doc.clone();
    d["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["count"] = json!(5);
    let m = err(&d, &bin);
    assert!(m.contains("buffer view 1") && m.contains("count 5"), "{m}");
    let mut d = doc.clone();
    d["bufferViews"][1]["extensions"] = json!({});
    let m = err(&d, &bin);
    assert!(
        m.contains("fallback") && m.contains("not compressed"),
        "{m}"
    );
    let mut d = doc.clone();
    d["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["byteStride"] = json!(6);
    d["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["count"] = json!(8);
    let m = err(&d, &bin);
    assert!(m.contains("byteStride 6"), "{m}");
}

#[test]
fn sparse_accessor_over_a_base_view_replaces_only_its_elements() {
    let (pos, idx) = quad();
    let mut bin = pos.clone(); // view 0
    bin.extend_from_slice(&idx); // view 1 at 48
    bin.extend_from_slice(&[2u8, 0, 0, 0]); // view 2 at 60: sparse index 2 (u8), padded
    bin.extend_from_slice(bytemuck::cast_slice(&[7.0f32, 8.0, 9.0])); // view 3 at 64
    let doc = json!({
        "asset": {"version": "2.0"},
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12},
            {"buffer": 0, "byteOffset": 60, "byteLength": 1},
            {"buffer": 0, "byteOffset": 64, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 4,
             "sparse": {"count": 1, "indices": {"bufferView": 2, "componentType": 5121},
                        "values": {"bufferView": 3}}},
            {"bufferView": 1, "componentType": 5123, "type": "SCALAR", "count": 6}
        ],
    });
    let mesh = load_gltf_slice(&glb(&doc, &bin), "s.glb", None)
        .unwrap()
        .baked_table()
        .unwrap();
    assert_eq!(
        mesh.positions,
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [7.0, 8.0, 9.0],
            [0.0, 1.0, 0.0]
        ]
        .map(Vec3::from_array)
    );
}

#[test]
fn integers_written_as_floats_and_animations_without_node_targets_are_valid() {
    let (pos, idx) = quad();
    let mut bin = pos.clone();
    bin.extend_from_slice(&idx);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 1.0,
        "scenes": [{"nodes": [0.0]}, {"nodes": [1.0]}],
        "nodes": [{"mesh": 0.0, "translation": [100.0, 0.0, 0.0]},
                  {"mesh": 0.0, "translation": [-0.0, 2.0, 0.0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0.0}, "indices": 1e0, "mode": 4.0}]}],
        "buffers": [{"byteLength": 60.0}],
        "bufferViews": [
            {"buffer": 0.0, "byteOffset": 0.0, "byteLength": 48.0},
            {"buffer": 0.0, "byteOffset": 48.0, "byteLength": 12.0}
        ],
        "accessors": [
            {"bufferView": 0.0, "componentType": 5126.0, "type": "VEC3", "count": 4.0},
            {"bufferView": 1.0, "componentType": 5123.0, "type": "SCALAR", "count": 6.0}
        ],
        "animations": [{
            "channels": [{"sampler": 0, "target": {"path": "pointer",
                "extensions": {"KHR_animation_pointer": {"pointer": "/nodes/0/weights"}}}}],
            "samplers": [{"input": 0, "output": 0}]
        }],
    });
    let scene = load_gltf_slice(&glb(&doc, &bin), "f.glb", None).unwrap();
    // "scene": 1 picks the second scene: only node 1.
    assert_eq!(scene.geometry.objects.len(), 1);
    assert_eq!(
        scene.geometry.objects[0].world_from_object.translation.y,
        2.0
    );
    // A fractional index is still an error.
    let mut d = doc.clone();
    d["accessors"][0]["count"] = json!(4.5);
    assert!(err(&d, &bin).contains("document"));
}

#[test]
fn non_triangle_primitives_and_primitives_without_positions_are_skipped_with_notes() {
    let (pos, idx) = quad();
    let mut bin = pos.clone();
    bin.extend_from_slice(&idx);
    let doc = quad_doc(
        json!([
            {"mesh": 0, "name": "mixed"},
            {"mesh": 1, "name": "lines"},
            {"mesh": 1, "name": "again"},
            {"mesh": 2, "name": "more"}
        ]),
        json!([
            {"primitives": [
                {"attributes": {"POSITION": 0}, "indices": 1, "mode": 1},
                {"attributes": {"POSITION": 0}, "indices": 1},
                {"attributes": {}, "indices": 1},
                {"attributes": {"POSITION": 0}, "mode": 0}
            ]},
            {"primitives": [{"attributes": {"POSITION": 0}, "mode": 3}]},
            {"primitives": [
                {"attributes": {"POSITION": 0}, "mode": 0},
                {"attributes": {"POSITION": 0}, "indices": 1}
            ]}
        ]),
    );
    let (scene, notes) = load_gltf_slice_with_notes(&glb(&doc, &bin), "m.glb", None).unwrap();
    assert_eq!(
        scene.geometry.objects.len(),
        2,
        "the nodes left without triangles are skipped"
    );
    assert_eq!(
        scene.geometry.objects[0].table.triangles,
        [[0, 1, 2], [0, 2, 3]]
    );
    assert_eq!(scene.geometry.objects[1].name, "more");
    // The notes come in the walk's order, a skipped node's own note where the walk reached it
    // (the tables are built after the walk).
    let expected: [&[&str]; 7] = [
        &["m.glb", "node 0 'mixed'", "primitive 0", "Lines", "skipped"],
        &["node 0 'mixed'", "primitive 2", "no POSITION"],
        &["node 0 'mixed'", "primitive 3", "Points"],
        &["node 1 'lines'", "mesh 1", "primitive 0", "LineStrip"],
        &[
            "node 1 'lines'",
            "mesh 1 has no triangles",
            "node is skipped",
        ],
        &[
            "node 2 'again'",
            "mesh 1 has no triangles",
            "node is skipped",
        ],
        &["node 3 'more'", "mesh 2", "primitive 0", "Points"],
    ];
    assert_eq!(notes.len(), expected.len(), "{notes:#?}");
    for (note, parts) in notes.iter().zip(expected) {
        assert!(parts.iter().all(|p| note.contains(p)), "{notes:#?}");
    }
}

#[test]
fn an_instance_whose_transform_takes_a_vertex_past_f32_is_refused_by_vertex() {
    let (pos, idx) = quad();
    let mut bin = pos.clone();
    bin.extend_from_slice(&idx);
    // Node 0 is in range; node 1 shares its mesh, and takes vertex 1 (x = 1) to 4e38.
    let doc = quad_doc(
        json!([
            {"mesh": 0},
            {"mesh": 0, "scale": [2e38, 1.0, 1.0], "translation": [2e38, 0.0, 0.0]}
        ]),
        json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}]),
    );
    let e = err(&doc, &bin);
    for part in [
        "t.glb",
        "node 1, mesh 0",
        "vertex 1",
        "coordinate x is inf",
        "past the f32 range",
    ] {
        assert!(e.contains(part), "{part:?} not in {e}");
    }
}

#[test]
fn unknown_required_extensions_are_refused_by_name() {
    let (pos, idx) = quad();
    let mut bin = pos.clone();
    bin.extend_from_slice(&idx);
    let mut doc = quad_doc(
        json!([{"mesh": 0}]),
        json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}]),
    );
    // Draco required, but no primitive uses it: the accessors are read.
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    assert!(load_gltf_slice(&glb(&doc, &bin), "t.glb", None).is_ok());
    doc["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    doc["extensionsRequired"] = json!(["EXT_mesh_gpu_instancing"]);
    let m = err(&doc, &bin);
    assert!(
        m.contains("EXT_mesh_gpu_instancing is required but not supported"),
        "{m}"
    );
    // Material extensions do not change geometry.
    doc["extensionsUsed"] = json!(["KHR_materials_unlit", "KHR_texture_transform"]);
    doc["extensionsRequired"] = json!(["KHR_materials_unlit", "KHR_texture_transform"]);
    assert!(load_gltf_slice(&glb(&doc, &bin), "t.glb", None).is_ok());
}
