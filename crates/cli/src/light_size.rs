//! `--light-radius` and `--light-samples`: the size of every light and how many points sample
//! it, shared by `render`, `view`, `silhouette` and `bench`.

use crate::CliError;
use glam::Vec3;
use shadowvol_robust_math::Light;
use shadowvol_scenes::{Scene, SceneLight};

/// The flags that give lights a size (soft shadows). Flatten it into a subcommand's arguments.
#[derive(Debug, Clone, Copy, Default, PartialEq, clap::Args)]
pub struct LightSizeArgs {
    /// Every light's size: the radius of a disk in world units for point and spot lights (facing
    /// the scene's bounding-box centre; a spot light's along its axis), an angular radius in
    /// radians for directional lights (the sun is about 0.0047). 0 is a point light with hard
    /// shadows. Replaces the scene's own sizes; a glTF light gives its own in `extras.radius`,
    /// since KHR_lights_punctual has no size field [default: the scene's, else 0].
    #[arg(long, value_name = "R", allow_hyphen_values = true)]
    pub light_radius: Option<f32>,

    /// Points sampling each light with a size: each draws an exact hard shadow and a pixel's
    /// visibility is the share of samples it sees [default: the plan's choice, from the width of
    /// the light's widest penumbra on screen: 1 under a pixel, at most 64].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub light_samples: Option<u32>,
}

impl LightSizeArgs {
    /// Sets every light's radius of `scene` to `--light-radius` when given.
    ///
    /// # Errors
    /// [`CliError::Usage`] for a radius that is negative, not finite, or (directional) not under
    /// π/2, naming the light.
    pub fn apply(&self, scene: &mut Scene) -> Result<(), CliError> {
        if let Some(r) = self.light_radius {
            scene
                .set_light_radius(r)
                .map_err(|e| CliError::Usage(format!("--light-radius {r}: {e}")))?;
        }
        Ok(())
    }
}

/// `--light-samples` where no plan chooses it (`silhouette`, `bench`: they have no camera to
/// measure a penumbra with).
pub const DEFAULT_SAMPLES: u32 = 16;

/// The lights of a call with every light of a size replaced by its samples
/// ([`LightSizeArgs::sampled`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SampledLights {
    /// Each original light's samples, in order (a light of radius 0: the light itself).
    pub lights: Vec<Light>,
    /// Per original light, its radius (world units, radians for a directional light).
    pub radii: Vec<f32>,
    /// Per original light, how many entries of `lights` are its samples.
    pub samples: Vec<u32>,
}

impl SampledLights {
    /// True when some light was replaced by more than one sample.
    #[must_use]
    pub fn is_sampled(&self) -> bool {
        self.samples.iter().any(|&n| n > 1)
    }
}

impl LightSizeArgs {
    /// `lights` with each one of a size replaced by its samples on its disk aimed at `aim`
    /// ([`SceneLight::samples`]): the radius is `--light-radius` when given, else the light's
    /// own (`own_radii[i]`, 0 where missing); the count is `--light-samples` when given, else
    /// `default_samples`. A light of radius 0 stays one point light.
    ///
    /// # Errors
    /// [`CliError::Usage`] for a radius that is negative, not finite, or (directional) not under
    /// π/2, naming the light.
    pub fn sampled(
        &self,
        lights: &[Light],
        own_radii: &[f32],
        aim: Vec3,
        default_samples: u32,
    ) -> Result<SampledLights, CliError> {
        let n = self.light_samples.unwrap_or(default_samples).max(1);
        let mut scene = Scene::new("lights");
        scene.lights = lights
            .iter()
            .enumerate()
            .map(|(i, &l)| {
                let mut sl = SceneLight::unit(l);
                sl.radius = own_radii.get(i).copied().unwrap_or(0.0);
                sl
            })
            .collect();
        self.apply(&mut scene)?;
        let mut out = SampledLights {
            lights: Vec::new(),
            radii: Vec::new(),
            samples: Vec::new(),
        };
        for l in &scene.lights {
            let s = l.samples(n, aim);
            out.radii.push(l.radius);
            out.samples.push(s.len() as u32);
            out.lights.extend(s);
        }
        Ok(out)
    }
}
