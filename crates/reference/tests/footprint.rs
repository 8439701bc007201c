//! The footprint rule on frames built by hand (no GPU): a raster that errs only where a shadow
//! boundary crosses a pixel has no artifact pixel, every pixel the rule moves lies within a pixel
//! of a shadow wedge (checked here by projecting the casters onto the ground in `f64`), and a
//! raster error a whole pixel away from every boundary stays an artifact.

use glam::{DVec2, DVec3, Vec3};
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_reference::occlusion::light_side;
use shadowvol_reference::{self as reference, Comparison, PixelState, Rule, Shot};
use shadowvol_robust_math::Light;
use shadowvol_scenes::{Camera, Receiver, Scene, SceneLight};
use shadowvol_test_support::shapes::{distance_to_triangles, Lcg};
use std::sync::Arc;

const SIZE: u32 = 96;
const LIGHT: [f32; 4] = [0.3, 0.2, 6.0, 1.0];

/// A frame by hand: the casters as one object over a ground at z = 0 that covers every pixel
/// (id `[2, 0]`), one unit point light; the stencil is the test's raster.
struct Frame {
    scene: Scene,
    camera: Camera,
    rgba: Vec<u8>,
    ids: Vec<[u32; 2]>,
    stencil: Vec<Vec<u8>>,
    colors: Vec<[f32; 3]>,
}

impl Frame {
    /// Every pixel's stencil as the reference states it (a raster with no error); the states.
    fn draw_as_the_reference(&mut self) -> Vec<Vec<PixelState>> {
        let shot = self.shot();
        let sp = reference::surface_points(&shot);
        let states = reference::reference_states(&shot, &sp);
        drop(shot);
        for (i, s) in states[0].iter().enumerate() {
            self.stencil[0][i] = u8::from(*s != PixelState::Lit);
        }
        states
    }

    fn new(casters: &[[Vec3; 3]]) -> Self {
        let soup = |tris: &[[Vec3; 3]]| Mesh {
            positions: tris.iter().flatten().copied().collect(),
            triangles: (0..tris.len() as u32)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect(),
        };
        let ground = [
            Vec3::new(-40.0, -40.0, 0.0),
            Vec3::new(40.0, -40.0, 0.0),
            Vec3::new(0.0, 60.0, 0.0),
        ];
        let mut scene = Scene::single("soup", &soup(casters)).unwrap();
        scene.receivers.push(Receiver {
            name: "ground".into(),
            table: Arc::new(EdgeTable::build(&soup(&[ground])).unwrap()),
            albedo: [1.0; 3],
        });
        scene.lights.push(SceneLight::unit(
            Light::new(LIGHT[0], LIGHT[1], LIGHT[2], LIGHT[3]).unwrap(),
        ));
        scene.effects.ambient = 0.0;
        let n = (SIZE * SIZE) as usize;
        Self {
            scene,
            camera: Camera {
                eye: Vec3::new(0.5, -5.0, 7.0),
                target: Vec3::ZERO,
                up: Vec3::Z,
                fov_y: 60f32.to_radians(),
                near: 0.01,
            },
            rgba: vec![0; n * 4],
            ids: vec![[2, 0]; n],
            stencil: vec![vec![0; n]],
            colors: vec![[1.0; 3]],
        }
    }

    fn shot(&self) -> Shot<'_> {
        Shot::new(
            &self.scene,
            self.camera,
            SIZE,
            SIZE,
            &self.rgba,
            &self.ids,
            &self.stencil,
            &self.colors,
        )
    }

    fn compare(&self, rule: Rule) -> Comparison {
        reference::compare_with(&self.shot(), rule)
    }
}

/// `n` triangles, each in a plane through the light as written (`p1` on the line from the light
/// through `p0`); rounding the vertices to `f32` leaves each plane a hair off the light, so each
/// casts a shadow wedge a tiny fraction of a pixel wide.
fn soup(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
    let mut rng = Lcg(seed);
    let l = DVec3::new(
        f64::from(LIGHT[0]),
        f64::from(LIGHT[1]),
        f64::from(LIGHT[2]),
    );
    let mut out = Vec::new();
    while out.len() < n {
        let p0 = DVec3::new(
            rng.next_f64() * 4.0 - 2.0,
            rng.next_f64() * 4.0 - 2.0,
            0.5 + rng.next_f64() * 2.0,
        );
        let p1 = p0 + (p0 - l) * (0.05 + 0.1 * rng.next_f64());
        let dir = DVec3::new(
            rng.next_f64() - 0.5,
            rng.next_f64() - 0.5,
            rng.next_f64() - 0.5,
        );
        let p2 = p0 + dir * 0.8;
        let t = [p0, p1, p2].map(|p| p.as_vec3());
        // Only triangles whose f32 plane misses the light cast a shadow (the others cast none,
        // in the reference and in the volumes).
        if light_side(t, LIGHT) != 0 {
            out.push(t);
        }
    }
    out
}

