//! The paper's scenes as presets (names as in DESIGN.md), generated lazily on request.

use crate::hard::{self, HardCase};
use crate::procedural::{icosphere, loop_subdivide_levels, town, TownParams};
use crate::scene::Scene;
use crate::Camera;
use crate::SceneError;
use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_robust_math::Light;
use std::sync::Arc;

/// The bundled Stanford bunny (3,674 triangles, closed 2-manifold), as OBJ text.
pub const BUNNY_OBJ: &str = include_str!("../../../assets/bunny.obj");

/// Loop subdivision levels applied to the bunny in the `bunnies-10-*` presets:
/// 3,674 · 4² = 58,784 triangles per bunny (587,840 for ten). The paper's ~65k per bunny is not
/// a power-of-four multiple of 3,674; two levels is the closest (−9.6 %).
pub const BUNNY_LEVELS: u32 = 2;

/// Loop subdivision levels of `bunny-10m`: 3,674 · 4⁶ = 15,048,704 triangles, the power-of-four
/// multiple of the bundled bunny closest to 10^7 in ratio (five levels give 3,762,176).
pub const BUNNY_10M_LEVELS: u32 = 6;

/// Triangles of `bunny-10m` (3,674 · 4⁶).
pub const BUNNY_10M_TRIANGLES: usize = 3_674 << (2 * BUNNY_10M_LEVELS);

/// Triangles per sphere in `spheres-10-*` (10 × 65,000 = 650,000 ≈ the paper's 6.5·10⁵).
pub const SPHERE_10_TRIANGLES: usize = 65_000;

/// The bundled bunny as a mesh (3,674 triangles).
///
/// # Panics
/// Never in practice: the bundled file is known to parse (a test checks it).
#[must_use]
pub fn bunny() -> Mesh {
    crate::obj::parse_obj(BUNNY_OBJ, "assets/bunny.obj").expect("bundled bunny parses")
}

/// One preset: its name and what it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PresetInfo {
    /// The name (`shadowvol scenes` lists these; every command accepts them as a scene).
    pub name: String,
    /// What it is, in words.
    pub description: String,
    /// Its size, known without generating it: set for the presets of 10^7 triangles and more,
    /// which take seconds to minutes and gigabytes to build (`None`: build it to count).
    pub size: Option<PresetSize>,
}

/// The size of a preset, as [`preset`] builds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PresetSize {
    /// Objects (instances).
    pub objects: usize,
    /// Triangles over all objects.
    pub triangles: usize,
    /// Lights.
    pub lights: usize,
}

struct Fixed {
    name: &'static str,
    description: &'static str,
    size: Option<PresetSize>,
}

/// One icosphere of `triangles` (exact for even counts from 320) and one light.
const fn one_sphere(triangles: usize) -> Option<PresetSize> {
    Some(PresetSize {
        objects: 1,
        triangles,
        lights: 1,
    })
}

const FIXED: &[Fixed] = &[
    Fixed {
        name: "bunnies-10-individual",
        description: "10 Loop-subdivided bunnies (58,784 triangles each), 10 objects sharing one mesh",
        size: None,
    },
    Fixed {
        name: "bunnies-10-baked",
        description: "the 10 bunnies merged into one world-space mesh (587,840 triangles)",
        size: None,
    },
    Fixed {
        name: "spheres-10-individual",
        description: "10 icospheres of 65,000 triangles, 10 objects sharing one mesh",
        size: None,
    },
    Fixed {
        name: "spheres-10-baked",
        description: "the 10 spheres merged into one world-space mesh (650,000 triangles)",
        size: None,
    },
    Fixed {
        name: "sphere-1m",
        description: "one icosphere of 1,000,000 triangles",
        size: None,
    },
    Fixed {
        name: "sphere-100k",
        description: "one icosphere of 100,000 triangles",
        size: None,
    },
    Fixed {
        name: "spheres-100x10k",
        description: "10 x 10 grid of icospheres of 10,000 triangles (100 objects, one mesh)",
        size: None,
    },
    Fixed {
        name: "spheres-100x1k",
        description: "10 x 10 grid of icospheres of 1,000 triangles (100 objects, one mesh)",
        size: None,
    },
    Fixed {
        name: "sphere-10k",
        description: "one icosphere of 10,000 triangles (time against triangles, 10^4)",
        size: None,
    },
    Fixed {
        name: "sphere-1k",
        description: "one icosphere of 1,000 triangles (time against triangles, 10^3)",
        size: None,
    },
    Fixed {
        name: "bunny",
        description: "the bundled Stanford bunny (3,674 triangles; the Toy Wars table)",
        size: None,
    },
    Fixed {
        name: "bunny-subdivided",
        description: "the bunny Loop-subdivided twice (58,784 triangles; the Toy Wars table)",
        size: None,
    },
    Fixed {
        name: "town",
        description: "~570k triangles of axis-aligned box buildings; sun exactly along +Y, so every wall is parallel to it",
        size: None,
    },
    Fixed {
        name: "sphere-10m",
        description: "one icosphere of 10,000,000 triangles (scale: about 1.2 GB to run on cpu)",
        size: one_sphere(10_000_000),
    },
    Fixed {
        name: "bunny-10m",
        description: "the bunny Loop-subdivided six times (15,048,704 triangles, about 10^7: real curvature at scale)",
        size: Some(PresetSize {
            objects: 1,
            triangles: BUNNY_10M_TRIANGLES,
            lights: 1,
        }),
    },
    Fixed {
        name: "sphere-100m",
        description: "one icosphere of 100,000,000 triangles (scale: refused before building when the memory is short)",
        size: one_sphere(100_000_000),
    },
];

