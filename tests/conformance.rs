//! Cross-backend conformance: every registered backend, on every corpus case, in every mode.
//!
//! One test per (backend, case, mode), named `conformance::<backend>::<case>::<mode>::<rule>`.
//! No trial compares a backend with itself: the references are computed in the test
//! (`support/values.rs`) and share no code with any backend. How each kind of trial can fail:
//!
//! * `::oracle` (exact mode): a multiplicity differs from the big-integer oracle (with a loose
//!   `f64` pre-filter of its own), or a chain is open;
//! * `::bit-exact` (original, robust, ordered on host backends and on devices that evaluate
//!   without contraction: lavapipe, PoCL): a multiplicity differs from the reference `f32`
//!   evaluation written in the test with the mode's rule; or, on any edge whose every pair the
//!   `f64` filter certifies with a margin above the `f32` error bound, differs from exact; or
//!   (robust, ordered) a chain is open;
//! * `::certified` (the same modes on any other device, which may contract): only the
//!   certified edges are compared, with exact; robust and ordered must close every chain;
//! * every trial: the result has one value per (edge, light) and compact silhouette lists that
//!   list exactly the edges with `m != 0`.
//!
//! `original`'s open vertices are reported after the run (it is the baseline). The
//! `checks_detect_corruption` trial corrupts a correct result (a changed, a negated and an
//! all-zero result, a wrong list, a wrong shape) under both rules and in every mode, and fails if
//! a check misses it.
//!
//! A backend that cannot start is a visible skip (`ignored (<backend> unavailable: reason)`),
//! except under CI (`shadowvol_test_support::ci::is_ci`: `CI=true`, `CI=True`, `CI=1`): then each
//! of its tests fails with the reason, a backend whose cargo feature is off included. Tests
//! listed in [`EXPECTED_FAILURES`] show `[xfail]` before their name; they pass when their check
//! fails and fail when it passes, so the list can't go stale.
//!
//! Backends come only from `shadowvol_registry::backends()`; cases only from
//! `shadowvol_test_support::corpus::cases()`.

use libtest_mimic::{Arguments, Completion, Failed, Trial};
#[path = "support/values.rs"]
mod values;

use shadowvol_cpu::CpuBackend;
use shadowvol_registry::BackendEntry;
use shadowvol_robust_math::Accuracy;
use shadowvol_silhouette::{
    extract_once, invariant, BackendError, ExtractStats, Light, Multiplicities, SilhouetteBackend,
    TopologyScene,
};
use shadowvol_test_support::corpus;
use std::collections::HashMap;
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;
use values::Rule;

/// Tests expected to fail, as `(test name, why)`. Empty: every backend must pass everything.
const EXPECTED_FAILURES: &[(&str, &str)] = &[];

/// How long a backend may take to start before it counts as unavailable.
const START_TIMEOUT: Duration = Duration::from_secs(180);

/// One corpus case, prepared once and shared by all trials.
struct Case {
    name: &'static str,
    scene: TopologyScene,
    lights: Vec<Light>,
}

/// A request to a backend's worker thread.
struct Job {
    case: usize,
    mode: Accuracy,
    reply: Sender<Result<(Multiplicities, ExtractStats), String>>,
}

/// Whether a backend started, as reported by its worker.
enum Started {
    Yes { device: String, jobs: Sender<Job> },
    NotCompiled(String),
    No(String),
}

fn is_ci() -> bool {
    shadowvol_test_support::ci::is_ci()
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_owned())
}

/// Starts `entry` on its own thread (backends need not be `Send`), which then serves jobs: the
/// scene of each case is prepared once, on first use.
fn spawn_worker(
    entry: BackendEntry,
    cases: Arc<Vec<Case>>,
) -> (Receiver<Started>, std::thread::JoinHandle<()>) {
    let (started_tx, started_rx) = mpsc::channel();
    let handle = std::thread::spawn(move || {
        let mut backend: Box<dyn SilhouetteBackend> = match entry.start() {
            Ok(b) => b,
            Err(e) => {
                let reason = match e {
                    BackendError::Unavailable { reason, .. } => reason,
                    other => other.to_string(),
                };
                let _ = started_tx.send(if entry.compiled {
                    Started::No(reason)
                } else {
                    Started::NotCompiled(reason)
                });
                return;
            }
        };
        let (jobs_tx, jobs_rx) = mpsc::channel::<Job>();
        let _ = started_tx.send(Started::Yes {
            device: backend.info().device,
            jobs: jobs_tx,
        });
        let mut prepared = HashMap::new();
        for job in jobs_rx {
            let case = &cases[job.case];
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let id = match prepared.get(&job.case) {
                    Some(&id) => id,
                    None => {
                        let id = backend.prepare(&case.scene)?;
                        prepared.insert(job.case, id);
                        id
                    }
                };
                let mut out = Multiplicities::default();
                let stats = backend.extract(id, &case.lights, job.mode, &mut out)?;
                Ok::<_, BackendError>((out, stats))
            }));
            let reply = match result {
                Ok(Ok(r)) => Ok(r),
                Ok(Err(e)) => Err(format!("backend error: {e}")),
                Err(p) => Err(format!("backend panicked: {}", panic_message(p.as_ref()))),
            };
            let _ = job.reply.send(reply);
        }
        // `backend` drops here, on its own thread: the caller joins this thread before the
        // process exits (see `join_workers`).
    });
    (started_rx, handle)
}

