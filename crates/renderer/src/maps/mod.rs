//! Shadow maps, the technique engines ship, built as a fair peer of the volumes: the settings
//! ([`MapSettings`]), each light's projection ([`fit`]) and the passes that
//! [`crate::MapPipeline`] records on the caller's device and in the caller's encoder, with
//! nothing read back during a frame.
//!
//! Per light, one map:
//! * directional: an orthographic map fitted to what the view sees of the scene's box and to
//!   every caster above it ([`fit::light_map`]);
//! * spot (outer cone up to [`fit::SPOT_MAX_HALF_ANGLE`]): a perspective map over the cone;
//! * point (and wider spots): a cube map of 6 faces.
//!
//! Maps are `Depth32Float`, reverse-Z with an infinite far plane, as Bevy 0.20's are. Only
//! shadow casters are drawn into them (receivers cast no volume either). The lookup offsets the
//! surface point as Bevy's does: by the depth bias along the direction to the light, and by the
//! normal bias times the texel size along the normal; the slope-scaled part is the map pass's
//! [`wgpu::DepthBiasState::slope_scale`]. The comparison is the hardware's: one tap
//! ([`MapFilter::Hard`]), 3x3 bilinear taps ([`MapFilter::Pcf`]), or Bevy's percentage-closer
//! soft shadows for lights with a size ([`MapFilter::Pcss`], [`pcss`]). The defaults are Bevy
//! 0.20's ([`MapSettings::default`]).

pub mod fit;
pub(crate) mod pass;
pub mod pcss;
mod resources;

pub use fit::{cube_face, light_map, FitBounds, LightMap, MapKind};
pub(crate) use pass::MapPass;
pub use shadowvol_report::{MapBias, MapFilter};

/// `shaders/render_maps.wgsl`: the map, mask and lit passes (appended to `render_raster.wgsl`).
pub const MAPS_WGSL: &str = include_str!("../../../../shaders/render_maps.wgsl");

/// The map pipeline's module: the renderer's `render_raster.wgsl`, then `render_maps.wgsl`.
#[must_use]
pub fn maps_source() -> String {
    format!("{}\n{MAPS_WGSL}", crate::raster::RASTER_WGSL)
}

/// Bevy 0.20's directional (and spot) map size, texels.
pub const BEVY_DIRECTIONAL_SIZE: u32 = 2048;
/// Bevy 0.20's point-light cube face size, texels.
pub const BEVY_POINT_SIZE: u32 = 1024;
/// Bevy 0.20's directional and spot light bias: depth 0.02, normal 1.8, no slope-scaled part.
pub const BEVY_DIRECTIONAL_BIAS: MapBias = MapBias {
    depth: 0.02,
    slope: 0.0,
    normal: 1.8,
};
/// Bevy 0.20's point light bias: depth 0.08, normal 0.6, no slope-scaled part.
pub const BEVY_POINT_BIAS: MapBias = MapBias {
    depth: 0.08,
    slope: 0.0,
    normal: 0.6,
};

/// What the shadow-map pipeline draws with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapSettings {
    /// Side of every map and cube face, texels; `None`: Bevy's, [`BEVY_DIRECTIONAL_SIZE`] for
    /// directional and spot lights and [`BEVY_POINT_SIZE`] for point lights.
    pub size: Option<u32>,
    /// How maps are read.
    pub filter: MapFilter,
    /// The bias of every map; `None`: Bevy's per light type ([`BEVY_DIRECTIONAL_BIAS`],
    /// [`BEVY_POINT_BIAS`]).
    pub bias: Option<MapBias>,
    /// Cascades of each directional light's map, 1 to 4, each a map of [`MapSettings::size`]
    /// over a slice of the view (practical split scheme); 1 (the default; 0 reads as 1): one
    /// map fitted to the whole view. Bevy ships 4 by default, with bounds in metres.
    pub cascades: u32,
}

impl Default for MapSettings {
    /// Bevy's sizes, bias and filter; one map per directional light.
    fn default() -> Self {
        Self {
            size: None,
            filter: MapFilter::default(),
            bias: None,
            cascades: 1,
        }
    }
}

impl MapSettings {
    /// The side of a `kind` map, texels.
    #[must_use]
    pub fn size_for(&self, kind: MapKind) -> u32 {
        self.size.unwrap_or(match kind {
            MapKind::Directional | MapKind::Spot => BEVY_DIRECTIONAL_SIZE,
            MapKind::Cube => BEVY_POINT_SIZE,
        })
    }

    /// The bias of a `kind` map.
    #[must_use]
    pub fn bias_for(&self, kind: MapKind) -> MapBias {
        self.bias.unwrap_or(match kind {
            MapKind::Directional | MapKind::Spot => BEVY_DIRECTIONAL_BIAS,
            MapKind::Cube => BEVY_POINT_BIAS,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bias_parses_three_finite_numbers() {
        let b: MapBias = "0.02, 0.5 ,1.8".parse().unwrap();
        assert_eq!(
            b,
            MapBias {
                depth: 0.02,
                slope: 0.5,
                normal: 1.8
            }
        );
        for bad in ["", "1,2", "1,2,3,4", "a,0,0", "nan,0,0", "0,inf,0"] {
            let e = bad.parse::<MapBias>().unwrap_err();
            assert!(e.contains("map bias"), "{bad}: {e}");
        }
    }

    #[test]
    fn defaults_are_bevys() {
        let s = MapSettings::default();
        assert_eq!(s.size_for(MapKind::Directional), 2048);
        assert_eq!(s.size_for(MapKind::Spot), 2048);
        assert_eq!(s.size_for(MapKind::Cube), 1024);
        assert_eq!(s.bias_for(MapKind::Cube).depth, 0.08);
        assert_eq!(s.bias_for(MapKind::Directional).normal, 1.8);
        assert_eq!(s.filter, MapFilter::Pcf);
    }
}
