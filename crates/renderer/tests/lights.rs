//! Lights as glTF's `KHR_lights_punctual` defines them: colour, intensity, range and spot cone
//! change the image as the spec says, checked pixel by pixel against the lighting model in
//! `f64` ([`shadowvol_reference::shading_check`]) and, for shadows, against the ray-traced reference; a
//! caster the light cannot reach is culled without changing the image.

mod common;

use common::{box_on_floor, renderer_with};
use glam::Vec3;
use shadowvol_reference::shading_check;
use shadowvol_renderer::{Camera, Exposure, Frame, RenderOptions, Scene, Technique};
use shadowvol_robust_math::Light;
use shadowvol_scenes::{Emission, SceneLight, SpotCone};
use shadowvol_test_support::{main, Outcome, Skip};

main!(
    a_spot_cone_only_removes_light_outside_it,
    range_cuts_the_light_off_at_its_distance,
    colour_and_intensity_scale_the_light,
    auto_exposure_is_independent_of_units,
    auto_exposure_meters_what_the_camera_sees,
    casters_the_light_cannot_reach_are_culled,
    the_range_scissor_changes_no_pixel,
    the_spot_cone_scissor_changes_no_pixel
);

const W: u32 = 96;

fn camera() -> Camera {
    Camera::look_at(Vec3::new(0.0, 9.0, 6.0), Vec3::ZERO)
}

fn scene(emission: Emission) -> Scene {
    let mut s = box_on_floor(Light::point(Vec3::new(0.5, 6.0, 0.3)), camera());
    s.lights[0].emission = Some(emission);
    s
}

/// Point lights at `positions` with `emissions`, one each.
fn lights(positions: &[Vec3], emissions: &[Emission]) -> Vec<SceneLight> {
    positions
        .iter()
        .zip(emissions)
        .map(|(&p, &e)| SceneLight {
            light: Light::point(p),
            emission: Some(e),
            radius: 0.0,
        })
        .collect()
}

fn render(scene: &Scene, exposure: Exposure) -> Result<Frame, Skip> {
    let mut opts = RenderOptions::new(W, W);
    opts.exposure = exposure;
    let mut r = renderer_with(opts)?;
    Ok(r.render(scene).expect("render"))
}

/// Renders, and checks shadows against the ray-traced reference and every agreeing pixel's
/// colour against the lighting model.
fn checked(scene: &Scene, exposure: Exposure) -> Result<Frame, Skip> {
    let frame = render(scene, exposure)?;
    let cmp = common::compare(&frame, scene);
    assert_eq!(cmp.artifact_pixels, 0, "shadow artifacts: {cmp:?}");
    let shading = shading_check(&common::shot(&frame, scene), &cmp, 2);
    assert!(shading.compared > (W * W / 2) as usize, "{shading:?}");
    assert_eq!(
        shading.mismatched, 0,
        "colours off the lighting model: {shading:?}"
    );
    Ok(frame)
}

/// Per pixel, the sum of the three channels.
fn brightness(f: &Frame) -> Vec<u32> {
    f.image
        .as_ref()
        .unwrap()
        .rgba
        .chunks(4)
        .map(|p| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]))
        .collect()
}

fn spot(inner: f32, outer: f32) -> Emission {
    Emission {
        intensity: 30.0,
        spot: Some(SpotCone {
            direction: Vec3::new(-0.1, -1.0, 0.0).normalize(),
            inner_cone_angle: inner,
            outer_cone_angle: outer,
        }),
        ..Emission::default()
    }
}

fn a_spot_cone_only_removes_light_outside_it() -> Outcome {
    let x = Exposure::Fixed(0.05);
    let wide = checked(
        &scene(Emission {
            intensity: 30.0,
            ..Emission::default()
        }),
        x,
    )?;
    let narrow = checked(&scene(spot(0.2, 0.35)), x).unwrap();
    let (a, b) = (brightness(&wide), brightness(&narrow));
    let darker = a.iter().zip(&b).filter(|(a, b)| b < a).count();
    let brighter = a.iter().zip(&b).filter(|(a, b)| b > a).count();
    assert!(
        darker > (W * W / 4) as usize,
        "the cone darkened only {darker} pixels"
    );
    assert_eq!(brighter, 0, "a cone never adds light");
    // A softer edge (smaller inner angle) is darker inside the outer cone, never brighter.
    let soft = checked(&scene(spot(0.0, 0.35)), x).unwrap();
    let c = brightness(&soft);
    assert!(c.iter().zip(&b).all(|(c, b)| c <= b));
    assert!(c.iter().zip(&b).filter(|(c, b)| c < b).count() > 50);
    Ok(())
}

fn range_cuts_the_light_off_at_its_distance() -> Outcome {
    let x = Exposure::Fixed(0.05);
    let base = Emission {
        intensity: 30.0,
        ..Emission::default()
    };
    let unbounded = checked(&scene(base), x)?;
    let ranged = checked(
        &scene(Emission {
            range: Some(7.0),
            ..base
        }),
        x,
    )
    .unwrap();
    let (a, b) = (brightness(&unbounded), brightness(&ranged));
    assert!(a.iter().zip(&b).all(|(a, b)| b <= a));
    assert!(a.iter().zip(&b).filter(|(a, b)| b < a).count() > (W * W / 4) as usize);
    Ok(())
}

