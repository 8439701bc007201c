//! Percentage-closer soft shadows as Bevy 0.20 ships them (`experimental_pbr_pcss`): the map
//! peer of lights with a size. The lookup is `shaders/render_maps.wgsl`'s `map_visibility_pcss`;
//! here are Bevy's constants (the shader holds the same values, a unit test compares them), the
//! light size Bevy reads ([`soft_shadow_size`]) and a host twin of the penumbra estimate
//! ([`blur_size`]).
//!
//! Per pixel, on the biased lookup point of the other filters:
//! 1. Blocker search: 8 bilinear depth reads at Direct3D's 8x multisample positions
//!    ([`SEARCH_PATTERN`]) scaled by the light's size `S`: `S` world units across a directional
//!    map, `S / (`[`SPOT_TEXEL`]` × size)` in texture coordinates on a spot map, and directions
//!    `S × distance` off the lookup direction on a cube map. The blocker depth is the mean of the
//!    reads nearer the light than the receiver (0 when none is).
//! 2. Penumbra estimate: `blur = max((blocker − receiver) × S / receiver, 0.5)` in reverse-Z
//!    depths ([`blur_size`]).
//! 3. Filter: 8 bilinear comparisons on Jimenez's spiral (radii 1/8 to 1, 135° apart), turned
//!    per pixel by interleaved gradient noise of the pixel's position (frame 1, Bevy's
//!    non-temporal filter: reproducible), `[`filter_scale`]`(texel) × blur` world units on a
//!    directional map (texel: its world size), the same over [`SPOT_TEXEL`] on a spot map, and
//!    [`POINT_SCALE`]` × blur × distance ×`[`POINT_OFFSET_SCALE`] off the direction on a cube
//!    map.
//!
//! A light whose size is 0 is read with PCF, as Bevy reads a light without a soft shadow size
//! with its normal filter.

use shadowvol_scenes::SceneLight;

/// Bevy's floor on the blur size ("or shadows will look unacceptably aliased").
pub const MIN_BLUR: f32 = 0.5;

/// Bevy's texel size of every spot map (`SPOT_SHADOW_TEXEL_SIZE`, 0.0134277345, "determined by
/// trial and error"; as `f32` exactly 55/4096): spot maps scale the search and the filter by it
/// instead of their own texel.
pub const SPOT_TEXEL: f32 = 0.013_427_734;

/// Bevy's cube-map filter scale (`POINT_SHADOW_SCALE`): radians of filter radius per unit of
/// blur, before [`POINT_OFFSET_SCALE`].
pub const POINT_SCALE: f32 = 0.003;

/// Bevy's scale of the spiral on a cube map (`POINT_SHADOW_TEMPORAL_OFFSET_SCALE`).
pub const POINT_OFFSET_SCALE: f32 = 0.5;

/// The texel sizes (world units) Bevy's 2-D filter scale is tuned between: 1/256 and 0.0229.
pub const FILTER_TEXELS: [f32; 2] = [0.003_906_25, 0.022_949_219];

/// The filter scales at [`FILTER_TEXELS`]: 0.015 and 0.035 (linear between, and beyond).
pub const FILTER_SCALES: [f32; 2] = [0.015, 0.035];

/// The blocker search's points, in eighths: Direct3D's standard 8x multisample positions.
pub const SEARCH_PATTERN: [[i8; 2]; 8] = [
    [1, -3],
    [-1, 3],
    [5, 1],
    [-3, -5],
    [-5, 5],
    [-7, -1],
    [3, 7],
    [7, -7],
];

/// Bevy's scale of the 2-D filter's spiral for a map of `texel` world units a texel: the linear
/// map of [`FILTER_TEXELS`] onto [`FILTER_SCALES`] ("empirically chosen ... across different
/// CSM cascades").
#[must_use]
pub fn filter_scale(texel: f32) -> f32 {
    let [t0, t1] = FILTER_TEXELS;
    let [f0, f1] = FILTER_SCALES;
    f0 + (texel - t0) * (f1 - f0) / (t1 - t0)
}

/// The penumbra estimate from reverse-Z depths (1 nearest the light): the mean `blocker` depth
/// (0 without blockers) and the `receiver`'s, for a light of Bevy's size `size`. For a
/// perspective map `(blocker − receiver) / receiver` is `d_receiver / d_blocker − 1` in
/// distances from the light, the classic PCSS ratio; for a directional map, in Bevy's depth
/// range (the view slice's, see [`crate::maps::LightMap::cascade_soft`]), it is the
/// blocker's height over the receiver's above the slice's bottom.
#[must_use]
pub fn blur_size(blocker: f32, receiver: f32, size: f32) -> f32 {
    ((blocker - receiver) * size / receiver).max(MIN_BLUR)
}

