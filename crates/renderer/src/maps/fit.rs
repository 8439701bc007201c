//! Each light's map projection: where its map looks and what it covers, computed on the host from
//! the camera, the scene's box and the casters' boxes. Every matrix maps camera-relative world
//! positions (world minus the eye) to reverse-Z clip space: depth 1 nearest the light.

use super::{MapBias, MapSettings};
use crate::Camera;
use glam::{DVec3, Mat4, Vec3, Vec4};
use shadowvol_scenes::SceneLight;

pub use shadowvol_report::MapKind;

/// The widest spot cone (half angle, radians) that gets a perspective map; wider cones get a
/// cube map, as a point light does (a perspective map over 150° wastes most of its texels).
pub const SPOT_MAX_HALF_ANGLE: f32 = 75.0 * std::f32::consts::PI / 180.0;

/// The rows of each cube face's view, in the layer order +X, -X, +Y, -Y, +Z, -Z: a direction
/// `d` from the light maps to `(sc, -tc, -ma)` of the Vulkan/WebGPU cube-map face selection
/// table, so that the perspective divide gives the face's `(s, t)` as the sampler reads them.
pub(crate) const CUBE_FACE_ROWS: [[[f32; 3]; 3]; 6] = [
    [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]],
    [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, -1.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
    [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
];

/// One light's map for one frame: its kind, the projection of each face and the bias in world
/// units, as the shaders read them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightMap {
    /// Which map.
    pub kind: MapKind,
    /// Side of the map (of each cube face), texels.
    pub size: u32,
    /// Clip from camera-relative world, per face (only the first is used unless
    /// [`MapKind::Cube`]).
    pub view_proj: [Mat4; 6],
    /// The bias in effect for this light's kind (Bevy's units: world units of depth bias, normal
    /// bias in texels).
    pub bias: MapBias,
    /// Normal bias in world units: times the texel size for a directional map, per unit of
    /// distance from the light for spot and cube maps (as Bevy scales it, with its `√2`).
    pub normal_offset: f32,
    /// Near plane of a perspective map (world units); 0 for a directional map.
    pub near: f32,
    /// The world size of one texel: directional maps in world units, perspective maps per unit of
    /// distance from the light.
    pub texel: f32,
    /// A spot light's axis (unit); for a cascaded directional map the camera's forward
    /// direction (unit), along which the cascade is chosen; zero otherwise.
    pub axis: Vec3,
    /// Cascades of a directional map ([`MapSettings::cascades`]); 1 for every other map. Cascade
    /// `i` uses `view_proj[i]`.
    pub cascades: u32,
    /// Per cascade: the far end of its slice of the view, distance along the camera's forward
    /// direction (world units); the last reaches the farthest scene point.
    pub cascade_far: [f32; 4],
    /// Per cascade: its normal offset in world units (its texel size differs).
    pub cascade_offset: [f32; 4],
    /// Bevy's PCSS light size for this light ([`super::pcss::soft_shadow_size`]), world units;
    /// 0 for a light of radius 0.
    pub soft_shadow_size: f32,
    /// Per cascade of a directional map, what its PCSS lookup needs: the map's width and height
    /// in world units, then `a, b` taking its depth `d` to Bevy's, `a d + b`: Bevy's depth runs
    /// from 0 at the bottom to 1 at the top of the box of the cascade's slice of the view
    /// (light space), ours from the scene's bottom to the casters' top. Zero for other maps.
    pub cascade_soft: [[f32; 4]; 4],
}

impl LightMap {
    /// What `--explain` and the report state of this map.
    #[must_use]
    pub fn summary(&self) -> shadowvol_report::MapSummary {
        shadowvol_report::MapSummary {
            kind: self.kind,
            size: self.size,
            cascades: self.cascades,
            texel: self.texel,
            near: self.near,
            bias: self.bias,
            normal_offset: self.normal_offset,
            soft_shadow_size: self.soft_shadow_size,
        }
    }
}

/// What a map is fitted to, in world space.
#[derive(Debug, Clone, Copy)]
pub struct FitBounds {
    /// The box of every surface (casters and receivers).
    pub scene: (Vec3, Vec3),
    /// The box of the shadow casters; `None` without any.
    pub casters: Option<(Vec3, Vec3)>,
}

