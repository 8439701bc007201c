//! glTF loading and GLB export: round trips and node transforms against hand-flattened meshes.

mod common;
use common::glb;

use glam::Vec3;
use serde_json::json;
use shadowvol_cpu::CpuBackend;
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_scenes::{
    load_gltf, load_gltf_slice, load_gltf_slice_with_notes, preset, to_glb, Scene,
};
use shadowvol_silhouette::{
    extract_once, invariant, Accuracy, Light, Multiplicities, TopologyScene,
};
use std::collections::BTreeMap;
use std::sync::Arc;

fn silhouettes(scene: &TopologyScene, lights: &[Light], mode: Accuracy) -> Multiplicities {
    extract_once(&mut CpuBackend::new(), scene, lights, mode)
        .unwrap()
        .0
}

/// Exports `scene` to a temporary .glb, loads it back, and checks that everything that matters
/// for silhouettes is identical: objects, meshes, transforms, sharing, lights, topology
/// statistics, and the multiplicities of every edge in every mode (cpu backend).
fn round_trip(name: &str) {
    let original = preset(name).unwrap();
    let path = std::env::temp_dir().join(format!(
        "shadowvol-roundtrip-{}-{name}.glb",
        std::process::id()
    ));
    shadowvol_scenes::export_glb(&original, &path).unwrap();
    let loaded = load_gltf(&path).unwrap();
    std::fs::remove_file(&path).ok();

    let (o0, o1) = (&original.geometry.objects, &loaded.geometry.objects);
    assert_eq!(o1.len(), o0.len(), "{name}");
    for (a, b) in o0.iter().zip(o1) {
        assert_eq!(a.name, b.name);
        assert_eq!(
            a.world_from_object, b.world_from_object,
            "{name}: {}",
            a.name
        );
        same_geometry(&a.table, &b.table, &format!("{name}: mesh of {}", a.name));
    }
    // Instances that shared a mesh still share one (and only those).
    for (i, a) in o0.iter().enumerate() {
        for (j, b) in o0.iter().enumerate().skip(i + 1) {
            assert_eq!(
                Arc::ptr_eq(&a.table, &b.table),
                Arc::ptr_eq(&o1[i].table, &o1[j].table),
                "{name}: sharing of objects {i} and {j}"
            );
        }
    }
    // glTF has no homogeneous lights: a point light with w other than 1 is written at xyz / w
    // (rounded once in f32) with w = 1; w = 0 (directional) and w = 1 are kept bit for bit.
    let representable: Vec<Light> = original
        .light_positions()
        .iter()
        .map(|l| {
            let [x, y, z, w] = l.to_array();
            if w == 0.0 || w == 1.0 {
                *l
            } else {
                Light::point(Vec3::new(x, y, z) / w)
            }
        })
        .collect();
    assert_eq!(loaded.light_positions(), representable, "{name}: lights");
    let (c0, c1) = (original.camera.unwrap(), loaded.camera.unwrap());
    assert_eq!(c0.target, c1.target);
    assert!((c0.eye - c1.eye).length() <= 1e-4 * c0.eye.length().max(1.0));
    assert_eq!(c0.fov_y, c1.fov_y);
    assert_eq!(c0.near, c1.near);

    let (t0, t1) = (&original.geometry, &loaded.geometry);
    let mut lights = original.light_positions();
    lights.push(Light::point(Vec3::new(0.25, 30.0, -0.5)));
    for mode in [Accuracy::Exact, Accuracy::Original] {
        let (m0, m1) = (
            silhouettes(t0, &lights, mode),
            silhouettes(t1, &lights, mode),
        );
        assert_eq!(m0.all_values(), m1.all_values(), "{name}: {mode:?}");
        for l in 0..lights.len() {
            assert_eq!(m0.silhouette(l), m1.silhouette(l));
            if mode == Accuracy::Exact {
                assert_eq!(invariant::open_vertices_scene(t1, &m1, l), 0, "{name}");
            }
        }
    }
    // The flattened (baked) tables agree too.
    let (b0, b1) = (
        original.baked_table().unwrap(),
        loaded.baked_table().unwrap(),
    );
    same_geometry(&b0, &b1, &format!("{name}: baked"));
}

