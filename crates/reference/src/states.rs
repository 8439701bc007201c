//! Per-pixel states: the surface point under each pixel, whether a light visibly reaches it,
//! and the lit/unlit state of each light by the raster's stencil and by ray casting.

use crate::bvh::Bvh;
use crate::occlusion::{light_side, Caster, Crossing, ShadowRay};
use crate::{PixelState, Shot};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;

/// The surface point of one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// World position (`f64`) on the rasterized triangle's plane, under the pixel centre.
    pub position: DVec3,
    /// Geometric normal turned towards the camera (unnormalised).
    pub normal: DVec3,
    /// Global triangle index (objects concatenated).
    pub triangle: u32,
    /// Largest albedo channel of the pixel's object (how much a light can change the pixel).
    pub albedo: f32,
}

/// The surface points of every pixel (`None` for background).
#[must_use]
pub fn surface_points(shot: &Shot<'_>) -> Vec<Option<SurfacePoint>> {
    let at = PixelPoints::new(shot);
    (0..at.pixels())
        .into_par_iter()
        .map(|i| at.point(shot, i))
        .collect()
}

/// What [`surface_points`] computes for any one pixel, for a pass that needs each pixel's point
/// once and need not hold them all.
pub(crate) struct PixelPoints {
    w: usize,
    h: usize,
    inv: DMat4,
    eye: DVec3,
    /// First global triangle of each surface.
    offsets: Vec<u32>,
}

impl PixelPoints {
    pub(crate) fn new(shot: &Shot<'_>) -> Self {
        let aspect = f64::from(shot.width) / f64::from(shot.height);
        let offsets = shot
            .triangle_counts()
            .iter()
            .scan(0u32, |acc, &n| {
                let o = *acc;
                *acc += n as u32;
                Some(o)
            })
            .collect();
        Self {
            w: shot.width as usize,
            h: shot.height as usize,
            inv: shot.camera.view_proj_f64(aspect).inverse(),
            eye: shot.camera.eye.as_dvec3(),
            offsets,
        }
    }

    pub(crate) fn pixels(&self) -> usize {
        self.w * self.h
    }

    /// Pixel `i`'s surface point, `None` for background.
    pub(crate) fn point(&self, shot: &Shot<'_>, i: usize) -> Option<SurfacePoint> {
        let (w, h, eye) = (self.w, self.h, self.eye);
        let [obj, tri] = shot.ids[i];
        if obj == 0 {
            return None;
        }
        let t = shot.triangle(obj as usize - 1, tri as usize)?;
        let t = [t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3()];
        let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        let ndc = DVec4::new(x / w as f64 * 2.0 - 1.0, 1.0 - y / h as f64 * 2.0, 0.5, 1.0);
        let p = self.inv * ndc;
        let dir = p.truncate() / p.w - eye;
        let mut n = (t[1] - t[0]).cross(t[2] - t[0]);
        let denom = n.dot(dir);
        let position = if denom != 0.0 && denom.is_finite() {
            eye + dir * (n.dot(t[0] - eye) / denom)
        } else {
            (t[0] + t[1] + t[2]) / 3.0
        };
        if n.dot(eye - position) < 0.0 {
            n = -n;
        }
        Some(SurfacePoint {
            position,
            normal: n,
            triangle: self.offsets[obj as usize - 1] + tri,
            albedo: shot
                .albedo(obj as usize - 1)
                .map_or(1.0, |a| a[0].max(a[1]).max(a[2])),
        })
    }
}

/// The vector from `p` to the light: towards the light for a directional light (`w = 0`), and
/// exactly to the light's position `xyz / w` for a point light, so that the shadow segment
/// `p + t·v`, `t ∈ (0, 1)`, ends at the light for every `w > 0` (not only `w = 1`).
pub(crate) fn light_vec(l: [f32; 4], p: DVec3) -> DVec3 {
    let xyz = DVec3::new(f64::from(l[0]), f64::from(l[1]), f64::from(l[2]));
    let w = f64::from(l[3]);
    if w == 0.0 {
        xyz
    } else {
        xyz / w - p
    }
}

