//! The memory check of `EdgeTable::check_size` and where `available_memory` reads its number.
//!
//! This file is its own test binary with a single test, because it sets
//! `SHADOWVOL_MEMORY_LIMIT` for the whole process: no other test runs beside it.

use shadowvol_mesh_topology::{
    available_memory, EdgeTable, MeshError, MEMORY_CHECK_THRESHOLD, MEMORY_LIMIT_ENV,
};

/// `MemAvailable` in bytes, parsed here independently of the crate (`None` off Linux).
fn meminfo_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut words = line.split_whitespace().skip(1);
    let kb: u64 = words.next()?.parse().ok()?;
    assert_eq!(words.next(), Some("kB"), "{line}");
    Some(kb << 10)
}

/// `memory.max - memory.current` of the cgroup v2, parsed here (`None` when not readable or
/// `max`).
fn cgroup_available() -> Option<u64> {
    let read = |f: &str| -> Option<u64> {
        std::fs::read_to_string(format!("/sys/fs/cgroup/{f}"))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    Some(read("memory.max")?.saturating_sub(read("memory.current")?))
}

#[test]
fn memory_limit_env_caps_the_build_and_falls_back_to_the_system() {
    // A small table (below MEMORY_CHECK_THRESHOLD): without the variable the check is skipped,
    // with it the variable is the limit, and the comparison is "needed > available".
    let (t, v) = (1000u64, 600u64);
    let needed = EdgeTable::estimate_bytes(t, v);
    assert_eq!(
        needed,
        1000 * 68 + 600 * 52,
        "the documented per-item bytes"
    );
    assert!(needed < MEMORY_CHECK_THRESHOLD);

    std::env::set_var(MEMORY_LIMIT_ENV, format!(" {needed} "));
    assert_eq!(
        available_memory(),
        Some((needed, format!("{MEMORY_LIMIT_ENV}={needed}"))),
        "the variable is read, trimmed, and named as the origin"
    );
    assert_eq!(EdgeTable::check_size(t, v), Ok(needed), "exactly enough");

    let short = needed - 1;
    std::env::set_var(MEMORY_LIMIT_ENV, short.to_string());
    assert_eq!(
        EdgeTable::check_size(t, v),
        Err(MeshError::OutOfMemory {
            triangles: t,
            vertices: v,
            needed,
            available: short,
            origin: format!("{MEMORY_LIMIT_ENV}={short}"),
        }),
        "one byte short is refused although the table is below the threshold"
    );
    // The index limits come before the memory check, whatever the limit.
    assert!(matches!(
        EdgeTable::check_size(u64::from(u32::MAX) / 3, 3),
        Err(MeshError::TooLarge { .. })
    ));

    // A value that is not a number is ignored: the system's numbers are used.
    std::env::set_var(MEMORY_LIMIT_ENV, "lots");
    let got = available_memory();
    std::env::remove_var(MEMORY_LIMIT_ENV);
    let expected = match (meminfo_available(), cgroup_available()) {
        (Some(m), Some(c)) => Some(m.min(c)),
        (m, c) => m.or(c),
    };
    match (got, expected) {
        (None, None) => {}
        (Some((n, origin)), Some(want)) => {
            // MemAvailable moves between two reads; a wrong unit or operation is off by 2^10.
            assert!(
                n / 2 <= want && want / 2 <= n,
                "{n} bytes from {origin}, {want} read here"
            );
            assert!(!origin.contains(MEMORY_LIMIT_ENV), "{origin}");
            if let (Some(m), Some(c)) = (meminfo_available(), cgroup_available()) {
                // The smaller of the two when they are far apart.
                if c < m / 2 {
                    assert!(origin.starts_with("cgroup"), "{origin}: {m} {c}");
                } else if m < c / 2 {
                    assert!(origin.starts_with("/proc/meminfo"), "{origin}: {m} {c}");
                }
            }
        }
        (got, want) => panic!("available_memory() = {got:?}, read here: {want:?}"),
    }
}