/// The cascaded map of the directional light `light` (towards `towards`), fitted to the view of
/// `camera` and the casters of `bounds`; `None` when it cannot cast.
fn directional_map(
    light: &SceneLight,
    towards: Vec3,
    camera: &Camera,
    aspect: f32,
    bounds: &FitBounds,
    settings: &MapSettings,
) -> Option<LightMap> {
    let casters = bounds.casters?;
    let eye = camera.eye;
    let to_light = towards.try_normalize()?;
    let size = settings.size_for(MapKind::Directional);
    let bias = settings.bias_for(MapKind::Directional);
    let n = settings.cascades.clamp(1, 4) as usize;
    let forward = (camera.target - camera.eye).normalize_or_zero();
    let far = corners(bounds.scene)
        .iter()
        .map(|c| (*c - eye).dot(forward))
        .fold(camera.near, f32::max);
    let splits = cascade_splits(camera.near, far, n);
    let mut view_proj = [Mat4::IDENTITY; 6];
    let mut cascade_far = [far; 4];
    let mut cascade_offset = [0.0; 4];
    let mut cascade_soft = [[0.0; 4]; 4];
    let mut texel0 = 0.0;
    for i in 0..n {
        let slice = (f64::from(splits[i]), f64::from(splits[i + 1]));
        let m = directional(to_light, camera, aspect, bounds, casters, size, slice)?;
        view_proj[i] = m.view_proj;
        cascade_far[i] = splits[i + 1];
        cascade_offset[i] = bias.normal * m.texel * std::f32::consts::SQRT_2;
        cascade_soft[i] = m.soft;
        if i == 0 {
            texel0 = m.texel;
        }
    }
    let view = LightSpace::new(to_light, camera.eye).frustum_box(
        camera,
        aspect,
        (f64::from(camera.near), f64::from(far)),
    );
    let view_depth = (view.1.z - view.0.z) as f32;
    Some(LightMap {
        kind: MapKind::Directional,
        size,
        view_proj,
        bias,
        normal_offset: cascade_offset[0],
        near: 0.0,
        texel: texel0,
        axis: if n > 1 { forward } else { Vec3::ZERO },
        cascades: n as u32,
        cascade_far,
        cascade_offset,
        soft_shadow_size: super::pcss::soft_shadow_size(light, view_depth),
        cascade_soft,
    })
}

/// The map of `light` for this frame, `None` for a light that cannot cast (no caster, or a
/// light that is not finite).
#[must_use]
pub fn light_map(
    light: &SceneLight,
    camera: &Camera,
    aspect: f32,
    bounds: &FitBounds,
    settings: &MapSettings,
) -> Option<LightMap> {
    let casters = bounds.casters?;
    let [x, y, z, w] = light.light.to_array();
    let spot = light.emission.as_ref().and_then(|e| e.spot);
    let eye = camera.eye;
    if w == 0.0 {
        return directional_map(light, Vec3::new(x, y, z), camera, aspect, bounds, settings);
    }
    let soft_shadow_size = super::pcss::soft_shadow_size(light, 0.0);
    let pos = Vec3::new(x, y, z) / w;
    if !pos.is_finite() {
        return None;
    }
    let near = near_plane(pos, bounds.scene, casters);
    let rel = pos - eye;
    match spot {
        Some(s) if s.outer_cone_angle <= SPOT_MAX_HALF_ANGLE => {
            let axis = s.direction.try_normalize()?;
            let size = settings.size_for(MapKind::Spot);
            let bias = settings.bias_for(MapKind::Spot);
            let half = s.outer_cone_angle;
            let up = if axis.y.abs() > 0.99 {
                Vec3::X
            } else {
                Vec3::Y
            };
            let view = glam::camera::rh::view::look_to_mat4(rel, axis, up);
            let proj = glam::camera::rh::proj::directx::perspective_infinite_reverse(
                2.0 * half,
                1.0,
                near,
            );
            let texel = 2.0 * half.tan() / size as f32;
            Some(LightMap {
                kind: MapKind::Spot,
                size,
                view_proj: [proj * view; 6],
                bias,
                normal_offset: bias.normal * texel * std::f32::consts::SQRT_2,
                near,
                texel,
                axis,
                cascades: 1,
                cascade_far: [0.0; 4],
                cascade_offset: [0.0; 4],
                soft_shadow_size,
                cascade_soft: [[0.0; 4]; 4],
            })
        }
        _ => {
            let size = settings.size_for(MapKind::Cube);
            let bias = settings.bias_for(MapKind::Cube);
            let proj = glam::camera::rh::proj::directx::perspective_infinite_reverse(
                std::f32::consts::FRAC_PI_2,
                1.0,
                near,
            );
            let view_proj = CUBE_FACE_ROWS.map(|r| proj * face_view(r, rel));
            let texel = 2.0 / size as f32;
            Some(LightMap {
                kind: MapKind::Cube,
                size,
                view_proj,
                bias,
                normal_offset: bias.normal * texel * std::f32::consts::SQRT_2,
                near,
                texel,
                axis: Vec3::ZERO,
                cascades: 1,
                cascade_far: [0.0; 4],
                cascade_offset: [0.0; 4],
                soft_shadow_size,
                cascade_soft: [[0.0; 4]; 4],
            })
        }
    }
}

