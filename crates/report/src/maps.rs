//! The shadow-map settings and per-light maps as a report states them.

use serde::{Deserialize, Serialize};

/// The kind of map a light gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MapKind {
    /// A directional light: one orthographic map fitted to the view and the casters.
    Directional,
    /// A spot light with a cone narrow enough for one perspective map over the cone.
    Spot,
    /// A point light (and a wider spot light): a cube map of 6 faces.
    Cube,
}

/// How a map is read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MapFilter {
    /// One hardware comparison with nearest filtering: visibility 0 or 1.
    Hard,
    /// Percentage-closer filtering: 3x3 taps one texel apart, each a bilinear hardware
    /// comparison (a soft edge over about 4 texels, like Bevy's default Gaussian filter).
    #[default]
    Pcf,
    /// Percentage-closer soft shadows as Bevy 0.20 ships them (`experimental_pbr_pcss`): a
    /// blocker search over a region sized by the light's size, then 8 rotated bilinear
    /// comparisons over a kernel sized from the average blocker depth. A light of radius 0 is
    /// read as with [`MapFilter::Pcf`], as Bevy reads a light without a soft shadow size with
    /// its normal filter.
    Pcss,
}

impl MapFilter {
    /// `"hard"`, `"pcf"` or `"pcss"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            MapFilter::Hard => "hard",
            MapFilter::Pcf => "pcf",
            MapFilter::Pcss => "pcss",
        }
    }
}

/// The three parts of a map's depth bias, in Bevy's units.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MapBias {
    /// Constant part: the looked-up point moves this far (world units) towards the light.
    pub depth: f32,
    /// Slope-scaled part: the map pass's depth bias slope scale, pushing the stored depth away
    /// from the light (0 in Bevy).
    pub slope: f32,
    /// Normal offset: the looked-up point moves this many texels (times `√2`, as Bevy scales
    /// it) along the surface normal turned towards the light.
    pub normal: f32,
}

impl MapBias {
    /// No bias at all (acne everywhere a surface faces the light).
    pub const NONE: MapBias = MapBias {
        depth: 0.0,
        slope: 0.0,
        normal: 0.0,
    };
}

impl std::str::FromStr for MapBias {
    type Err = String;

    /// `DEPTH,SLOPE,NORMAL`, three finite numbers.
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let [d, sl, n] = parts[..] else {
            return Err(format!(
                "map bias {s:?}: expected DEPTH,SLOPE,NORMAL, for example 0.02,0,1.8"
            ));
        };
        let num = |v: &str, what: &str| -> Result<f32, String> {
            let x: f32 = v
                .parse()
                .map_err(|e| format!("map bias {s:?}: {what} {v:?}: {e}"))?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(format!("map bias {s:?}: {what} must be finite"))
            }
        };
        Ok(MapBias {
            depth: num(d, "depth")?,
            slope: num(sl, "slope")?,
            normal: num(n, "normal")?,
        })
    }
}

/// One light's map in a frame, as `--explain` states it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MapSummary {
    /// Which map.
    pub kind: MapKind,
    /// Side of the map (of each cube face), texels.
    pub size: u32,
    /// Cascades of a directional map; 1 for every other map.
    pub cascades: u32,
    /// The world size of one texel: directional maps in world units, perspective maps per unit
    /// of distance from the light.
    pub texel: f32,
    /// Near plane of a perspective map (world units); 0 for a directional map.
    pub near: f32,
    /// The bias in effect for this light's kind.
    pub bias: MapBias,
    /// Normal bias in world units: times the texel size for a directional map, per unit of
    /// distance from the light for spot and cube maps.
    pub normal_offset: f32,
    /// Bevy's PCSS light size this light's map is read with under [`MapFilter::Pcss`]: world
    /// units (a point or spot light's radius; for a directional light its angular radius's
    /// tangent times the depth of the view's box along the light). 0 for a light of radius 0,
    /// and in records written before PCSS.
    #[serde(default)]
    pub soft_shadow_size: f32,
}
