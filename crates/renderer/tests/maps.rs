//! The shadow-map pipeline against the exact reference: maps agree with it away from shadow
//! boundaries at high resolution, lose at low resolution, and every light type's map looks
//! where its shadows fall.

mod common;

use common::{box_on_floor, compare, cuboid, floor, scene_of, started};
use glam::{Affine3A, Vec3};
use shadowvol_reference::Comparison;
use shadowvol_renderer::{
    Camera, MapBias, MapFilter, MapPipeline, MapSettings, RenderDevice, RenderOptions, Renderer,
    Scene,
};
use shadowvol_robust_math::Light;
use shadowvol_scenes::{Emission, SpotCone};
use shadowvol_test_support::{main, Skip};

main!(
    a_box_on_a_floor_agrees_with_the_reference_under_every_light_type,
    a_point_light_casts_through_every_cube_face,
    cascades_agree_with_the_reference,
    cascades_sharpen_a_deep_view,
    a_homogeneous_point_light_casts_from_its_point,
    without_bias_a_lit_floor_shadows_itself,
    a_caster_out_of_view_still_shadows_what_the_view_sees,
    higher_resolution_maps_leave_fewer_artifacts,
    the_map_pipeline_reports_its_maps_and_repeats_its_image,
);

/// A map-pipeline renderer of `size` pixels with `settings`, or a visible skip.
fn map_renderer(size: u32, settings: MapSettings) -> Result<Renderer, Skip> {
    let device = match RenderDevice::open() {
        Ok(d) => d,
        Err(e) => return started(Err(e)),
    };
    started(Renderer::new(
        device,
        Box::new(MapPipeline::new(settings)),
        RenderOptions::new(size, size),
    ))
}

/// `scene` drawn with maps of `settings` at `size` pixels, compared with the reference.
fn map_comparison(scene: &Scene, size: u32, settings: MapSettings) -> Result<Comparison, Skip> {
    let mut r = map_renderer(size, settings)?;
    let frame = r.render(scene).expect("render");
    Ok(compare(&frame, scene))
}

fn at(size: u32) -> MapSettings {
    MapSettings {
        size: Some(size),
        ..MapSettings::default()
    }
}

fn camera() -> Camera {
    Camera::look_at(Vec3::new(0.0, 9.0, 6.0), Vec3::ZERO)
}

/// The box on the floor under each light type: directional, point, spot.
fn lit_box(kind: &str) -> Scene {
    match kind {
        "directional" => box_on_floor(Light::directional(Vec3::new(0.4, 1.0, 0.3)), camera()),
        "point" => box_on_floor(Light::point(Vec3::new(0.5, 6.0, 0.3)), camera()),
        "spot" => {
            let mut s = box_on_floor(Light::point(Vec3::new(0.5, 6.0, 0.3)), camera());
            s.lights[0].emission = Some(Emission {
                intensity: 30.0,
                spot: Some(SpotCone {
                    direction: Vec3::new(-0.1, -1.0, 0.0).normalize(),
                    inner_cone_angle: 0.5,
                    outer_cone_angle: 0.7,
                }),
                ..Emission::default()
            });
            s
        }
        _ => unreachable!("{kind}"),
    }
}

fn assert_shadowed(c: &Comparison, what: &str) {
    assert!(
        c.reference_shadow_pixels > 500,
        "{what}: the scene must have a shadow ({} reference shadow pixels)",
        c.reference_shadow_pixels
    );
}

/// At 4096 texels a map texel is far smaller than a pixel: every disagreement with the reference
/// lies within a pixel of a shadow boundary, and none counts.
fn a_box_on_a_floor_agrees_with_the_reference_under_every_light_type() -> Result<(), Skip> {
    for kind in ["directional", "point", "spot"] {
        for filter in [MapFilter::Hard, MapFilter::Pcf] {
            let c = map_comparison(&lit_box(kind), 256, MapSettings { filter, ..at(4096) })?;
            let what = format!("{kind} light, {} filter", filter.name());
            assert_shadowed(&c, &what);
            assert_eq!(
                c.artifact_pixels,
                0,
                "{what}: {c:?}",
                c = (c.artifact_pixels, c.boundary_pixels)
            );
        }
    }
    Ok(())
}

