//! Turning a command-line mesh argument into a mesh: the one entry point for every subcommand.

use crate::CliError;
use shadowvol_mesh_topology::Mesh;
use shadowvol_robust_math::Light;
use shadowvol_scenes::Scene;

/// A loaded input: one mesh (object transforms already applied in `f32` on the host) and the
/// lights the input itself defines, if any.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// How to name the input in messages and reports (the path or preset name as given).
    pub name: String,
    /// The mesh, in world space: all objects baked into one, vertices numbered object by object
    /// (for glTF: depth-first node order, then primitive order, then accessor order).
    pub mesh: Mesh,
    /// Lights defined by the input (glTF `KHR_lights_punctual`, preset lights; none for OBJ).
    /// Used when no `--light` is given.
    pub lights: Vec<Light>,
    /// What the loader skipped, one sentence each naming the file and element (glTF primitives
    /// that are not triangles or have no positions, nodes left without triangles); empty for
    /// the other formats and presets.
    pub notes: Vec<String>,
}

/// The input formats every subcommand accepts, for `--help`.
pub const INPUT_FORMATS: &str = "Input formats (by extension, case-insensitive): .gltf/.glb \
    (glTF 2.0: node transforms, KHR_lights_punctual, cameras, KHR_mesh_quantization, \
    EXT_meshopt_compression, KHR_draco_mesh_compression, sparse accessors; points and lines are \
    skipped with a note), .obj \
    (v and f; polygons fanned), .stl (ASCII or binary; a triangle soup, welded by exact \
    position), .ply (ASCII or binary little/big-endian; vertex x, y, z and face vertex_indices, \
    polygons fanned, other properties ignored), or a preset name (`shadowvol scenes`).";

/// Loads `path_or_name`: a `.obj`, `.gltf`, `.glb`, `.stl` or `.ply` file (case-insensitive
/// extension) or a scene preset name (`shadowvol scenes` lists them), through
/// [`Scene::from_name_or_path_with_notes`]. Several objects are baked into one world-space mesh with
/// [`Scene::baked_mesh`] (transforms applied in `f32` on the host).
///
/// # Errors
/// [`CliError::Scene`] for an unreadable or malformed file (naming the file and the line,
/// accessor or vertex), an unsupported extension, or an unknown preset name;
/// [`CliError::Other`] for an input without triangles (an empty or garbage file).
pub fn load_input(path_or_name: &str) -> Result<Input, CliError> {
    let (scene, notes) = Scene::from_name_or_path_with_notes(path_or_name)?;
    let mesh = scene.baked_mesh()?;
    if mesh.triangles.is_empty() {
        let skipped = if notes.is_empty() {
            String::new()
        } else {
            format!(" ({})", notes.join("; "))
        };
        return Err(CliError::Other(format!(
            "{path_or_name}: no triangles found, nothing can cast a shadow{}{skipped}",
            not_text_hint(path_or_name)
        )));
    }
    Ok(Input {
        name: path_or_name.to_owned(),
        mesh,
        lights: scene.lights.clone(),
        notes,
    })
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
