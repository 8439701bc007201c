//! What a run costs in memory, as the JSON reports it: the process's peak resident set, measured
//! by the kernel, and the bytes the prepared scene holds.

use shadowvol_silhouette::PreparedBytes;

/// The process's peak resident set size in bytes (`VmHWM` in `/proc/self/status`: the kernel's
/// high-water mark of resident memory since the process started, device memory included where
/// the driver keeps it in the process, as lavapipe and PoCL do). The kernel sums per-CPU
/// counters for the current resident set, so two readings may differ by a few hundred KB even
/// when nothing was freed. `None` where that file does not exist (non-Linux hosts).
#[must_use]
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map(|kb| kb * 1024)
}

pub use shadowvol_report::TableBytes;

/// The tables of `topology_bytes` plus what a backend or pipeline reports for its prepared
/// scene.
#[must_use]
pub fn table_bytes(topology_bytes: u64, prepared: PreparedBytes) -> TableBytes {
    TableBytes {
        topology: topology_bytes,
        host: prepared.host,
        device: prepared.device,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_rss_grows_with_a_touched_allocation() {
        let Some(before) = peak_rss_bytes() else {
            eprintln!("SKIP: no /proc/self/status on this host");
            return;
        };
        // 64 MiB, every page written, so it is resident.
        let v = vec![1u8; 64 << 20];
        let after = peak_rss_bytes().expect("read once, readable again");
        assert!(v.iter().step_by(4096).all(|&b| b == 1));
        assert!(
            after >= before.max(64 << 20),
            "peak {after} after touching 64 MiB (before: {before})"
        );
    }
}
