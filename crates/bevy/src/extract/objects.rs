//! Which of the scene's objects the frame draws and casts with, from Bevy's visibility, render
//! layers and transforms.

use super::*;

/// Per object of the current scene: its transform, whether it is in the pre-pass (into
/// `frame`), and whether it casts and on which render layers (returned). An object whose entity
/// is gone while its rebuild waits, is hidden, is on other layers than the camera or has a
/// singular transform (a zero scale) is neither drawn nor casting.
pub(super) fn object_states(
    frame: &mut VolumeFrame,
    candidates: &[CandidateItem<'_>],
    decision: &Decision,
) -> (Vec<bool>, Vec<RenderLayers>) {
    let layers = decision
        .camera
        .as_ref()
        .map_or_else(RenderLayers::default, |c| c.2.clone());
    let everywhere = RenderLayers::default();
    let by_entity: HashMap<Entity, &CandidateItem<'_>> =
        candidates.iter().map(|c| (c.0, c)).collect();
    let n = frame.objects.len();
    let (mut transforms, mut drawn, mut casts, mut their_layers) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    for e in &frame.objects {
        their_layers.push(
            by_entity
                .get(e)
                .and_then(|c| c.4)
                .unwrap_or(&everywhere)
                .clone(),
        );
        let (t, d, c) = by_entity.get(e).map_or(
            (glam::Affine3A::IDENTITY, false, false),
            |&&(_, _, t, visible, theirs, not_caster, _)| {
                let t = to_affine(t);
                let invertible = t.is_finite() && t.matrix3.determinant() != 0.0;
                let seen = visible.get() && theirs.unwrap_or(&everywhere).intersects(&layers);
                let d = seen && invertible;
                let t = if invertible {
                    t
                } else {
                    glam::Affine3A::IDENTITY
                };
                (t, d, d && !not_caster)
            },
        );
        transforms.push(t);
        drawn.push(d);
        casts.push(c);
    }
    frame.transforms = transforms;
    frame.drawn = drawn;

    (casts, their_layers)
}