/// The export writes welded tables, so a reloaded table has the same positions, triangles,
/// edges and opposite vertices (what silhouettes and images depend on); the input numbering
/// (vertex names, triangle sources, input counts) is the welded one.
fn same_geometry(a: &EdgeTable, b: &EdgeTable, what: &str) {
    assert_eq!(a.positions, b.positions, "{what}: positions");
    assert_eq!(a.triangles, b.triangles, "{what}: triangles");
    assert_eq!(a.edges, b.edges, "{what}: edges");
    assert_eq!(a.ov_offsets, b.ov_offsets, "{what}: ov_offsets");
    assert_eq!(a.ov_refs, b.ov_refs, "{what}: ov_refs");
    assert_eq!(
        b.stats.vertices, a.stats.welded_vertices,
        "{what}: vertices"
    );
    assert_eq!(b.stats.degenerate_triangles, 0, "{what}: degenerate");
}

#[test]
fn round_trip_sphere_grid() {
    round_trip("spheres-100x1k");
}

#[test]
fn round_trip_bunnies() {
    round_trip("bunnies-10-individual");
}

#[test]
fn round_trip_every_hard_case() {
    let names = shadowvol_scenes::preset_names();
    let hard: Vec<_> = names.iter().filter(|n| n.starts_with("hard-")).collect();
    assert!(hard.len() >= 3);
    for name in hard {
        round_trip(name);
    }
}

#[test]
fn glb_is_well_formed() {
    let scene = preset("hard-multi-object-transforms").unwrap();
    let glb = to_glb(&scene).unwrap();
    assert_eq!(&glb[0..4], b"glTF");
    assert_eq!(u32::from_le_bytes(glb[4..8].try_into().unwrap()), 2);
    assert_eq!(
        u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize,
        glb.len()
    );
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    assert_eq!(&glb[16..20], b"JSON");
    assert_eq!(json_len % 4, 0);
    let doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    assert_eq!(doc["asset"]["version"], "2.0");
    assert_eq!(doc["extensionsUsed"][0], "KHR_lights_punctual");
    let bin = &glb[20 + json_len..];
    assert_eq!(&bin[4..8], b"BIN\0");
    assert_eq!(
        u32::from_le_bytes(bin[0..4].try_into().unwrap()) as u64,
        doc["buffers"][0]["byteLength"].as_u64().unwrap()
    );
    // And the gltf crate, with its full validation (POSITION min/max included), accepts it.
    let gltf = gltf::Gltf::from_slice(&glb).unwrap();
    assert_eq!(gltf.meshes().count(), scene.geometry.objects.len());
}

struct Bin {
    data: Vec<u8>,
    views: Vec<serde_json::Value>,
    accessors: Vec<serde_json::Value>,
}

impl Bin {
    fn add(&mut self, bytes: &[u8], component: u32, ty: &str, count: usize) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len()}));
        self.data.extend_from_slice(bytes);
        self.accessors.push(
            json!({"bufferView": self.views.len() - 1, "componentType": component,
            "type": ty, "count": count}),
        );
        self.accessors.len() - 1
    }
    fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        self.add(bytemuck::cast_slice(p), 5126, "VEC3", p.len())
    }
}

const TETRA: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const TETRA_IDX: [u16; 12] = [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];
const QUAD: [[f32; 3]; 6] = [
    [2.0, 0.0, 0.0],
    [3.0, 0.0, 0.0],
    [2.0, 1.0, 0.0],
    [3.0, 0.0, 0.0],
    [3.0, 1.0, 0.0],
    [2.0, 1.0, 0.0],
];
const STRIP: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 1.0, 0.0],
];

