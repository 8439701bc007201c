//! Percentage-closer soft shadows (`MapFilter::Pcss`, Bevy's `experimental_pbr_pcss`) on a plate
//! over a floor, seen from straight above, under each light type with a size: the penumbra,
//! measured on the rendered image, widens with the light's radius and with the floor's distance
//! from the plate; far outside it the floor is fully lit, deep inside the umbra fully dark; and
//! a light of radius 0 draws PCF's image, byte for byte.
//!
//! Visibility is read from the image: the scene has no ambient term, so a floor pixel's colour
//! over the same pixel without the plate (drawn with PCF: PCSS would search the floor itself for
//! blockers) is the light's visibility there, to 8 bits.
//!
//! The maps use the biases of Bevy's own PCSS example (`examples/3d/pcss.rs`: depth 0.2 for
//! directional and spot lights, 0.35 for point lights, "higher than the default to avoid shadow
//! acne"): with the default 0.02 the blocker search finds the floor, sloped 45° to the light,
//! and the filter darkens it (the journal, 2026-12-07-pcss).

mod common;

use common::{cuboid, floor, scene_of, started};
use glam::{Affine3A, Vec3};
use shadowvol_renderer::RenderError;
use shadowvol_renderer::{
    Camera, Exposure, FrameImage, MapBias, MapFilter, MapPipeline, MapSettings, RenderDevice,
    RenderOptions, Renderer, Scene,
};
use shadowvol_robust_math::Light;
use shadowvol_scenes::{Emission, SpotCone};
use shadowvol_test_support::{main, skip, Skip};

main!(
    penumbrae_widen_with_the_radius_and_the_gap,
    far_outside_is_lit_and_deep_inside_is_dark,
    radius_zero_draws_pcfs_image,
    the_spiral_turns_per_pixel_and_repeats,
    the_report_states_each_lights_pcss_size,
    opengl_refuses_pcss_with_the_reason,
);

/// Image width and height, pixels.
const W: u32 = 256;
const H: u32 = 64;

/// The light's type.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Directional,
    Spot,
    Point,
}

const KINDS: [Kind; 3] = [Kind::Directional, Kind::Spot, Kind::Point];

/// Each light type's two radii, the second twice the first: angles for the directional light,
/// world units for the others. Bevy's filter is narrow for the size it is given (its spiral
/// spans 0.0015 to 0.035 of the penumbra estimate), so the point and spot lights are large for
/// their penumbrae to span pixels.
fn radii(kind: Kind) -> [f32; 2] {
    match kind {
        Kind::Directional => [0.05, 0.1],
        Kind::Spot | Kind::Point => [1.5, 3.0],
    }
}

/// The plate's two heights over the floor (the point and spot lights stand at `LIGHT_HEIGHT`).
const HEIGHTS: [f32; 2] = [2.25, 2.5];

/// Where the point and spot lights stand: above the floor, to `-x` of the plate's edge (`x = 0`).
const LIGHT_HEIGHT: f32 = 3.0;
const LIGHT_X: f32 = -0.5;

/// One setup: the light, its radius, and the plate's height over the floor.
#[derive(Debug, Clone, Copy)]
struct Setup {
    kind: Kind,
    radius: f32,
    height: f32,
}

impl Setup {
    /// Where the plate's edge shadows the floor (`x`), seen from the light's centre.
    fn edge_x(&self) -> f32 {
        match self.kind {
            // The direction to the light leans 45° towards -x.
            Kind::Directional => self.height,
            Kind::Spot | Kind::Point => -LIGHT_X * self.height / (LIGHT_HEIGHT - self.height),
        }
    }

    /// The true penumbra's width on the floor (world units), for the report: the light's disk
    /// seen past the edge (the point and spot lights' disks taken as level).
    fn true_width(&self) -> f32 {
        match self.kind {
            Kind::Directional => {
                let t = std::f32::consts::FRAC_PI_4;
                self.height * ((t + self.radius).tan() - (t - self.radius).tan())
            }
            Kind::Spot | Kind::Point => {
                2.0 * self.radius * self.height / (LIGHT_HEIGHT - self.height)
            }
        }
    }

    fn light(&self) -> Light {
        match self.kind {
            Kind::Directional => Light::directional(Vec3::new(-1.0, 1.0, 0.0)),
            Kind::Spot | Kind::Point => Light::point(Vec3::new(LIGHT_X, LIGHT_HEIGHT, 0.0)),
        }
    }

    /// The camera straight above the edge's shadow, looking down, seeing 1 unit of floor across
    /// (the plate, over `x <= 0`, stays out of view).
    fn camera(&self) -> Camera {
        let x = self.edge_x();
        Camera {
            fov_y: 0.025,
            ..Camera::look_at(Vec3::new(x, 10.0, 0.0), Vec3::new(x, 0.0, 0.0))
        }
    }

