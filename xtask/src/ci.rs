//! Whether this run is a CI run: `CI` set to `true` in any case, or `1`, surrounding white space
//! ignored; the tests read it the same way (`shadowvol_test_support::ci`). xtask keeps its own
//! copy of these few lines so that it builds without the workspace's crates.

/// Whether the environment variable `CI` means a CI run (see [`means_ci`]).
pub fn is_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| means_ci(&v))
}

/// Whether `value`, the text of `CI`, means a CI run.
fn means_ci(value: &str) -> bool {
    let v = value.trim();
    v.eq_ignore_ascii_case("true") || v == "1"
}

#[cfg(test)]
mod tests {
    use super::means_ci;

    /// The same values as `shadowvol_test_support::ci::means_ci`'s example.
    #[test]
    fn reads_ci_like_the_tests() {
        for v in ["true", "True", "TRUE", "1", " true "] {
            assert!(means_ci(v), "{v}");
        }
        for v in ["", "0", "false", "yes"] {
            assert!(!means_ci(v), "{v}");
        }
    }
}