fn colour_and_intensity_scale_the_light() -> Outcome {
    let x = Exposure::Fixed(0.05);
    let white = Emission {
        intensity: 20.0,
        ..Emission::default()
    };
    let w = checked(&scene(white), x)?;
    let red = checked(
        &scene(Emission {
            color: [1.0, 0.0, 0.0],
            ..white
        }),
        x,
    )
    .unwrap();
    let dark = render(
        &scene(Emission {
            intensity: 0.0,
            ..white
        }),
        x,
    )
    .unwrap();
    let twice = checked(
        &scene(Emission {
            intensity: 40.0,
            ..white
        }),
        x,
    )
    .unwrap();
    let mut lit = 0;
    for i in 0..(W * W) as usize {
        let px = |f: &Frame, ch: usize| i32::from(f.image.as_ref().unwrap().rgba[i * 4 + ch]);
        // Red light: green and blue stay at the ambient level.
        assert!((px(&red, 1) - px(&dark, 1)).abs() <= 1 && (px(&red, 2) - px(&dark, 2)).abs() <= 1);
        assert!((px(&red, 0) - px(&w, 0)).abs() <= 1);
        // Twice the candela, twice the light above ambient (below saturation).
        let (l1, l2) = (px(&w, 1) - px(&dark, 1), px(&twice, 1) - px(&dark, 1));
        if l1 > 4 && px(&twice, 1) < 250 {
            lit += 1;
            assert!((l2 - 2 * l1).abs() <= 2, "pixel {i}: {l1} -> {l2}");
        }
    }
    assert!(lit > (W * W / 8) as usize, "only {lit} lit pixels compared");
    Ok(())
}

/// Auto exposure keeps a file's units out of the picture: the same light at a thousand times
/// the candela gives the same image, and not a burnt-out one.
fn auto_exposure_is_independent_of_units() -> Outcome {
    let a = Emission {
        intensity: 1.0,
        ..Emission::default()
    };
    let b = Emission {
        intensity: 1000.0,
        ..Emission::default()
    };
    let fa = checked(&scene(a), Exposure::Auto)?;
    let fb = checked(&scene(b), Exposure::Auto).unwrap();
    let (x, y) = (brightness(&fa), brightness(&fb));
    assert!(x.iter().zip(&y).all(|(x, y)| x.abs_diff(*y) <= 3));
    let burnt = fb
        .image
        .as_ref()
        .unwrap()
        .rgba
        .chunks(4)
        .filter(|p| p[0] == 255)
        .count();
    assert!(burnt < (W * W / 100) as usize, "{burnt} burnt-out pixels");
    Ok(())
}

/// A glTF point light 0.12 above a large ground, beside a small box: bright right under the
/// light, dark elsewhere. Auto exposure meters the lit points in view, so the box, its shadow
/// and the ground around them show in many grey levels, not as a near-black image of a few.
fn auto_exposure_meters_what_the_camera_sees() -> Outcome {
    let mut s = common::scene_of(
        vec![
            ("ground", common::floor(10.0, 8), glam::Affine3A::IDENTITY),
            (
                "box",
                common::cuboid(Vec3::new(-0.3, 0.0, -0.3), Vec3::new(0.3, 0.6, 0.3)),
                glam::Affine3A::IDENTITY,
            ),
        ],
        &[Light::point(Vec3::new(0.7, 0.12, 0.4))],
        Camera::look_at(Vec3::new(0.0, 6.0, 8.0), Vec3::ZERO),
        0.15,
    );
    s.lights[0].emission = Some(Emission::default());
    let frame = checked(&s, Exposure::Auto)?;
    let img = frame.read_image().unwrap();
    let mut levels = [false; 256];
    for p in img.rgba.chunks(4) {
        levels[usize::from(p[1])] = true;
    }
    let distinct = levels.iter().filter(|&&l| l).count();
    let covered = img.ids.iter().filter(|id| id[0] != 0).count();
    let bright = img
        .rgba
        .chunks(4)
        .zip(&img.ids)
        .filter(|(p, id)| id[0] != 0 && p[1] > 80)
        .count();
    assert!(distinct > 40, "only {distinct} grey levels");
    assert!(
        bright * 50 > covered,
        "only {bright} of {covered} covered pixels are brighter than 80"
    );
    Ok(())
}