    /// The floor, and with `plate` a thin plate over `x <= 0` at the setup's height.
    fn scene(&self, plate: bool) -> Scene {
        let mut objects = vec![("floor", floor(8.0, 8), Affine3A::IDENTITY)];
        if plate {
            let lo = Vec3::new(-4.0, self.height, -4.0);
            objects.push((
                "plate",
                cuboid(lo, Vec3::new(0.0, self.height + 0.02, 4.0)),
                Affine3A::IDENTITY,
            ));
        }
        let mut scene = scene_of(objects, &[self.light()], self.camera(), 0.0);
        let l = &mut scene.lights[0];
        l.radius = self.radius;
        if self.kind == Kind::Spot {
            let target = Vec3::new(self.edge_x(), 0.0, 0.0);
            l.emission = Some(Emission {
                intensity: 20.0,
                spot: Some(SpotCone {
                    direction: (target - Vec3::new(LIGHT_X, LIGHT_HEIGHT, 0.0)).normalize(),
                    inner_cone_angle: 0.6,
                    outer_cone_angle: 0.9,
                }),
                ..Emission::default()
            });
        }
        scene
    }

    /// The bias of Bevy's PCSS example for this light type.
    fn bias(&self) -> MapBias {
        let (depth, normal) = match self.kind {
            Kind::Directional | Kind::Spot => (0.2, 1.8),
            Kind::Point => (0.35, 0.6),
        };
        MapBias {
            depth,
            slope: 0.0,
            normal,
        }
    }
}

/// A map-pipeline renderer with `filter` and `setup`'s bias, at a fixed exposure (the images
/// with and without the plate are lit alike), or a visible skip.
fn renderer(filter: MapFilter, setup: Setup) -> Result<Renderer, Skip> {
    let device = match RenderDevice::open() {
        Ok(d) => d,
        Err(e) => return started(Err(e)),
    };
    let settings = MapSettings {
        filter,
        bias: Some(setup.bias()),
        ..MapSettings::default()
    };
    let options = RenderOptions {
        exposure: Exposure::Fixed(1.0),
        ..RenderOptions::new(W, H)
    };
    started(Renderer::new(
        device,
        Box::new(MapPipeline::new(settings)),
        options,
    ))
}

fn image(r: &mut Renderer, scene: &Scene) -> FrameImage {
    r.render(scene)
        .expect("render")
        .read_image()
        .expect("image")
        .clone()
}

/// What the image says of a setup drawn with a filter.
struct Profile {
    /// Per pixel, `[row][column]`: the light's visibility.
    rows: Vec<Vec<f64>>,
    /// Per column: the mean visibility over the rows (the edge runs along the columns).
    visibility: Vec<f64>,
    /// Per column: the floor's `x` at its centre.
    x: Vec<f64>,
}

impl Profile {
    /// `setup` drawn with `filter`, over the floor drawn without the plate with PCF.
    fn of(filter: MapFilter, setup: Setup) -> Result<Profile, Skip> {
        let lit = image(&mut renderer(MapFilter::Pcf, setup)?, &setup.scene(false));
        let shadowed = image(&mut renderer(filter, setup)?, &setup.scene(true));
        assert!(
            shadowed.ids.iter().all(|id| id[0] == 1),
            "{setup:?}: the view shows more than the floor"
        );
        let green = |im: &FrameImage, i: usize| f64::from(im.rgba[4 * i + 1]);
        let mut rows = vec![vec![0.0; W as usize]; H as usize];
        for (y, row) in rows.iter_mut().enumerate() {
            for (x, v) in row.iter_mut().enumerate() {
                let i = y * W as usize + x;
                let l = green(&lit, i);
                assert!(l > 40.0, "{setup:?}: the floor is dim at ({x}, {y}): {l}");
                *v = (green(&shadowed, i) / l).min(1.0);
            }
        }
        let visibility = (0..W as usize)
            .map(|x| rows.iter().map(|r| r[x]).sum::<f64>() / f64::from(H))
            .collect();
        // Looking straight down, the camera maps the floor's x linearly to columns.
        let vp = setup.camera().view_proj(W as f32 / H as f32);
        let column = |x: f32| {
            let c = vp * Vec3::new(x, 0.0, 0.0).extend(1.0);
            f64::from(0.5 * (c.x / c.w + 1.0) * W as f32)
        };
        let (c0, c1) = (column(0.0), column(1.0));
        let x = (0..W)
            .map(|px| (f64::from(px) + 0.5 - c0) / (c1 - c0))
            .collect();
        Ok(Profile {
            rows,
            visibility,
            x,
        })
    }

