//! Opening a scene: the file loaders chosen by extension, and presets by name.

use crate::scene::{file_name, Scene};
use crate::SceneError;
use std::path::Path;

impl Scene {
    /// Loads a scene file: `.gltf` or `.glb` (objects, lights, camera), or `.obj`, `.stl`,
    /// `.ply` (one object, identity transform, no lights or camera). Extensions are
    /// case-insensitive.
    ///
    /// # Errors
    /// [`SceneError::UnsupportedFormat`] for another extension, otherwise any error of the
    /// loader, naming the file and what in it is wrong.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        Self::load_with_notes(path).map(|(s, _)| s)
    }

    /// As [`Scene::load`], and also returns notes about what the loader skipped (glTF
    /// primitives that are not triangles or have no positions; OBJ lines, points, curves and
    /// surfaces; none for STL and PLY).
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn load_with_notes(path: impl AsRef<Path>) -> Result<(Self, Vec<String>), SceneError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("gltf" | "glb") => crate::gltf_load::load_gltf_with_notes(path),
            Some("stl") => {
                // Welded as it is read: the file's table, without the file or its soup.
                let table = crate::stl::load_stl_table(path)?;
                let name = file_name(path);
                let mut scene = Self::new(name.clone());
                scene.add_object(name, std::sync::Arc::new(table), glam::Affine3A::IDENTITY);
                Ok((scene, Vec::new()))
            }
            Some(ext @ ("obj" | "ply")) => {
                let (mesh, notes) = match ext {
                    "obj" => crate::obj::load_obj_with_notes(path)?,
                    _ => (crate::ply::load_ply(path)?, Vec::new()),
                };
                let name = file_name(path);
                // The table names the file alone: the loader's own errors already did. The
                // mesh is freed as its table is built.
                let scene = Self::single_owned(name, mesh).map_err(|e| match e {
                    SceneError::Mesh { source, .. } => SceneError::Mesh {
                        what: path.display().to_string(),
                        source,
                    },
                    e => e,
                })?;
                Ok((scene, notes))
            }
            _ => Err(SceneError::UnsupportedFormat {
                path: path.display().to_string(),
            }),
        }
    }

    /// A preset if `s` is a preset name (see [`crate::preset_names`]), otherwise a file path
    /// loaded with [`Scene::load`].
    ///
    /// # Errors
    /// As [`Scene::load`]; for a string that is neither a preset nor has a known extension,
    /// [`SceneError::UnknownPreset`] listing the preset names.
    pub fn from_name_or_path(s: &str) -> Result<Self, SceneError> {
        Self::from_name_or_path_with_notes(s).map(|(s, _)| s)
    }

    /// As [`Scene::from_name_or_path`], and also returns the loader's notes (see
    /// [`Scene::load_with_notes`]; none for a preset).
    ///
    /// # Errors
    /// As [`Scene::from_name_or_path`].
    pub fn from_name_or_path_with_notes(s: &str) -> Result<(Self, Vec<String>), SceneError> {
        if crate::presets::is_preset(s) {
            return crate::preset(s).map(|p| (p, Vec::new()));
        }
        // `load_with_notes` refuses an unknown extension before reading anything.
        match Self::load_with_notes(s) {
            Err(SceneError::UnsupportedFormat { .. }) => crate::preset(s).map(|p| (p, Vec::new())),
            loaded => loaded,
        }
    }
}