/// A glTF with nested node transforms (TRS and matrix), a mesh of two primitives (indexed u16 and
/// non-indexed) shared by two nodes, a triangle strip with u8 indices, a point light under a
/// scaled parent, a directional light and a camera.
fn nested_glb() -> Vec<u8> {
    let mut b = Bin {
        data: vec![],
        views: vec![],
        accessors: vec![],
    };
    let p0 = b.positions(&TETRA);
    let i0 = b.add(bytemuck::cast_slice(&TETRA_IDX), 5123, "SCALAR", 12);
    let p1 = b.positions(&QUAD);
    let p2 = b.positions(&STRIP);
    let i2 = b.add(&[0u8, 1, 2, 3], 5121, "SCALAR", 4);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 4, 6, 7]}],
        "nodes": [
            {"name": "root", "translation": [10.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0], "children": [1, 2, 5]},
            {"name": "a", "mesh": 0, "translation": [0.0, 3.0, 0.0]},
            // 90° about Z (x -> y, y -> -x), then up 5 in z.
            {"name": "b", "matrix": [0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 5.0, 1.0],
             "children": [3]},
            {"name": "c", "mesh": 0, "translation": [1.0, 1.0, 1.0]},
            {"name": "d", "mesh": 1, "translation": [-4.0, 0.0, 0.0]},
            {"name": "lamp", "translation": [3.0, 20.0, 7.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            // Shines down -Z of a frame whose Z column is world +Y: towards the light is +Y.
            {"name": "sun", "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "eye", "camera": 0, "translation": [0.0, 5.0, 30.0]}
        ],
        "meshes": [
            {"name": "pair", "primitives": [
                {"attributes": {"POSITION": p0}, "indices": i0},
                {"attributes": {"POSITION": p1}, "mode": 4}]},
            {"name": "strip", "primitives": [{"attributes": {"POSITION": p2}, "indices": i2, "mode": 5}]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "spot": {}}, {"type": "directional"}]}},
        "buffers": [{"byteLength": b.data.len()}],
        "bufferViews": b.views,
        "accessors": b.accessors,
    });
    glb(&doc, &b.data)
}

/// The same scene flattened by hand (integer arithmetic, exact in f32).
fn hand_flattened() -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let pair: Vec<[f32; 3]> = TETRA.iter().chain(QUAD.iter()).copied().collect();
    let mut pair_tris: Vec<[u32; 3]> = TETRA_IDX
        .chunks(3)
        .map(|c| [c[0].into(), c[1].into(), c[2].into()])
        .collect();
    pair_tris.extend([[4, 5, 6], [7, 8, 9]]);
    // a: root(T(10,0,0) S2) * T(0,3,0)
    let a = |[x, y, z]: [f32; 3]| Vec3::new(10.0 + 2.0 * x, 2.0 * (y + 3.0), 2.0 * z);
    // c: root * b(R_z(90°), T(0,0,5)) * T(1,1,1)
    let c = |[x, y, z]: [f32; 3]| {
        Vec3::new(
            10.0 - 2.0 * (y + 1.0),
            2.0 * (x + 1.0),
            2.0 * (z + 1.0 + 5.0),
        )
    };
    for f in [&a as &dyn Fn([f32; 3]) -> Vec3, &c] {
        let base = positions.len() as u32;
        positions.extend(pair.iter().map(|&p| f(p)));
        triangles.extend(pair_tris.iter().map(|t| t.map(|i| i + base)));
    }
    let base = positions.len() as u32;
    positions.extend(STRIP.iter().map(|&[x, y, z]| Vec3::new(x - 4.0, y, z)));
    triangles.extend([[base, base + 1, base + 2], [base + 2, base + 1, base + 3]]);
    Mesh::new(positions, triangles).unwrap()
}

/// Global edges `(name_a, name_b) -> m` of a scene whose objects are concatenated in order
/// (the numbering of the baked mesh), for light `l`.
fn edge_map(scene: &TopologyScene, m: &Multiplicities, l: usize) -> BTreeMap<(u32, u32), i32> {
    let offsets = scene.edge_offsets();
    let mut out = BTreeMap::new();
    let mut vertex_base = 0u32;
    for (i, o) in scene.objects.iter().enumerate() {
        for (e, &[a, b]) in o.table.edges.iter().enumerate() {
            let v = m.values(l)[offsets[i] + e];
            if v != 0 {
                let key = (
                    o.table.vertex_names.get(a as usize) + vertex_base,
                    o.table.vertex_names.get(b as usize) + vertex_base,
                );
                out.insert(key, v);
            }
        }
        vertex_base += o.table.stats.vertices as u32;
    }
    out
}

