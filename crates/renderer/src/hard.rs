//! Hard scenes for the renderer: the four scenes of our Figure 1 (and the tests).
//!
//! Each is a [`Scene`] with a receiver ground or backdrop so that the shadow and its artifacts
//! are visible:
//! * [`edge_on_frustum`]: a truncated cone whose side faces all point at the light (the light
//!   sits on the cone's apex), so every side triangle is edge-on to the light: `f32` signs of
//!   its three edges disagree at random in `original`;
//! * [`bunny_offset`]: the Stanford bunny with `10⁴` added to every coordinate (in the mesh
//!   itself, so the predicate sees the large coordinates);
//! * [`uv_sphere_pole`]: a UV sphere with a point light on its axis, exactly where the planes of
//!   one band of quads meet the axis, so that whole band is edge-on;
//! * [`town`]: the `town` preset with a sun exactly parallel to half of its walls.

use crate::{Camera, RenderError};
use glam::Vec3;
use shadowvol_mesh_topology::Mesh;
use shadowvol_robust_math::Light;
use shadowvol_scenes::Scene;

/// A truncated cone around `+Y`: `segments` sides, bottom radius `r0` at `y = 0`, top radius
/// `r1` at `y = h`, closed by fan caps. Its apex (where the side planes meet) is at
/// `y = h · r0 / (r0 − r1)`.
///
/// # Panics
/// Panics if `segments < 3` or `r1 >= r0`.
#[must_use]
pub fn frustum_mesh(segments: u32, r0: f32, r1: f32, h: f32) -> Mesh {
    assert!(segments >= 3 && r1 < r0, "need segments >= 3 and r1 < r0");
    let mut positions = Vec::with_capacity(2 * segments as usize + 2);
    for k in 0..segments {
        let a = std::f32::consts::TAU * k as f32 / segments as f32;
        positions.push(Vec3::new(r0 * a.cos(), 0.0, r0 * a.sin()));
        positions.push(Vec3::new(r1 * a.cos(), h, r1 * a.sin()));
    }
    let bottom = positions.len() as u32;
    positions.push(Vec3::ZERO);
    let top = bottom + 1;
    positions.push(Vec3::new(0.0, h, 0.0));
    let mut triangles = Vec::with_capacity(4 * segments as usize);
    for k in 0..segments {
        let (b0, t0) = (2 * k, 2 * k + 1);
        let (b1, t1) = (2 * ((k + 1) % segments), 2 * ((k + 1) % segments) + 1);
        triangles.push([b0, t0, t1]);
        triangles.push([b0, t1, b1]);
        triangles.push([bottom, b0, b1]);
        triangles.push([top, t1, t0]);
    }
    Mesh {
        positions,
        triangles,
    }
}

/// A scene of `mesh` named `name` at the identity, lit by `light`, seen from `camera`, with the
/// ambient of the figures (0.15) and a ground at `ground_y`.
fn figure_scene(
    name: &str,
    mesh: &Mesh,
    light: Light,
    camera: Camera,
    ground_y: f32,
) -> Result<Scene, RenderError> {
    let mut scene =
        Scene::single(name, mesh).map_err(|e| RenderError::InvalidInput(e.to_string()))?;
    scene.add_unit_lights([light]);
    scene.camera = Some(camera);
    scene.effects.ambient = 0.15;
    scene.set_ground(Some(ground_y));
    Ok(scene)
}

/// The edge-on frustum: 64 sides, the light exactly on the apex of the side planes, a ground
/// below.
///
/// # Errors
/// Never in practice (the mesh is valid).
pub fn edge_on_frustum() -> Result<Scene, RenderError> {
    figure_scene(
        "frustum",
        &frustum_mesh(64, 1.0, 0.5, 1.0),
        Light::point(Vec3::new(0.0, 2.0, 0.0)),
        Camera::look_at(Vec3::new(2.6, 3.4, 4.2), Vec3::new(0.0, -0.6, 0.0)),
        -1.2,
    )
}