/// True when light `li` of `shot` visibly lights the surface point: the Lambert term
/// `albedo × intensity × attenuation × cos θ` is at least one 8-bit step (1/255), with the
/// attenuation of the light's emission ([`light_attenuation`]). Below that, lit and shadowed
/// give the same 8-bit pixel, so the state is invisible (and, for faces edge-on to the light,
/// ill-posed for the raster and the ray caster alike); such pixels count as unlit on both sides.
#[must_use]
pub fn faces_light(shot: &Shot<'_>, sp: &SurfacePoint, li: usize) -> bool {
    let l = shot.light(li);
    let v = light_vec(l, sp.position);
    let d = sp.normal.dot(v);
    let gain = f64::from(sp.albedo)
        * f64::from(shot.light_colors[li].iter().copied().fold(0.0, f32::max))
        * light_attenuation(shot, sp, li);
    d > 0.0 && gain > 0.0 && d * gain * 255.0 >= sp.normal.length() * v.length()
}

/// True when the surface point faces light `li` at all (`cos θ > 0`), however dimly: the
/// geometric facing of DESIGN.md's literal metric, without the 8-bit visibility threshold of
/// [`faces_light`].
#[must_use]
pub fn faces_light_geometric(shot: &Shot<'_>, sp: &SurfacePoint, li: usize) -> bool {
    let l = shot.light(li);
    sp.normal.dot(light_vec(l, sp.position)) > 0.0 && light_attenuation(shot, sp, li) > 0.0
}

/// The attenuation of light `li` at the surface point: range window, inverse square and cone
/// ([`shadowvol_scenes::Emission::attenuation`], in `f64`), 1 for a unit light.
#[must_use]
pub fn light_attenuation(shot: &Shot<'_>, sp: &SurfacePoint, li: usize) -> f64 {
    shot.scene.lights[li]
        .emission
        .map_or(1.0, |e| e.attenuation(shot.light(li), sp.position))
}

/// The raster's per-light states (light-major), from the stencil and the facing
/// ([`faces_light`]).
#[must_use]
pub fn raster_states(shot: &Shot<'_>, points: &[Option<SurfacePoint>]) -> Vec<Vec<PixelState>> {
    raster_states_with(shot, points, faces_light)
}

/// The raster's per-light states with the geometric facing ([`faces_light_geometric`]).
#[must_use]
pub fn raster_states_geometric(
    shot: &Shot<'_>,
    points: &[Option<SurfacePoint>],
) -> Vec<Vec<PixelState>> {
    raster_states_with(shot, points, faces_light_geometric)
}

