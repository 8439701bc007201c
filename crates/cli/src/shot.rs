//! A rendered frame as the exact reference reads it. The renderer and its judge share no code,
//! so the frame is handed over here, once: `render --reference` uses it, and the renderer's
//! tests and examples, the CLI's tests and the Bevy plugin's tests include this file.

// Each includer uses part of it.
#![allow(dead_code)]

use shadowvol_renderer::{Frame, RenderError, Scene};

/// `frame`, a render of `scene`, as the reference reads it: the camera, the image with its ids
/// and stencil, and the lights' gains.
///
/// # Errors
/// [`RenderError::InvalidInput`] for a frame drawn into the caller's view (no image).
pub fn shot<'a>(
    frame: &'a Frame,
    scene: &'a Scene,
) -> Result<shadowvol_reference::Shot<'a>, RenderError> {
    let img = frame.read_image()?;
    shot_with(frame, scene, &img.stencil, &frame.report.light_colors)
}

/// `frame` as the reference reads it, drawn from `scene`'s lights with `stencil` and
/// `light_colors` (one each per light of `scene`) instead of the frame's own.
///
/// # Errors
/// [`RenderError::InvalidInput`] for a frame drawn into the caller's view (no image).
pub fn shot_with<'a>(
    frame: &'a Frame,
    scene: &'a Scene,
    stencil: &'a [Vec<u8>],
    light_colors: &'a [[f32; 3]],
) -> Result<shadowvol_reference::Shot<'a>, RenderError> {
    let img = frame.read_image()?;
    Ok(shadowvol_reference::Shot::new(
        scene,
        frame.camera,
        img.width,
        img.height,
        &img.rgba,
        &img.ids,
        stencil,
        light_colors,
    ))
}

/// What a frame with lights of several samples drew as hard lights, for the reference's exact
/// check of each sample's shadow: every sample as a point light (and the lights of one sample
/// as themselves), with the stencil each left and its colour.
pub struct HardLights {
    /// The scene with those lights.
    pub scene: Scene,
    /// Per light of `scene`: its stencil (0 = lit).
    pub stencil: Vec<Vec<u8>>,
    /// Per light of `scene`: its colour (its scene light's).
    pub colors: Vec<[f32; 3]>,
    /// Per light of `scene`: the scene light it belongs to and its sample index (0 for a light
    /// of one sample).
    pub owner: Vec<(usize, u32)>,
}

/// The hard lights of `frame` ([`HardLights`]); `None` when no light had several samples or
/// nothing was read back.
#[must_use]
pub fn hard_lights(frame: &Frame) -> Option<HardLights> {
    use shadowvol_renderer::soft::LightPass;
    let e = frame.samples.as_ref()?;
    let img = frame.image.as_ref()?;
    let mut scene = e.scene.clone();
    let mut lights = Vec::new();
    let mut stencil = Vec::new();
    let mut colors = Vec::new();
    let mut owner = Vec::new();
    for (li, pass) in e.passes.iter().enumerate() {
        let (light, index) = match *pass {
            LightPass::Hard => (e.of[li], 0),
            LightPass::Sample { light, index, .. } => (light, index),
            LightPass::Composite { .. } => continue,
        };
        lights.push(e.scene.lights[li]);
        stencil.push(img.stencil.get(li)?.clone());
        colors.push(*frame.report.light_colors.get(light)?);
        owner.push((light, index));
    }
    scene.lights = lights;
    Some(HardLights {
        scene,
        stencil,
        colors,
        owner,
    })
}

/// `frame` as the reference reads it with `hard`'s lights ([`hard_lights`]) instead of the
/// scene's.
///
/// # Errors
/// [`RenderError::InvalidInput`] for a frame drawn into the caller's view (no image).
pub fn hard_shot<'a>(
    frame: &'a Frame,
    hard: &'a HardLights,
) -> Result<shadowvol_reference::Shot<'a>, RenderError> {
    shot_with(frame, &hard.scene, &hard.stencil, &hard.colors)
}