#[test]
fn nested_transforms_match_the_hand_flattened_mesh() {
    let scene = load_gltf_slice(&nested_glb(), "nested.glb", None).unwrap();
    let objects = &scene.geometry.objects;
    let names: Vec<_> = objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["a", "c", "d"], "depth-first node order");
    assert!(
        Arc::ptr_eq(&objects[0].table, &objects[1].table),
        "mesh 0 is shared"
    );
    assert_eq!(
        scene.light_positions(),
        vec![
            Light::point(Vec3::new(16.0, 40.0, 14.0)),
            Light::directional(Vec3::Y)
        ],
        "spot read as a point light under the scaled parent; directional along +Y"
    );
    let cam = scene.camera.unwrap();
    assert_eq!(
        (cam.eye, cam.target, cam.fov_y, cam.near),
        (
            Vec3::new(0.0, 5.0, 30.0),
            Vec3::new(0.0, 5.0, 29.0),
            0.8,
            0.1
        )
    );

    let flat = EdgeTable::build(&hand_flattened()).unwrap();
    let baked = scene.baked_table().unwrap();
    assert_eq!(
        *baked, flat,
        "numbering and f32 positions follow the CLI contract"
    );

    // Exact silhouettes: the flattened mesh, the loaded scene baked, and the loaded scene with
    // its objects kept separate (lights brought into object space) all agree.
    let flat_scene = TopologyScene::single(flat);
    let baked_scene = TopologyScene::single((*baked).clone());
    let objects = &scene.geometry;
    let mut lights = scene.light_positions();
    lights.extend([
        Light::point(Vec3::new(12.0, 6.0, 0.0)), // at a vertex of object a
        Light::point(Vec3::new(15.0, 6.0, 0.0)), // in the plane of a's quad, on an edge line
        Light::point(Vec3::new(-3.5, 0.5, 0.0)), // in the plane of the strip
        Light::directional(Vec3::new(1.0, 0.0, 0.0)), // parallel to the quad and the strip
    ]);
    let mf = silhouettes(&flat_scene, &lights, Accuracy::Exact);
    let mb = silhouettes(&baked_scene, &lights, Accuracy::Exact);
    let mo = silhouettes(objects, &lights, Accuracy::Exact);
    assert_eq!(mf.all_values(), mb.all_values());
    for l in 0..lights.len() {
        let fm = edge_map(&flat_scene, &mf, l);
        assert!(!fm.is_empty(), "light {l} has a silhouette");
        assert_eq!(
            fm,
            edge_map(objects, &mo, l),
            "light {l}: per-object vs flattened"
        );
        assert_eq!(invariant::open_vertices_scene(objects, &mo, l), 0);
    }
}

#[test]
fn gltf_text_with_external_buffer_loads_like_the_glb() {
    // The same document as .gltf + .bin next to it.
    let bytes = nested_glb();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin = &bytes[20 + json_len + 8..];
    let dir = std::env::temp_dir().join(format!("shadowvol-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("nested.bin"), bin).unwrap();
    doc["buffers"][0]["uri"] = json!("nested.bin");
    let path = dir.join("nested.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let a = Scene::load(&path).unwrap();
    let b = load_gltf_slice(&bytes, "nested.glb", None).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(a.baked_table().unwrap(), b.baked_table().unwrap());
    assert_eq!(a.lights, b.lights);
    assert_eq!(a.name, "nested.gltf");
}

#[test]
fn sparse_strided_and_fan_accessors_are_read() {
    // Positions interleaved with a padding float (byteStride 16); a sparse accessor without a
    // buffer view (zeros, then 3 substituted elements); a triangle fan with u16 indices.
    let mut data: Vec<u8> = Vec::new();
    let interleaved: [[f32; 4]; 4] = [
        [0.0, 0.0, 0.0, 9.0],
        [1.0, 0.0, 0.0, 9.0],
        [1.0, 1.0, 0.0, 9.0],
        [0.0, 1.0, 0.0, 9.0],
    ];
    data.extend_from_slice(bytemuck::cast_slice(&interleaved)); // view 0: 64 bytes
    data.extend_from_slice(bytemuck::cast_slice(&[0u16, 1, 2, 3])); // view 1: 8 bytes at 64
    data.extend_from_slice(bytemuck::cast_slice(&[1u32, 2, 3])); // view 2: sparse indices at 72
    let sparse_values: [[f32; 3]; 3] = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]];
    data.extend_from_slice(bytemuck::cast_slice(&sparse_values)); // view 3: at 84
    let doc = json!({
        "asset": {"version": "2.0"},
        "nodes": [{"name": "fan", "mesh": 0}, {"name": "tet", "mesh": 1, "translation": [0.0, 0.0, 10.0]}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 6}]},
            {"primitives": [{"attributes": {"POSITION": 2}, "indices": 3}]}
        ],
        "buffers": [{"byteLength": data.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 64, "byteStride": 16},
            {"buffer": 0, "byteOffset": 64, "byteLength": 8},
            {"buffer": 0, "byteOffset": 72, "byteLength": 12},
            {"buffer": 0, "byteOffset": 84, "byteLength": 36},
            {"buffer": 0, "byteOffset": 64, "byteLength": 8}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 4},
            {"bufferView": 1, "componentType": 5123, "type": "SCALAR", "count": 4},
            {"componentType": 5126, "type": "VEC3", "count": 4,
             "sparse": {"count": 3, "indices": {"bufferView": 2, "componentType": 5125},
                        "values": {"bufferView": 3}}},
            // The first three of the same u16 indices: one triangle of the sparse mesh.
            {"bufferView": 4, "componentType": 5123, "type": "SCALAR", "count": 3}
        ],
    });
    // No "scenes": every root node is visited in index order.
    let scene = load_gltf_slice(&glb(&doc, &data), "sparse.glb", None).unwrap();
    let baked = scene.baked_table().unwrap();
    let positions = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 10.0],
        [5.0, 0.0, 10.0],
        [0.0, 5.0, 10.0],
        [0.0, 0.0, 15.0],
    ]
    .map(Vec3::from_array);
    let expected = Mesh::new(positions.to_vec(), vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]]).unwrap();
    assert_eq!(*baked, EdgeTable::build(&expected).unwrap());
}

