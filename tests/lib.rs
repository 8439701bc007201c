//! Cross-backend conformance tests for shadowvol.
//!
//! The tests live in `conformance.rs` (a `harness = false` test built on `libtest-mimic`): one
//! test per (backend, corpus case, accuracy mode), named
//! `conformance::<backend>::<case>::<mode>::<rule>` (the rule is in `conformance.rs`),
//! generated from the backend registry (`shadowvol_registry::backends()`) and the shared corpus
//! (`shadowvol_test_support::corpus::cases()`). Run them with
//!
//! ```text
//! cargo test -p shadowvol-tests                      # all backends (features on by default)
//! cargo test -p shadowvol-tests -- conformance::wgpu  # one backend
//! CI=true cargo test -p shadowvol-tests               # an unavailable backend fails instead of skipping
//!                                                    # (CI=1 and CI=True alike)
//! ```
//!
//! `shaders.rs` (also `harness = false`) validates every shader source in `shaders/` as the
//! crates build it: the WGSL modules with naga, the GLSL stages with `glslangValidator` and the
//! definitions of each committed SPIR-V file. It needs no GPU:
//!
//! ```text
//! cargo test -p shadowvol-tests --test shaders
//! ```
//!
//! This library itself is empty; it exists so that the package can carry the backend features.
