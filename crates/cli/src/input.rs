//! Turning a command-line mesh argument into a scene or one edge table: the one entry point for
//! every subcommand.

use crate::CliError;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_robust_math::Light;
use shadowvol_scenes::Scene;
use std::sync::Arc;

/// A loaded input: one edge table (object transforms already applied in `f32` on the host) and
/// the lights the input itself defines, if any.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// How to name the input in messages and reports (the path or preset name as given).
    pub name: String,
    /// The welded table in world space: all objects baked into one, vertices named by input
    /// index object by object (for glTF: depth-first node order, then primitive order, then
    /// accessor order).
    pub table: Arc<EdgeTable>,
    /// Lights defined by the input (glTF `KHR_lights_punctual`, preset lights; none for OBJ).
    /// Used when no `--light` is given.
    pub lights: Vec<Light>,
    /// The radius of each of `lights` (glTF `extras.radius`; 0 for a point light).
    pub light_radii: Vec<f32>,
    /// The point a light with a size faces ([`Scene::light_aim`]).
    pub light_aim: glam::Vec3,
    /// What the loader skipped, one sentence each naming the file and element (glTF primitives
    /// that are not triangles or have no positions, nodes left without triangles; OBJ lines,
    /// points, curves and surfaces); empty for STL, PLY and presets.
    pub notes: Vec<String>,
}

/// The input formats every subcommand accepts, for `--help`.
pub const INPUT_FORMATS: &str = "Input formats (by extension, case-insensitive): .gltf/.glb \
    (glTF 2.0: node transforms, KHR_lights_punctual, cameras, KHR_mesh_quantization, \
    EXT_meshopt_compression, KHR_draco_mesh_compression, sparse accessors; points and lines are \
    skipped with a note), .obj \
    (v and f; polygons fanned; l, p, curv and surf are skipped with a note), .stl (ASCII or binary; a triangle soup, welded by exact \
    position), .ply (ASCII or binary little/big-endian; vertex x, y, z and face vertex_indices, \
    polygons fanned, other properties ignored), or a preset name (`shadowvol scenes`).";

/// Loads `path_or_name`: a `.obj`, `.gltf`, `.glb`, `.stl` or `.ply` file (case-insensitive
/// extension) or a scene preset name (`shadowvol scenes` lists them), through
/// [`Scene::from_name_or_path_with_notes`]. Several objects are baked into one world-space table
/// with [`Scene::baked_table`] (transforms applied in `f32` on the host).
///
/// # Errors
/// [`CliError::Scene`] for an unreadable or malformed file (naming the file and the line,
/// accessor or vertex), an unsupported extension, or an unknown preset name;
/// [`CliError::Other`] for an input without triangles (an empty or garbage file).
pub fn load_input(path_or_name: &str) -> Result<Input, CliError> {
    let (scene, notes) = load_scene(path_or_name)?;
    let lights = scene.light_positions();
    let light_radii = scene.lights.iter().map(|l| l.radius).collect();
    let light_aim = scene.light_aim();
    Ok(Input {
        name: path_or_name.to_owned(),
        table: scene.into_baked_table()?,
        lights,
        light_radii,
        light_aim,
        notes,
    })
}

/// Loads `path_or_name` (a file of [`INPUT_FORMATS`] or a preset) through
/// [`Scene::from_name_or_path_with_notes`], and refuses a scene without a triangle, since nothing
/// in it can cast a shadow. Returns the scene and the loader's notes (what it skipped), which the
/// caller reports.
///
/// # Errors
/// [`CliError::Scene`] as [`load_input`]; [`CliError::Other`] for a scene without triangles, naming
/// `path_or_name`, with the notes and, for a file that is not UTF-8 text, where its first invalid
/// byte is.
pub fn load_scene(path_or_name: &str) -> Result<(Scene, Vec<String>), CliError> {
    let (scene, notes) = Scene::from_name_or_path_with_notes(path_or_name)?;
    if scene.triangle_count() > 0 {
        return Ok((scene, notes));
    }
    let skipped = if notes.is_empty() {
        String::new()
    } else {
        format!(" ({})", notes.join("; "))
    };
    Err(CliError::Other(format!(
        "{path_or_name}: no triangles found, nothing can cast a shadow{}{skipped}",
        not_text_hint(path_or_name)
    )))
}

/// For a file that is not UTF-8 text (a binary or garbage file given as `.obj`), where the
/// first invalid byte is; empty otherwise.
fn not_text_hint(path: &str) -> String {
    let Ok(bytes) = std::fs::read(path) else {
        return String::new();
    };
    let is_glb = bytes.starts_with(b"glTF");
    match std::str::from_utf8(&bytes) {
        Err(e) if !is_glb => {
            let at = e.valid_up_to();
            let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
            format!(" (the file is not UTF-8 text: first invalid byte at offset {at}, line {line})")
        }
        _ => String::new(),
    }
}

/// The error for a scene whose world-space bounds `lo`..`hi` are too large for `what` (a camera
/// that frames them, a ring of generated lights) in `f32`: it names `scene_arg`, prints the bounds
/// in scientific notation so a reader sees the magnitude, and ends with `hint`, the way out.
#[must_use]
pub fn bounds_too_large(
    scene_arg: &str,
    lo: glam::Vec3,
    hi: glam::Vec3,
    what: &str,
    hint: &str,
) -> CliError {
    let v = |p: glam::Vec3| format!("[{:e}, {:e}, {:e}]", p.x, p.y, p.z);
    CliError::Other(format!(
        "{scene_arg}: the scene's bounds ({} to {}) are too large for {what} in f32; {hint}",
        v(lo),
        v(hi)
    ))
}
