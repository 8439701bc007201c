//! One frame's inputs to the map passes.

use super::super::fit::LightMap;
use super::super::MapFilter;
use glam::{Mat4, Vec3};

/// One light of a frame, as the map passes draw it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MapLight {
    /// Camera-relative homogeneous light.
    pub(crate) light: [f32; 4],
    /// Colour times gain.
    pub(crate) color: [f32; 3],
    /// Range and cone.
    pub(crate) emission: Option<shadowvol_scenes::Emission>,
    /// Its map, `None` when nothing casts.
    pub(crate) map: Option<LightMap>,
    /// Scissor of its mask and lit passes.
    pub(crate) scissor: Option<[u32; 4]>,
}

/// One frame's inputs to the map passes.
#[derive(Debug, Clone)]
pub(crate) struct MapFrame<'a> {
    /// The camera's `projection * view` at the origin (camera-relative).
    pub(crate) view_proj: Mat4,
    /// The eye in world space.
    pub(crate) eye: Vec3,
    /// Ambient factor.
    pub(crate) ambient: f32,
    /// How the maps are read.
    pub(crate) filter: MapFilter,
    /// The lights.
    pub(crate) lights: &'a [MapLight],
}
