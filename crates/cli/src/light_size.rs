//! `--light-radius` and `--light-samples`: the size of every light and how many points sample
//! it, shared by `render`, `view`, `silhouette` and `bench`.

use crate::CliError;
use shadowvol_scenes::Scene;

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