/// The casters' shadows on the ground z = 0, projected from the light in `f64`.
fn shadows(casters: &[[Vec3; 3]]) -> Vec<[DVec2; 3]> {
    let l = DVec3::new(
        f64::from(LIGHT[0]),
        f64::from(LIGHT[1]),
        f64::from(LIGHT[2]),
    );
    casters
        .iter()
        .map(|t| {
            t.map(|v| {
                let v = v.as_dvec3();
                let p = l + (v - l) * (l.z / (l.z - v.z));
                DVec2::new(p.x, p.y)
            })
        })
        .collect()
}

/// Per pixel: the ground point under its centre and the pixel's width there (the distance to
/// the next pixel's point).
fn ground_points(frame: &Frame) -> (Vec<DVec2>, Vec<f64>) {
    let points = reference::surface_points(&frame.shot());
    let w = SIZE as usize;
    let p: Vec<DVec2> = points
        .iter()
        .map(|sp| {
            let q = sp.expect("the ground covers the view").position;
            DVec2::new(q.x, q.y)
        })
        .collect();
    let width = (0..p.len())
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let nx = if x + 1 < w { i + 1 } else { i - 1 };
            let ny = if y + 1 < w { i + w } else { i - w };
            p[i].distance(p[nx]).min(p[i].distance(p[ny]))
        })
        .collect();
    (p, width)
}

/// The soup: the reference shadows no pixel centre; a raster that shadows every pixel whose
/// centre lies within a fifth of a pixel of a wedge (as a raster's rounding may) has that many
/// artifact pixels by the 3×3 rule alone and none with the footprint rule, which moves exactly
/// those pixels, each within a pixel of a wedge. A stencil bit flipped two pixels away from
/// every wedge stays an artifact, and only it.
#[test]
fn sub_pixel_wedges_are_boundaries_and_errors_away_from_them_are_not() {
    let casters = soup(40, 7);
    let mut frame = Frame::new(&casters);
    let wedges = shadows(&casters);
    let (points, width) = ground_points(&frame);
    let near: Vec<usize> = (0..points.len())
        .filter(|&i| distance_to_triangles(points[i], &wedges) < 0.2 * width[i])
        .collect();
    assert!(near.len() >= 40, "only {} pixels near a wedge", near.len());
    for &i in &near {
        frame.stencil[0][i] = 1;
    }

    let before = frame.compare(Rule::Neighbourhood);
    assert_eq!(before.reference_shadow_pixels, 0, "no centre is shadowed");
    assert_eq!(before.artifact_pixels, near.len());
    assert_eq!(before.footprint_boundary_pixels, 0);

    let after = frame.compare(Rule::Footprint);
    assert_eq!(
        after.artifact_pixels, 0,
        "moved {:?}",
        after.footprint_moved
    );
    assert_eq!(after.footprint_moved, near);
    assert_eq!(after.footprint_boundary_pixels, near.len());
    assert_eq!(after.boundary_pixels, near.len());
    assert_eq!(after.geometric_artifact_pixels, 0);
    for &i in &after.footprint_moved {
        let d = distance_to_triangles(points[i], &wedges);
        assert!(
            d < width[i],
            "pixel {i}: {d} from a wedge, {} wide",
            width[i]
        );
    }

    // A raster error two pixels from every wedge, where the reference is uniform.
    let w = SIZE as usize;
    let planted = (0..points.len())
        .find(|&i| {
            let (x, y) = (i % w, i / w);
            x > 0
                && y > 0
                && x + 1 < w
                && y + 1 < w
                && distance_to_triangles(points[i], &wedges) > 2.0 * width[i]
        })
        .expect("a pixel away from the wedges");
    frame.stencil[0][planted] = 1;
    let planted_cmp = frame.compare(Rule::Footprint);
    assert_eq!(planted_cmp.artifact_pixels, 1, "pixel {planted} hidden");
    assert_eq!(planted_cmp.classes[planted], 3);
    assert_eq!(planted_cmp.footprint_moved, near);
}

