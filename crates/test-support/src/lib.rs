//! Fixtures for the workspace's tests (dev-only, not published).
//!
//! * [`corpus`]: the conformance corpus, the hard cases every backend must pass;
//! * [`shapes`]: the test shapes ([`shapes::uv_sphere_y`] and the exact shapes tests share);
//! * [`ci`]: whether this is a CI run, read one way by every test;
//! * visible skips and per-backend trials, below.
//!
//! A test that needs something the machine may lack (a GPU adapter, an OpenCL platform, a
//! Vulkan driver, a display, a tool) returns an [`Outcome`]: `Ok(())` when it ran, or
//! `Err(`[`Skip`]`)` when it could not. [`skip`] is the only way to make a [`Skip`], and under CI
//! ([`ci::is_ci`]: `CI=true`, `CI=True`, `CI=1`) it panics instead, so in
//! CI every skip is a failure. Elsewhere the test binary, built with [`main!`] on
//! [libtest-mimic](libtest_mimic) (`harness = false`), reports it as
//! `test name ... ignored (<reason>)`, never as `ok`.
//!
//! ```no_run
//! use shadowvol_test_support::{main, skip, Outcome};
//!
//! fn needs_a_tool() -> Outcome {
//!     if std::process::Command::new("some-tool").output().is_err() {
//!         return Err(skip("some-tool is not installed"));
//!     }
//!     assert_eq!(1 + 1, 2);
//!     Ok(())
//! }
//!
//! main!(needs_a_tool);
//! ```
//!
//! A test that never skips stays a plain `fn()`. Every listed function becomes a trial named
//! after it, so `cargo test --test NAME FILTER`
//! filters as with the standard harness. A function left out of the list is dead code, which
//! `cargo clippy --all-targets -- -D warnings` rejects. A panicking test fails (libtest-mimic
//! catches the panic); there is no `#[should_panic]`: assert on the error or on a
//! `std::panic::catch_unwind` result instead. [`per_backend`] makes one trial per backend, so
//! that a backend that can't start shows as a skip under its own name.

pub mod ci;
pub mod corpus;
pub mod filters;
pub mod parts;
pub mod shapes;

use shadowvol_silhouette::BackendError;
use std::fmt;

pub use libtest_mimic::{Arguments, Trial};

/// Why a test did not run: shown as `ignored (<reason>)`. Made only by [`skip`], so that under
/// CI a skip is always a failure.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Skip {
    reason: String,
}

impl Skip {
    /// The reason, as the test output shows it.
    #[must_use]
    pub fn reason(&self) -> &str {
        &self.reason
    }
}

impl fmt::Display for Skip {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.reason)
    }
}

/// What a skippable test returns: `Ok(())` when it ran (its assertions passed), `Err` when it
/// was skipped. A failure is a panic, as in any test.
pub type Outcome = Result<(), Skip>;

/// A skip for `reason` (what is missing, and why).
///
/// # Panics
///
/// Under CI ([`ci::is_ci`]), with a message naming the reason: CI requires
/// every backend and tool, so there a skip fails the test.
#[must_use]
#[track_caller]
pub fn skip(reason: impl fmt::Display) -> Skip {
    let reason = reason.to_string();
    assert!(
        !ci::is_ci(),
        "this test would be skipped ({reason}), but CI is set ({}=true) and CI requires \
         every backend and tool, so it fails",
        ci::CI_ENV
    );
    Skip { reason }
}

/// A started backend, or a [`skip`] when it is [`BackendError::Unavailable`] here (no driver,
/// no device), with the error as the reason (it names the backend and what is missing).
///
/// # Panics
///
/// On any other start error (a backend that is present but fails to start is a bug; `what`
/// names it in the message), and under CI on an unavailable one (see [`skip`]).
#[track_caller]
pub fn started<B>(what: &str, result: Result<B, BackendError>) -> Result<B, Skip> {
    match result {
        Ok(b) => Ok(b),
        Err(e @ BackendError::Unavailable { .. }) => Err(skip(e)),
        Err(e) => panic!("{what} failed to start: {e}"),
    }
}

/// What a test function may return: `()` (a test that never skips) or an [`Outcome`].
pub trait IntoOutcome {
    /// The outcome: `()` is `Ok(())`.
    fn into_outcome(self) -> Outcome;
}