/// Bevy's light size (`PointLight::radius` and `SpotLight::radius` with
/// `soft_shadows_enabled`, `DirectionalLight::soft_shadow_size`) for `light`: a point or spot
/// light's radius (world units); for a directional light of angular radius `θ`, `tan θ ×
/// view_depth`, where `view_depth` is the depth along the light of the box of the view's frustum
/// (camera near plane to the farthest scene point), Bevy's depth range of a directional map.
/// Bevy's directional size is a world length: the blocker search spans it across the map. A
/// sun of angular radius `θ` shadows a receiver only through blockers within `h tan θ` of it
/// across the light, `h` their height above it, and blockers higher than the view's box are
/// clamped to its top in Bevy's map; so `tan θ × view_depth` is the search the sun's cone
/// needs. 0 for radius 0 (or a radius that is no valid size).
#[must_use]
pub fn soft_shadow_size(light: &SceneLight, view_depth: f32) -> f32 {
    let Some(disk) = light.disk(glam::Vec3::ZERO) else {
        return 0.0;
    };
    let r = disk.radius as f32;
    if disk.directional {
        r * view_depth
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowvol_robust_math::Light;

    #[test]
    fn bevys_constants_are_the_shaders() {
        let src = super::super::MAPS_WGSL;
        for line in [
            format!("const PCSS_MIN_BLUR: f32 = {MIN_BLUR:?};"),
            format!("const PCSS_SPOT_TEXEL: f32 = {SPOT_TEXEL:?};"),
            format!("const PCSS_POINT_SCALE: f32 = {POINT_SCALE:?};"),
            format!("const PCSS_POINT_OFFSET_SCALE: f32 = {POINT_OFFSET_SCALE:?};"),
            format!(
                "const PCSS_FILTER_TEXELS: vec2<f32> = vec2<f32>({:?}, {:?});",
                FILTER_TEXELS[0], FILTER_TEXELS[1]
            ),
            format!(
                "const PCSS_FILTER_SCALES: vec2<f32> = vec2<f32>({:?}, {:?});",
                FILTER_SCALES[0], FILTER_SCALES[1]
            ),
        ] {
            assert!(src.contains(&line), "render_maps.wgsl lacks `{line}`");
        }
        let points: Vec<String> = SEARCH_PATTERN
            .iter()
            .map(|[x, y]| format!("vec2<f32>({x}.0, {y}.0)"))
            .collect();
        let pattern = format!(
            "const PCSS_SEARCH: array<vec2<f32>, 8> = array<vec2<f32>, 8>({});",
            points.join(", ")
        );
        assert!(src.contains(&pattern), "render_maps.wgsl lacks `{pattern}`");
    }

    #[test]
    fn the_spot_filter_scale_is_a_fortieth() {
        // Bevy's spot constant sits where its 2-D filter scale is 0.025.
        assert!((filter_scale(SPOT_TEXEL) - 0.025).abs() < 1e-6);
        assert_eq!(filter_scale(FILTER_TEXELS[0]), FILTER_SCALES[0]);
        assert!((filter_scale(FILTER_TEXELS[1]) - FILTER_SCALES[1]).abs() < 1e-7);
    }

    #[test]
    fn the_blur_grows_with_the_size_and_the_gap_and_has_a_floor() {
        // Perspective depths near / d: blocker at 2, receiver at 4 from the light.
        let (b, r) = (0.1 / 2.0, 0.1 / 4.0);
        assert!((blur_size(b, r, 3.0) - 3.0).abs() < 1e-5);
        assert!(blur_size(b, r, 6.0) > blur_size(b, r, 3.0));
        assert!(blur_size(0.1 / 1.5, r, 3.0) > blur_size(b, r, 3.0));
        assert_eq!(blur_size(0.0, r, 3.0), MIN_BLUR);
        assert_eq!(blur_size(b, r, 0.0), MIN_BLUR);
    }

    #[test]
    fn sizes_are_radii_and_a_directional_one_spans_the_view() {
        let mut point = SceneLight::unit(Light::point(glam::Vec3::new(0.0, 5.0, 0.0)));
        assert_eq!(soft_shadow_size(&point, 10.0), 0.0);
        point.radius = 0.25;
        assert_eq!(soft_shadow_size(&point, 10.0), 0.25);
        let mut sun = SceneLight::unit(Light::directional(glam::Vec3::new(0.0, 1.0, 0.0)));
        sun.radius = 0.1;
        let s = soft_shadow_size(&sun, 20.0);
        assert!((s - 20.0 * 0.1f32.tan()).abs() < 1e-5, "{s}");
        sun.radius = f32::NAN;
        assert_eq!(soft_shadow_size(&sun, 20.0), 0.0);
    }
}