/// A quad split into two triangles shadows a square on the ground whose inside the shared
/// edge's shadow crosses: a raster that lights a pixel on that seam is an artifact (the two
/// shadows cover the footprint between them, exactly), while one that lights a pixel on the
/// square's outline is at a boundary by the 3×3 rule.
#[test]
fn a_seam_inside_a_shadow_is_no_boundary() {
    // Over the ground at z = 1, a 2.4 × 2.4 quad; its diagonal from (-1.2, -1.2) to (1.2, 1.2).
    let (a, b, c, d) = (
        Vec3::new(-1.2, -1.2, 1.0),
        Vec3::new(1.2, -1.2, 1.0),
        Vec3::new(1.2, 1.2, 1.0),
        Vec3::new(-1.2, 1.2, 1.0),
    );
    let casters = [[a, b, c], [a, c, d]];
    let mut frame = Frame::new(&casters);
    let wedges = shadows(&casters);
    let (points, width) = ground_points(&frame);
    // The raster equals the reference, except at pixels on the seam's shadow (the diagonal
    // through the light's projection), deep inside the square.
    let states = frame.draw_as_the_reference();
    let l = DVec2::new(f64::from(LIGHT[0]), f64::from(LIGHT[1]));
    let seam = |p: DVec2| {
        let s = wedges[0];
        // The shared edge a-c projects to s[0]-s[2].
        let along = (s[2] - s[0]).normalize();
        ((p - s[0]).perp_dot(along)).abs()
    };
    let mut flipped = Vec::new();
    for i in 0..points.len() {
        let p = points[i];
        let inside = (p - l).abs().max_element() < 0.6 * 1.2 * 6.0 / 5.0;
        if inside && seam(p) < 0.3 * width[i] && states[0][i] == PixelState::Unlit {
            frame.stencil[0][i] = 0;
            flipped.push(i);
        }
    }
    assert!(flipped.len() >= 5, "only {} seam pixels", flipped.len());
    let cmp = frame.compare(Rule::Footprint);
    assert_eq!(
        cmp.artifact_pixels,
        flipped.len(),
        "{:?}",
        cmp.footprint_moved
    );
    assert!(cmp.footprint_moved.is_empty());
    for &i in &flipped {
        assert_eq!(cmp.classes[i], 2, "pixel {i}");
    }
}

/// A slit a few thousandths of a pixel wide between two casters lets light through inside their
/// shadow: no pixel centre sees it, and a raster that lights the pixels it crosses is at a
/// boundary by the footprint rule (the unshadowed part of the footprint has positive area).
#[test]
fn a_lit_slit_inside_a_shadow_is_a_boundary() {
    let gap = 1.0e-4f32;
    let casters = [
        [
            Vec3::new(-1.2, -1.2, 1.0),
            Vec3::new(-gap, -1.2, 1.0),
            Vec3::new(-gap, 1.2, 1.0),
        ],
        [
            Vec3::new(-1.2, -1.2, 1.0),
            Vec3::new(-gap, 1.2, 1.0),
            Vec3::new(-1.2, 1.2, 1.0),
        ],
        [
            Vec3::new(gap, -1.2, 1.0),
            Vec3::new(1.2, -1.2, 1.0),
            Vec3::new(1.2, 1.2, 1.0),
        ],
        [
            Vec3::new(gap, -1.2, 1.0),
            Vec3::new(1.2, 1.2, 1.0),
            Vec3::new(gap, 1.2, 1.0),
        ],
    ];
    let mut frame = Frame::new(&casters);
    let (points, width) = ground_points(&frame);
    let states = frame.draw_as_the_reference();
    // The slit's shadow on the ground: x = ±gap · 6/5 scaled about the light, a line x ≈ 0.06.
    let slit_x = f64::from(LIGHT[0]) * (1.0 - 6.0 / 5.0);
    let mut lit = Vec::new();
    for i in 0..points.len() {
        let p = points[i];
        let inside = (p.y - f64::from(LIGHT[1])).abs() < 1.0;
        if inside && (p.x - slit_x).abs() < 0.25 * width[i] && states[0][i] == PixelState::Unlit {
            frame.stencil[0][i] = 0;
            lit.push(i);
        }
    }
    assert!(lit.len() >= 5, "only {} slit pixels", lit.len());
    let before = frame.compare(Rule::Neighbourhood);
    assert_eq!(before.artifact_pixels, lit.len());
    let cmp = frame.compare(Rule::Footprint);
    assert_eq!(cmp.artifact_pixels, 0);
    assert_eq!(cmp.footprint_moved, lit);
}