/// Lit where the stencil is 0 and `facing` holds.
fn raster_states_with(
    shot: &Shot<'_>,
    points: &[Option<SurfacePoint>],
    facing: fn(&Shot<'_>, &SurfacePoint, usize) -> bool,
) -> Vec<Vec<PixelState>> {
    (0..shot.scene.lights.len())
        .map(|li| {
            points
                .iter()
                .zip(&shot.stencil[li])
                .map(|(p, &s)| match p {
                    None => PixelState::Background,
                    Some(sp) if s == 0 && facing(shot, sp, li) => PixelState::Lit,
                    Some(_) => PixelState::Unlit,
                })
                .collect()
        })
        .collect()
}

/// The reference's per-light states (light-major), by ray casting; lit needs [`faces_light`].
#[must_use]
pub fn reference_states(shot: &Shot<'_>, points: &[Option<SurfacePoint>]) -> Vec<Vec<PixelState>> {
    let geometric = reference_states_geometric(shot, points);
    visible_only(shot, points, geometric)
}

/// Turns geometric reference states into visible ones: a pixel the light can't visibly light
/// ([`faces_light`] false) is unlit.
pub(crate) fn visible_only(
    shot: &Shot<'_>,
    points: &[Option<SurfacePoint>],
    mut states: Vec<Vec<PixelState>>,
) -> Vec<Vec<PixelState>> {
    for (li, row) in states.iter_mut().enumerate() {
        for (state, p) in row.iter_mut().zip(points) {
            if let Some(sp) = p {
                if !faces_light(shot, sp, li) {
                    *state = PixelState::Unlit;
                }
            }
        }
    }
    states
}

/// The reference's per-light states by ray casting, with the geometric facing
/// ([`faces_light_geometric`]): every surface point with `cos θ > 0` is ray cast, and every caster
/// the shadow ray's BVH boxes reach is decided exactly ([`crate::occlusion`]): unlit when one
/// blocks, [`PixelState::Uncertain`] when none blocks but one is [`Crossing::Undecidable`], else
/// lit. The pixel's own triangle is skipped (the surface point lies on it).
#[must_use]
pub fn reference_states_geometric(
    shot: &Shot<'_>,
    points: &[Option<SurfacePoint>],
) -> Vec<Vec<PixelState>> {
    reference_states_with(shot, points, &Casters::new(shot))
}

/// Every caster triangle of a shot with what the shadow rays and the footprint rule reuse: the
/// BVH, each triangle's exact-test data and, per light, which side of its plane the light is on.
pub(crate) struct Casters {
    /// The `f32` triangles (canonical vertex order), in BVH input order.
    pub(crate) raw: Vec<[glam::Vec3; 3]>,
    pub(crate) casters: Vec<Caster>,
    /// Global triangle index of each (what [`SurfacePoint::triangle`] names).
    pub(crate) ids: Vec<u32>,
    pub(crate) bvh: Bvh,
    /// Per light, per caster: [`light_side`] (0: the light is in its plane, it never blocks).
    pub(crate) sides: Vec<Vec<i8>>,
}

impl Casters {
    pub(crate) fn new(shot: &Shot<'_>) -> Self {
        let mut tris: Vec<[DVec3; 3]> = Vec::new();
        let mut casters: Vec<Caster> = Vec::new();
        let mut raw: Vec<[glam::Vec3; 3]> = Vec::new();
        let mut ids = Vec::new();
        let mut next = 0u32;
        for (oi, obj) in shot.triangles().iter().enumerate() {
            for t in obj {
                if shot.casts_shadows(oi) {
                    let c = Caster::new(*t);
                    tris.push(c.v);
                    casters.push(c);
                    raw.push(*t);
                    ids.push(next);
                }
                next += 1;
            }
        }
        let bvh = Bvh::build_with_ids(tris, ids.clone());
        let sides = (0..shot.scene.lights.len())
            .map(|li| {
                let l = shot.light(li);
                raw.par_iter().map(|t| light_side(*t, l)).collect()
            })
            .collect();
        Self {
            raw,
            casters,
            ids,
            bvh,
            sides,
        }
    }
}

/// [`reference_states_geometric`] over casters already gathered.
pub(crate) fn reference_states_with(
    shot: &Shot<'_>,
    points: &[Option<SurfacePoint>],
    set: &Casters,
) -> Vec<Vec<PixelState>> {
    let eye = shot.camera.eye.as_dvec3();
    (0..shot.scene.lights.len())
        .map(|li| {
            let l = shot.light(li);
            let sides = &set.sides[li];
            let t_max = if l[3] == 0.0 { f64::INFINITY } else { 1.0 };
            points
                .par_iter()
                .map(|p| match p {
                    None => PixelState::Background,
                    Some(sp) => {
                        if !faces_light_geometric(shot, sp, li) {
                            return PixelState::Unlit;
                        }
                        let ray = ShadowRay::new(sp.position, l, eye);
                        let mut undecidable = false;
                        let blocked =
                            set.bvh
                                .visit(sp.position, light_vec(l, sp.position), t_max, |i| {
                                    if set.ids[i] == sp.triangle {
                                        return false;
                                    }
                                    match ray.crossing(&set.casters[i], sides[i]) {
                                        Crossing::Blocks => true,
                                        Crossing::Clear => false,
                                        Crossing::Undecidable => {
                                            undecidable = true;
                                            false
                                        }
                                    }
                                });
                        if blocked {
                            PixelState::Unlit
                        } else if undecidable {
                            PixelState::Uncertain
                        } else {
                            PixelState::Lit
                        }
                    }
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: the shadow segment `p + t·v`, `t ∈ (0, 1)`, must end at the light for every
    /// `w > 0`; it used to end at `L.xyz - (w - 1)·p`, which is the light only for `w = 1`.
    #[test]
    fn shadow_segment_ends_at_the_light_for_any_w() {
        let p = DVec3::new(0.5, -1.0, 0.25);
        for (l, light) in [
            ([0.0f32, 0.0, 4.0, 2.0], DVec3::new(0.0, 0.0, 2.0)),
            ([3.0, 1.5, -6.0, 0.75], DVec3::new(4.0, 2.0, -8.0)),
            ([1.0, 2.0, 3.0, 1.0], DVec3::new(1.0, 2.0, 3.0)),
        ] {
            let end = p + light_vec(l, p);
            assert!(
                (end - light).length() < 1e-12,
                "{l:?}: ends at {end}, light at {light}"
            );
        }
        // Directional: the direction towards the light, whatever the point.
        assert_eq!(
            light_vec([1.0, 2.0, 3.0, 0.0], p),
            DVec3::new(1.0, 2.0, 3.0)
        );
    }
}
