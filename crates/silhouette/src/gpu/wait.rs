//! How long a GPU backend waits for its device before giving up.
//!
//! Every GPU backend bounds each wait for the device (a fence, a queue finish, a buffer mapping)
//! by [`wait_limit`], so a hung kernel or a lost device becomes a
//! [`BackendError::Device`] instead of a hang. The limit is [`DEFAULT_TIMEOUT`] unless the
//! environment variable [`TIMEOUT_ENV`] gives another one in seconds.

use crate::BackendError;
use std::time::Duration;

/// The environment variable that sets [`wait_limit`], in seconds (a positive decimal
/// number, for example `SHADOWVOL_GPU_TIMEOUT=30` or `0.5`).
pub const TIMEOUT_ENV: &str = "SHADOWVOL_GPU_TIMEOUT";

/// The wait limit when [`TIMEOUT_ENV`] is not set: 600 s, far beyond any extraction of the
/// bundled scenes, even on a CPU-emulated device.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(600);

/// The longest a GPU backend waits for one submission, readback or mapping.
///
/// # Errors
///
/// [`BackendError::InvalidInput`] naming [`TIMEOUT_ENV`] and its value when the variable is set
/// but is not a positive, finite number of seconds (at most 10⁹).
pub fn wait_limit() -> Result<Duration, BackendError> {
    limit_from_env().map_err(BackendError::InvalidInput)
}

fn limit_from_env() -> Result<Duration, String> {
    match std::env::var(TIMEOUT_ENV) {
        Err(std::env::VarError::NotPresent) => Ok(DEFAULT_TIMEOUT),
        Err(std::env::VarError::NotUnicode(v)) => Err(format!(
            "{TIMEOUT_ENV}={v:?} is not valid text; give the limit in seconds, e.g. {TIMEOUT_ENV}=30"
        )),
        Ok(v) => parse_limit(&v),
    }
}

/// `limit` as error messages state it after "within": `"<seconds> s (the limit set by
/// SHADOWVOL_GPU_TIMEOUT, in seconds; default 600 s)"`, the seconds in full (`0.000001`, not
/// rounded to `0.000`), so every backend words a timeout the same way.
#[must_use]
pub fn describe_wait_limit(limit: Duration) -> String {
    format!(
        "{} s (the limit set by {TIMEOUT_ENV}, in seconds; default {} s)",
        limit.as_secs_f64(),
        DEFAULT_TIMEOUT.as_secs()
    )
}

fn parse_limit(v: &str) -> Result<Duration, String> {
    match v.trim().parse::<f64>() {
        Ok(s) if s.is_finite() && s > 0.0 && s <= 1e9 => Ok(Duration::from_secs_f64(s)),
        _ => Err(format!(
            "{TIMEOUT_ENV}={v:?} is not a positive number of seconds (at most 1e9); \
             give the limit in seconds, e.g. {TIMEOUT_ENV}=30"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_limit_is_described_in_full_with_its_variable() {
        let d = describe_wait_limit(Duration::from_micros(1));
        assert!(
            d.starts_with("0.000001 s") && d.contains(TIMEOUT_ENV),
            "{d}"
        );
        assert!(describe_wait_limit(DEFAULT_TIMEOUT).starts_with("600 s"));
    }

    #[test]
    fn parses_seconds_and_refuses_nonsense() {
        assert_eq!(parse_limit("30"), Ok(Duration::from_secs(30)));
        assert_eq!(parse_limit(" 0.5 "), Ok(Duration::from_millis(500)));
        for bad in ["", "0", "-1", "nan", "inf", "1e10", "ten"] {
            let e = parse_limit(bad).unwrap_err();
            assert!(e.contains(TIMEOUT_ENV) && e.contains(bad), "{bad}: {e}");
        }
    }
}
