//! What every pipeline draws with: the surface vertex and light uniform layouts, the render
//! states and pipeline descriptors, the frame's attachments and their readback, and the bounded
//! waits every GPU read goes through. Shared code below the pipelines: the host and GPU
//! pipelines (and the resident pass) build on it, and neither imports the other.

/// `shaders/render_raster.wgsl`: the raster shaders every pipeline builds on (fragment shaders
/// and the uniforms they share).
pub const RASTER_WGSL: &str = include_str!("../../../../shaders/render_raster.wgsl");

pub(crate) mod pipelines;
pub(crate) mod soft;
pub(crate) mod states;
mod stencil_bits;
mod targets;

pub use soft::{SOFT_WGSL, VISIBILITY_FORMAT};
pub use stencil_bits::STENCIL_BITS_WGSL;
pub(crate) use targets::{finish_uploads, map_read, wait, FrameTargets};
pub use targets::{read_texture, Attachments};

use bytemuck::{Pod, Zeroable};
use shadowvol_scenes::Emission;

/// The colour format of every frame (linear RGBA8).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The format of the per-pixel surface ids, `[surface + 1, triangle]`.
pub const IDS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;

/// Byte stride of the per-light uniforms (dynamic offsets).
pub(crate) const LIGHT_STRIDE: u64 = 256;

/// The clear colour behind the scene.
pub(crate) const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.02,
    g: 0.02,
    b: 0.04,
    a: 1.0,
};

/// Vertex of the visible surfaces (non-indexed; flat triangle data repeated on its 3 vertices).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct SurfaceVertex {
    /// Camera-relative world position, `w = 1`.
    pub pos: [f32; 4],
    /// Geometric normal of the triangle in canonical order (`w` unused).
    pub normal: [f32; 4],
    /// Albedo (`a` unused).
    pub albedo: [f32; 4],
    /// `[surface + 1, triangle index within the surface]`.
    pub ids: [u32; 2],
    /// Padding.
    pub pad: [u32; 2],
}

/// Appends surface `index`'s triangles (of `table`, at world `positions`) to `out`, in
/// canonical vertex order (ascending ids, the sign convention's), relative to `origin`, with the
/// flat normal, `albedo` and ids `[index + 1, triangle]`: what every pipeline's pre-pass and lit
/// pass draw.
pub(crate) fn push_surface(
    out: &mut Vec<SurfaceVertex>,
    index: usize,
    table: &shadowvol_mesh_topology::EdgeTable,
    positions: &[glam::Vec3],
    albedo: [f32; 3],
    origin: glam::Vec3,
) {
    let all = 0..table.triangles.len();
    push_triangles(out, index, table, all, positions, albedo, origin);
}

/// [`push_surface`] for the triangles `triangles` of the surface only (their ids stay those
/// within the surface): a surface written in blocks.
pub(crate) fn push_triangles(
    out: &mut Vec<SurfaceVertex>,
    index: usize,
    table: &shadowvol_mesh_topology::EdgeTable,
    triangles: std::ops::Range<usize>,
    positions: &[glam::Vec3],
    albedo: [f32; 3],
    origin: glam::Vec3,
) {
    out.reserve(3 * triangles.len());
    let first = triangles.start;
    for (k, t) in table.triangles[triangles].iter().enumerate() {
        let ti = first + k;
        let mut k = *t;
        k.sort_unstable();
        let p = k.map(|k| positions[k as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        for v in p {
            let v = v - origin;
            out.push(SurfaceVertex {
                pos: [v.x, v.y, v.z, 1.0],
                normal: [n.x, n.y, n.z, 0.0],
                albedo: [albedo[0], albedo[1], albedo[2], 1.0],
                ids: [index as u32 + 1, ti as u32],
                pad: [0; 2],
            });
        }
    }
}

/// A vertex buffer holding `contents` (with `usage` besides `VERTEX`), or
/// [`RenderError::TooLarge`](crate::RenderError::TooLarge) naming its size and the
/// device's `max_buffer_size` when it is larger: wgpu would otherwise fail to map it at creation
/// and panic.
pub(crate) fn vertex_buffer(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, crate::RenderError> {
    use wgpu::util::DeviceExt;
    let max = device.limits().max_buffer_size;
    if contents.len() as u64 > max {
        return Err(crate::RenderError::TooLarge(format!(
            "the {label} vertex buffer takes {} bytes; the device allows buffers of at most {max} (max_buffer_size)",
            contents.len()
        )));
    }
    Ok(
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::VERTEX | usage,
        }),
    )
}

/// `light` (homogeneous) relative to `origin`: a point light's position minus `origin` (in
/// homogeneous form, `xyz - w origin`), a directional light unchanged. The one conversion
/// every pipeline applies to draw camera-relative.
#[must_use]
pub(crate) fn relative_light(light: [f32; 4], origin: glam::Vec3) -> [f32; 4] {
    let [x, y, z, w] = light;
    [x - origin.x * w, y - origin.y * w, z - origin.z * w, w]
}

/// Whether `scissor` is a rectangle without pixels, where a light's passes draw nothing.
#[must_use]
pub(crate) fn empty_scissor(scissor: Option<[u32; 4]>) -> bool {
    scissor.is_some_and(|r| r[2] == 0 || r[3] == 0)
}

/// The shader's `LightU` for a light at `light` (camera-relative, homogeneous) of linear
/// `color` (times gain): position, colour, then `emit = (inverse square 0/1, 1 / range or 0,
/// cone scale, cone offset)` and `spot = (axis, 1 for a cone)` (see `fs_lit`). A unit light
/// (`emission` `None`) and a directional light have no falloff.
#[must_use]
pub fn light_uniform(light: [f32; 4], color: [f32; 3], emission: Option<&Emission>) -> [f32; 16] {
    let mut v = [0f32; 16];
    v[..4].copy_from_slice(&light);
    v[4..7].copy_from_slice(&color);
    v[7] = 1.0;
    if let (Some(e), true) = (emission, light[3] != 0.0) {
        v[8] = 1.0;
        v[9] = e.range.map_or(0.0, |r| 1.0 / r);
        if let Some(s) = e.spot {
            let (scale, offset) = s.scale_offset();
            v[10] = scale;
            v[11] = offset;
            v[12..15].copy_from_slice(&s.direction.normalize().to_array());
            v[15] = 1.0;
        }
    }
    v
}

/// A `w` x `h` 2-D texture with one mip level and one sample: an attachment a pipeline draws
/// into, or any other 2-D target of the application.
#[must_use]
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}
