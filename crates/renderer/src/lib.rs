//! Placeholder crate: not implemented yet (see the issue list).
