//! A rendered frame as the exact reference reads it. The renderer and its judge share no code,
//! so the frame is handed over here, once: `render --reference` uses it, and the renderer's
//! tests and examples, the CLI's tests and the Bevy plugin's tests include this file.

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
    Ok(shadowvol_reference::Shot::new(
        scene,
        frame.camera,
        img.width,
        img.height,
        &img.rgba,
        &img.ids,
        &img.stencil,
        &frame.report.light_colors,
    ))
}
