//! Quietening Mesa's Vulkan device-select layer on a machine without a display.
//!
//! The layer, an implicit Vulkan layer of Debian's `mesa-vulkan-drivers`, orders the GPUs by the
//! one the display uses. Without a display it has nothing to order by, and its attempt to
//! connect to Wayland prints `error: XDG_RUNTIME_DIR is invalid or not set in the environment.`
//! once per Vulkan instance, although nothing failed. `NODEVICE_SELECT=1` turns the layer off.
//! Every program of the project that may start Vulkan calls [`quiet_without_display`] first:
//! the `shadowvol` binary, the test binaries (through `shadowvol_test_support::run`), the
//! examples; `cargo xtask` sets the variable for the processes it starts.

use std::ffi::OsStr;

/// The environment variable that turns Mesa's Vulkan device-select layer off.
pub const NODEVICE_SELECT: &str = "NODEVICE_SELECT";

/// The value [`quiet_without_display`] gives [`NODEVICE_SELECT`] for these values of
/// `DISPLAY`, `WAYLAND_DISPLAY` and `NODEVICE_SELECT` (`None`: unset): `Some("1")` when neither
/// display variable is set to something non-empty and `NODEVICE_SELECT` is unset, else `None`
/// (leave the environment as it is).
#[must_use]
pub fn device_select_value(
    display: Option<&OsStr>,
    wayland_display: Option<&OsStr>,
    nodevice_select: Option<&OsStr>,
) -> Option<&'static str> {
    let set = |v: Option<&OsStr>| v.is_some_and(|s| !s.is_empty());
    (!set(display) && !set(wayland_display) && nodevice_select.is_none()).then_some("1")
}

/// On a machine without a display (`DISPLAY` and `WAYLAND_DISPLAY` unset or empty), turns off
/// Mesa's Vulkan device-select layer (`NODEVICE_SELECT=1`, unless the variable is set already),
/// so that a run in which nothing failed prints no `error:` line (see the module
/// documentation). With a display it does nothing: there the layer has a display to order the
/// GPUs by.
///
/// Call it first in `main`, before any other thread or Vulkan instance exists: it changes the
/// process's environment, which a C library (the Vulkan loader, Mesa) may be reading on another
/// thread. A unit test of the standard harness, which has no `main` of its own, calls it at its
/// start; that is safe only while no other test of the binary starts Vulkan.
pub fn quiet_without_display() {
    let var = std::env::var_os;
    let value = device_select_value(
        var("DISPLAY").as_deref(),
        var("WAYLAND_DISPLAY").as_deref(),
        var(NODEVICE_SELECT).as_deref(),
    );
    if let Some(value) = value {
        std::env::set_var(NODEVICE_SELECT, value);
    }
}

#[cfg(test)]
mod tests {
    use super::device_select_value;
    use std::ffi::OsStr;

    #[test]
    fn the_layer_goes_off_only_without_a_display_and_without_a_choice() {
        let s = |v: &'static str| Some(OsStr::new(v));
        assert_eq!(device_select_value(None, None, None), Some("1"));
        assert_eq!(device_select_value(s(""), s(""), None), Some("1"));
        assert_eq!(device_select_value(s(":0"), None, None), None);
        assert_eq!(device_select_value(None, s("wayland-0"), None), None);
        // The user's own choice stands, whatever it is.
        assert_eq!(device_select_value(None, None, s("0")), None);
        assert_eq!(device_select_value(None, None, s("")), None);
    }
}