    /// The penumbra: the floor's `x` from the first to the last column whose mean visibility
    /// lies between 0.05 and 0.95 (exclusive), each widened by half a column; `None` without
    /// one.
    fn penumbra(&self) -> Option<(f64, f64)> {
        let half = 0.5 * (self.x[1] - self.x[0]).abs();
        let (lo, hi) = self
            .visibility
            .iter()
            .zip(&self.x)
            .filter(|(v, _)| **v > 0.05 && **v < 0.95)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, x)| {
                (lo.min(*x), hi.max(*x))
            });
        (lo <= hi).then_some((lo - half, hi + half))
    }

    /// The penumbra's width, world units (0 without one).
    fn width(&self) -> f64 {
        self.penumbra().map_or(0.0, |(lo, hi)| hi - lo)
    }

    /// Where the mean visibility first reaches one half, going from the lit side (larger `x`)
    /// into the shadow: the hard shadow's edge for PCF.
    fn half_way(&self) -> f64 {
        let mut cols: Vec<(f64, f64)> = self
            .x
            .iter()
            .copied()
            .zip(self.visibility.iter().copied())
            .collect();
        cols.sort_by(|a, b| b.0.total_cmp(&a.0));
        cols.iter()
            .find(|(_, v)| *v < 0.5)
            .map_or(f64::NAN, |(x, _)| *x)
    }
}

/// Under each light type the penumbra is wider than PCF's, wider for the larger radius and
/// wider for the higher plate (the floor farther from the blocker).
fn penumbrae_widen_with_the_radius_and_the_gap() -> Result<(), Skip> {
    for kind in KINDS {
        let mut widths = [[0.0; 2]; 2];
        for (i, radius) in radii(kind).into_iter().enumerate() {
            for (j, height) in HEIGHTS.into_iter().enumerate() {
                let setup = Setup {
                    kind,
                    radius,
                    height,
                };
                let soft = Profile::of(MapFilter::Pcss, setup)?;
                let hard = Profile::of(MapFilter::Pcf, setup)?;
                let (w, pcf) = (soft.width(), hard.width());
                let (lo, hi) = soft.penumbra().unwrap_or_default();
                let edge = hard.half_way();
                eprintln!(
                    "{kind:?} radius {radius}, plate at {height}: penumbra {w:.4} from {lo:.3} to \
                     {hi:.3} (pcf {pcf:.4}, edge {edge:.3}; geometric {:.3})",
                    setup.true_width()
                );
                assert!(w > pcf, "{setup:?}: pcss {w} not wider than pcf {pcf}");
                // The filter is centred on the lookup: the penumbra reaches out on both sides of
                // PCF's edge.
                assert!(
                    edge - lo > 0.25 * w && hi - edge > 0.25 * w,
                    "{setup:?}: penumbra {lo}..{hi} is not across PCF's edge {edge}"
                );
                widths[i][j] = w;
            }
        }
        for j in 0..2 {
            assert!(
                widths[1][j] > widths[0][j],
                "{kind:?}, plate at {}: radii {:?} give {:?}",
                HEIGHTS[j],
                radii(kind),
                [widths[0][j], widths[1][j]]
            );
        }
        for (i, w) in widths.iter().enumerate() {
            assert!(
                w[1] > w[0],
                "{kind:?}, radius {}: plates at {HEIGHTS:?} give {w:?}",
                radii(kind)[i]
            );
        }
    }
    Ok(())
}

/// Over 0.3 units from the edge's shadow (beyond the penumbra PCSS draws for the smaller radius)
/// every floor pixel is fully lit on the light's side and fully dark on the plate's.
fn far_outside_is_lit_and_deep_inside_is_dark() -> Result<(), Skip> {
    for kind in KINDS {
        let setup = Setup {
            kind,
            radius: radii(kind)[0],
            height: HEIGHTS[1],
        };
        let p = Profile::of(MapFilter::Pcss, setup)?;
        let edge = f64::from(setup.edge_x());
        let (mut lit, mut dark) = (0, 0);
        for (col, x) in p.x.iter().enumerate() {
            for row in &p.rows {
                let v = row[col];
                if *x > edge + 0.3 {
                    assert_eq!(v, 1.0, "{setup:?}: x {x} beyond the penumbra sees {v}");
                    lit += 1;
                } else if *x < edge - 0.3 {
                    assert_eq!(v, 0.0, "{setup:?}: x {x} in the umbra sees {v}");
                    dark += 1;
                }
            }
        }
        assert!(
            lit > 3000 && dark > 3000,
            "{setup:?}: {lit} lit and {dark} dark pixels checked"
        );
    }
    Ok(())
}

