//! Bounded waits for OpenCL events.
//!
//! `clFinish`, `clWaitForEvents` and blocking reads and writes have no timeout, so a hung kernel
//! or a lost device would hang the process. Instead the backend enqueues everything
//! non-blocking, flushes the queue and waits for the commands' events here, each wait ending
//! when the command is `CL_COMPLETE`, reports an error (a negative status), or a deadline passes.
//!
//! A wait has two phases:
//!
//! 1. **Spin** (devices other than the host CPU only): read
//!    `CL_EVENT_COMMAND_EXECUTION_STATUS` in a loop, yielding the core between reads, for up to
//!    [`GPU_SPIN`]. A GPU's short commands (tens of µs) are seen finished at once, as `clFinish`
//!    saw them; NVIDIA's completion callbacks arrive ~30 µs late, which made every wait that
//!    much slower. On a CPU device (PoCL) the spinning thread would take a core from the
//!    device's worker threads (it made short extractions 10–25 % slower), so there is no spin.
//! 2. **Sleep**: register a completion callback (`clSetEventCallback`) that signals a condition
//!    variable, and sleep on it with a timeout: the thread is woken as soon as the driver reports
//!    the end. Between wake-ups it also reads the status, so a driver whose callbacks are late or
//!    missing is still seen finished within [`MAX_STEP`]; the steps grow from [`MIN_STEP`] by
//!    1/16 of the time waited so far. Where the callback cannot be registered, the same steps are
//!    slept through.

use opencl3::error_codes::ClError;
use opencl3::event::{Event, CL_COMPLETE};
use opencl3::types::{cl_event, cl_int};
use std::ffi::c_void;
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// How long a wait for a device other than the host CPU spins before it sleeps.
pub(crate) const GPU_SPIN: Duration = Duration::from_millis(2);

/// The first interval between two status reads while sleeping.
pub(crate) const MIN_STEP: Duration = Duration::from_micros(50);
/// The longest interval between two status reads.
pub(crate) const MAX_STEP: Duration = Duration::from_millis(1);

/// How a wait for one event ended.
#[derive(Debug)]
pub(crate) enum Outcome {
    /// The command finished (`CL_COMPLETE`).
    Complete,
    /// The command was terminated with this (negative) error code.
    Failed(i32),
    /// `clGetEventInfo` failed with this error.
    QueryFailed(ClError),
    /// The deadline passed first; the command may still be queued or running.
    TimedOut,
}

/// The deadline `limit` from now; `None` (never) when that instant cannot be represented.
pub(crate) fn deadline_after(limit: Duration) -> Option<Instant> {
    Instant::now().checked_add(limit)
}

/// Set by [`on_end`] to the event's final status.
#[derive(Default)]
struct Signal {
    status: Mutex<Option<cl_int>>,
    ended: Condvar,
}

/// The completion callback: records the status and wakes the waiter.
extern "C" fn on_end(_event: cl_event, status: cl_int, user_data: *mut c_void) {
    // SAFETY: `user_data` is the `Arc::into_raw` made for this one registration in `wait`; the
    // driver calls the callback once, so this takes over that reference exactly once.
    let signal = unsafe { Arc::from_raw(user_data.cast_const().cast::<Signal>()) };
    *signal.status.lock().unwrap_or_else(PoisonError::into_inner) = Some(status);
    signal.ended.notify_all();
}

/// The outcome for a final status read from the event or given to the callback; `None` while
/// the command is queued, submitted or running.
fn ended(status: cl_int) -> Option<Outcome> {
    match status {
        CL_COMPLETE => Some(Outcome::Complete),
        s if s < 0 => Some(Outcome::Failed(s)),
        _ => None,
    }
}

/// Waits until `event` finishes, fails, or `deadline` passes (`None`: no deadline), spinning
/// for up to `spin` first (zero: no spin).
pub(crate) fn wait(event: &Event, deadline: Option<Instant>, spin: Duration) -> Outcome {
    let start = Instant::now();
    loop {
        match event.command_execution_status() {
            Ok(s) => {
                if let Some(o) = ended(s.0) {
                    return o;
                }
            }
            Err(e) => return Outcome::QueryFailed(e),
        }
        let now = Instant::now();
        if deadline.is_some_and(|d| now >= d) {
            return Outcome::TimedOut;
        }
        if now - start >= spin {
            break;
        }
        std::thread::yield_now();
    }
    let signal = Arc::new(Signal::default());
    let raw = Arc::into_raw(Arc::clone(&signal))
        .cast_mut()
        .cast::<c_void>();
    if event.set_callback(CL_COMPLETE, on_end, raw).is_err() {
        // SAFETY: not registered, so the callback never runs: take the reference back.
        drop(unsafe { Arc::from_raw(raw.cast_const().cast::<Signal>()) });
        return poll(event, deadline, None);
    }
    poll(event, deadline, Some(&signal))
}

/// Reads the status between steps, sleeping on `signal` (when given) or the thread.
fn poll(event: &Event, deadline: Option<Instant>, signal: Option<&Signal>) -> Outcome {
    let start = Instant::now();
    loop {
        let now = Instant::now();
        let mut step = ((now - start) / 16).clamp(MIN_STEP, MAX_STEP);
        if let Some(d) = deadline {
            step = step.min(d.saturating_duration_since(now));
        }
        if let Some(signal) = signal {
            let guard = signal.status.lock().unwrap_or_else(PoisonError::into_inner);
            let (guard, _) = signal
                .ended
                .wait_timeout_while(guard, step, |s| s.is_none())
                .unwrap_or_else(PoisonError::into_inner);
            if let Some(o) = guard.and_then(ended) {
                return o;
            }
        } else {
            std::thread::sleep(step);
        }
        match event.command_execution_status() {
            Ok(s) => {
                if let Some(o) = ended(s.0) {
                    return o;
                }
            }
            Err(e) => return Outcome::QueryFailed(e),
        }
        if deadline.is_some_and(|d| Instant::now() >= d) {
            return Outcome::TimedOut;
        }
    }
}

/// True when `event`'s command has ended (finished or failed), so that nothing it uses is
/// touched any more; false while it is queued or running, or when its status cannot be read.
pub(crate) fn has_ended(event: &Event) -> bool {
    event
        .command_execution_status()
        .is_ok_and(|s| s.0 <= CL_COMPLETE)
}
