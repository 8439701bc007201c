//! The render states every pipeline shares (the host pipeline's raster, the resident pass), so
//! that they count the stencil and light pixels by the same rules.

/// Surface vertex attributes of [`super::SurfaceVertex`]: position, normal, albedo, ids.
pub(crate) const SURFACE_ATTRS: [wgpu::VertexAttribute; 4] =
    wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4, 2 => Float32x4, 3 => Uint32x2];

/// The vertex buffer layout of [`super::SurfaceVertex`].
pub(crate) fn surface_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<super::SurfaceVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &SURFACE_ATTRS,
    }
}

/// A two-sided stencil face that always passes the stencil test and applies `pass` or
/// `depth_fail`.
pub(crate) fn stencil_face(
    pass: wgpu::StencilOperation,
    depth_fail: wgpu::StencilOperation,
) -> wgpu::StencilFaceState {
    wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: depth_fail,
        pass_op: pass,
    }
}

/// Z-pass volume faces: count the faces in front of the surface (front +1, back -1).
pub(crate) fn zpass_faces() -> (wgpu::StencilFaceState, wgpu::StencilFaceState) {
    use wgpu::StencilOperation::{DecrementWrap, IncrementWrap, Keep};
    (
        stencil_face(IncrementWrap, Keep),
        stencil_face(DecrementWrap, Keep),
    )
}

/// Z-fail volume faces: count the faces behind the surface (back +1, front -1).
pub(crate) fn zfail_faces() -> (wgpu::StencilFaceState, wgpu::StencilFaceState) {
    use wgpu::StencilOperation::{DecrementWrap, IncrementWrap, Keep};
    (
        stencil_face(Keep, DecrementWrap),
        stencil_face(Keep, IncrementWrap),
    )
}

/// The depth pre-pass: depth `less` with writes, stencil untouched.
pub(crate) fn prepass_depth(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: wgpu::StencilState {
            front: wgpu::StencilFaceState::IGNORE,
            back: wgpu::StencilFaceState::IGNORE,
            read_mask: 0xff,
            write_mask: 0,
        },
        bias: wgpu::DepthBiasState::default(),
    }
}

/// A lit pass: depth `equal` (the pre-pass's surface only), stencil `== reference` (0: lit).
pub(crate) fn lit_depth(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    let face = stencil_op(wgpu::CompareFunction::Equal, wgpu::StencilOperation::Keep);
    on_prepass_depth(format, face, 0)
}

/// The shadow-map pipeline's mask pass: depth `equal` (the pre-pass's surface only) without
/// writes; the stencil set to the reference (1) wherever a fragment survives (shadowed).
pub(crate) fn map_mask_depth(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    let face = stencil_op(
        wgpu::CompareFunction::Always,
        wgpu::StencilOperation::Replace,
    );
    on_prepass_depth(format, face, 0xff)
}

/// A stencil face that tests `compare` and applies `pass` where both tests pass.
pub(crate) fn stencil_op(
    compare: wgpu::CompareFunction,
    pass: wgpu::StencilOperation,
) -> wgpu::StencilFaceState {
    wgpu::StencilFaceState {
        compare,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: pass,
    }
}

/// Depth untouched (test `always`, no writes), both stencil faces `face`, reading the stencil
/// bits of `read_mask` and writing those of `write_mask`: a full-screen pass over the stencil.
pub(crate) fn stencil_only_depth(
    format: wgpu::TextureFormat,
    face: wgpu::StencilFaceState,
    read_mask: u32,
    write_mask: u32,
) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: wgpu::StencilState {
            front: face,
            back: face,
            read_mask,
            write_mask,
        },
        bias: wgpu::DepthBiasState::default(),
    }
}

/// Depth `equal` without writes (the pre-pass's surface only), both stencil faces `face`,
/// writing the stencil bits of `write_mask`.
fn on_prepass_depth(
    format: wgpu::TextureFormat,
    face: wgpu::StencilFaceState,
    write_mask: u32,
) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Equal),
        stencil: wgpu::StencilState {
            front: face,
            back: face,
            read_mask: 0xff,
            write_mask,
        },
        bias: wgpu::DepthBiasState::default(),
    }
}

/// The shadow-map pipeline's lit pass: depth `equal` without writes, no stencil test (the map's
/// visibility scales the light in the shader).
pub(crate) fn map_lit_depth(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Equal),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

