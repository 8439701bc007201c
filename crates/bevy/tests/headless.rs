//! The plugin in a Bevy app without a window, on whatever adapter wgpu finds (Mesa's lavapipe in
//! CI), against the project's exact reference for the same scene, camera and lights.
//!
//! One Bevy app for all three checks, in one test: Bevy keeps process-wide state (its logger),
//! and one start on a software device costs seconds.
//! - two lights of different colours (red, green) over a box on a floor, then the bundled bunny
//!   OBJ: each light's shadow, read from its own colour channel, agrees with the reference;
//! - moving the box changes its shadow in the next frame, without preparing the casters again;
//! - the bunny's mesh changed in place is prepared again; a directional and a spot light, each
//!   against the reference;
//! - the camera inside a shadow volume (under a roof), where only z-fail is right; then the
//!   target resized to another aspect;
//! - a caster with a NaN position, a camera with TAA's `TemporalJitter`, or an orthographic
//!   one, gets an error naming it.

mod common;

use bevy::prelude::*;
use common::{agreement, reference_from, Driver};
use shadowvol_bevy::ShadowVolumeLight;

const W: u32 = 320;
const H: u32 = 240;
/// DESIGN's bound on artifact pixels: 0.05 % of a `width × height` image.
fn max_artifacts(width: u32, height: u32) -> usize {
    (width * height) as usize / 2000
}
const LIGHTS: [Vec3; 2] = [Vec3::new(3.0, 2.5, 0.5), Vec3::new(-3.0, 4.0, 2.0)];

/// [`LIGHTS`] as homogeneous points, for the reference.
fn points() -> Vec<Vec4> {
    LIGHTS.iter().map(|p| p.extend(1.0)).collect()
}

/// The view every scene but the roof is seen from.
const HOME: (Vec3, Vec3) = (common::EYE, common::TARGET);

/// Each light's agreement with the reference, seen from `eye` looking at `target` (where the
/// caller has put the camera), or why it fails.
fn check(
    d: &mut Driver,
    (eye, target): (Vec3, Vec3),
    what: &str,
    meshes: &[(&Mesh, Transform)],
    lights: &[Entity],
    homogeneous: &[Vec4],
    failures: &mut Vec<String>,
) -> Vec<u8> {
    for _ in 0..4 {
        d.update();
    }
    let shadowed = d.capture();
    for &l in lights {
        d.world().entity_mut(l).remove::<ShadowVolumeLight>();
    }
    for _ in 0..2 {
        d.update();
    }
    let unshadowed = d.capture();
    for &l in lights {
        d.world().entity_mut(l).insert(ShadowVolumeLight);
    }
    let (w, h) = (d.width, d.height);
    let bound = max_artifacts(w, h);
    let states = reference_from(eye, target, meshes, homogeneous, w, h);
    for (li, states) in states.iter().enumerate() {
        let a = agreement(&shadowed, &unshadowed, states, li);
        println!(
            "{what}, light {li}: {} artifact pixels of {} compared ({} in shadow), bound {bound}",
            a.artifacts, a.compared, a.shadowed
        );
        if a.artifacts > bound {
            failures.push(format!(
                "{what}, light {li}: {} artifact pixels, over {bound}",
                a.artifacts
            ));
        }
        if a.compared < 10_000 || a.shadowed < 300 {
            failures.push(format!(
                "{what}, light {li}: too little to compare ({} pixels lit by it, {} in shadow)",
                a.compared, a.shadowed
            ));
        }
    }
    shadowed
}