/// Every preset: the fixed ones, then `hard-<case>` for each case of [`hard::cases`].
#[must_use]
pub fn presets() -> Vec<PresetInfo> {
    let mut v: Vec<PresetInfo> = FIXED
        .iter()
        .map(|f| PresetInfo {
            name: f.name.to_owned(),
            description: f.description.to_owned(),
            size: f.size,
        })
        .collect();
    for case in hard::cases() {
        v.push(PresetInfo {
            name: format!("hard-{}", case.name),
            description: case.description.to_owned(),
            size: None,
        });
    }
    v
}

/// The names of all presets, in listing order.
#[must_use]
pub fn preset_names() -> Vec<String> {
    presets().into_iter().map(|p| p.name).collect()
}

/// True if `name` is a preset.
#[must_use]
pub fn is_preset(name: &str) -> bool {
    if FIXED.iter().any(|p| p.name == name) {
        return true;
    }
    name.strip_prefix("hard-")
        .is_some_and(|case| hard::cases().iter().any(|c| c.name == case))
}

/// Builds the preset `name` (generation happens here, on request).
///
/// # Errors
/// [`SceneError::UnknownPreset`] listing the known names.
pub fn preset(name: &str) -> Result<Scene, SceneError> {
    let scene = match name {
        "bunnies-10-individual" => bunnies(name)?,
        "bunnies-10-baked" => bunnies(name)?.baked()?,
        "spheres-10-individual" => sphere_grid(name, SPHERE_10_TRIANGLES, 5, 2)?,
        "spheres-10-baked" => sphere_grid(name, SPHERE_10_TRIANGLES, 5, 2)?.baked()?,
        "sphere-1m" => sphere_grid(name, 1_000_000, 1, 1)?,
        "sphere-100k" => sphere_grid(name, 100_000, 1, 1)?,
        "spheres-100x10k" => sphere_grid(name, 10_000, 10, 10)?,
        "spheres-100x1k" => sphere_grid(name, 1_000, 10, 10)?,
        "sphere-10k" => sphere_grid(name, 10_000, 1, 1)?,
        "sphere-1k" => sphere_grid(name, 1_000, 1, 1)?,
        "bunny" => single_bunny(name, 0)?,
        "bunny-subdivided" => single_bunny(name, BUNNY_LEVELS)?,
        "town" => town_scene()?,
        "sphere-10m" => sphere_grid(name, 10_000_000, 1, 1)?,
        "sphere-100m" => sphere_grid(name, 100_000_000, 1, 1)?,
        "bunny-10m" => {
            refuse_beyond_memory(name, BUNNY_10M_TRIANGLES)?;
            single_bunny(name, BUNNY_10M_LEVELS)?
        }
        _ => match name
            .strip_prefix("hard-")
            .and_then(|case| hard::cases().into_iter().find(|c| c.name == case))
        {
            Some(case) => hard_scene(name, &case)?,
            None => {
                return Err(SceneError::UnknownPreset {
                    name: name.to_owned(),
                    known: preset_names().join(", "),
                })
            }
        },
    };
    Ok(scene)
}

