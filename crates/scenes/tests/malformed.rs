//! Malformed glTF, GLB, OBJ, STL and PLY files fail with a message naming the file and what is wrong.

use shadowvol_scenes::{Scene, SceneError};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Loads a fixture, expects an error, returns its message (and checks it names the file).
fn message(name: &str) -> String {
    let err = match Scene::load(data(name)) {
        Ok(s) => panic!(
            "{name} loaded ({} objects) but should fail",
            s.geometry.objects.len()
        ),
        Err(e) => e,
    };
    let msg = err.to_string();
    eprintln!("{name}: {msg}");
    assert!(
        msg.contains(name),
        "message for {name} does not name the file: {msg}"
    );
    msg
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "expected {p:?} in: {msg}");
    }
}

#[test]
fn index_out_of_range_names_accessor_and_element() {
    let m = message("index_out_of_range.gltf");
    assert_has(
        &m,
        &[
            "node 0 'thing'",
            "mesh 0 'tri'",
            "primitive 0",
            "accessor 1 (indices)",
            "element 2",
            "vertex index 7 is out of range",
            "3 vertices",
        ],
    );
}

#[test]
fn non_finite_positions_name_accessor_element_and_axis() {
    let m = message("nan_position.gltf");
    assert_has(
        &m,
        &["accessor 0 (POSITION)", "element 1", "coordinate y is NaN"],
    );
    let m = message("inf_position.gltf");
    assert_has(
        &m,
        &["accessor 0 (POSITION)", "element 2", "coordinate z is inf"],
    );
}

#[test]
fn zero_count_is_rejected() {
    let m = message("zero_count.gltf");
    assert!(m.contains("count"), "{m}");
    assert!(m.contains("accessor"), "{m}");
}

#[test]
fn non_triangle_modes_are_skipped_with_a_note_and_partial_triangles_rejected() {
    // Lines are valid glTF, but cast no shadow: skipped, with a note naming them.
    let (scene, notes) = Scene::load_with_notes(data("lines_mode.gltf")).unwrap();
    assert!(scene.geometry.objects.is_empty());
    assert_has(
        &notes.join("\n"),
        &[
            "lines_mode.gltf",
            "primitive 0",
            "Lines",
            "not a triangle mode",
            "skipped",
        ],
    );
    let m = message("partial_triangle.gltf");
    assert_has(
        &m,
        &[
            "accessor 1 (indices)",
            "4 indices do not make whole triangles",
        ],
    );
}

#[test]
fn accessor_past_its_view_is_rejected() {
    let m = message("past_view.gltf");
    assert_has(
        &m,
        &["accessor 0 (POSITION)", "run past the end of buffer view 0"],
    );
}

#[test]
fn wrong_types_are_rejected_and_missing_positions_skipped() {
    let m = message("integer_positions.gltf");
    assert_has(&m, &["accessor 0 (POSITION)", "must be VEC3 of FLOAT"]);
    // A primitive without POSITION is valid glTF with nothing to cast: skipped, with a note.
    let (scene, notes) = Scene::load_with_notes(data("missing_position.gltf")).unwrap();
    assert!(scene.geometry.objects.is_empty());
    assert_has(
        &notes.join("\n"),
        &["primitive 0", "no POSITION", "skipped"],
    );
}

#[test]
fn node_cycles_are_rejected() {
    let m = message("node_cycle.gltf");
    assert_has(&m, &["node 0 'a'", "reached twice"]);
}

#[test]
fn singular_transforms_are_rejected() {
    let m = message("zero_scale.gltf");
    assert_has(&m, &["node 1 'leaf'", "singular"]);
}

#[test]
fn broken_documents_and_buffers_are_rejected() {
    let m = message("not_json.gltf");
    assert_has(&m, &["document"]);
    let m = message("missing_buffer.gltf");
    assert_has(&m, &["buffers"]);
    let m = message("truncated.glb");
    assert_has(&m, &["document", "GLB header declares", "truncated"]);
    let m = message("bad_magic.glb");
    assert_has(&m, &["document", "not a binary glTF file", "\"glTX\""]);
}

#[test]
fn malformed_obj_files_name_file_and_line() {
    let m = message("bad_number.obj");
    assert_has(&m, &[":3:", "vertex 2", "malformed number \"1.5.2\""]);
    let m = message("index_out_of_range.obj");
    assert_has(&m, &[":4:", "face index 9 is out of range"]);
    let m = message("nan_position.obj");
    assert_has(&m, &[":3:", "coordinate y is NaN"]);
    let m = message("short_face.obj");
    assert_has(&m, &[":4:", "face has 2 corner(s)"]);
    assert!(matches!(
        Scene::load(data("short_face.obj")),
        Err(SceneError::Obj(_))
    ));
}

#[test]
fn missing_files_and_unknown_formats_are_clear() {
    let err = Scene::load(data("does_not_exist.glb")).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }), "{err}");
    assert!(err.to_string().contains("does_not_exist.glb"));
    let err = Scene::load(data("make_fixtures.py")).unwrap_err();
    assert!(
        err.to_string().contains("unsupported scene format"),
        "{err}"
    );
    let err = Scene::from_name_or_path("no-such-preset").unwrap_err();
    assert_has(
        &err.to_string(),
        &["unknown scene 'no-such-preset'", "sphere-1m", "town"],
    );
}

/// Regressions from fuzzing and the reliability corpus: inputs that used to panic
/// inside the gltf crates, or to load although they lie about their data.
#[test]
fn fuzz_regressions_are_errors_not_panics() {
    let base = std::fs::read_to_string(data("index_out_of_range.gltf")).unwrap();
    let uri_at = base.find("\"uri\": \"").unwrap() + "\"uri\": \"".len();
    let uri_end = uri_at + base[uri_at..].find('"').unwrap();
    let with_uri = |uri: &str| format!("{}{uri}{}", &base[..uri_at], &base[uri_end..]);
    let load = |text: &str| {
        shadowvol_scenes::load_gltf_slice(text.as_bytes(), "regression.gltf", None)
            .map(|s| s.geometry.objects.len())
            .unwrap_err()
            .to_string()
    };
    // gltf_loader crash-330f0110: percent escapes that decode to invalid UTF-8 (gltf's import
    // unwrapped the decoding).
    let m = load(&with_uri("bad%AAescape.bin"));
    assert_has(&m, &["regression.gltf", "buffer 0", "not UTF-8"]);
    // A POSITION accessor index past the accessors (gltf-json's validation indexed it).
    let m = load(&base.replace("\"POSITION\": 0", "\"POSITION\": 5"));
    assert_has(
        &m,
        &["POSITION", "accessor 5 does not exist", "2 accessors"],
    );
    // A data URI holding more bytes than byteLength declares.
    let m = load(&base.replace("\"byteLength\": 48", "\"byteLength\": 8"));
    assert_has(
        &m,
        &["buffer 0", "holds 48 bytes but byteLength declares 8"],
    );
}