/// A caster outside the cone or beyond the range is culled with the reason, and the image is
/// the reference's: its shadow would not have been lit anyway.
fn casters_the_light_cannot_reach_are_culled() -> Outcome {
    let x = Exposure::Fixed(0.05);
    for (emission, why) in [
        (spot(0.05, 0.1), "outside the spot light's cone"),
        (
            Emission {
                intensity: 30.0,
                range: Some(3.0),
                ..Emission::default()
            },
            "beyond the light's range",
        ),
    ] {
        let mut s = scene(emission);
        s.lights[0].light = Light::point(Vec3::new(-4.0, 1.0, 0.0));
        let frame = checked(&s, x)?;
        let box_entry = frame
            .report
            .plan
            .iter()
            .find(|e| e.object_name == "box")
            .unwrap();
        assert_eq!(box_entry.technique, Technique::Culled, "{box_entry:?}");
        assert!(box_entry.reason.contains(why), "{}", box_entry.reason);
        let floor = frame
            .report
            .plan
            .iter()
            .find(|e| e.object_name == "floor")
            .unwrap();
        assert_ne!(floor.technique, Technique::Culled, "{floor:?}");
    }
    Ok(())
}

/// Renders `s` with and without scissor and checks that the image, and every light's stencil
/// inside its rectangle, are the same pixel for pixel, that each rectangle is smaller than the
/// image and that more than `min_saved` pixels were kept out of the passes.
fn assert_scissor_changes_no_pixel(s: &Scene, min_saved: usize) -> Outcome {
    let mut opts = RenderOptions::new(W, W);
    opts.exposure = Exposure::Fixed(0.05);
    let mut r = renderer_with(opts)?;
    let with = r.render(s).unwrap();
    opts.scissor = false;
    let without = renderer_with(opts).unwrap().render(s).unwrap();
    assert_eq!(without.report.scissor_pixels_saved, 0);
    assert!(
        with.report.scissor_pixels_saved > min_saved,
        "{} {:?}",
        with.report.scissor_pixels_saved,
        with.report
            .plan
            .iter()
            .map(|e| e.scissor)
            .collect::<Vec<_>>()
    );
    let (wi, wo) = (with.read_image().unwrap(), without.read_image().unwrap());
    assert!(wi.rgba == wo.rgba, "the scissor changed the image");
    assert!(without.report.plan.iter().all(|e| e.scissor.is_none()));
    for li in 0..s.lights.len() {
        let rect = with
            .report
            .plan
            .iter()
            .find(|e| e.light == li)
            .unwrap()
            .scissor
            .unwrap_or_else(|| panic!("light {li} has no scissor"));
        assert!(rect[2] * rect[3] < W * W, "light {li}: {rect:?}");
        for y in rect[1]..rect[1] + rect[3] {
            for x in rect[0]..rect[0] + rect[2] {
                let i = (y * W + x) as usize;
                assert_eq!(
                    wi.stencil[li][i], wo.stencil[li][i],
                    "light {li} at ({x}, {y})"
                );
            }
        }
    }
    let cmp = common::compare(&with, s);
    assert_eq!(cmp.artifact_pixels, 0, "{cmp:?}");
    assert_eq!(
        shading_check(&common::shot(&with, s), &cmp, 2).mismatched,
        0
    );
    Ok(())
}

/// Scissor: lights with a range draw their stencil and lit passes only over the screen rectangle
/// of the range sphere. The image and every light's stencil inside the rectangle are the same
/// pixel for pixel as without it, and the plan reports the rectangle.
fn the_range_scissor_changes_no_pixel() -> Outcome {
    let mut s = scene(Emission {
        intensity: 30.0,
        range: Some(2.5),
        ..Emission::default()
    });
    let first = s.lights[0].emission.unwrap();
    s.lights = lights(
        &[Vec3::new(-1.5, 1.2, 0.5), Vec3::new(1.5, 2.0, -1.0)],
        &[
            first,
            Emission {
                intensity: 20.0,
                range: Some(3.0),
                ..Emission::default()
            },
        ],
    );
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 16.0, 11.0), Vec3::ZERO));
    assert_scissor_changes_no_pixel(&s, (W * W / 4) as usize)?;
    Ok(())
}

/// A spot light without a range is scissored to its cone, cut where the scene's bounds end;
/// a narrow cone and a hemisphere (outer angle π/2, the sphere's box) alike change no pixel.
fn the_spot_cone_scissor_changes_no_pixel() -> Outcome {
    let mut s = scene(spot(0.2, 0.35));
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 16.0, 11.0), Vec3::ZERO));
    assert_scissor_changes_no_pixel(&s, (W * W / 4) as usize)?;
    // Two lights: a tilted narrow cone with a range, and a hemisphere without one that shines
    // towards +x, so that only the half of the view beyond its plane can be lit.
    let tilted = SpotCone {
        direction: Vec3::new(0.4, -1.0, 0.2).normalize(),
        inner_cone_angle: 0.1,
        outer_cone_angle: 0.3,
    };
    s.lights = lights(
        &[Vec3::new(-1.0, 3.0, 0.5), Vec3::new(1.0, 0.8, -0.5)],
        &[
            Emission {
                intensity: 30.0,
                range: Some(6.0),
                spot: Some(tilted),
                ..Emission::default()
            },
            Emission {
                intensity: 10.0,
                spot: Some(SpotCone {
                    direction: Vec3::X,
                    inner_cone_angle: 1.0,
                    outer_cone_angle: std::f32::consts::FRAC_PI_2,
                }),
                ..Emission::default()
            },
        ],
    );
    assert_scissor_changes_no_pixel(&s, 0)?;
    Ok(())
}