/// The view of one cube face from a light at camera-relative `light`: rows `r` applied to the
/// direction from the light.
fn face_view(r: [[f32; 3]; 3], light: Vec3) -> Mat4 {
    let row = |k: usize| Vec3::from(r[k]);
    Mat4::from_cols(
        Vec4::new(r[0][0], r[1][0], r[2][0], 0.0),
        Vec4::new(r[0][1], r[1][1], r[2][1], 0.0),
        Vec4::new(r[0][2], r[1][2], r[2][2], 0.0),
        Vec4::new(
            -row(0).dot(light),
            -row(1).dot(light),
            -row(2).dot(light),
            1.0,
        ),
    )
}

/// A perspective map's near plane: half the distance from the light to the nearest caster box
/// point, so no caster is clipped, and at least a millionth of the scene's size (a light inside
/// a caster's box).
fn near_plane(light: Vec3, scene: (Vec3, Vec3), casters: (Vec3, Vec3)) -> f32 {
    let nearest = light.clamp(casters.0, casters.1);
    let d = (nearest - light).length();
    let size = (scene.1 - scene.0).length().max(f32::MIN_POSITIVE);
    (0.5 * d).max(1e-6 * size)
}

/// A directional light's orthographic map for one slice of the view.
struct Directional {
    /// Clip from camera-relative world.
    view_proj: Mat4,
    /// World size of a texel.
    texel: f32,
    /// [`LightMap::cascade_soft`] of the slice.
    soft: [f32; 4],
}

/// Light space of a directional light about the eye: `x` right, `y` top, `z` towards the light.
struct LightSpace {
    right: DVec3,
    top: DVec3,
    d: DVec3,
    eye: DVec3,
}

impl LightSpace {
    fn new(to_light: Vec3, eye: Vec3) -> Self {
        let d = to_light.as_dvec3();
        let up = if d.y.abs() > 0.99 { DVec3::X } else { DVec3::Y };
        let right = up.cross(d).normalize();
        let top = d.cross(right);
        Self {
            right,
            top,
            d,
            eye: eye.as_dvec3(),
        }
    }

    /// World point `p` in light space.
    fn of(&self, p: DVec3) -> DVec3 {
        let q = p - self.eye;
        DVec3::new(self.right.dot(q), self.top.dot(q), self.d.dot(q))
    }

    /// The light-space box of the camera's frustum between the view distances `slice`.
    fn frustum_box(
        &self,
        camera: &Camera,
        aspect: f32,
        (slice_near, slice_far): (f64, f64),
    ) -> (DVec3, DVec3) {
        let near = camera.near_corners(f64::from(aspect));
        let (a, b) = (
            slice_near / f64::from(camera.near),
            slice_far / f64::from(camera.near),
        );
        near.iter()
            .flat_map(|&c| [self.eye + (c - self.eye) * a, self.eye + (c - self.eye) * b])
            .map(|p| self.of(p))
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            })
    }
}

