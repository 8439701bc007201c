//! A progress bar on stderr, with elapsed time and an estimate of the time left.

use std::time::Instant;

/// A progress bar on stderr (no dependency: xtask builds fast).
pub(crate) struct Progress {
    total: u64,
    done: u64,
    start: Instant,
}

impl Progress {
    /// A bar of `total` steps, started now.
    pub fn new(total: u64) -> Self {
        Self {
            total: total.max(1),
            done: 0,
            start: Instant::now(),
        }
    }

    /// Counts one step and redraws the bar with `what`.
    pub fn step(&mut self, what: &str) {
        self.done += 1;
        let frac = self.done as f64 / self.total as f64;
        let width = 30;
        let filled = ((frac * width as f64) as usize).min(width);
        let elapsed = self.start.elapsed().as_secs_f64();
        let eta = if self.done > 0 {
            elapsed / self.done as f64 * (self.total - self.done.min(self.total)) as f64
        } else {
            0.0
        };
        eprint!(
            "\r[{}{}] {}/{} {:>4.0}s eta {:>4.0}s  {:<48.48}",
            "#".repeat(filled),
            ".".repeat(width - filled),
            self.done,
            self.total,
            elapsed,
            eta,
            what
        );
    }

    /// Ends the bar's line.
    pub fn finish(&self) {
        eprintln!();
    }
}
