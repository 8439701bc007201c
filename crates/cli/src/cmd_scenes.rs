//! `shadowvol scenes` (list the presets) and `shadowvol scene export NAME OUT.glb`.

use serde::Serialize;
use shadowvol::{CliError, Format};
use shadowvol_scenes::Scene;
use std::io::Write;
use std::path::PathBuf;

/// The long help of `shadowvol scenes`.
pub const LONG_ABOUT: &str =
    "List the scene presets (the paper's scenes and the hard cases of the \
     conformance corpus) with their number of objects, triangles and lights. Every command that \
     takes a scene accepts these names as well as .gltf, .glb, .obj, .stl and .ply files. Presets are \
     generated on request, so listing them builds each once.\n\n\
     JSON: [{\"name\": \"...\", \"objects\": N, \"triangles\": N, \"lights\": N}, ...]";

/// The long help of `shadowvol scene`.
pub const SCENE_LONG_ABOUT: &str = "Work with one scene. `shadowvol scene export NAME OUT.glb` \
     writes a preset (or any .gltf/.glb/.obj/.stl/.ply file) as binary glTF 2.0 that other tools can \
     open: one node per object with its transform, meshes shared between instances, lights as \
     KHR_lights_punctual, and the camera. Loading the file back gives the same objects, lights \
     and silhouettes bit for bit.\n\n\
     JSON (--format json): {\"name\": \"...\", \"path\": \"...\", \"bytes\": N, \"objects\": N, \
     \"triangles\": N, \"lights\": N}";

/// Arguments of `shadowvol scenes`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// Arguments of `shadowvol scene`.
#[derive(Debug, clap::Args)]
pub struct SceneArgs {
    #[command(subcommand)]
    command: SceneCommand,
}

#[derive(Debug, clap::Subcommand)]
enum SceneCommand {
    /// Write a preset (or a .gltf/.glb/.obj file) as binary glTF (.glb).
    Export {
        /// A preset name (see `shadowvol scenes`) or a .gltf, .glb or .obj file.
        name: String,
        /// The .glb file to write.
        out: PathBuf,
        /// Output format of the summary line.
        #[arg(long, value_enum, default_value_t = Format::Text)]
        format: Format,
    },
}

/// One row of `shadowvol scenes --format json` (the contract: these fields, extend only).
#[derive(Debug, Serialize)]
struct Row {
    name: String,
    objects: usize,
    triangles: usize,
    lights: usize,
    #[serde(skip)]
    description: String,
}

/// Runs `shadowvol scenes`.
///
/// # Errors
/// [`CliError::Scene`] if a preset fails to build (never expected), [`CliError::Output`] if
/// writing fails.
pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), CliError> {
    let mut rows = Vec::new();
    for info in shadowvol_scenes::presets() {
        // The largest presets say their size; the others are built and counted.
        let size = match info.size {
            Some(size) => size,
            None => {
                let scene = shadowvol_scenes::preset(&info.name)?;
                shadowvol_scenes::PresetSize {
                    objects: scene.geometry.objects.len(),
                    triangles: scene.triangle_count(),
                    lights: scene.lights.len(),
                }
            }
        };
        rows.push(Row {
            name: info.name,
            objects: size.objects,
            triangles: size.triangles,
            lights: size.lights,
            description: info.description,
        });
    }
    match args.format {
        Format::Json => {
            serde_json::to_writer(&mut *out, &rows).map_err(|e| CliError::Output(e.into()))?;
            writeln!(out)?;
        }
        Format::Text => {
            let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(4);
            writeln!(
                out,
                "{:width$}  {:>7}  {:>9}  {:>6}  description",
                "name", "objects", "triangles", "lights"
            )?;
            for r in &rows {
                writeln!(
                    out,
                    "{:width$}  {:>7}  {:>9}  {:>6}  {}",
                    r.name, r.objects, r.triangles, r.lights, r.description
                )?;
            }
        }
    }
    Ok(())
}

#[derive(Debug, Serialize)]
struct ExportSummary {
    name: String,
    path: String,
    bytes: usize,
    objects: usize,
    triangles: usize,
    lights: usize,
}

/// Runs `shadowvol scene ...`.
///
/// # Errors
/// [`CliError::Usage`] for an output name that is not `.glb`, [`CliError::Scene`] naming the
/// scene or file for anything that fails to load or encode, [`CliError::Other`] naming the
/// output file if it cannot be written.
pub fn run_scene(args: &SceneArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.command {
        SceneCommand::Export {
            name,
            out: path,
            format,
        } => {
            let is_glb = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
            if !is_glb {
                return Err(CliError::Usage(format!(
                    "{}: scene export writes binary glTF; give a file name ending in .glb",
                    path.display()
                )));
            }
            let scene = Scene::from_name_or_path(name)?;
            let bytes = shadowvol_scenes::to_glb(&scene)?;
            std::fs::write(path, &bytes)
                .map_err(|e| CliError::Other(format!("cannot write {}: {e}", path.display())))?;
            let summary = ExportSummary {
                name: name.clone(),
                path: path.display().to_string(),
                bytes: bytes.len(),
                objects: scene.geometry.objects.len(),
                triangles: scene.triangle_count(),
                lights: scene.lights.len(),
            };
            match format {
                Format::Json => {
                    serde_json::to_writer(&mut *out, &summary)
                        .map_err(|e| CliError::Output(e.into()))?;
                    writeln!(out)?;
                }
                Format::Text => writeln!(
                    out,
                    "wrote {} ({} bytes): {} objects, {} triangles, {} lights",
                    summary.path, summary.bytes, summary.objects, summary.triangles, summary.lights
                )?,
            }
            Ok(())
        }
    }
}
