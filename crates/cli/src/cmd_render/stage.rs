//! What `render` and `view` share: the flags that name and stage the scene ([`SceneArgs`]), and
//! what they add to it: lights, camera, ground.

use super::{parse_light, Args, GroundArg, PipelineArg};
use shadowvol::CliError;
use shadowvol_robust_math::{Accuracy, Light};
use std::path::PathBuf;

/// The flags `render` and `view` share: the scene, its lights and ground, the accuracy mode and
/// where silhouettes are built.
#[derive(Debug, clap::Args)]
pub(crate) struct SceneArgs {
    /// The scene: a preset name (see `shadowvol scenes`) or a .gltf/.glb/.obj/.stl/.ply file
    /// (`shadowvol --help` lists what each format reads).
    #[arg(value_name = "SCENE")]
    pub(crate) scene: String,

    /// A light as homogeneous X,Y,Z,W (w = 1 point, w = 0 directional towards (X,Y,Z)); repeat
    /// for several. Replaces the scene's own lights; without any light anywhere, a default key
    /// light is placed from the scene's bounds.
    #[arg(
        long = "light",
        value_name = "X,Y,Z,W",
        allow_hyphen_values = true,
        value_parser = parse_light
    )]
    pub(crate) lights: Vec<Light>,

    #[command(flatten)]
    pub(crate) light_size: shadowvol::LightSizeArgs,

    /// A receiver plane under the scene: auto (under files with nothing below their casters),
    /// on or off.
    #[arg(long, value_enum, default_value_t = GroundArg::Auto)]
    pub(crate) ground: GroundArg,

    /// Accuracy mode of silhouettes and caps (`view`: at start; keys 1-4 switch it).
    #[arg(long, value_parser = shadowvol::mode_parser(), default_value = "exact")]
    pub(crate) mode: Accuracy,

    /// Silhouette backend of the host pipeline (see `shadowvol backends`), or `auto`: the first
    /// backend on a hardware GPU, else `simd`, with a warning naming what was skipped. Giving it
    /// selects the host pipeline [default with --pipeline host: cpu].
    #[arg(long, value_name = "NAME")]
    pub(crate) backend: Option<String>,

    /// gpu: extraction, sides and caps on the renderer's device, nothing read back during a
    /// frame; host: the backend's multiplicities come to the host, which builds the volumes
    /// [default: gpu where the adapter supports it and no --backend is given, else host]. In
    /// `view`, showing the volumes (V, --volumes) uses the host pipeline.
    #[arg(long, value_enum, value_name = "gpu|host")]
    pub(crate) pipeline: Option<PipelineArg>,

    /// What draws the shadows: `volumes` (the pipeline --pipeline picks) or `map`, shadow maps
    /// on the renderer's device, Bevy 0.20's defaults unless the --map-* flags say otherwise: a
    /// fitted orthographic map per directional light, a perspective map per spot light, a cube
    /// map per point light (`view`: key M switches).
    #[arg(long, value_enum, default_value_t = ShadowsArg::Volumes)]
    pub(crate) shadows: ShadowsArg,

    /// --shadows map: the side of every map and cube face in texels, 1 to the device's texture
    /// limit [default: Bevy's, 2048 for directional and spot lights, 1024 for point lights].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub(crate) map_size: Option<u32>,

    /// --shadows map: how maps are read: `hard` (one hardware comparison), `pcf` (3x3 bilinear
    /// comparisons, the soft edge of Bevy's default filter) or `pcss` (percentage-closer soft
    /// shadows as Bevy 0.20's experimental_pbr_pcss: a blocker search over a region the size of
    /// the light (--light-radius), then 8 bilinear comparisons over a kernel sized from the mean
    /// blocker depth; a light of radius 0 is read with pcf, as Bevy does).
    #[arg(long, value_enum, default_value_t = MapFilterArg::Pcf)]
    pub(crate) map_filter: MapFilterArg,

    /// --shadows map: the bias of every map, DEPTH,SLOPE,NORMAL: world units towards the light,
    /// the map pass's slope-scaled depth bias, texels along the normal [default: Bevy's,
    /// 0.02,0,1.8 for directional and spot lights, 0.08,0,0.6 for point lights].
    #[arg(long, value_name = "DEPTH,SLOPE,NORMAL", allow_hyphen_values = true)]
    pub(crate) map_bias: Option<shadowvol_renderer::MapBias>,

    /// --shadows map: cascades of each directional light's map, 1 to 4, each --map-size texels
    /// over a slice of the view (1: one map fitted to the whole view; Bevy ships 4).
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=4))]
    pub(crate) map_cascades: u32,
}

/// `--shadows`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum ShadowsArg {
    /// Stencil shadow volumes (--pipeline gpu or host).
    #[default]
    Volumes,
    /// Shadow maps (the map pipeline).
    Map,
}

/// `--map-filter`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum MapFilterArg {
    /// One hardware depth comparison per lookup.
    Hard,
    /// Percentage-closer filtering over 3x3 bilinear comparisons.
    #[default]
    Pcf,
    /// Percentage-closer soft shadows (Bevy's PCSS), sized by each light's radius.
    Pcss,
}