/// The bunny with `offset` added to every vertex (in the mesh), a light above and to the side,
/// a ground under it.
///
/// # Errors
/// Never in practice (the bundled bunny is valid).
pub fn bunny_offset(offset: f32) -> Result<Scene, RenderError> {
    let mut mesh = shadowvol_scenes::presets::bunny();
    let (lo, hi) = shadowvol_scenes::mesh_bounds(&mesh)
        .ok_or_else(|| RenderError::InvalidInput("empty bunny".into()))?;
    let size = (hi - lo).length();
    let shift = Vec3::splat(offset);
    for p in &mut mesh.positions {
        *p += shift;
    }
    let (lo, hi) = (lo + shift, hi + shift);
    let c = (lo + hi) * 0.5;
    figure_scene(
        "bunny",
        &mesh,
        Light::point(c + Vec3::new(-1.2, 0.9, 0.3) * size),
        Camera::look_at(
            c + Vec3::new(0.5, 0.55, 1.0) * size * 1.3,
            c - Vec3::Y * size * 0.1,
        ),
        lo.y,
    )
}

/// A UV sphere of about `triangles` triangles, radius 1, with a point light on its axis above the
/// north pole, exactly (to `f32`) where the planes of one band of quads (a third of the way to
/// the equator) meet the axis: that whole band is edge-on to the light.
///
/// # Errors
/// Never in practice (the sphere is valid).
pub fn uv_sphere_pole(triangles: usize) -> Result<Scene, RenderError> {
    let mesh = shadowvol_scenes::procedural::uv_sphere(triangles, 1.0);
    // The band just below the north-pole fan: find the vertex rings by height.
    let mut ys: Vec<f32> = mesh.positions.iter().map(|p| p.y).collect();
    ys.sort_by(|a, b| b.total_cmp(a));
    ys.dedup();
    let light_y = if ys.len() >= 4 {
        // Ring heights from the pole down: the quad band between rings k and k + 1 (k about a
        // third of the way to the equator) is a cone whose apex is where its planes meet the axis.
        let k = (ys.len() / 6).max(1);
        let r = |y: f32| (1.0 - y * y).max(0.0).sqrt();
        let (y1, y2) = (ys[k], ys[k + 1]);
        let (r1, r2) = (r(y1), r(y2));
        // Line through (r1, y1) and (r2, y2) at radius 0. (The faces are planar trapezoids, so
        // the apex of their planes lies a little off this cone line; rounding makes it hard.)
        y1 + (y1 - y2) * r1 / (r2 - r1)
    } else {
        2.0
    };
    figure_scene(
        "sphere",
        &mesh,
        Light::point(Vec3::new(0.0, light_y, 0.0)),
        Camera::look_at(Vec3::new(2.4, 2.6, 3.6), Vec3::new(0.0, -0.8, 0.0)),
        -1.6,
    )
}

/// The `town` preset with its ground plane, lit by a sun in the `XY` plane, direction `(1, 2, 0)`
/// (integers, exact in `f32`): every wall facing `±Z` is exactly parallel to the light (its
/// determinant is exactly 0) while the other walls cast long shadows. (The preset's own sun
/// points straight down, which makes every wall edge-on and leaves nothing to see.)
///
/// # Errors
/// [`RenderError::InvalidInput`] if the preset cannot be built.
pub fn town() -> Result<Scene, RenderError> {
    let mut s =
        shadowvol_scenes::preset("town").map_err(|e| RenderError::InvalidInput(e.to_string()))?;
    s.lights.clear();
    s.add_unit_lights([Light::directional(Vec3::new(1.0, 2.0, 0.0))]);
    Ok(s)
}

/// The `hard-*` preset `name` of the scenes crate, with a receiver-only backdrop behind it (seen
/// from its first light).
///
/// # Errors
/// [`RenderError::InvalidInput`] for an unknown name.
pub fn hard_preset(name: &str) -> Result<Scene, RenderError> {
    let mut s =
        shadowvol_scenes::preset(name).map_err(|e| RenderError::InvalidInput(e.to_string()))?;
    if s.ground_y().is_none() {
        s.add_backdrop();
    }
    Ok(s)
}

/// The names of the scenes crate's `hard-*` presets.
#[must_use]
pub fn hard_preset_names() -> Vec<String> {
    shadowvol_scenes::preset_names()
        .into_iter()
        .filter(|n| n.starts_with("hard-"))
        .collect()
}