#[test]
fn shadows_match_the_reference() {
    let mut d = Driver::new(W, H);
    let mut failures = Vec::new();
    let lights: Vec<Entity> = [Color::srgb(1.0, 0.0, 0.0), Color::srgb(0.0, 1.0, 0.0)]
        .iter()
        .zip(LIGHTS)
        .map(|(c, p)| d.spawn_light(p, *c))
        .collect();

    // 1. A box on a floor, two lights.
    let (floor, cube) = (common::floor(), common::unit_box());
    let box_at = Transform::from_xyz(-0.3, 0.5, 0.2);
    d.spawn_caster(floor.clone(), Transform::IDENTITY);
    let cube_entity = d.spawn_caster(cube.clone(), box_at);
    let before = check(
        &mut d,
        HOME,
        "box on floor",
        &[(&floor, Transform::IDENTITY), (&cube, box_at)],
        &lights,
        &points(),
        &mut failures,
    );

    // 2. The box moves: the next frame shows its new shadow, with no new preparation.
    let prepares = d.stats().prepares();
    let moved = Transform::from_xyz(0.6, 0.5, -0.4).with_rotation(Quat::from_rotation_y(0.5));
    d.world().entity_mut(cube_entity).insert(moved);
    let after = d.capture();
    let changed = before
        .chunks_exact(4)
        .zip(after.chunks_exact(4))
        .filter(|(a, b)| a != b)
        .count();
    println!("moved box: {changed} pixels changed in the next frame");
    if changed < 1000 {
        failures.push(format!("moving the box changed only {changed} pixels"));
    }
    check(
        &mut d,
        HOME,
        "moved box",
        &[(&floor, Transform::IDENTITY), (&cube, moved)],
        &lights,
        &points(),
        &mut failures,
    );
    if d.stats().prepares() != prepares {
        failures.push(format!(
            "moving the box prepared the casters again ({} preparations, {prepares} before)",
            d.stats().prepares()
        ));
    }
    if prepares == 0 {
        failures.push("the casters were never prepared".into());
    }
    d.world().entity_mut(cube_entity).despawn();

    // 3. The bundled bunny OBJ on the floor: its mesh changed the casters, so it is prepared.
    let bunny = common::bunny();
    let bunny_at = common::stand_on_floor(&bunny, 2.0);
    let bunny_entity = d.spawn_caster(bunny.clone(), bunny_at);
    check(
        &mut d,
        HOME,
        "bunny.obj",
        &[(&floor, Transform::IDENTITY), (&bunny, bunny_at)],
        &lights,
        &points(),
        &mut failures,
    );
    if d.stats().prepares() <= prepares {
        failures.push("adding the bunny did not prepare the casters again".into());
    }
    if let Some(e) = d.stats().error() {
        failures.push(format!("the plugin reported: {e}"));
    }

    // 4. The bunny's mesh changes in place (stretched along x), so the casters are prepared
    // again; then the other two kinds of light: a directional light (red) and a spot light
    // (green).
    let before_change = d.stats().prepares();
    let stretched = stretch_x(&bunny, 1.5);
    let handle = d
        .world()
        .get::<Mesh3d>(bunny_entity)
        .expect("Mesh3d")
        .0
        .clone();
    *d.world()
        .resource_mut::<Assets<Mesh>>()
        .get_mut(&handle)
        .expect("the bunny's mesh") = stretched.clone();
    let bunny = stretched;
    for l in lights {
        d.world().entity_mut(l).despawn();
    }
    let towards = Vec3::new(-2.0, 4.0, 3.0);
    let (spot_at, spot_to) = (Vec3::new(-2.5, 3.5, -1.5), Vec3::new(0.5, 0.0, 0.5));
    let others = [
        d.spawn_directional(towards, Color::srgb(1.0, 0.0, 0.0), 3000.0),
        d.spawn_spot(spot_at, spot_to, Color::srgb(0.0, 1.0, 0.0), 0.9),
    ];
    check(
        &mut d,
        HOME,
        "directional and spot",
        &[(&floor, Transform::IDENTITY), (&bunny, bunny_at)],
        &others,
        &[towards.normalize().extend(0.0), spot_at.extend(1.0)],
        &mut failures,
    );
    if d.stats().prepares() <= before_change {
        failures.push("changing the bunny's mesh did not prepare the casters again".into());
    }

    // 5. The camera inside a shadow volume: under a roof, lit from above. z-pass would invert
    // the shadows here; the plan must pick z-fail.
    for l in others {
        d.world().entity_mut(l).despawn();
    }
    d.world().entity_mut(bunny_entity).despawn();
    let roof = Cuboid::new(3.0, 0.2, 3.0).into();
    let roof_at = Transform::from_xyz(0.0, 2.0, 0.0);
    d.spawn_caster(Mesh::clone(&roof), roof_at);
    let above = Vec3::new(0.4, 6.0, 0.3);
    let sun = [d.spawn_light(above, Color::srgb(1.0, 0.0, 0.0))];
    let (eye, target) = (Vec3::new(0.3, 1.0, 1.2), Vec3::new(-1.0, 0.0, -3.0));
    d.look(eye, target);
    check(
        &mut d,
        (eye, target),
        "camera under a roof",
        &[(&floor, Transform::IDENTITY), (&roof, roof_at)],
        &sun,
        &[above.extend(1.0)],
        &mut failures,
    );
    d.look(common::EYE, common::TARGET);

    // 6. The target resized to another aspect (a window resized): the mask follows.
    d.resize(256, 160);
    check(
        &mut d,
        HOME,
        "roof, target resized to 256x160",
        &[(&floor, Transform::IDENTITY), (&roof, roof_at)],
        &sun,
        &[above.extend(1.0)],
        &mut failures,
    );

    // 7. TAA's jitter would misalign the mask: a clear error, and the lights unshadowed.
    let camera = d.camera;
    d.world()
        .entity_mut(camera)
        .insert(bevy::render::camera::TemporalJitter {
            offset: Vec2::new(0.25, -0.25),
        });
    d.update();
    d.update();
    match d.stats().error() {
        Some(e) if e.contains("TemporalJitter") => println!("jittered camera: {e}"),
        other => failures.push(format!("a jittered camera gave {other:?}, not an error")),
    }
    d.world()
        .entity_mut(camera)
        .remove::<bevy::render::camera::TemporalJitter>();
    d.update();
    d.update();
    if let Some(e) = d.stats().error() {
        failures.push(format!("the error stayed after the jitter went: {e}"));
    }

    // 8. A caster with a NaN position, added with a good one: an error naming the bad entity,
    // and the other casters, the new one too, are built and cast; the error goes with the bad
    // caster.
    let mut bad = common::unit_box();
    if let Some(bevy::mesh::VertexAttributeValues::Float32x3(p)) =
        bad.attribute_mut(Mesh::ATTRIBUTE_POSITION)
    {
        p[3][1] = f32::NAN;
    }
    let bad_entity = d.spawn_caster(bad, Transform::from_xyz(2.0, 0.5, 2.0));
    let good_at = Transform::from_xyz(-2.5, 0.5, 1.5);
    let good = d.spawn_caster(common::unit_box(), good_at);
    d.update();
    d.update();
    match d.stats().error() {
        Some(e) if e.contains(&format!("{bad_entity}")) => println!("NaN caster: {e}"),
        other => failures.push(format!(
            "a NaN caster gave {other:?}, not an error naming it"
        )),
    }
    check(
        &mut d,
        HOME,
        "roof and a new box, a NaN caster beside them left out",
        &[
            (&floor, Transform::IDENTITY),
            (&roof, roof_at),
            (&common::unit_box(), good_at),
        ],
        &sun,
        &[above.extend(1.0)],
        &mut failures,
    );
    d.world().entity_mut(bad_entity).despawn();
    d.world().entity_mut(good).despawn();
    d.update();
    d.update();
    if let Some(e) = d.stats().error() {
        failures.push(format!("the error stayed after the NaN caster went: {e}"));
    }

    // 9. An orthographic camera: refused by name too.
    let perspective = d.world().get::<Projection>(camera).cloned();
    d.world()
        .entity_mut(camera)
        .insert(Projection::Orthographic(
            OrthographicProjection::default_3d(),
        ));
    d.update();
    d.update();
    match d.stats().error() {
        Some(e) if e.contains("orthographic") => println!("orthographic camera: {e}"),
        other => failures.push(format!(
            "an orthographic camera gave {other:?}, not an error"
        )),
    }
    if let Some(p) = perspective {
        d.world().entity_mut(camera).insert(p);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `mesh` with every position's x scaled by `s`.
fn stretch_x(mesh: &Mesh, s: f32) -> Mesh {
    let mut m = mesh.clone();
    if let Some(bevy::mesh::VertexAttributeValues::Float32x3(p)) =
        m.attribute_mut(Mesh::ATTRIBUTE_POSITION)
    {
        for v in p.iter_mut() {
            v[0] *= s;
        }
    }
    m
}
