//! What the reference's integration tests share: a frame drawn by hand, as a renderer would hand
//! it to the reference.

use shadowvol_reference::Shot;
use shadowvol_scenes::{Camera, Scene};

/// A square frame by hand: the scene, its camera and size, and the raster's per-pixel data
/// (colour, surface ids, each light's stencil) with each light's colour.
#[derive(Clone)]
pub struct Frame {
    pub scene: Scene,
    pub camera: Camera,
    pub size: u32,
    pub rgba: Vec<u8>,
    pub ids: Vec<[u32; 2]>,
    pub stencil: Vec<Vec<u8>>,
    pub colors: Vec<[f32; 3]>,
}

impl Frame {
    /// The frame as the reference reads it.
    pub fn shot(&self) -> Shot<'_> {
        Shot::new(
            &self.scene,
            self.camera,
            self.size,
            self.size,
            &self.rgba,
            &self.ids,
            &self.stencil,
            &self.colors,
        )
    }
}
