//! Scene loading, procedural meshes and presets.

pub mod obj;
