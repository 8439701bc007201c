//! What a renderer adds to a scene that does not say everything: a key light when it has no
//! lights, and a ground plane when nothing lies below its casters.
//!
//! Both are placed from the scene's world-space bounds and its camera, with `y` up (the glTF
//! convention). They are deterministic functions of the scene, so the same file always renders
//! the same way.

use crate::scene::Scene;
use crate::Camera;
use glam::Vec3;
use shadowvol_robust_math::Light;

/// Distance of the default key light from the centre of the bounds, in bounding radii.
pub const KEY_LIGHT_DISTANCE: f32 = 4.0;

/// Gap between the lowest vertex of the scene and the added ground plane, as a fraction of the
/// bounds' diagonal: small enough that shadows stay in contact, large enough that a flat base
/// does not z-fight with the ground.
pub const GROUND_GAP: f32 = 1e-3;

impl Scene {
    /// The default key light: a point light (`w = 1`) above the scene, to the left of `camera`
    /// and slightly towards it, at [`KEY_LIGHT_DISTANCE`] bounding radii from the centre of the
    /// bounds. Seen from `camera`, it lights the faces in view and its shadow falls on the
    /// ground to the right of the objects, about half an object's height long.
    ///
    /// In the camera's horizontal frame (right `r`, forward `f`, both with `y = 0`), the light
    /// lies along `normalize(-0.7 r + 1.6 y - 0.3 f)` from the centre. A camera looking
    /// straight down uses its `up` vector for forward.
    ///
    /// `None` for a scene without vertices, and for one so large that the light's position is
    /// beyond the `f32` range (coordinates within a few bounding radii of `f32::MAX`).
    #[must_use]
    pub fn key_light(&self, camera: &Camera) -> Option<Light> {
        let (lo, hi) = self.bounds()?;
        let (centre, radius) = crate::box_centre_radius(lo, hi);
        let radius = radius.max(1e-3);
        let view = camera.target - camera.eye;
        let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).try_normalize();
        let forward = flat(view)
            .or_else(|| flat(camera.up))
            .unwrap_or(Vec3::NEG_Z);
        let right = forward.cross(Vec3::Y);
        let dir = (-0.7 * right + 1.6 * Vec3::Y - 0.3 * forward).normalize();
        let p = centre + dir * (KEY_LIGHT_DISTANCE * radius);
        Light::new(p.x, p.y, p.z, 1.0).ok()
    }

    /// The index of an object that serves as the scene's floor: among two or more objects, a
    /// flat one (height at most 2 % of the scene's horizontal extent) at the bottom of the
    /// bounds whose horizontal footprint covers every other object's. `None` when there is no
    /// such object.
    #[must_use]
    pub fn floor_object(&self) -> Option<usize> {
        if self.geometry.objects.len() < 2 {
            return None;
        }
        let (lo, hi) = self.bounds()?;
        let extent = (hi.x - lo.x).max(hi.z - lo.z).max(f32::MIN_POSITIVE);
        let world: Vec<Option<(Vec3, Vec3)>> = (0..self.geometry.objects.len())
            .map(|i| self.object_bounds(i))
            .collect();
        let tol = 0.02 * extent;
        (0..self.geometry.objects.len()).find(|&i| {
            let Some((flo, fhi)) = world[i] else {
                return false;
            };
            let flat = fhi.y - flo.y <= tol && fhi.y <= lo.y + tol;
            flat && world.iter().enumerate().all(|(j, b)| {
                j == i
                    || b.is_none_or(|(olo, ohi)| {
                        flo.x <= olo.x + tol
                            && flo.z <= olo.z + tol
                            && fhi.x >= ohi.x - tol
                            && fhi.z >= ohi.z - tol
                    })
            })
        })
    }

    /// The height of a ground plane to add when nothing lies below the casters: `None` when
    /// the scene already has a ground ([`Scene::ground_y`]) or a [`Scene::floor_object`], or has
    /// no vertices; otherwise the lowest world-space `y` minus [`GROUND_GAP`] of the bounds'
    /// diagonal. A single-object scene (every OBJ, STL or PLY file) always gets one.
    #[must_use]
    pub fn auto_ground_y(&self) -> Option<f32> {
        if self.ground_y().is_some() || self.floor_object().is_some() {
            return None;
        }
        self.ground_y_below()
    }

    /// The lowest world-space `y` of the scene minus [`GROUND_GAP`] of its bounds' diagonal,
    /// whether or not the scene has a floor; `None` without vertices.
    #[must_use]
    pub fn ground_y_below(&self) -> Option<f32> {
        let (lo, hi) = self.bounds()?;
        let gap =
            (GROUND_GAP * 2.0 * crate::box_centre_radius(lo, hi).1).max(f32::EPSILON * lo.y.abs());
        Some(lo.y - gap)
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::Scene;
    use crate::Camera;
    use glam::{Affine3A, Vec3};

    fn scene(objects: &[(Vec3, Vec3)]) -> Scene {
        let mut s = Scene::new("t");
        for (i, &(lo, hi)) in objects.iter().enumerate() {
            let t = s.add_mesh("cube", &crate::shapes::cuboid(lo, hi)).unwrap();
            s.add_object(format!("o{i}"), t, Affine3A::IDENTITY);
        }
        s
    }

    #[test]
    fn a_single_object_gets_a_ground_just_below_it() {
        let s = scene(&[(Vec3::new(-1., 2., -1.), Vec3::new(1., 4., 1.))]);
        let y = s.auto_ground_y().unwrap();
        assert!(y < 2.0 && y > 2.0 - 0.01, "{y}");
    }

    #[test]
    fn a_floor_under_the_casters_is_recognised() {
        let floor = (Vec3::new(-5., -0.1, -5.), Vec3::new(5., 0., 5.));
        let caster = (Vec3::new(-1., 0., -1.), Vec3::new(1., 2., 1.));
        let s = scene(&[floor, caster]);
        assert_eq!(s.floor_object(), Some(0));
        assert_eq!(s.auto_ground_y(), None);
        // A plate smaller than the caster's footprint is not a floor.
        let plate = (Vec3::new(-0.5, -0.1, -0.5), Vec3::new(0.5, 0., 0.5));
        let s = scene(&[plate, caster]);
        assert_eq!(s.floor_object(), None);
        assert!(s.auto_ground_y().is_some());
        // A scene that declares its ground keeps it.
        let mut s = scene(&[caster]);
        s.set_ground(Some(-3.0));
        assert_eq!(s.auto_ground_y(), None);
    }

    /// The key light is above the scene, outside its bounds, on the camera's left, and its
    /// shadow (the direction from the light through the centre) reaches the ground to the
    /// camera's right.
    #[test]
    fn the_key_light_is_above_and_left_of_the_camera() {
        let s = scene(&[(Vec3::new(-1., 0., -1.), Vec3::new(1., 2., 1.))]);
        for from in [
            Vec3::new(0.6, 0.5, 1.0),
            Vec3::new(-3.0, 1.0, 0.2),
            Vec3::new(0.0, 1.0, 0.0),
        ] {
            let cam = Camera::framing(Vec3::new(-1., 0., -1.), Vec3::new(1., 2., 1.), from);
            let l = s.key_light(&cam).unwrap().to_array();
            assert_eq!(l[3], 1.0);
            let p = Vec3::new(l[0], l[1], l[2]);
            let c = Vec3::new(0., 1., 0.);
            assert!(p.y > 2.0 && (p - c).length() > 3.0, "{from}: {p}");
            let view = cam.target - cam.eye;
            let right = view.cross(cam.up);
            if right.length() > 1e-3 {
                assert!(
                    (p - c).dot(right) < 0.0,
                    "{from}: light {p} not on the left"
                );
            }
        }
    }
}
