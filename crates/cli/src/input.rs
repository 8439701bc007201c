//! Turning a command-line mesh argument into a mesh: the one entry point for every subcommand.

use crate::CliError;
use shadowvol_mesh_topology::Mesh;
use shadowvol_robust_math::Light;
use shadowvol_scenes::obj;
use std::path::Path;

/// A loaded input: one mesh (object transforms already applied in `f32` on the host) and the
/// lights the input itself defines, if any.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// How to name the input in messages and reports (the path or preset name as given).
    pub name: String,
    /// The mesh, in world space.
    pub mesh: Mesh,
    /// Lights defined by the input (none for OBJ). Used when no `--light` is given.
    pub lights: Vec<Light>,
}

/// Loads `path_or_name`: a `.obj` file now (case-insensitive extension).
///
/// glTF files and scene presets are to be added here, so that every subcommand accepts the same
/// inputs.
///
/// # Errors
/// [`CliError::Load`] for an unreadable or malformed file (naming file and line),
/// [`CliError::Other`] for an unsupported or missing extension.
pub fn load_input(path_or_name: &str) -> Result<Input, CliError> {
    let path = Path::new(path_or_name);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => Ok(Input {
            name: path_or_name.to_owned(),
            mesh: obj::load_obj(path)?,
            lights: Vec::new(),
        }),
        Some("gltf" | "glb") => Err(CliError::Other(format!(
            "{path_or_name}: glTF input is not supported by this build yet; convert it to .obj"
        ))),
        _ => Err(CliError::Other(format!(
            "{path_or_name}: unknown mesh format; expected a file ending in .obj, .gltf or .glb"
        ))),
    }
}