/// A light of radius 0 under PCSS is read with PCF, as Bevy reads a light without a soft shadow
/// size with its normal filter: the same image, byte for byte.
fn radius_zero_draws_pcfs_image() -> Result<(), Skip> {
    for kind in KINDS {
        let setup = Setup {
            kind,
            radius: 0.0,
            height: HEIGHTS[1],
        };
        let scene = setup.scene(true);
        let pcss = image(&mut renderer(MapFilter::Pcss, setup)?, &scene);
        let pcf = image(&mut renderer(MapFilter::Pcf, setup)?, &scene);
        assert!(pcss.rgba == pcf.rgba, "{kind:?}: the images differ");
    }
    Ok(())
}

/// Bevy's non-temporal filter turns its spiral per pixel by interleaved gradient noise of the
/// pixel's position: along the edge (the floor is the same along it) the penumbra's rows differ
/// from each other, and a second frame repeats the first byte for byte.
fn the_spiral_turns_per_pixel_and_repeats() -> Result<(), Skip> {
    for kind in KINDS {
        let setup = Setup {
            kind,
            radius: radii(kind)[1],
            height: HEIGHTS[1],
        };
        let mut r = renderer(MapFilter::Pcss, setup)?;
        let scene = setup.scene(true);
        let first = image(&mut r, &scene);
        assert!(
            first.rgba == image(&mut r, &scene).rgba,
            "{kind:?}: frames differ"
        );
        let row = |y: usize| &first.rgba[4 * W as usize * y..4 * W as usize * (y + 1)];
        let distinct = (0..H as usize)
            .map(row)
            .collect::<std::collections::HashSet<_>>()
            .len();
        assert!(
            distinct > H as usize / 2,
            "{kind:?}: {distinct} distinct rows of {H}"
        );
    }
    Ok(())
}

/// The report states each light's PCSS size (Bevy's `soft_shadow_size`): the radius for point
/// and spot lights, `tan θ` times the view's depth along the light for a directional one; 0
/// without a size.
fn the_report_states_each_lights_pcss_size() -> Result<(), Skip> {
    for kind in KINDS {
        for radius in [0.0, radii(kind)[0]] {
            let setup = Setup {
                kind,
                radius,
                height: HEIGHTS[0],
            };
            let mut r = renderer(MapFilter::Pcss, setup)?;
            let frame = r.render(&setup.scene(true)).expect("render");
            let size = frame.report.shadow_maps[0].expect("a map").soft_shadow_size;
            match kind {
                _ if radius == 0.0 => assert_eq!(size, 0.0, "{kind:?}"),
                // The view looks down from 10 units up, 45° to the light: its box is at least
                // 10 cos 45° deep along the light.
                Kind::Directional => {
                    let view_depth = size / radius.tan();
                    assert!(
                        (7.07..12.0).contains(&view_depth),
                        "{kind:?}: size {size}, view depth {view_depth}"
                    );
                }
                _ => assert_eq!(size, radius, "{kind:?}"),
            }
        }
    }
    Ok(())
}

/// OpenGL samples a texture with one sampler only and PCSS reads each map with two: a light with
/// a size is refused with that reason (not a validation error), and lights of radius 0 are still
/// drawn, with PCF.
fn opengl_refuses_pcss_with_the_reason() -> Result<(), Skip> {
    let device = match RenderDevice::open_with(wgpu::Backends::GL) {
        Ok(d) => d,
        Err(RenderError::NoAdapter(why)) => {
            return Err(skip(format!(
                "no OpenGL adapter ({why}); install Mesa's EGL and llvmpipe (libegl-mesa0, \
                 libgl1-mesa-dri) to run this test"
            )))
        }
        Err(e) => panic!("the OpenGL device failed to open: {e}"),
    };
    for radius in [0.0, 0.1] {
        let setup = Setup {
            kind: Kind::Directional,
            radius,
            height: HEIGHTS[1],
        };
        let settings = MapSettings {
            filter: MapFilter::Pcss,
            ..MapSettings::default()
        };
        let mut r = Renderer::new(
            device.clone(),
            Box::new(MapPipeline::new(settings)),
            RenderOptions::new(W, H),
        )
        .expect("renderer");
        match (r.render(&setup.scene(true)), radius == 0.0) {
            (Ok(_), true) => {}
            (Err(RenderError::Unsupported(why)), false) => {
                assert!(why.contains("OpenGL") && why.contains("pcss"), "{why}");
            }
            (other, _) => panic!("radius {radius} on {}: {other:?}", device.description),
        }
    }
    Ok(())
}