/// A tetrahedron and one light of `light` (a KHR_lights_punctual light object) at a node that
/// turns `-Z` towards world `-Y` and stands at (1, 8, 2).
fn lit_glb(light: serde_json::Value) -> Vec<u8> {
    let mut b = Bin {
        data: vec![],
        views: vec![],
        accessors: vec![],
    };
    let p0 = b.positions(&TETRA);
    let i0 = b.add(bytemuck::cast_slice(&TETRA_IDX), 5123, "SCALAR", 12);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "t", "mesh": 0},
            // Columns: x -> x, y -> -z, z -> +y: the node's -Z is world -Y.
            {"name": "lamp", "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 8.0, 2.0, 1.0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p0}, "indices": i0}]}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [light]}},
        "buffers": [{"byteLength": b.data.len()}],
        "bufferViews": b.views,
        "accessors": b.accessors,
    });
    glb(&doc, &b.data)
}

/// Colour, intensity, range and the spot cone are read as the spec defines them, with the spot's
/// axis the node's `-Z`; a point light without them gets the spec's defaults.
#[test]
fn light_emission_is_read() {
    let spot = json!({"type": "spot", "color": [1.0, 0.5, 0.25], "intensity": 40.0, "range": 12.5,
                      "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}});
    let s = load_gltf_slice(&lit_glb(spot), "spot.glb", None).unwrap();
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.lights[0].light.to_array(), [1.0, 8.0, 2.0, 1.0]);
    let e = s.lights[0].emission.unwrap();
    assert_eq!(e.color, [1.0, 0.5, 0.25]);
    assert_eq!(e.intensity, 40.0);
    assert_eq!(e.range, Some(12.5));
    let cone = e.spot.unwrap();
    assert_eq!((cone.inner_cone_angle, cone.outer_cone_angle), (0.2, 0.5));
    assert!((cone.direction - Vec3::NEG_Y).length() < 1e-6, "{cone:?}");

    let s = load_gltf_slice(&lit_glb(json!({"type": "point"})), "p.glb", None).unwrap();
    assert_eq!(
        s.lights[0].emission,
        Some(shadowvol_scenes::Emission::default())
    );
    // The spec's default outer cone is π/4, inner 0.
    let s = load_gltf_slice(&lit_glb(json!({"type": "spot", "spot": {}})), "s.glb", None).unwrap();
    let cone = s.lights[0].emission.unwrap().spot.unwrap();
    assert_eq!(cone.inner_cone_angle, 0.0);
    assert!((cone.outer_cone_angle - std::f32::consts::FRAC_PI_4).abs() < 1e-6);
}

#[test]
fn bad_light_emission_is_refused_naming_the_light() {
    for (light, what) in [
        (json!({"type": "point", "intensity": -1.0}), "intensity"),
        (json!({"type": "point", "range": 0.0}), "range"),
        (json!({"type": "point", "color": [2.0, 0.0, 0.0]}), "color"),
        (
            json!({"type": "spot", "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.5}}),
            "cone",
        ),
    ] {
        let e = load_gltf_slice(&lit_glb(light.clone()), "bad.glb", None).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("light 0") && msg.contains(what),
            "{light}: {msg}"
        );
    }
}

/// A `.gltf` whose buffer has no `uri` is valid JSON (such a buffer names a GLB's binary chunk,
/// and the Khronos validator reports no error for it), but the file has no chunk: the loader
/// says which buffer and why its data is missing (as for the validator's
/// `root/named_objects.gltf` and `root/unused_objects.gltf`), not the gltf crate's "missing
/// binary portion of binary glTF".
#[test]
fn a_gltf_buffer_without_uri_is_refused_naming_the_missing_data() {
    let json = r#"{
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36}]
    }"#;
    let e = load_gltf_slice(json.as_bytes(), "no_uri.gltf", None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("buffer 0 has no uri and no GLB binary chunk holds it"),
        "{e}"
    );
    assert!(e.contains("the 36 bytes"), "{e}");
}