/// How long the backends get to shut down after the last test.
const SHUTDOWN_TIMEOUT: Duration = Duration::from_secs(120);

/// Waits for every worker thread to drop its backend.
///
/// Without this, `process::exit` ran the drivers' exit-time destructors (Mesa's and PoCL's LLVM,
/// the Vulkan loader) while worker threads were still destroying their devices, and the process
/// could die with SIGSEGV after every test had passed (seen once in CI). A worker that does not
/// finish in [`SHUTDOWN_TIMEOUT`] is named and the run fails rather than hanging.
fn join_workers(handles: Vec<(&'static str, std::thread::JoinHandle<()>)>) -> Result<(), String> {
    let deadline = std::time::Instant::now() + SHUTDOWN_TIMEOUT;
    let mut problems = Vec::new();
    for (name, handle) in handles {
        while !handle.is_finished() && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        if !handle.is_finished() {
            problems.push(format!(
                "{name}: the backend did not shut down within {} s",
                SHUTDOWN_TIMEOUT.as_secs()
            ));
            continue;
        }
        if let Err(p) = handle.join() {
            problems.push(format!(
                "{name}: dropping the backend panicked: {}",
                panic_message(p.as_ref())
            ));
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// Observations of non-asserted quantities, printed after the run.
type Notes = Arc<Mutex<Vec<String>>>;

/// The references of every case, one per mode, computed on first use and shared by all backends.
type References = Arc<Vec<[OnceLock<values::Reference>; 4]>>;

fn mode_index(mode: Accuracy) -> usize {
    Accuracy::ALL
        .iter()
        .position(|&m| m == mode)
        .expect("a mode")
}

fn check(
    backend: &str,
    case: &Case,
    mode: Accuracy,
    rule: Rule,
    reference: &values::Reference,
    got: &Multiplicities,
    notes: &Notes,
) -> Result<(), String> {
    let edges = case.scene.total_edges();
    if got.edge_count() != edges || got.light_count() != case.lights.len() {
        return Err(format!(
            "result has {} edges x {} lights, expected {edges} x {}",
            got.edge_count(),
            got.light_count(),
            case.lights.len()
        ));
    }
    if !got.silhouettes_consistent() {
        return Err("compact silhouette lists do not list exactly the edges with m != 0".into());
    }
    let open: Vec<usize> = (0..case.lights.len())
        .map(|l| invariant::open_vertices_scene(&case.scene, got, l))
        .collect();
    if mode.is_consistent() && open.iter().any(|&o| o != 0) {
        return Err(format!("{mode} leaves open vertices per light: {open:?}"));
    }
    // The certified comparison holds on every device; the bit-exact one adds every other edge.
    let mut compared = values::check(
        &case.scene,
        &case.lights,
        mode,
        Rule::Certified,
        reference,
        got,
    )?;
    if rule == Rule::BitExact {
        compared = values::check(&case.scene, &case.lights, mode, rule, reference, got)?;
    }
    if mode == Accuracy::Original && open.iter().any(|&o| o != 0) {
        notes.lock().unwrap().push(format!(
            "{backend:>7} {:<24} original open vertices per light {open:?}",
            case.name
        ));
    }
    if rule == Rule::Certified && mode != Accuracy::Exact {
        notes
            .lock()
            .unwrap()
            .push(format!("{backend:>7} {:<24} {compared}", case.name));
    }
    Ok(())
}

/// A real mesh of moderate size next to the small hard cases: the bundled bunny (about 3.7k
/// triangles, loaded as the CLI loads it: one baked table), with lights outside, inside, directional
/// and several per call, so that size- and light-count-dependent bugs (dispatch limits, buffer
/// strides) show up.
fn bunny_case() -> Case {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/bunny.obj");
    let table = shadowvol_scenes::Scene::from_name_or_path(path)
        .and_then(shadowvol_scenes::Scene::into_baked_table)
        .unwrap_or_else(|e| panic!("{e}"));
    let light = |x, y, z, w| Light::new(x, y, z, w).expect("finite light");
    Case {
        name: "asset-bunny",
        scene: TopologyScene::one("bunny", table),
        lights: vec![
            light(0.0, 0.3, 0.5, 1.0),
            light(1.0, 1.0, 1.0, 0.0),
            light(0.05, 0.1, 0.0, 1.0),
            light(-0.2, 0.1, 0.0, 1.0),
            light(0.0, -1.0, 0.0, 0.0),
        ],
    }
}

/// Scenes with no edges at all: no triangles, and only triangles that welding makes degenerate.
/// Backends must return an empty, well-shaped result (zero-sized buffers are a classic GPU
/// failure).
fn empty_cases() -> Vec<Case> {
    use glam::Vec3;
    use shadowvol_mesh_topology::{EdgeTable, Mesh};
    let lights = vec![
        Light::new(1.0, 2.0, 3.0, 1.0).expect("finite light"),
        Light::new(0.0, 1.0, 0.0, 0.0).expect("finite light"),
    ];
    let no_triangles = Mesh::new(vec![Vec3::ZERO, Vec3::X], vec![]).expect("valid mesh");
    let degenerate_only = Mesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::X, Vec3::Y],
        vec![[0, 1, 2], [3, 3, 0]],
    )
    .expect("valid mesh");
    [
        ("no-triangles", no_triangles),
        ("degenerate-only", degenerate_only),
    ]
    .into_iter()
    .map(|(name, mesh)| Case {
        name,
        scene: TopologyScene::single(EdgeTable::build(&mesh).expect("valid mesh")),
        lights: lights.clone(),
    })
    .collect()
}

/// Every case: the corpus, the bunny, and the empty scenes.
fn all_cases() -> Vec<Case> {
    let mut cases: Vec<Case> = corpus::cases()
        .into_iter()
        .map(|c| Case {
            name: c.name,
            scene: c
                .scene()
                .unwrap_or_else(|e| panic!("corpus case {} is invalid: {e}", c.name)),
            lights: c.lights.clone(),
        })
        .collect();
    cases.push(bunny_case());
    cases.extend(empty_cases());
    cases
}

/// Waits for the worker of `entry` to say whether its backend started; a backend still starting
/// after [`START_TIMEOUT`] counts as unavailable and its thread is no longer joined at the end.
/// Prints what it found.
fn wait_started(
    entry: &BackendEntry,
    rx: &Receiver<Started>,
    handles: &mut Vec<(&'static str, std::thread::JoinHandle<()>)>,
) -> (Started, Option<Rule>) {
    let started = rx.recv_timeout(START_TIMEOUT).unwrap_or_else(|_| {
        // Still starting: it can't be joined at the end without waiting on its driver.
        handles.retain(|(n, _)| *n != entry.name);
        Started::No(format!(
            "did not start within {} s",
            START_TIMEOUT.as_secs()
        ))
    });
    let rule = match &started {
        Started::Yes { device, .. } => {
            let rule = if entry.host {
                Rule::BitExact
            } else {
                Rule::for_device(device)
            };
            eprintln!(
                "  {:>7}: available: {device} (f32 modes: {} rule)",
                entry.name,
                rule.name()
            );
            Some(rule)
        }
        Started::NotCompiled(r) | Started::No(r) => {
            eprintln!("  {:>7}: UNAVAILABLE: {r}", entry.name);
            None
        }
    };
    (started, rule)
}

/// The name of the trial of `backend` on `case` in `mode`. The rule that applies is part of the
/// name: `oracle` for exact (always bit for bit against the big-integer oracle), `bit-exact` or
/// `certified` for the f32 modes (see `support/values.rs`); none when the backend did not start.
fn trial_name(backend: &str, case: &str, mode: Accuracy, rule: Option<Rule>) -> String {
    match rule {
        Some(_) if mode == Accuracy::Exact => {
            format!("conformance::{backend}::{case}::{mode}::oracle")
        }
        Some(r) => format!("conformance::{backend}::{case}::{mode}::{}", r.name()),
        None => format!("conformance::{backend}::{case}::{mode}"),
    }
}

/// What every trial of the run shares.
struct Shared {
    cases: Arc<Vec<Case>>,
    references: References,
    notes: Notes,
    ci: bool,
}

/// The trial `name` of `backend` (as it `started`) on case `ci_idx` in `mode`: skipped or failed
/// when the backend did not start, otherwise a job for its worker whose result is checked.
fn backend_trial(
    shared: &Shared,
    name: String,
    (backend, started, rule): (&'static str, &Started, Option<Rule>),
    (ci_idx, mode): (usize, Accuracy),
    xfail_reason: Option<&'static str>,
) -> Trial {
    match started {
        Started::NotCompiled(reason) if !shared.ci => {
            let why = format!("{backend}: {reason}");
            Trial::ignorable_test(name, move || Ok(Completion::ignored_with(why)))
        }
        Started::No(reason) if !shared.ci => {
            let why = format!("{backend} unavailable: {reason}");
            Trial::ignorable_test(name, move || Ok(Completion::ignored_with(why)))
        }
        Started::No(reason) | Started::NotCompiled(reason) => {
            let why = format!("{backend} unavailable (CI is set, so this fails): {reason}");
            Trial::test(name, move || Err(Failed::from(why)))
        }
        Started::Yes { jobs, .. } => {
            let jobs = jobs.clone();
            let cases = Arc::clone(&shared.cases);
            let notes = Arc::clone(&shared.notes);
            let references = Arc::clone(&shared.references);
            let rule = rule.expect("a started backend has a rule");
            Trial::test(name, move || {
                let (tx, rx) = mpsc::channel();
                jobs.send(Job {
                    case: ci_idx,
                    mode,
                    reply: tx,
                })
                .map_err(|_| "the backend's worker thread is gone")?;
                let outcome = rx
                    .recv()
                    .map_err(|_| "the backend's worker thread died".to_owned())
                    .and_then(|r| r)
                    .and_then(|(m, stats)| {
                        if stats.uncertain > 0 {
                            notes.lock().unwrap().push(format!(
                                "{backend:>7} {:<24} {mode:<8} {} (edge, vertex, light) evaluations not certified on the device, decided on the host",
                                cases[ci_idx].name, stats.uncertain
                            ));
                        }
                        let case = &cases[ci_idx];
                        let reference = references[ci_idx][mode_index(mode)]
                            .get_or_init(|| values::reference(&case.scene, &case.lights, mode));
                        check(backend, case, mode, rule, reference, &m, &notes)
                    });
                match (outcome, xfail_reason) {
                    (Ok(()), None) => Ok(()),
                    (Err(e), None) => Err(e.into()),
                    (Err(_), Some(_)) => Ok(()),
                    (Ok(()), Some(why)) => Err(format!(
                        "listed in EXPECTED_FAILURES ({why}) but passed: remove it from the list"
                    )
                    .into()),
                }
            })
        }
    }
}

/// The checks must be able to fail: corrupts a correct result in each checked way, under both
/// rules and in every mode, and fails if a check misses it.
fn checks_detect_corruption(cases: &[Case]) -> Result<(), Failed> {
    let case = cases
        .iter()
        .find(|c| c.scene.total_edges() > 0)
        .ok_or("no case with edges")?;
    let notes: Notes = Arc::default();
    let mut cpu = CpuBackend::new();
    for (mode, rule) in Accuracy::ALL
        .into_iter()
        .flat_map(|m| [(m, Rule::BitExact), (m, Rule::Certified)])
    {
        let reference = values::reference(&case.scene, &case.lights, mode);
        let (good, _) =
            extract_once(&mut cpu, &case.scene, &case.lights, mode).map_err(|e| e.to_string())?;
        check("self-test", case, mode, rule, &reference, &good, &notes)?;
        let corrupt = |bad: &Multiplicities, what: &str| {
            if check("self-test", case, mode, rule, &reference, bad, &notes).is_ok() {
                Err(format!(
                    "{mode}, {} rule: {what} went unnoticed",
                    rule.name()
                ))
            } else {
                Ok(())
            }
        };
        // A changed multiplicity (with its list kept consistent).
        let mut bad = good.clone();
        bad.values_mut(0)[0] += 1;
        bad.rebuild_silhouettes();
        corrupt(&bad, "a changed multiplicity")?;
        // Every sign negated, and every sign 0: both close every chain.
        let mut bad = good.clone();
        bad.all_values_mut().iter_mut().for_each(|m| *m = -*m);
        bad.rebuild_silhouettes();
        corrupt(&bad, "a negated result")?;
        let bad = Multiplicities::zeroed(good.edge_count(), good.light_count());
        corrupt(&bad, "an all-zero result")?;
        // A compact list that does not match the values.
        let mut bad = good.clone();
        bad.set_silhouette(0, vec![]);
        if good.silhouette(0).is_empty() {
            bad.set_silhouette(0, vec![0]);
        }
        corrupt(&bad, "an inconsistent compact list")?;
        // A result of the wrong shape.
        let bad = Multiplicities::zeroed(case.scene.total_edges() + 1, case.lights.len());
        corrupt(&bad, "a wrongly sized result")?;
    }
    Ok(())
}

/// The trials about the run itself: the expected-failure list names real tests (of
/// `known_names`), the checks detect corruption, the corpus reaches the exact fallback with both
/// signs, and the corpus is not empty.
fn self_trials(cases: &Arc<Vec<Case>>, known_names: &[String]) -> Vec<Trial> {
    let stale: Vec<&str> = EXPECTED_FAILURES
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| !known_names.iter().any(|k| k == n))
        .collect();
    let self_test_cases = Arc::clone(cases);
    // The corpus must make the exact fallback answer both signs, so that exact mode's trials
    // check the fallback of every backend (and of `cpu`) against the oracle, not only zeros.
    let fallback_cases = Arc::clone(cases);
    let case_count = cases.len();
    vec![
        Trial::test("conformance::expected_failures_exist", move || {
            if stale.is_empty() {
                Ok(())
            } else {
                Err(format!("EXPECTED_FAILURES names unknown tests: {stale:?}").into())
            }
        }),
        Trial::test("conformance::checks_detect_corruption", move || {
            checks_detect_corruption(&self_test_cases)
        }),
        Trial::test(
            "conformance::corpus_reaches_exact_fallback_with_both_signs",
            move || {
                let mut total = [0; 3];
                for c in fallback_cases.iter() {
                    let n = values::fallback_signs(&c.scene, &c.lights);
                    (0..3).for_each(|i| total[i] += n[i]);
                }
                if total[0] > 0 && total[2] > 0 {
                    Ok(())
                } else {
                    Err(format!(
                        "pairs left to the exact fallback by sign [-1, 0, +1]: {total:?}; \
                         the corpus needs both non-zero answers"
                    )
                    .into())
                }
            },
        ),
        Trial::test("conformance::corpus_not_empty", move || {
            if case_count > 0 {
                Ok(())
            } else {
                Err("the conformance corpus is empty".into())
            }
        }),
    ]
}

/// Prints what the run reported without asserting it.
fn print_notes(notes: &Notes) {
    let mut notes = notes.lock().map(|n| n.clone()).unwrap_or_default();
    if !notes.is_empty() {
        notes.sort();
        eprintln!(
            "\nreported, not asserted (original's open vertices: it is the baseline; what the certified rule compared):"
        );
        for n in notes {
            eprintln!("  {n}");
        }
    }
}

fn main() {
    // No `error: XDG_RUNTIME_DIR ...` line from Mesa on a machine without a display.
    shadowvol_silhouette::gpu::quiet_without_display();
    let args = Arguments::from_args();
    let ci = is_ci();
    let cases = Arc::new(all_cases());
    let shared = Shared {
        references: Arc::new(cases.iter().map(|_| Default::default()).collect()),
        notes: Arc::default(),
        cases: Arc::clone(&cases),
        ci,
    };

    // Start every backend in parallel, then wait for each to report.
    let entries = shadowvol_registry::backends();
    let mut handles = Vec::new();
    let starting: Vec<(BackendEntry, Receiver<Started>)> = entries
        .iter()
        .map(|&e| {
            let (rx, handle) = spawn_worker(e, Arc::clone(&cases));
            handles.push((e.name, handle));
            (e, rx)
        })
        .collect();
    let mut trials = Vec::new();
    let mut known_names = Vec::new();
    let mut workers = Vec::new();
    eprintln!("conformance: {} corpus cases, CI={ci}", cases.len());
    for (entry, rx) in starting {
        let (started, rule) = wait_started(&entry, &rx, &mut handles);
        for (ci_idx, case) in cases.iter().enumerate() {
            for mode in Accuracy::ALL {
                let name = trial_name(entry.name, case.name, mode, rule);
                known_names.push(name.clone());
                let xfail = EXPECTED_FAILURES.iter().find(|(n, _)| *n == name);
                let trial = backend_trial(
                    &shared,
                    name,
                    (entry.name, &started, rule),
                    (ci_idx, mode),
                    xfail.map(|(_, why)| *why),
                );
                trials.push(if xfail.is_some() {
                    trial.with_kind("xfail")
                } else {
                    trial
                });
            }
        }
        workers.push(started);
    }
    trials.extend(self_trials(&cases, &known_names));

    let conclusion = libtest_mimic::run(&args, trials);
    drop(workers); // closes the job channels so the worker threads end
    if let Err(e) = join_workers(handles) {
        eprintln!("conformance: backend shutdown failed: {e}");
        std::process::exit(101);
    }
    print_notes(&shared.notes);
    conclusion.exit();
}