/// `cols × rows` instances of `mesh` (footprint `spacing`) on the `XZ` plane, centred at the
/// origin at height `y`, translated only (translations are small integers: exact in `f32`).
fn grid_objects(
    scene: &mut Scene,
    prefix: &str,
    mesh: Mesh,
    (cols, rows): (u32, u32),
    spacing: f32,
    y: f32,
) -> Result<(), SceneError> {
    let table = scene.add_mesh_owned(prefix, mesh)?;
    for r in 0..rows {
        for c in 0..cols {
            let x = (c as f32 - (cols - 1) as f32 * 0.5) * spacing;
            let z = (r as f32 - (rows - 1) as f32 * 0.5) * spacing;
            scene.add_object(
                format!("{prefix}{}", r * cols + c),
                Arc::clone(&table),
                Affine3A::from_translation(Vec3::new(x, y, z)),
            );
        }
    }
    Ok(())
}

/// Places the ground at y = 0 under the objects, the `lights` and a camera framing the
/// objects from `from`.
fn on_ground_framed(mut scene: Scene, lights: Vec<Light>, from: Vec3) -> Scene {
    scene.set_ground(Some(0.0));
    framed(scene, lights, from)
}

fn framed(mut scene: Scene, lights: Vec<Light>, from: Vec3) -> Scene {
    scene.add_unit_lights(lights);
    if let Some((lo, hi)) = scene.bounds() {
        scene.camera = Some(Camera::framing(lo, hi, from));
    }
    scene
}

fn bunnies(name: &str) -> Result<Scene, SceneError> {
    let mesh = loop_subdivide_levels(&bunny(), BUNNY_LEVELS);
    // The bunny spans about 10 x 9.7 x 7.5 units, standing on y = 0.
    let mut scene = Scene::new(name);
    grid_objects(&mut scene, "bunny", mesh, (5, 2), 12.0, 0.0)?;
    Ok(on_ground_framed(
        scene,
        vec![Light::point(Vec3::new(-20.0, 40.0, 25.0))],
        Vec3::new(0.4, 0.6, 1.0),
    ))
}

/// One bunny (`levels` Loop subdivisions) standing on the ground, lit from above and to the side.
fn single_bunny(name: &str, levels: u32) -> Result<Scene, SceneError> {
    let base = bunny();
    let mesh = if levels == 0 {
        base
    } else {
        loop_subdivide_levels(&base, levels)
    };
    let mut scene = Scene::new(name);
    grid_objects(&mut scene, "bunny", mesh, (1, 1), 12.0, 0.0)?;
    Ok(on_ground_framed(
        scene,
        vec![Light::point(Vec3::new(-8.0, 25.0, 12.0))],
        Vec3::new(0.4, 0.6, 1.0),
    ))
}

/// Refuses, before generating it, a preset of `triangles` triangles (a closed mesh: half as many
/// vertices, plus two) whose edge table the memory could not hold.
fn refuse_beyond_memory(name: &str, triangles: usize) -> Result<(), SceneError> {
    shadowvol_mesh_topology::EdgeTable::check_size(triangles as u64, triangles as u64 / 2 + 2)
        .map(drop)
        .map_err(|source| SceneError::Mesh {
            what: format!("preset '{name}' ({triangles} triangles)"),
            source,
        })
}

fn sphere_grid(name: &str, triangles: usize, cols: u32, rows: u32) -> Result<Scene, SceneError> {
    refuse_beyond_memory(name, triangles)?;
    let mesh = icosphere(triangles, 1.0);
    // Spheres of radius 1 stand on y = 0 (centre at y = 1), 3 units apart.
    let mut scene = Scene::new(name);
    grid_objects(&mut scene, "sphere", mesh, (cols, rows), 3.0, 1.0)?;
    let extent = 3.0 * cols.max(rows) as f32;
    Ok(on_ground_framed(
        scene,
        vec![Light::point(Vec3::new(
            -0.6 * extent,
            2.0 * extent + 4.0,
            0.5 * extent,
        ))],
        Vec3::new(0.4, 0.7, 1.0),
    ))
}

fn town_scene() -> Result<Scene, SceneError> {
    let mut scene = Scene::new("town");
    let table = scene.add_mesh("town", &town(&TownParams::default()))?;
    scene.add_object("town", table, Affine3A::IDENTITY);
    // The sun exactly along +Y: every wall triangle is exactly parallel to the light.
    Ok(on_ground_framed(
        scene,
        vec![Light::directional(Vec3::Y)],
        Vec3::new(0.5, 0.8, 1.0),
    ))
}

fn hard_scene(name: &str, case: &HardCase) -> Result<Scene, SceneError> {
    let mut scene = Scene::new(name);
    for (i, (mesh, t)) in case.objects.iter().enumerate() {
        let what = format!("{}#{i}", case.name);
        let table = scene.add_mesh(&what, mesh)?;
        scene.add_object(what, table, *t);
    }
    Ok(framed(scene, case.lights.clone(), Vec3::new(0.6, 0.5, 1.0)))
}