/// A point light low over a floor with a box hovering on each side, off the axes so that a
/// mirrored face shows: the shadows fall through
/// the cube faces +X, -X, +Z and -Z; the same scene turned a quarter about x puts them behind
/// +Y and -Y. Each face must render where the sampler reads it.
fn a_point_light_casts_through_every_cube_face() -> Result<(), Skip> {
    for turn in [
        Affine3A::IDENTITY,
        Affine3A::from_rotation_x(std::f32::consts::FRAC_PI_2),
    ] {
        let boxes = [(2.0, 0.7), (-2.0, -0.5), (0.6, 2.0), (-0.8, -2.0)].map(|(x, z)| {
            let lo = Vec3::new(x - 0.3, 0.2, z - 0.3);
            ("box", cuboid(lo, lo + Vec3::new(0.6, 1.0, 0.6)), turn)
        });
        let mut objects = vec![("floor", floor(8.0, 4), turn)];
        objects.extend(boxes);
        let camera = Camera {
            eye: turn.transform_point3(Vec3::new(0.0, 12.0, 4.0)),
            target: Vec3::ZERO,
            up: turn.transform_vector3(Vec3::Y),
            ..Camera::look_at(Vec3::new(0.0, 12.0, 4.0), Vec3::ZERO)
        };
        let light = Light::point(turn.transform_point3(Vec3::new(0.0, 0.6, 0.0)));
        let scene = scene_of(objects, &[light], camera, 0.15);
        let settings = MapSettings {
            filter: MapFilter::Hard,
            ..at(2048)
        };
        let c = map_comparison(&scene, 256, settings)?;
        assert_shadowed(&c, "boxes around a point light");
        assert_eq!(c.artifact_pixels, 0, "turn {turn:?}");
    }
    Ok(())
}

/// Boxes along a long floor, seen from low down its length, under a directional light: their
/// shadows fall into every cascade of a 4-cascade map.
fn deep_floor() -> Scene {
    let mut objects = vec![("floor", floor(24.0, 8), Affine3A::IDENTITY)];
    for (i, z) in [6.0, 0.0, -7.0, -16.0].into_iter().enumerate() {
        let x = if i % 2 == 0 { -1.0 } else { 1.0 };
        let lo = Vec3::new(x - 0.5, 0.3, z - 0.5);
        objects.push((
            "box",
            cuboid(lo, lo + Vec3::new(1.0, 1.5, 1.0)),
            Affine3A::IDENTITY,
        ));
    }
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 12.0), Vec3::new(0.0, 0.0, -12.0));
    scene_of(
        objects,
        &[Light::directional(Vec3::new(0.5, 1.0, 0.3))],
        camera,
        0.15,
    )
}

/// Each cascade of a directional map renders and is looked up where its slice of the view is:
/// at 4096 texels, 4 cascades agree with the reference as one map does.
fn cascades_agree_with_the_reference() -> Result<(), Skip> {
    let scene = deep_floor();
    for cascades in [1, 2, 4] {
        let settings = MapSettings {
            cascades,
            filter: MapFilter::Hard,
            ..at(4096)
        };
        let c = map_comparison(&scene, 256, settings)?;
        assert_shadowed(&c, "boxes along a floor");
        assert_eq!(c.artifact_pixels, 0, "{cascades} cascades");
    }
    Ok(())
}

/// Cascades spend the texels where the view needs them: at 256 texels, 4 cascades leave fewer
/// artifact pixels than one map over the whole view.
fn cascades_sharpen_a_deep_view() -> Result<(), Skip> {
    let scene = deep_floor();
    let with = |cascades| MapSettings {
        cascades,
        filter: MapFilter::Hard,
        ..at(256)
    };
    let one = map_comparison(&scene, 256, with(1))?;
    let four = map_comparison(&scene, 256, with(4))?;
    eprintln!(
        "deep floor at 256 texels: {} artifact pixels with one map, {} with 4 cascades",
        one.artifact_pixels, four.artifact_pixels
    );
    assert!(four.artifact_pixels < one.artifact_pixels);
    Ok(())
}

/// A point light written with w != 1 (`(w P, w)`) casts from its point P, as
/// the reference reads it.
fn a_homogeneous_point_light_casts_from_its_point() -> Result<(), Skip> {
    let p = Vec3::new(0.5, 6.0, 0.3);
    for w in [2.5f32, 0.25] {
        let light = Light::new(w * p.x, w * p.y, w * p.z, w).expect("a finite light");
        let scene = box_on_floor(light, camera());
        let settings = MapSettings {
            filter: MapFilter::Hard,
            ..at(4096)
        };
        let c = map_comparison(&scene, 256, settings)?;
        assert_shadowed(&c, "homogeneous point light");
        assert_eq!(c.artifact_pixels, 0, "w = {w}");
    }
    Ok(())
}

