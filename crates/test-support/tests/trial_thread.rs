//! `trial` runs each test on a thread of its own and joins it: a thread-local destructor the
//! test registered (as a driver may) has finished when the trial reports. Its own `main`, since
//! it looks at what `libtest_mimic::run` leaves behind. (That a panic in the test still fails
//! its trial is seen in every planted bug of the workspace's `main!` tests; a planted failure
//! here would count as a failed test in `cargo xtask test`'s totals.)

use shadowvol_test_support::{trial, Arguments};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

static DROPPED: AtomicBool = AtomicBool::new(false);

/// A thread-local whose destructor takes a while and then records that it ran.
struct SlowDrop;

impl Drop for SlowDrop {
    fn drop(&mut self) {
        std::thread::sleep(Duration::from_millis(200));
        DROPPED.store(true, Ordering::SeqCst);
    }
}

thread_local! {
    static SLOW: SlowDrop = const { SlowDrop };
}

fn registers_a_slow_thread_local() {
    SLOW.with(|_| {});
}

fn main() {
    // Worker threads, as libtest-mimic uses by default on a multi-core machine.
    let args = Arguments {
        test_threads: Some(2),
        ..Arguments::default()
    };
    let c = libtest_mimic::run(
        &args,
        vec![trial(
            "registers_a_slow_thread_local",
            registers_a_slow_thread_local,
        )],
    );
    assert!(!c.has_failed(), "{c:?}");
    assert!(
        DROPPED.load(Ordering::SeqCst),
        "the trial reported before its thread-local destructor finished"
    );
    println!("trial_thread: ok");
}
