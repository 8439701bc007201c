//! The conformance corpus through the command line: each single-object corpus case is written as
//! an OBJ file (coordinates printed with Rust's shortest round-trip formatting, so the `f32`
//! values are exactly those of the corpus), then `shadowvol silhouette` runs on it and its JSON
//! is compared with the library's cpu reference on the corpus scene itself.
//!
//! This checks the OBJ writer/reader round trip on hard coordinates (1e4 offsets, tiny offsets
//! off a plane), the edge naming of the JSON (welded names, `a < b`, sorted, only `m != 0`),
//! `open_vertices`, and `exact` on every backend through the CLI, one trial per backend (`::BACKEND`).

#[macro_use]
mod common;

use glam::Affine3A;
use shadowvol_cpu::CpuBackend;
use shadowvol_silhouette::{extract_once, invariant, Accuracy};
use shadowvol_test_support::corpus;
use std::path::PathBuf;

fn main() {
    shadowvol_test_support::run(per_backend!(corpus_cases_through_the_cli_match_the_library))
}

/// Every exportable corpus case through `shadowvol silhouette --backend BACKEND`: on `cpu` in
/// every mode, elsewhere in `exact` (the only mode whose values must match across backends).
fn corpus_cases_through_the_cli_match_the_library(backend: &str) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-corpus-{backend}"));
    std::fs::create_dir_all(&dir).unwrap();
    let modes: &[Accuracy] = if backend == "cpu" {
        &Accuracy::ALL
    } else {
        &[Accuracy::Exact]
    };
    let mut exported = 0;
    for case in corpus::cases() {
        if case.objects.len() != 1 || case.objects[0].1 != Affine3A::IDENTITY {
            continue; // several objects or a transform: not one OBJ file
        }
        exported += 1;
        let mesh = &case.objects[0].0;
        let mut text = format!("# corpus case {}\n", case.name);
        for p in &mesh.positions {
            // `{}` prints the shortest decimal that parses back to the same f32.
            text.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        for t in &mesh.triangles {
            text.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
        }
        let path = dir.join(format!("{}.obj", case.name));
        std::fs::write(&path, text).unwrap();

        let scene = case.scene().unwrap();
        let table = &scene.objects[0].table;
        let light_args: Vec<String> = case
            .lights
            .iter()
            .map(|l| {
                let [x, y, z, w] = l.to_array();
                format!("--light={x},{y},{z},{w}")
            })
            .collect();
        for &mode in modes {
            let mut cpu = CpuBackend::new();
            let (reference, _) = extract_once(&mut cpu, &scene, &case.lights, mode).unwrap();
            let mut args = vec![
                "silhouette",
                path.to_str().unwrap(),
                "--format",
                "json",
                "--mode",
                mode.name(),
                "--backend",
                backend,
            ];
            args.extend(light_args.iter().map(String::as_str));
            let v = common::json_of(&args);
            let what = format!("{} {mode} {backend}", case.name);
            assert_eq!(v["mesh"]["vertices"], mesh.positions.len(), "{what}");
            assert_eq!(v["mesh"]["edges"], table.edges.len(), "{what}");
            let lights = v["lights"].as_array().unwrap();
            assert_eq!(lights.len(), case.lights.len(), "{what}");
            for (l, got) in lights.iter().enumerate() {
                let want = common::nonzero_edges(table, reference.values(l));
                let edges = common::edges_of(got);
                assert!(
                    edges
                        .windows(2)
                        .all(|w| (w[0].0, w[0].1) < (w[1].0, w[1].1)),
                    "{what}: sorted by (a, b)"
                );
                assert!(edges.iter().all(|e| e.0 < e.1 && e.2 != 0), "{what}");
                assert_eq!(edges, want, "{what} light {l}");
                let open = invariant::open_vertices_scene(&scene, &reference, l);
                assert_eq!(got["open_vertices"], open, "{what} light {l}");
                if mode.is_consistent() {
                    assert_eq!(open, 0, "{what} light {l}");
                }
            }
        }
    }
    assert!(
        exported >= 10,
        "only {exported} corpus cases could be exported"
    );
}