impl SceneArgs {
    /// The pipeline the flags ask for: `Some(true)` for the host one (`--pipeline host`, or any
    /// `--backend`), `Some(false)` for `--pipeline gpu`, `None` to let the device decide.
    ///
    /// # Errors
    /// [`CliError::Other`] for `--backend` with `--pipeline gpu`.
    pub(crate) fn wants_host(&self) -> Result<Option<bool>, CliError> {
        match (self.pipeline, &self.backend) {
            (Some(PipelineArg::Gpu), Some(b)) => Err(CliError::Other(format!(
                "--backend {b} selects the host pipeline; it cannot be combined with --pipeline gpu \
                 (the GPU pipeline runs the wgpu kernels on the renderer's device)"
            ))),
            _ if self.shadows == ShadowsArg::Map
                && (self.pipeline.is_some() || self.backend.is_some()) =>
            {
                Err(CliError::Other(
                    "--shadows map draws shadow maps with the map pipeline on the renderer's \
                     device; leave out --pipeline and --backend, which choose a volume pipeline"
                        .to_owned(),
                ))
            }
            (Some(PipelineArg::Gpu), None) => Ok(Some(false)),
            (Some(PipelineArg::Host), _) | (None, Some(_)) => Ok(Some(true)),
            (None, None) => Ok(None),
        }
    }

    /// The shadow-map settings of the --map-* flags (with a warning when they are given without
    /// --shadows map, where nothing reads them).
    pub(crate) fn map_settings(&self) -> shadowvol_renderer::MapSettings {
        let map_flags = self.map_size.is_some()
            || self.map_bias.is_some()
            || self.map_cascades != 1
            || self.map_filter != MapFilterArg::Pcf;
        if self.shadows != ShadowsArg::Map && map_flags {
            eprintln!(
                "warning: --map-size, --map-filter, --map-bias and --map-cascades apply to \
                 --shadows map only"
            );
        }
        shadowvol_renderer::MapSettings {
            size: self.map_size,
            filter: match self.map_filter {
                MapFilterArg::Hard => shadowvol_renderer::MapFilter::Hard,
                MapFilterArg::Pcf => shadowvol_renderer::MapFilter::Pcf,
                MapFilterArg::Pcss => shadowvol_renderer::MapFilter::Pcss,
            },
            bias: self.map_bias,
            cascades: self.map_cascades,
        }
    }

    /// The pipeline these flags ask for on `device`: the map pipeline with --shadows map, else
    /// the volume pipeline of [`SceneArgs::wants_host`] (see [`super::pipeline`]).
    ///
    /// # Errors
    /// As [`SceneArgs::wants_host`] and [`super::pipeline`].
    pub(crate) fn pipeline(
        &self,
        device: &shadowvol_renderer::RenderDevice,
    ) -> Result<Box<dyn shadowvol_renderer::ShadowPipeline>, CliError> {
        let wants_host = self.wants_host()?;
        let settings = self.map_settings();
        if self.shadows == ShadowsArg::Map {
            return Ok(Box::new(shadowvol_renderer::MapPipeline::new(settings)));
        }
        super::pipeline(wants_host, self.backend.as_deref(), device)
    }

    /// Loads the scene, prints its loader's notes on stderr and [`stage`]s it with the flags.
    ///
    /// # Errors
    /// The loader's error, or [`stage`]'s.
    pub(crate) fn load(
        &self,
    ) -> Result<(shadowvol_scenes::Scene, LightsSource, Option<Ground>), CliError> {
        let (mut scene, notes) = shadowvol::load_scene(&self.scene)?;
        for n in &notes {
            eprintln!("note: {n}");
        }
        let (lights_source, ground) = stage(&mut scene, &self.scene, &self.lights, self.ground)?;
        self.light_size.apply(&mut scene)?;
        if self.shadows == ShadowsArg::Map
            && self.map_filter == MapFilterArg::Pcss
            && scene.lights.iter().all(|l| l.radius == 0.0)
        {
            eprintln!(
                "note: --map-filter pcss: every light has radius 0, so every map is read with pcf \
                 (as Bevy reads a light without a soft shadow size); give --light-radius"
            );
        }
        Ok((scene, lights_source, ground))
    }
}

pub(crate) use shadowvol_report::{Ground, LightsSource};

/// Chooses the lights and the ground of `scene` from the flags: `--light` replaces the scene's
/// lights, a scene without any gets [`shadowvol_scenes::Scene::key_light`] seen from its camera
/// (or the default framing), which becomes the scene's camera; `--ground` sets the ground
/// receiver ([`shadowvol_scenes::Scene::set_ground`]).
fn stage(
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
    let own = scene.ground_y().map(|y| Ground {
        y,
        source: "scene".to_owned(),
    });
    let ground = match ground {
        GroundArg::Off => None,
        GroundArg::On => own.or_else(|| {
            scene.ground_y_below().map(|y| Ground {
                y,
                source: "flags".to_owned(),
            })
        }),
        GroundArg::Auto if shadowvol_scenes::is_preset(scene_arg) => own,
        GroundArg::Auto => own.or_else(|| {
            scene.auto_ground_y().map(|y| Ground {
                y,
                source: "auto".to_owned(),
            })
        }),
    };
    scene.set_ground(ground.as_ref().map(|g| g.y));
    Ok((lights_source, ground))
}

/// `--out`, or SCENE's file stem (a preset's name) + `.png` in the current directory.
pub(super) fn out_path(args: &Args) -> PathBuf {
    args.out.clone().unwrap_or_else(|| {
        let stem = std::path::Path::new(&args.input.scene)
            .file_stem()
            .map_or_else(|| "render".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{stem}.png"))
    })
}