/// Without any bias the lit floor shadows itself (acne): the metric sees it.
fn without_bias_a_lit_floor_shadows_itself() -> Result<(), Skip> {
    for kind in ["directional", "point"] {
        let settings = MapSettings {
            bias: Some(MapBias::NONE),
            filter: MapFilter::Hard,
            ..at(1024)
        };
        let c = map_comparison(&lit_box(kind), 256, settings)?;
        assert!(
            c.artifact_pixels > 500,
            "{kind}: {} artifact pixels without bias",
            c.artifact_pixels
        );
    }
    Ok(())
}

/// A box above the view casts its shadow into it: the directional map's depth range holds every
/// caster, not only what the view sees.
fn a_caster_out_of_view_still_shadows_what_the_view_sees() -> Result<(), Skip> {
    let camera = Camera::look_at(Vec3::new(0.0, 2.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let scene = scene_of(
        vec![
            ("floor", floor(8.0, 4), Affine3A::IDENTITY),
            (
                "box",
                cuboid(Vec3::new(-1.0, 6.0, -2.0), Vec3::new(1.0, 7.0, 0.0)),
                Affine3A::IDENTITY,
            ),
        ],
        &[Light::directional(Vec3::new(0.0, 1.0, 0.15))],
        camera,
        0.15,
    );
    let c = map_comparison(&scene, 256, at(4096))?;
    assert_shadowed(&c, "out-of-view caster");
    assert_eq!(c.artifact_pixels, 0);
    Ok(())
}

/// Blocks and a real mesh on a floor, under a point and a directional light: at 4096 texels at
/// most 0.3 % of the pixels are artifacts, and 512 texels leave no fewer.
fn higher_resolution_maps_leave_fewer_artifacts() -> Result<(), Skip> {
    let blocks = scene_of(
        vec![
            ("floor", floor(6.0, 4), Affine3A::IDENTITY),
            (
                "a",
                cuboid(Vec3::new(-2.0, 0.0, -1.0), Vec3::new(-1.0, 2.0, 0.0)),
                Affine3A::IDENTITY,
            ),
            (
                "b",
                cuboid(Vec3::new(0.5, 0.0, -0.5), Vec3::new(1.2, 0.6, 1.5)),
                Affine3A::IDENTITY,
            ),
            (
                "c",
                cuboid(Vec3::new(-0.6, 0.0, 1.0), Vec3::new(0.1, 1.2, 1.6)),
                Affine3A::IDENTITY,
            ),
        ],
        &[Light::directional(Vec3::new(-0.5, 1.0, 0.4))],
        camera(),
        0.15,
    );
    let mut bunny = shadowvol_scenes::preset("bunny").expect("bundled bunny");
    bunny.lights.truncate(1);
    let mut bunny_point = bunny.clone();
    if let Some((lo, hi)) = bunny.bounds() {
        let c = (lo + hi) * 0.5;
        let r = (hi - lo).length();
        bunny_point.lights[0].light = Light::point(c + Vec3::new(-0.4 * r, 1.2 * r, 0.5 * r));
        bunny.lights[0].light = Light::directional(Vec3::new(-0.3, 1.0, 0.5));
    }
    let total = 256.0 * 256.0;
    for (name, scene) in [
        ("blocks", &blocks),
        ("bunny, directional", &bunny),
        ("bunny, point", &bunny_point),
    ] {
        let fine = map_comparison(scene, 256, at(4096))?;
        let coarse = map_comparison(scene, 256, at(512))?;
        assert_shadowed(&fine, name);
        eprintln!(
            "{name}: artifact pixels {} at 512 texels, {} at 4096",
            coarse.artifact_pixels, fine.artifact_pixels
        );
        assert!(
            fine.artifact_pixels as f64 <= 0.003 * total,
            "{name}: {} artifact pixels at 4096",
            fine.artifact_pixels
        );
        assert!(
            coarse.artifact_pixels >= fine.artifact_pixels,
            "{name}: 512 texels {} < 4096 texels {}",
            coarse.artifact_pixels,
            fine.artifact_pixels
        );
    }
    Ok(())
}

/// The report names the pipeline and one map per light; a timed frame reads nothing back, and
/// the next frame repeats the image.
fn the_map_pipeline_reports_its_maps_and_repeats_its_image() -> Result<(), Skip> {
    let scene = lit_box("point");
    let mut r = map_renderer(128, MapSettings::default())?;
    let read = r.render(&scene).expect("render");
    assert_eq!(read.report.pipeline, shadowvol_renderer::Pipeline::Map);
    assert_eq!(read.report.shadow_maps.len(), 1);
    let timed = r.render_timed(&scene).expect("render");
    assert_eq!(timed.readback_bytes, 0);
    let again = r.render(&scene).expect("render");
    assert_eq!(
        read.read_image().expect("image").rgba,
        again.read_image().expect("image").rgba
    );
    Ok(())
}