/// A directional light's orthographic map towards `-to_light`, its texel size (world units) and
/// its PCSS data: across, the part of the scene box the view can see (the box of the frustum up
/// to the farthest scene point, met with the scene's box, both in light space); along the light,
/// from the casters' top to the scene's bottom, so that every caster that can shadow a visible
/// point is in the map (such a caster lies on the same light-space column as the point).
fn directional(
    to_light: Vec3,
    camera: &Camera,
    aspect: f32,
    bounds: &FitBounds,
    casters: (Vec3, Vec3),
    size: u32,
    slice: (f64, f64),
) -> Option<Directional> {
    let ls = LightSpace::new(to_light, camera.eye);
    let scene = box_in(bounds.scene, |p| ls.of(p));
    let caster_box = box_in(casters, |p| ls.of(p));
    let frustum = ls.frustum_box(camera, aspect, slice);
    let (mut lo, mut hi) = (scene.0.max(frustum.0), scene.1.min(frustum.1));
    if lo.x > hi.x || lo.y > hi.y {
        // A slice of the view that holds no part of the scene: the whole scene, so that the
        // map is still a valid projection.
        (lo, hi) = scene;
    }
    // A margin of one part in 10^4 of the extent (and a little more along the light), so that
    // points on the box's faces round inside.
    let extent = (hi - lo)
        .max_element()
        .max(scene.1.z - scene.0.z)
        .max(1e-30);
    let m = 1e-4 * extent;
    let (x0, x1) = (lo.x - m, hi.x + m);
    let (y0, y1) = (lo.y - m, hi.y + m);
    let z_top = caster_box.1.z.max(hi.z) + 4.0 * m;
    let z_bottom = scene.0.z - 4.0 * m;
    // Light space (right, top, d) about the eye, then x, y to [-1, 1] and z to depth: 1 at the
    // top (nearest the light), 0 at the bottom.
    let (right, top, d) = (ls.right, ls.top, ls.d);
    let view = glam::DMat4::from_cols(
        glam::DVec4::new(right.x, top.x, d.x, 0.0),
        glam::DVec4::new(right.y, top.y, d.y, 0.0),
        glam::DVec4::new(right.z, top.z, d.z, 0.0),
        glam::DVec4::W,
    );
    let sx = 2.0 / (x1 - x0);
    let sy = 2.0 / (y1 - y0);
    let sz = 1.0 / (z_top - z_bottom);
    let proj = glam::DMat4::from_cols(
        glam::DVec4::new(sx, 0.0, 0.0, 0.0),
        glam::DVec4::new(0.0, sy, 0.0, 0.0),
        glam::DVec4::new(0.0, 0.0, sz, 0.0),
        glam::DVec4::new(
            -(x0 + x1) * 0.5 * sx,
            -(y0 + y1) * 0.5 * sy,
            -z_bottom * sz,
            1.0,
        ),
    );
    let texel = ((x1 - x0).max(y1 - y0) / f64::from(size)) as f32;
    // Bevy's depth of a cascade is 0 at the bottom and 1 at the top of its slice's box.
    let bevy = (frustum.1.z - frustum.0.z).max(1e-30);
    let soft = [
        (x1 - x0) as f32,
        (y1 - y0) as f32,
        ((z_top - z_bottom) / bevy) as f32,
        ((z_bottom - frustum.0.z) / bevy) as f32,
    ];
    Some(Directional {
        view_proj: (proj * view).as_mat4(),
        texel,
        soft,
    })
}

/// The `n + 1` ends of `n` cascades over the view distances `near..far`: the practical split
/// scheme, the mean of the logarithmic and the uniform splits (Bevy's own bounds are fixed
/// distances in metres, which do not follow a scene's scale).
fn cascade_splits(near: f32, far: f32, n: usize) -> [f32; 5] {
    let mut s = [far; 5];
    for (i, v) in s.iter_mut().enumerate().take(n + 1) {
        let t = i as f32 / n as f32;
        *v = 0.5 * (near * (far / near).powf(t)) + 0.5 * (near + (far - near) * t);
    }
    s[0] = near;
    s[n] = far;
    s
}

/// The 8 corners of a box.
fn corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// The box of `b`'s corners mapped by `f`.
fn box_in(b: (Vec3, Vec3), f: impl Fn(DVec3) -> DVec3) -> (DVec3, DVec3) {
    corners(b)
        .iter()
        .map(|c| f(c.as_dvec3()))
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        })
}

