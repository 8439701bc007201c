//! Whether this run is a CI run, read one way everywhere.
//!
//! Under CI every backend must start: a test that finds a driver missing fails instead of
//! skipping ([`skip`](crate::skip) panics). Every test of the workspace asks [`is_ci`], and
//! `cargo xtask test` reads the variable the same way, so `CI=1`, `CI=True` and `CI=true` behave
//! the same everywhere.

/// The environment variable CI services set.
pub const CI_ENV: &str = "CI";

/// Whether `value`, the text of [`CI_ENV`], means a CI run: `true` in any case, or `1`
/// (surrounding white space ignored).
///
/// ```
/// use shadowvol_test_support::ci::means_ci;
/// for v in ["true", "True", "TRUE", "1", " true "] {
///     assert!(means_ci(v), "{v}");
/// }
/// for v in ["", "0", "false", "yes"] {
///     assert!(!means_ci(v), "{v}");
/// }
/// ```
#[must_use]
pub fn means_ci(value: &str) -> bool {
    let v = value.trim();
    v.eq_ignore_ascii_case("true") || v == "1"
}

/// Whether [`CI_ENV`] is set to a value that [`means_ci`] (unset, or not valid text: no).
#[must_use]
pub fn is_ci() -> bool {
    std::env::var(CI_ENV).is_ok_and(|v| means_ci(&v))
}
