//! Integration tests of the `shadowvol` binary: JSON contracts checked against an independent
//! integer reference, and every kind of bad input checked for its message and exit code.

#[macro_use]
mod common;

use common::{edges_of, json_of, nonzero_edges, run};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn main() {
    let mut trials = shadowvol_test_support::trials![
        tetrahedron_matches_integer_reference_in_every_mode,
        welded_duplicates_are_named_by_smallest_index,
        nonmanifold_book_counts_and_closes,
        text_format_is_readable,
        backends_json_follows_the_contract,
        non_finite_coordinates_name_vertex_and_line,
        malformed_numbers_and_indices_name_the_line,
        out_of_range_indices_name_the_line,
        unreadable_and_unknown_files_fail_cleanly,
        the_valid_fixture_loads,
        usage_errors_exit_2_and_name_the_argument,
        unavailable_backend_exits_1_with_its_reason,
        presets_load_with_their_own_lights,
        help_describes_commands_and_contract,
        bench_json_follows_the_contract_for_several_light_counts,
        light_samples_replace_each_light_in_silhouette_and_bench,
    ];
    trials.extend(per_backend!(exact_mode_matches_the_integer_reference));
    shadowvol_test_support::run(trials)
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Runs a command that must fail; returns (exit code, stderr).
fn failure(args: &[&str]) -> (i32, String) {
    let out = run(args);
    assert!(!out.status.success(), "shadowvol {args:?} should fail");
    assert!(out.stdout.is_empty(), "nothing on stdout for a failure");
    (
        out.status.code().expect("exit code"),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn write_obj(name: &str, positions: &[[i64; 3]], faces: &[Vec<i64>]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli-tests");
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::new();
    for p in positions {
        text.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    for f in faces {
        text.push('f');
        for i in f {
            text.push_str(&format!(" {i}"));
        }
        text.push('\n');
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

// ---------------------------------------------------------------------------------------------
// Independent reference: integer arithmetic (exact for integer coordinates), its own welding and
// edge collection, written from DESIGN.md's definitions only.

/// Silhouette `(a, b, m)` sorted, and the open-vertex count, for integer positions and light.
fn reference(
    positions: &[[i64; 3]],
    faces: &[Vec<i64>],
    light: [i64; 4],
) -> (Vec<(u64, u64, i64)>, u64) {
    // Weld: a group is named by its smallest input index.
    let name: Vec<usize> = (0..positions.len())
        .map(|i| (0..=i).find(|&j| positions[j] == positions[i]).unwrap())
        .collect();
    // Resolve 1-based / negative OBJ indices and fan polygons.
    let mut triangles = Vec::new();
    for f in faces {
        let idx: Vec<usize> = f
            .iter()
            .map(|&i| {
                if i > 0 {
                    (i - 1) as usize
                } else {
                    (positions.len() as i64 + i) as usize
                }
            })
            .collect();
        for k in 1..idx.len() - 1 {
            triangles.push([name[idx[0]], name[idx[k]], name[idx[k + 1]]]);
        }
    }
    let mut m = std::collections::BTreeMap::<(usize, usize), i64>::new();
    for t in triangles {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            continue;
        }
        for i in 0..3 {
            let (u, v, o) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            let (a, b) = (u.min(v), u.max(v));
            let (pa, pb, po) = (positions[a], positions[b], positions[o]);
            let vv: Vec<i128> = (0..3)
                .map(|k| i128::from(light[k]) - i128::from(light[3]) * i128::from(pa[k]))
                .collect();
            let e: Vec<i128> = (0..3).map(|k| i128::from(pa[k] - pb[k])).collect();
            let n = [
                e[1] * vv[2] - e[2] * vv[1],
                e[2] * vv[0] - e[0] * vv[2],
                e[0] * vv[1] - e[1] * vv[0],
            ];
            let d: i128 = (0..3).map(|k| n[k] * i128::from(po[k] - pa[k])).sum();
            *m.entry((a, b)).or_default() += d.signum() as i64;
        }
    }
    let edges: Vec<(u64, u64, i64)> = m
        .into_iter()
        .filter(|&(_, v)| v != 0)
        .map(|((a, b), v)| (a as u64, b as u64, v))
        .collect();
    let mut sum = std::collections::BTreeMap::<u64, i64>::new();
    for &(a, b, v) in &edges {
        *sum.entry(a).or_default() -= v;
        *sum.entry(b).or_default() += v;
    }
    let open = sum.values().filter(|&&s| s != 0).count() as u64;
    (edges, open)
}

const TET: [[i64; 3]; 4] = [[0, 0, 0], [4, 0, 0], [0, 4, 0], [0, 0, 4]];

fn tet_faces() -> Vec<Vec<i64>> {
    vec![vec![1, 3, 2], vec![1, 2, 4], vec![2, 3, 4], vec![1, 4, 3]]
}

const LIGHTS: [[i64; 4]; 5] = [
    [7, 9, 11, 1],
    [-3, 1, 2, 1],
    [1, 2, 3, 0],
    [0, 0, -1, 0],
    // In the plane z = 0 of a face: edge-on.
    [5, 6, 0, 1],
];

fn light_arg(l: [i64; 4]) -> String {
    format!("--light={},{},{},{}", l[0], l[1], l[2], l[3])
}

/// Runs `silhouette` for `path` with all `LIGHTS` and checks every field against the reference.
fn check_against_reference(
    path: &Path,
    positions: &[[i64; 3]],
    faces: &[Vec<i64>],
    backend: &str,
    mode: &str,
) -> Value {
    let mut args = vec![
        "silhouette".to_owned(),
        path.to_str().unwrap().to_owned(),
        "--format".to_owned(),
        "json".to_owned(),
        "--backend".to_owned(),
        backend.to_owned(),
        "--mode".to_owned(),
        mode.to_owned(),
    ];
    args.extend(LIGHTS.iter().map(|&l| light_arg(l)));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let v = json_of(&args);
    assert_eq!(v["backend"], backend);
    assert_eq!(v["mode"], mode);
    let lights = v["lights"].as_array().unwrap();
    assert_eq!(lights.len(), LIGHTS.len());
    for (l, got) in LIGHTS.iter().zip(lights) {
        let want: Vec<f64> = l.iter().map(|&x| x as f64).collect();
        let light: Vec<f64> = got["light"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(light, want);
        let (edges, open) = reference(positions, faces, *l);
        assert_eq!(edges_of(got), edges, "{backend} {mode} light {l:?}");
        assert_eq!(got["open_vertices"], open, "{backend} {mode} light {l:?}");
    }
    v
}

fn tetrahedron_matches_integer_reference_in_every_mode() {
    let path = write_obj("tet.obj", &TET, &tet_faces());
    for mode in ["original", "robust", "ordered", "exact"] {
        // Small integers: every f32 operation is exact, so all four modes equal the reference.
        let v = check_against_reference(&path, &TET, &tet_faces(), "cpu", mode);
        let mesh = &v["mesh"];
        assert_eq!(mesh["vertices"], 4);
        assert_eq!(mesh["welded_vertices"], 4);
        assert_eq!(mesh["triangles"], 4);
        assert_eq!(mesh["edges"], 6);
        assert_eq!(mesh["boundary_edges"], 0);
        assert_eq!(mesh["nonmanifold_edges"], 0);
        for l in v["lights"].as_array().unwrap() {
            assert_eq!(l["open_vertices"], 0);
        }
    }
    // A closed convex mesh seen from outside has a silhouette.
    let (edges, _) = reference(&TET, &tet_faces(), LIGHTS[0]);
    assert!(!edges.is_empty());
}

/// `exact` on `backend` equals the integer reference on the tetrahedron.
fn exact_mode_matches_the_integer_reference(backend: &str) {
    let path = write_obj(&format!("tet_{backend}.obj"), &TET, &tet_faces());
    check_against_reference(&path, &TET, &tet_faces(), backend, "exact");
}

fn welded_duplicates_are_named_by_smallest_index() {
    // Vertex 4 duplicates vertex 1, vertex 5 duplicates vertex 0; faces use the duplicates and
    // negative indices; a quad is fanned; a triangle made degenerate by welding is dropped.
    let positions = [
        [0, 0, 0],
        [4, 0, 0],
        [0, 4, 0],
        [0, 0, 4],
        [4, 0, 0],
        [0, 0, 0],
        [4, 4, 4],
    ];
    let faces = vec![
        vec![6, 3, 5],
        vec![1, 5, 4],
        vec![-1, -4, 3, 2], // quad of 0-based vertices 6 3 2 1, fanned into two triangles
        vec![2, 5, 7],      // degenerate after welding (0-based 1 and 4 are the same point)
    ];
    let path = write_obj("welded.obj", &positions, &faces);
    let v = check_against_reference(&path, &positions, &faces, "cpu", "exact");
    assert_eq!(v["mesh"]["vertices"], 7);
    assert_eq!(v["mesh"]["welded_vertices"], 5);
    assert_eq!(v["mesh"]["triangles"], 5);
    assert_eq!(v["mesh"]["degenerate_triangles"], 1);
    for l in v["lights"].as_array().unwrap() {
        for (a, b, _) in edges_of(l) {
            assert!(
                a < b && a != 4 && b != 4 && a != 5 && b != 5,
                "names are smallest indices"
            );
        }
    }
}

fn nonmanifold_book_counts_and_closes() {
    // Three pages on the spine (0, 1).
    let positions = [[0, 0, 0], [0, 0, 4], [4, 0, 0], [0, 4, 0], [-4, -4, 0]];
    let faces = vec![vec![1, 2, 3], vec![1, 2, 4], vec![1, 2, 5]];
    let path = write_obj("book.obj", &positions, &faces);
    let v = check_against_reference(&path, &positions, &faces, "cpu", "exact");
    assert_eq!(v["mesh"]["edges"], 7);
    assert_eq!(v["mesh"]["nonmanifold_edges"], 1);
    assert_eq!(v["mesh"]["boundary_edges"], 6);
    for l in v["lights"].as_array().unwrap() {
        assert_eq!(l["open_vertices"], 0);
    }
}

fn text_format_is_readable() {
    let path = write_obj("tet_text.obj", &TET, &tet_faces());
    let out = run(&["silhouette", path.to_str().unwrap(), "--light", "7,9,11,1"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("4 vertices (4 welded), 4 triangles"),
        "{text}"
    );
    assert!(
        text.contains("6: 0 boundary, 6 manifold, 0 non-manifold"),
        "{text}"
    );
    assert!(text.contains("mode     exact"), "{text}");
    let (edges, _) = reference(&TET, &tet_faces(), [7, 9, 11, 1]);
    assert!(
        text.contains(&format!("{} silhouette edges", edges.len())),
        "{text}"
    );
    assert!(text.contains("open vertices: 0 (closed)"), "{text}");
}

fn backends_json_follows_the_contract() {
    let v = json_of(&["backends", "--format", "json"]);
    let rows = v.as_array().unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["cpu", "simd", "wgpu", "opencl", "vulkan"]);
    for r in rows {
        let keys: Vec<&String> = r.as_object().unwrap().keys().collect();
        for k in ["name", "available", "device", "reason"] {
            assert!(keys.iter().any(|x| *x == k), "missing {k} in {r}");
        }
        let available = r["available"].as_bool().unwrap();
        assert_eq!(r["device"].is_string(), available, "{r}");
        assert_eq!(r["reason"].is_string(), !available, "{r}");
        if !available {
            assert!(!r["reason"].as_str().unwrap().is_empty());
        }
    }
    assert_eq!(rows[0]["available"], true, "cpu is always available");
    let text = run(&["backends"]);
    assert!(
        text.status.success(),
        "backends: {}\n{}",
        text.status,
        String::from_utf8_lossy(&text.stderr)
    );
    let text = String::from_utf8(text.stdout).unwrap();
    for n in names {
        assert!(text.contains(n));
    }
}

// ---------------------------------------------------------------------------------------------
// Bad input: message names the problem and where; exit code 1 for input, 2 for usage.

fn input_error(file: &str, expected: &[&str]) {
    let path = data(file);
    let (code, stderr) = failure(&["silhouette", path.to_str().unwrap(), "--light", "1,2,3,1"]);
    assert_eq!(code, 1, "{file}: {stderr}");
    for e in expected {
        assert!(stderr.contains(e), "{file}: expected {e:?} in:\n{stderr}");
    }
}

fn non_finite_coordinates_name_vertex_and_line() {
    input_error(
        "nan_coordinate.obj",
        &["nan_coordinate.obj:4:", "vertex 2", "coordinate y is NaN"],
    );
    input_error(
        "inf_coordinate.obj",
        &["inf_coordinate.obj:4:", "vertex 3", "coordinate z is -inf"],
    );
}

fn malformed_numbers_and_indices_name_the_line() {
    input_error(
        "malformed_number.obj",
        &["malformed_number.obj:3:", "malformed number \"1,5\""],
    );
    input_error(
        "malformed_index.obj",
        &["malformed_index.obj:4:", "malformed face index \"three\""],
    );
    input_error(
        "short_face.obj",
        &["short_face.obj:5:", "face has 2 corner(s)"],
    );
}

fn out_of_range_indices_name_the_line() {
    input_error(
        "index_out_of_range.obj",
        &[
            "index_out_of_range.obj:6:",
            "face index 7 is out of range",
            "3 vertices",
        ],
    );
    input_error(
        "zero_index.obj",
        &["zero_index.obj:4:", "face index 0 is invalid"],
    );
    input_error(
        "relative_off_start.obj",
        &[
            "relative_off_start.obj:3:",
            "relative face index -3 runs off the start",
        ],
    );
    input_error(
        "index_beyond_u32.obj",
        &[
            "index_beyond_u32.obj:4:",
            "4294967296 is beyond the u32 range",
        ],
    );
}

fn unreadable_and_unknown_files_fail_cleanly() {
    input_error("does_not_exist.obj", &["cannot read", "does_not_exist.obj"]);
    // A directory with an .obj name cannot be read either.
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("a_directory.obj");
    std::fs::create_dir_all(&dir).unwrap();
    let (code, stderr) = failure(&["silhouette", dir.to_str().unwrap(), "--light", "1,2,3,1"]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("cannot read") && stderr.contains("a_directory.obj"),
        "{stderr}"
    );
    let (code, stderr) = failure(&["silhouette", "mesh.xyz", "--light", "1,2,3,1"]);
    assert_eq!(code, 1);
    assert!(stderr.contains("unknown scene 'mesh.xyz'"), "{stderr}");
}

fn the_valid_fixture_loads() {
    let path = data("ok_triangle.obj");
    let v = json_of(&[
        "silhouette",
        path.to_str().unwrap(),
        "--light",
        "1,2,3,1",
        "--format",
        "json",
    ]);
    assert_eq!(v["mesh"]["triangles"], 1);
    assert_eq!(v["mesh"]["boundary_edges"], 3);
}

fn usage_errors_exit_2_and_name_the_argument() {
    let ok = data("ok_triangle.obj");
    let ok = ok.to_str().unwrap();
    for (light, why) in [
        ("1,2,3", "found 3 component(s)"),
        ("1,2,x,1", "component 3"),
        ("1,2,3,nan", "light component w is NaN"),
        ("1,2,3,inf", "light component w is inf"),
        ("1,2,3,-1", "must be 0 (directional) or positive"),
        ("0,0,0,0", "non-zero direction"),
    ] {
        let (code, stderr) = failure(&["silhouette", ok, "--light", light]);
        assert_eq!(code, 2, "{light}: {stderr}");
        assert!(
            stderr.contains("--light") && stderr.contains(why),
            "{light}: {stderr}"
        );
    }
    let (code, stderr) = failure(&["silhouette", ok, "--light", "1,2,3,1", "--mode", "fast"]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("'fast'") && stderr.contains("--mode"),
        "{stderr}"
    );
    let (code, stderr) = failure(&["silhouette", ok, "--light", "1,2,3,1", "--backend", "metal"]);
    assert_eq!(code, 2);
    assert!(stderr.contains("unknown backend \"metal\""), "{stderr}");
    let (code, stderr) = failure(&["silhouette", ok]);
    assert_eq!(code, 2);
    assert!(stderr.contains("no light given"), "{stderr}");
    let (code, _) = failure(&["silhouette"]);
    assert_eq!(code, 2);
    let (code, _) = failure(&["frobnicate"]);
    assert_eq!(code, 2);
}

fn unavailable_backend_exits_1_with_its_reason() {
    let v = json_of(&["backends", "--format", "json"]);
    let unavailable: Vec<(String, String)> = v
        .as_array()
        .unwrap()
        .iter()
        .filter(|b| b["available"] == Value::Bool(false))
        .map(|b| {
            (
                b["name"].as_str().unwrap().to_owned(),
                b["reason"].as_str().unwrap().to_owned(),
            )
        })
        .collect();
    if unavailable.is_empty() {
        eprintln!("every backend is available here; nothing to check");
    }
    let ok = data("ok_triangle.obj");
    for (name, reason) in unavailable {
        let (code, stderr) = failure(&[
            "silhouette",
            ok.to_str().unwrap(),
            "--light",
            "1,2,3,1",
            "--backend",
            &name,
        ]);
        assert_eq!(code, 1, "{stderr}");
        assert!(
            stderr.contains(&name) && stderr.contains(&reason),
            "{stderr}"
        );
    }
}

fn presets_load_with_their_own_lights() {
    // `hard-<case>` presets carry the corpus case's lights; without --light they are used.
    let case = shadowvol_test_support::corpus::case("tetrahedron").expect("corpus case");
    let scene = case.scene().unwrap();
    let v = json_of(&["silhouette", "hard-tetrahedron", "--format", "json"]);
    let lights = v["lights"].as_array().unwrap();
    assert_eq!(lights.len(), case.lights.len());
    let mut cpu = shadowvol_cpu::CpuBackend::new();
    let (reference, _) = shadowvol_silhouette::extract_once(
        &mut cpu,
        &scene,
        &case.lights,
        shadowvol_silhouette::Accuracy::Exact,
    )
    .unwrap();
    let table = &scene.objects[0].table;
    for (l, got) in lights.iter().enumerate() {
        let want = nonzero_edges(table, reference.values(l));
        assert_eq!(edges_of(got), want, "light {l}");
    }
    let (code, stderr) = failure(&["silhouette", "no-such-preset", "--light", "1,2,3,1"]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("unknown scene 'no-such-preset'"),
        "{stderr}"
    );
}

fn help_describes_commands_and_contract() {
    for args in [
        vec!["--help"],
        vec!["silhouette", "--help"],
        vec!["backends", "--help"],
    ] {
        let out = run(&args);
        assert!(out.status.success(), "{args:?}");
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(!text.is_empty());
        if args[0] == "silhouette" {
            for word in [
                "--light",
                "--mode",
                "--backend",
                "--format",
                "open_vertices",
                "welded_vertices",
            ] {
                assert!(text.contains(word), "silhouette --help lacks {word}");
            }
        }
        if args[0] == "--help" {
            assert!(text.contains("backends") && text.contains("silhouette"));
            assert!(text.contains("Exit codes"));
        }
    }
}

fn bench_json_follows_the_contract_for_several_light_counts() {
    let path = write_obj("bench_tet.obj", &TET, &tet_faces());
    let path = path.to_str().unwrap();
    // The two host backends, which every build has.
    let backends = ["cpu", "simd"];
    let modes = ["original", "robust", "ordered", "exact"];
    for schedule in ["interleaved", "sequential"] {
        let v = json_of(&[
            "bench",
            "--scene",
            path,
            "--backend",
            &backends.join(","),
            "--frames",
            "7",
            "--warmup",
            "1",
            "--lights",
            "1,3",
            "--schedule",
            schedule,
            "--format",
            "json",
        ]);
        assert_eq!(v["schedule"], schedule);
        // One floor per light count, in order; the output grows with the lights, the input not.
        let floors = v["floors"].as_array().unwrap();
        assert_eq!(floors.len(), 2);
        assert_eq!(
            (floors[0]["lights"].as_u64(), floors[1]["lights"].as_u64()),
            (Some(1), Some(3))
        );
        let w = |k: usize| floors[k]["floor_bytes_written"].as_u64().unwrap();
        assert_eq!(
            w(0),
            6 * 4,
            "a tetrahedron has 6 edges, 4 bytes each per light"
        );
        assert_eq!(w(1), 3 * w(0));
        assert_eq!(floors[0]["floor_bytes_read"], floors[1]["floor_bytes_read"]);
        // The top-level floor is the first count's (the contract's single-count shape).
        assert_eq!(v["floor_ms"], floors[0]["floor_ms"]);
        let records = v["records"].as_array().unwrap();
        assert_eq!(records.len(), backends.len() * modes.len() * 2);
        for b in &backends {
            for m in modes {
                for (k, lights) in [1u64, 3].into_iter().enumerate() {
                    let r = records
                        .iter()
                        .find(|r| r["backend"] == **b && r["mode"] == m && r["lights"] == lights)
                        .unwrap_or_else(|| panic!("no record for {b} {m} {lights}"));
                    for key in [
                        "scene",
                        "triangles",
                        "edges",
                        "objects",
                        "median_ms",
                        "p10_ms",
                        "p90_ms",
                    ] {
                        assert!(!r[key].is_null(), "{key} missing in {r}");
                    }
                    assert_eq!(
                        (r["triangles"].as_u64(), r["edges"].as_u64()),
                        (Some(4), Some(6))
                    );
                    let (p10, med, p90) = (
                        r["p10_ms"].as_f64().unwrap(),
                        r["median_ms"].as_f64().unwrap(),
                        r["p90_ms"].as_f64().unwrap(),
                    );
                    assert!(0.0 < p10 && p10 <= med && med <= p90, "{r}");
                    assert_eq!(r["frames"], 7);
                    assert_eq!(r["floor_ms"], floors[k]["floor_ms"], "{r}");
                }
            }
        }
    }
    // A light count given twice is a usage error.
    let (code, stderr) = failure(&["bench", "--scene", path, "--lights", "2,2"]);
    assert_eq!(code, 2);
    assert!(stderr.contains("--lights lists 2 twice"), "{stderr}");
}

/// `--light-radius` and `--light-samples` on `silhouette` and `bench`: each light is replaced by
/// its samples in one call, each sample's edges are those of a one-light call for that sample,
/// the JSON gives each original light's radius and sample count, and `bench` times the point
/// lights next to the samples.
fn light_samples_replace_each_light_in_silhouette_and_bench() {
    for backend in ["cpu", "simd"] {
        let v = json_of(&[
            "silhouette",
            "hard-light-at-vertex",
            "--backend",
            backend,
            "--light-radius",
            "0.25",
            "--light-samples",
            "5",
            "--format",
            "json",
        ]);
        let radii = v["light_radii"].as_array().unwrap();
        let samples = v["light_samples"].as_array().unwrap();
        let lights = v["lights"].as_array().unwrap();
        assert_eq!(radii.len(), 4, "the preset has 4 lights");
        assert!(radii.iter().all(|r| r.as_f64() == Some(0.25)), "{radii:?}");
        assert!(samples.iter().all(|n| n.as_u64() == Some(5)), "{samples:?}");
        assert_eq!(lights.len(), 4 * 5);
        // Distinct samples, each equal to its own one-light call.
        for (i, l) in lights.iter().enumerate() {
            let [x, y, z, w] = [0, 1, 2, 3].map(|c| l["light"][c].as_f64().unwrap() as f32);
            assert!(lights[..i].iter().all(|o| o["light"] != l["light"]));
            let one = json_of(&[
                "silhouette",
                "hard-light-at-vertex",
                "--backend",
                backend,
                "--light",
                &format!("{x},{y},{z},{w}"),
                "--format",
                "json",
            ]);
            assert_eq!(one["light_samples"], serde_json::json!([1]));
            assert_eq!(
                edges_of(&one["lights"][0]),
                edges_of(l),
                "{backend}: sample {i} ({x},{y},{z},{w})"
            );
        }
    }
    // Without a size: one sample each, radius 0; the help names the default count.
    let v = json_of(&["silhouette", "hard-tetrahedron", "--format", "json"]);
    assert_eq!(v["light_radii"], serde_json::json!([0.0, 0.0]));
    assert_eq!(v["light_samples"], serde_json::json!([1, 1]));
    let help = String::from_utf8(run(&["silhouette", "--help"]).stdout).unwrap();
    assert!(
        help.contains("--light-samples") && help.contains("default: 16"),
        "{help}"
    );
    let (code, stderr) = failure(&["silhouette", "hard-tetrahedron", "--light-radius", "-1"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--light-radius -1"), "{stderr}");
    // bench: the samples' record against the point lights', same mode, in one run.
    let v = json_of(&[
        "bench",
        "--scene",
        "hard-tetrahedron",
        "--backend",
        "simd",
        "--mode",
        "exact,ordered",
        "--frames",
        "5",
        "--warmup",
        "1",
        "--light-radius",
        "0.1",
        "--format",
        "json",
    ]);
    let records = v["records"].as_array().unwrap();
    assert_eq!(records.len(), 4);
    for mode in ["exact", "ordered"] {
        let of = |lights: u64| {
            records
                .iter()
                .find(|r| r["mode"] == mode && r["lights"] == lights)
                .unwrap_or_else(|| panic!("no {mode} record of {lights} lights"))
        };
        let (sampled, point) = (of(2 * 16), of(2));
        assert_eq!(sampled["light_samples"], serde_json::json!([16, 16]));
        assert_eq!(point["light_samples"], serde_json::json!([1, 1]));
        assert_eq!(point["light_radii"], serde_json::json!([0.0, 0.0]));
        assert!(point.get("samples_vs_point").is_none(), "{point}");
        assert_eq!(sampled["point_median_ms"], point["median_ms"]);
        let ratio = sampled["samples_vs_point"].as_f64().unwrap();
        let (a, b) = (
            sampled["median_ms"].as_f64().unwrap(),
            point["median_ms"].as_f64().unwrap(),
        );
        assert!((ratio - a / b).abs() <= 1e-9 * ratio, "{sampled}");
    }
}
