//! What `render` and `view` add to a scene from the flags: lights, camera, ground.

use super::{Args, GroundArg};
use shadowvol::CliError;
use std::path::PathBuf;

/// Where the lights of a render came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum LightsSource {
    /// The scene file or preset.
    File,
    /// `--light`.
    Flags,
    /// The default key light ([`shadowvol_scenes::Scene::key_light`]).
    Default,
}

/// The receiver plane `y = ground_y` and why it is there.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct Ground {
    pub(super) y: f32,
    /// `scene` (the preset declares it), `auto` (nothing lay below the casters) or `flags`
    /// (`--ground on`).
    pub(super) source: &'static str,
}

/// Chooses the lights and the ground of `scene` from the flags: `--light` replaces the scene's
/// lights, a scene without any gets [`shadowvol_scenes::Scene::key_light`] seen from its camera
/// (or the default framing), which becomes the scene's camera; `--ground` sets the ground
/// receiver ([`shadowvol_scenes::Scene::set_ground`]).
pub(crate) fn stage(
    scene: &mut shadowvol_scenes::Scene,
    scene_arg: &str,
    lights: &[shadowvol_robust_math::Light],
    ground: GroundArg,
) -> Result<(LightsSource, Option<Ground>), CliError> {
    let camera = scene.camera_or_default().ok_or_else(|| {
        CliError::Other(format!(
            "{scene_arg}: no vertices, nothing to render or light"
        ))
    })?;
    let too_large = |what: &str| {
        let (lo, hi) = scene.bounds().unwrap_or_default();
        shadowvol::bounds_too_large(scene_arg, lo, hi, what, "scale the model down")
    };
    if camera.validate().is_err() {
        return Err(too_large("a camera that frames them"));
    }
    let lights_source = if !lights.is_empty() {
        scene.lights.clear();
        scene.add_unit_lights(lights.iter().copied());
        LightsSource::Flags
    } else if !scene.lights.is_empty() {
        LightsSource::File
    } else {
        let key = scene
            .key_light(&camera)
            .ok_or_else(|| too_large("the default key light (give --light)"))?;
        scene.add_unit_lights([key]);
        LightsSource::Default
    };
    // The camera the renderer would frame the scene with, made explicit: every command after
    // this one sees the same view.
    scene.camera = Some(camera);
    let own = scene.ground_y().map(|y| Ground { y, source: "scene" });
    let ground = match ground {
        GroundArg::Off => None,
        GroundArg::On => own.or_else(|| {
            scene
                .ground_y_below()
                .map(|y| Ground { y, source: "flags" })
        }),
        GroundArg::Auto if shadowvol_scenes::is_preset(scene_arg) => own,
        GroundArg::Auto => {
            own.or_else(|| scene.auto_ground_y().map(|y| Ground { y, source: "auto" }))
        }
    };
    scene.set_ground(ground.map(|g| g.y));
    Ok((lights_source, ground))
}

/// `--out`, or SCENE's file stem (a preset's name) + `.png` in the current directory.
pub(super) fn out_path(args: &Args) -> PathBuf {
    args.out.clone().unwrap_or_else(|| {
        let stem = std::path::Path::new(&args.scene)
            .file_stem()
            .map_or_else(|| "render".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{stem}.png"))
    })
}
