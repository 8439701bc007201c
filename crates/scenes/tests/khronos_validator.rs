//! The Khronos glTF-Validator's test assets (its repository's `test/` folder, not committed
//! here) through the loader. Each asset has the validator's own `.report.json` beside it.
//!
//! Run with the folder extracted somewhere:
//! `GLTF_VALIDATOR_TEST_DIR=/tmp/gv/test cargo test -p shadowvol-scenes --test khronos_validator -- --ignored --nocapture`
//!
//! It asserts: no panic, no file taking over 10 s; every asset the validator reports free of
//! errors and with triangles loads with at least one triangle, unless all its triangles are
//! outside the scene that is loaded (then it loads without objects) or their data is not in the
//! file (`DATA_NOT_IN_FILE`, refused naming the buffer); every error-free asset without
//! triangles loads. It prints the invalid assets that load, with the validator's error
//! codes, so each can be judged (most concern what shadowvol does not read: materials, images,
//! animations).

use std::collections::BTreeMap;

/// Error-free assets whose triangles cannot be read: `.gltf` files whose buffer has no `uri`
/// (valid JSON; such a buffer names a GLB's binary chunk, and a `.gltf` has none), so the data of
/// their positions and indices is not in the file. Each must be refused with this message; if
/// one starts to load, or fails otherwise, the test says so.
const DATA_NOT_IN_FILE: [&str; 2] = [
    "base/data/root/named_objects.gltf",
    "base/data/root/unused_objects.gltf",
];
const DATA_NOT_IN_FILE_MESSAGE: &str = "has no uri and no GLB binary chunk holds it";
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            walk(&p, out);
        } else if p
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.ends_with(".report.json"))
        {
            out.push(p);
        }
    }
}

#[test]
#[ignore = "needs the glTF-Validator test assets: set GLTF_VALIDATOR_TEST_DIR"]
fn khronos_validator_test_assets() {
    let dir = std::env::var("GLTF_VALIDATOR_TEST_DIR")
        .expect("set GLTF_VALIDATOR_TEST_DIR to the glTF-Validator repository's test/ folder");
    let mut reports = Vec::new();
    walk(Path::new(&dir), &mut reports);
    assert!(
        reports.len() > 300,
        "{} reports found in {dir}",
        reports.len()
    );
    let mut failures = Vec::new();
    let mut panics = Vec::new();
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    let mut invalid_loaded: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut slowest = (Duration::ZERO, String::new());
    for r in &reports {
        let report: serde_json::Value = serde_json::from_slice(&std::fs::read(r).unwrap()).unwrap();
        let asset = PathBuf::from(r.to_str().unwrap().trim_end_matches(".report.json"));
        let name = asset
            .strip_prefix(&dir)
            .unwrap_or(&asset)
            .display()
            .to_string();
        if !asset.exists() {
            continue;
        }
        let errors = report["issues"]["numErrors"].as_u64().unwrap_or(0);
        let triangles = report["info"]["totalTriangleCount"].as_u64().unwrap_or(0);
        let start = Instant::now();
        let result = std::panic::catch_unwind(|| {
            shadowvol_scenes::Scene::load_with_notes(&asset)
                .map(|(s, notes)| (s.triangle_count(), notes))
        });
        let took = start.elapsed();
        if took > slowest.0 {
            slowest = (took, name.clone());
        }
        assert!(took < Duration::from_secs(10), "{name} took {took:?}");
        let Ok(result) = result else {
            panics.push(name);
            continue;
        };
        match (errors, triangles > 0, &result) {
            (0, true, Ok((n, _))) if *n > 0 => {
                *counts.entry("valid with triangles: loaded").or_default() += 1
            }
            (0, true, Ok((_, notes))) => {
                *counts
                    .entry("valid with triangles: none in the loaded scene")
                    .or_default() += 1;
                println!("valid, triangles outside the loaded scene: {name} {notes:?}");
            }
            (0, true, Err(e))
                if DATA_NOT_IN_FILE.contains(&name.as_str())
                    && e.to_string().contains(DATA_NOT_IN_FILE_MESSAGE) =>
            {
                *counts
                    .entry("valid with triangles: refused, their data is not in the file")
                    .or_default() += 1;
            }
            (0, true, Err(e)) => failures.push(format!("{name} (valid, with triangles): {e}")),
            (0, false, Ok(_)) => *counts.entry("valid without triangles: loaded").or_default() += 1,
            (0, false, Err(e)) => failures.push(format!("{name} (valid, no triangles): {e}")),
            (_, _, Err(_)) => *counts.entry("invalid: refused").or_default() += 1,
            (_, _, Ok(_)) => {
                *counts.entry("invalid: loaded").or_default() += 1;
                let codes: Vec<String> = report["issues"]["messages"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter(|m| m["severity"] == 0)
                    .map(|m| {
                        format!(
                            "{} at {}",
                            m["code"].as_str().unwrap_or("?"),
                            m["pointer"].as_str().unwrap_or("")
                        )
                    })
                    .collect();
                invalid_loaded.insert(name, codes);
            }
        }
    }
    for (name, codes) in &invalid_loaded {
        println!("invalid but loaded: {name}: {}", codes.join(", "));
    }
    println!("{counts:#?}");
    println!("slowest: {} in {:?}", slowest.1, slowest.0);
    assert!(panics.is_empty(), "panics: {panics:#?}");
    assert!(failures.is_empty(), "valid assets refused: {failures:#?}");
}