impl IntoOutcome for () {
    fn into_outcome(self) -> Outcome {
        Ok(())
    }
}

impl IntoOutcome for Outcome {
    fn into_outcome(self) -> Outcome {
        self
    }
}

/// A libtest-mimic trial named `name` that runs `test`: `Ok` (or `()`) passes, `Err(Skip)` is
/// ignored with its reason, a panic fails.
///
/// The test runs on a thread of its own, named after the trial, which is joined before the trial
/// reports. Joining waits for the thread's thread-local destructors, which a driver may have
/// registered; libtest-mimic's scoped worker threads are not waited for that far, and a driver's
/// destructor (Mesa's) still running on one of them while the process exits can corrupt the
/// heap.
///
/// # Panics
///
/// When `test` panics (the panic is passed on, so the trial fails with its message), or when the
/// thread cannot be spawned.
pub fn trial<R: IntoOutcome>(
    name: impl Into<String>,
    test: impl FnOnce() -> R + Send + 'static,
) -> Trial {
    let name = name.into();
    let thread = name.clone();
    Trial::ignorable_test(name, move || {
        let outcome = std::thread::Builder::new()
            .name(thread.clone())
            .spawn(move || test().into_outcome())
            .unwrap_or_else(|e| panic!("cannot start the thread of trial {thread}: {e}"))
            .join()
            .unwrap_or_else(|payload| std::panic::resume_unwind(payload));
        Ok(match outcome {
            Ok(()) => libtest_mimic::Completion::Completed,
            Err(s) => libtest_mimic::Completion::ignored_with(s.reason),
        })
    })
}

/// One trial per backend of `backends`, named `NAME::BACKEND`, each running `test(backend)`.
///
/// A backend that can't start here then shows as `ignored (<reason>)` under its own name (a
/// failure under CI) when `test` returns a [`skip`], instead of a loop over the available
/// backends quietly testing fewer. The list comes from the caller (the backend registry, or the
/// CLI's `shadowvol backends`), never from a list of its own.
///
/// ```no_run
/// use shadowvol_test_support::{per_backend, run, skip, Outcome};
///
/// fn starts(backend: &str) -> Outcome {
///     if backend == "missing" {
///         return Err(skip("no driver"));
///     }
///     Ok(())
/// }
///
/// run(per_backend("starts", ["cpu", "missing"], starts));
/// ```
pub fn per_backend<R: IntoOutcome>(
    name: &str,
    backends: impl IntoIterator<Item = impl Into<String>>,
    test: impl Fn(&str) -> R + Clone + Send + 'static,
) -> Vec<Trial> {
    backends
        .into_iter()
        .map(|b| {
            let backend: String = b.into();
            let test = test.clone();
            trial(format!("{name}::{backend}"), move || test(&backend))
        })
        .collect()
}

/// Runs `trials` with the command line's arguments (filters, `--ignored`, `--test-threads`, ...)
/// and exits with the run's status.
///
/// First, on a machine without a display, it turns Mesa's Vulkan device-select layer off
/// ([`quiet_without_display`](shadowvol_silhouette::gpu::quiet_without_display)), so that a
/// trial that starts Vulkan prints no `error: XDG_RUNTIME_DIR ...` line when nothing failed.
/// Call it before the test binary starts a thread or a device.
pub fn run(trials: Vec<Trial>) -> ! {
    shadowvol_silhouette::gpu::quiet_without_display();
    libtest_mimic::run(&Arguments::from_args(), trials).exit()
}

/// The trials of the listed test functions (`fn()` or `fn() -> Outcome`), each named after its function:
/// `trials![a, b]` is `vec![trial("a", a), trial("b", b)]`.
#[macro_export]
macro_rules! trials {
    ($($test:ident),* $(,)?) => {
        ::std::vec![$($crate::trial(::std::stringify!($test), $test)),*]
    };
}

/// A test binary's `main` (for a `harness = false` test) that runs the listed test functions
/// (`fn()` or `fn() -> Outcome`) as trials named after them (see [`trials!`] and [`run`]).
#[macro_export]
macro_rules! main {
    ($($test:ident),* $(,)?) => {
        fn main() {
            $crate::run($crate::trials![$($test),*])
        }
    };
}

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