/// The layer of the cube face a direction `v` from the light falls on, with its `(s, t)` in
/// `[0, 1]`: the Vulkan/WebGPU face selection the sampler applies (CPU twin of
/// `textureSampleCompareLevel` on a cube, for tests).
#[must_use]
pub fn cube_face(v: Vec3) -> (usize, [f32; 2]) {
    let a = v.abs();
    let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
        if v.x >= 0.0 {
            (0, -v.z, -v.y, a.x)
        } else {
            (1, v.z, -v.y, a.x)
        }
    } else if a.y >= a.z {
        if v.y >= 0.0 {
            (2, v.x, v.z, a.y)
        } else {
            (3, v.x, -v.z, a.y)
        }
    } else if v.z >= 0.0 {
        (4, v.x, -v.y, a.z)
    } else {
        (5, -v.x, -v.y, a.z)
    };
    (face, [0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowvol_robust_math::Light;

    fn camera() -> Camera {
        Camera::look_at(Vec3::new(3.0, 2.0, 4.0), Vec3::ZERO)
    }

    fn bounds() -> FitBounds {
        FitBounds {
            scene: (Vec3::new(-5.0, -1.0, -5.0), Vec3::new(5.0, 2.0, 5.0)),
            casters: Some((Vec3::new(-0.5, -1.0, -0.5), Vec3::new(0.5, 2.0, 0.5))),
        }
    }

    /// Where a camera-relative point lands in a face's map: `(u, v, depth)`.
    fn project(m: Mat4, p: Vec3) -> Vec3 {
        let c = m * p.extend(1.0);
        let n = c.truncate() / c.w;
        Vec3::new(0.5 * (n.x + 1.0), 0.5 * (1.0 - n.y), n.z)
    }

    #[test]
    fn each_cube_face_renders_where_the_sampler_reads() {
        let light = SceneLight::unit(Light::point(Vec3::new(0.0, 3.0, 0.0)));
        let cam = camera();
        let map = light_map(&light, &cam, 1.0, &bounds(), &MapSettings::default()).unwrap();
        assert_eq!(map.kind, MapKind::Cube);
        let dirs = [
            Vec3::new(1.0, 0.3, -0.2),
            Vec3::new(-1.0, -0.4, 0.1),
            Vec3::new(0.2, 1.0, 0.45),
            Vec3::new(-0.3, -1.0, 0.2),
            Vec3::new(0.25, -0.1, 1.0),
            Vec3::new(0.4, 0.35, -1.0),
        ];
        for (k, d) in dirs.iter().enumerate() {
            let (face, st) = cube_face(*d);
            assert_eq!(face, k);
            let p = Vec3::new(0.0, 3.0, 0.0) + 2.0 * *d - cam.eye;
            let uvz = project(map.view_proj[face], p);
            assert!((uvz.x - st[0]).abs() < 1e-5, "face {k}: {uvz} vs {st:?}");
            assert!((uvz.y - st[1]).abs() < 1e-5, "face {k}: {uvz} vs {st:?}");
            let major = (2.0 * *d).abs().max_element();
            assert!((uvz.z - map.near / major).abs() < 1e-6, "face {k} depth");
        }
    }

    #[test]
    fn a_directional_map_holds_every_caster_and_the_visible_scene() {
        let light = SceneLight::unit(Light::directional(Vec3::new(0.3, 1.0, 0.2)));
        let cam = camera();
        let b = bounds();
        let map = light_map(&light, &cam, 1.5, &b, &MapSettings::default()).unwrap();
        for c in corners(b.casters.unwrap()) {
            let uvz = project(map.view_proj[0], c - cam.eye);
            assert!(
                (0.0..=1.0).contains(&uvz.x) && (0.0..=1.0).contains(&uvz.y),
                "{c}"
            );
            assert!(
                uvz.z > 0.0 && uvz.z < 1.0,
                "caster corner {c} at depth {}",
                uvz.z
            );
        }
        // The view's centre on the ground is in the map, and below the casters' top.
        let uvz = project(map.view_proj[0], Vec3::new(0.0, -1.0, 0.0) - cam.eye);
        assert!((0.0..=1.0).contains(&uvz.x) && uvz.z >= 0.0);
    }

    #[test]
    fn a_spot_map_looks_along_the_cone() {
        let mut light = SceneLight::unit(Light::point(Vec3::new(0.0, 4.0, 0.0)));
        light.emission = Some(shadowvol_scenes::Emission {
            spot: Some(shadowvol_scenes::SpotCone {
                direction: Vec3::NEG_Y,
                inner_cone_angle: 0.3,
                outer_cone_angle: 0.6,
            }),
            ..Default::default()
        });
        let cam = camera();
        let map = light_map(&light, &cam, 1.0, &bounds(), &MapSettings::default()).unwrap();
        assert_eq!(map.kind, MapKind::Spot);
        let uvz = project(map.view_proj[0], Vec3::new(0.0, 1.0, 0.0) - cam.eye);
        assert!((uvz.x - 0.5).abs() < 1e-5 && (uvz.y - 0.5).abs() < 1e-5);
        assert!((uvz.z - map.near / 3.0).abs() < 1e-6);
    }
}