/// A shadow map's depth pass (reverse-Z): `Depth32Float`, `greater-equal` with writes, and the
/// slope-scaled bias pushing stored depths away from the light by `slope`.
pub(crate) fn map_depth(slope: f32) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: wgpu::TextureFormat::Depth32Float,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState {
            constant: 0,
            slope_scale: -slope,
            clamp: 0.0,
        },
    }
}

/// A shadow-volume draw: depth `less` without writes, two-sided stencil `(front, back)`.
pub(crate) fn volume_depth(
    format: wgpu::TextureFormat,
    (front, back): (wgpu::StencilFaceState, wgpu::StencilFaceState),
) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: wgpu::StencilState {
            front,
            back,
            read_mask: 0xff,
            write_mask: 0xff,
        },
        bias: wgpu::DepthBiasState::default(),
    }
}

/// Additive blending of the lit passes (each light adds its light).
pub(crate) fn additive() -> wgpu::BlendState {
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    wgpu::BlendState {
        color: add,
        alpha: add,
    }
}

/// A colour attachment cleared to `clear` and stored.
pub(crate) fn cleared(
    view: &wgpu::TextureView,
    clear: wgpu::Color,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(clear),
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A colour attachment of `view`, loaded (a later part of the same frame draws over it).
pub(crate) fn loaded(view: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: keep(),
    })
}

/// The pre-pass: the colour attachments `color`, and depth cleared to 1 and stencil to 0 when
/// `clear` (otherwise loaded: a later part of a scene drawn in parts).
pub(crate) fn begin_prepass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: &[Option<wgpu::RenderPassColorAttachment<'_>>],
    depth: &wgpu::TextureView,
    clear: bool,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    let depth = if clear {
        prepass_attachment(
            depth,
            stored(wgpu::LoadOp::Clear(1.0)),
            stored(wgpu::LoadOp::Clear(0)),
        )
    } else {
        prepass_attachment(depth, keep(), keep())
    };
    begin_pass(enc, label, color, depth, None, timestamp_writes)
}

/// `load`, then store.
fn stored<V>(load: wgpu::LoadOp<V>) -> wgpu::Operations<V> {
    wgpu::Operations {
        load,
        store: wgpu::StoreOp::Store,
    }
}

/// The pre-pass's depth-stencil attachment with these operations.
fn prepass_attachment(
    view: &wgpu::TextureView,
    depth: wgpu::Operations<f32>,
    stencil: wgpu::Operations<u32>,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(depth),
        stencil_ops: Some(stencil),
    }
}

/// A stencil pass of one light: no colour, depth loaded (the pre-pass's), the stencil cleared to
/// 0 or loaded as `stencil` says, limited to `scissor` when given.
pub(crate) fn begin_stencil_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    depth: &wgpu::TextureView,
    stencil: wgpu::LoadOp<u32>,
    scissor: Option<[u32; 4]>,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    let depth = wgpu::RenderPassDepthStencilAttachment {
        view: depth,
        depth_ops: Some(keep()),
        stencil_ops: Some(wgpu::Operations {
            load: stencil,
            store: wgpu::StoreOp::Store,
        }),
    };
    begin_pass(enc, label, &[], depth, scissor, timestamp_writes)
}

/// A lit pass of one light: colour, depth and stencil loaded, limited to `scissor` when given.
pub(crate) fn begin_lit_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: &wgpu::TextureView,
    depth: &wgpu::TextureView,
    scissor: Option<[u32; 4]>,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    let color = [Some(wgpu::RenderPassColorAttachment {
        view: color,
        depth_slice: None,
        resolve_target: None,
        ops: keep(),
    })];
    let depth = wgpu::RenderPassDepthStencilAttachment {
        view: depth,
        depth_ops: Some(keep()),
        stencil_ops: Some(keep()),
    };
    begin_pass(enc, label, &color, depth, scissor, timestamp_writes)
}

/// A pass over `color` and `depth`, limited to `scissor` when given.
fn begin_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: &[Option<wgpu::RenderPassColorAttachment<'_>>],
    depth: wgpu::RenderPassDepthStencilAttachment<'_>,
    scissor: Option<[u32; 4]>,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: color,
        depth_stencil_attachment: Some(depth),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    if let Some([x, y, w, h]) = scissor {
        pass.set_scissor_rect(x, y, w, h);
    }
    pass
}

/// Load what the attachment holds and store what the pass draws.
fn keep<V>() -> wgpu::Operations<V> {
    stored(wgpu::LoadOp::Load)
}