/// A triangle as a GLB, with `extra` merged into the document (for the enum tests).
fn triangle_gltf(extra: serde_json::Value) -> Vec<u8> {
    let mut bytes = Vec::new();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 0., 1.] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let mut doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 0, 1]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36}]
    });
    for (k, v) in extra.as_object().unwrap() {
        match (doc.get_mut(k), v) {
            (Some(serde_json::Value::Array(a)), serde_json::Value::Array(more)) => {
                a.extend(more.iter().cloned());
            }
            _ => doc[k] = v.clone(),
        }
    }
    glb(&doc, &bytes)
}

/// Enum values the spec may extend (the validator warns, VALUE_NOT_IN_LIST): an unread accessor
/// of an unknown type loads with a note, a read one is refused; a light of an unknown type is
/// left out with a note, and the nodes that name the lights after it keep theirs.
#[test]
fn unknown_enum_values_load_with_notes_where_nothing_reads_them() {
    let unread = triangle_gltf(serde_json::json!({
        "accessors": [{"componentType": 5126, "count": 1, "type": "NotaVEC3"}]
    }));
    let (scene, notes) = load_gltf_slice_with_notes(&unread, "unread.glb", None).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    assert!(
        notes
            .iter()
            .any(|n| n.contains("accessor 1 has the unknown type \"NotaVEC3\"")),
        "{notes:?}"
    );

    // The same triangle whose POSITION accessor has the unknown type: refused by name.
    let read = triangle_gltf(serde_json::json!({
        "meshes": [{"primitives": [{"attributes": {"POSITION": 1}}]}],
        "accessors": [{"componentType": 5126, "count": 3, "type": "NotaVEC3"}],
        "nodes": [{"mesh": 1}],
        "scenes": [{"nodes": [1]}],
        "scene": 1
    }));
    let e = load_gltf_slice(&read, "read.glb", None).unwrap_err();
    assert!(e.to_string().contains("accessors[1].type"), "{e}");

    let lights = triangle_gltf(serde_json::json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "area"},
            {"type": "point", "intensity": 2.0}
        ]}},
        "nodes": [
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 5, 0]},
            {"extensions": {"KHR_lights_punctual": {"light": 1}}, "translation": [1, 4, 0]}
        ],
        "scenes": [{"nodes": [0, 1, 2]}],
        "scene": 1
    }));
    let (scene, notes) = load_gltf_slice_with_notes(&lights, "lights.glb", None).unwrap();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("light 0 has the unknown type \"area\"")),
        "{notes:?}"
    );
    assert_eq!(scene.lights.len(), 1, "{:?}", scene.lights);
    assert_eq!(scene.lights[0].light.to_array(), [1.0, 4.0, 0.0, 1.0]);
}

/// Bytes after the end of a GLB stream are ignored with a note (the validator warns,
/// GLB_EXTRA_DATA); a stream shorter than its header says stays an error.
#[test]
fn extra_bytes_after_a_glb_stream_are_ignored_with_a_note() {
    let mut glb = to_glb(&preset("hard-tetrahedron").unwrap()).unwrap();
    let want = load_gltf_slice(&glb, "t.glb", None).unwrap();
    glb.push(0);
    let (got, notes) = load_gltf_slice_with_notes(&glb, "t.glb", None).unwrap();
    assert_eq!(got.triangle_count(), want.triangle_count());
    assert!(
        notes
            .iter()
            .any(|n| n.contains("1 bytes after the end of the GLB stream")),
        "{notes:?}"
    );
    glb.truncate(glb.len() - 2);
    let e = load_gltf_slice(&glb, "t.glb", None).unwrap_err();
    assert!(e.to_string().contains("truncated"), "{e}");
}
