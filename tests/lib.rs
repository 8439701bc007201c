//! Cross-backend conformance tests live in `tests/`.
