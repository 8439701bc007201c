//! The GPU-resident shadow-volume pass: extraction, sides and caps on the caller's device, in the
//! caller's command encoder, with nothing read back.
//!
//! Per frame the host writes only small inputs ([`ShadowPass::update`]: camera, lights,
//! transforms, the plan's per-(light, object) technique). [`ShadowPass::encode_extract`] records
//! one compute pass, first of the frame: a vertex pass (every vertex to camera-relative world
//! space, read by every draw, so shared vertices are bit-identical), then:
//! 1. a triangle pass: one sign per (light, triangle) in the accuracy mode, in the triangle's
//!    canonical vertex order; exact mode runs the certified filter of the `wgpu` backend and
//!    marks what it cannot certify as pending, and a second dispatch, sized on the device (no
//!    workgroup when nothing is pending), decides those pairs with exact integer arithmetic on
//!    the `f32` bits (`shaders/exact_int.wgsl`), so no triple goes to the host and the integer
//!    code is not compiled into the triangle pass, where it would slow every triangle;
//! 2. an edge pass: each edge sums the parity-signed signs of its opposite vertices' triangles
//!    into `m` (`original`: the naive per-(edge, opposite vertex) sign, the baseline) and appends
//!    `|m|` side records to the light's z-pass or z-fail list; the list lengths are the instance
//!    counts of indirect draws.
//!
//! Then, per light, [`ShadowPass::encode_stencil`] draws the sides instanced from the records
//! (extruded to `w = 0` in the vertex shader) and the caps of z-fail objects from the same
//! triangle signs, into the caller's depth-stencil attachment (two-sided stencil, wrapping
//! increment and decrement), so sides and caps meet by construction. The caller's lit pass then
//! tests stencil == 0; [`ShadowPass::encode_lit`] is a ready one, and
//! [`ShadowPass::encode_prepass`] the depth pre-pass whose depths the front caps match bit for
//! bit.
//!
//! The shaders are the `wgpu` silhouette backend's module (same bindings, sign functions and
//! filter) with `shaders/resident_extract.wgsl` appended, and the renderer's
//! `shaders/render_raster.wgsl` with `shaders/resident_draw.wgsl` appended. [`twin`] is the CPU
//! port of the new kernels.
//!
//! Every pipeline fits `wgpu::Limits::default()` (WebGPU's 8 storage buffers per stage): the
//! scene's tables and the object of each vertex are one storage buffer
//! ([`shadowvol_gpu::TablePacking`]) with the word offsets in a uniform, shared by the compute
//! passes and the draws. The most storage buffers in one stage is 7 (the pending dispatch's
//! arguments); the side and cap draws bind 6 in the vertex stage.
//!
//! ```no_run
//! # fn main() -> Result<(), shadowvol_renderer::RenderError> {
//! use shadowvol_renderer::resident::{PassFormats, ShadowPass};
//! let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
//! let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
//!     .map_err(|e| shadowvol_renderer::RenderError::NoAdapter(e.to_string()))?;
//! let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
//!     required_features: ShadowPass::optional_features(&adapter),
//!     required_limits: ShadowPass::required_limits(&adapter)?,
//!     ..Default::default()
//! }))
//! .map_err(|e| shadowvol_renderer::RenderError::Device(e.to_string()))?;
//! let formats = PassFormats {
//!     color: wgpu::TextureFormat::Rgba8Unorm,
//!     ids: None,
//!     depth: wgpu::TextureFormat::Depth24PlusStencil8,
//! };
//! let pass = ShadowPass::new(&adapter, &device, &queue, formats)?;
//! # let _ = pass; Ok(()) }
//! ```
//! `examples/embed.rs` renders a whole frame this way.

mod batch;
mod encode;
mod groups;
pub mod layout;
mod pipeline;
mod readback;
mod scene;
pub mod twin;

use batch::FrameBuffers;
pub use groups::NOT_SHARED;
pub use layout::ResidentLayout;

use crate::plan::Technique;
use crate::{Camera, RenderError};
use glam::{Affine3A, DAffine3};
use shadowvol_gpu::shaders;
use shadowvol_robust_math::Accuracy;
use shadowvol_scenes::SceneLight;
use shadowvol_silhouette::gpu::{mode_code, ExactFilter, FIRST_EDGE, FIRST_TRIANGLE};
use shadowvol_silhouette::{object_light, vec_bytes, PreparedBytes};
use wgpu::util::DeviceExt;

/// `shaders/resident_extract.wgsl`: the triangle, edge and reset kernels.
pub const EXTRACT_WGSL: &str = include_str!("../../../../shaders/resident_extract.wgsl");
/// `shaders/resident_draw.wgsl`: the vertex-pulling shaders of the surfaces, sides and caps.
pub const DRAW_WGSL: &str = include_str!("../../../../shaders/resident_draw.wgsl");

/// Threads per workgroup of the triangle and edge passes (the `wgpu` backend's
/// `WORKGROUP_SIZE`, whose module they join).
const WORKGROUP: u32 = shaders::WORKGROUP_SIZE;
/// Byte stride of the per-light uniforms (dynamic offsets).
const LIGHT_STRIDE: u64 = 256;
/// Bytes of one light uniform (`LightU`).
const LIGHT_BYTES: u64 = 96;

/// The compute module: the `wgpu` backend's kernel for `filter`, the integer exact sign, then
/// the resident kernels.
#[must_use]
pub fn extract_source(filter: ExactFilter) -> String {
    let mut s = shaders::module_source_with(filter, true);
    s.push('\n');
    s.push_str(EXTRACT_WGSL);
    s
}

/// The draw module: the renderer's `render_raster.wgsl`, then the resident vertex shaders.
#[must_use]
pub fn draw_source() -> String {
    format!("{}\n{DRAW_WGSL}", crate::raster::RASTER_WGSL)
}

pub use crate::raster::texture_2d;

/// The attachment formats the pass draws into.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PassFormats {
    /// The colour target of the pre-pass and the lit pass.
    pub color: wgpu::TextureFormat,
    /// An optional second pre-pass target receiving `[object + 1, triangle]` (`Rg32Uint`).
    pub ids: Option<wgpu::TextureFormat>,
    /// The depth-stencil attachment (a format with a stencil aspect).
    pub depth: wgpu::TextureFormat,
}

/// One frame's small inputs.
#[derive(Debug, Clone, Copy)]
pub struct PassFrame<'a> {
    /// The camera (positions are drawn relative to its eye).
    pub camera: &'a Camera,
    /// Width / height of the target.
    pub aspect: f32,
    /// World lights, each with its emission.
    pub lights: &'a [SceneLight],
    /// Per light: linear RGB colour times gain of its lit pass.
    pub colors: &'a [[f32; 3]],
    /// Per surface: world from object ([`shadowvol_scenes::Scene::surfaces`] order, as
    /// [`ShadowPass::prepare`] laid them out).
    pub transforms: &'a [Affine3A],
    /// Per surface: albedo.
    pub albedo: &'a [[f32; 3]],
    /// Per (light, object), light-major: the plan's technique.
    pub techniques: &'a [Technique],
    /// Per light: scissor `[x, y, width, height]` of its stencil and lit passes.
    pub scissors: &'a [Option<[u32; 4]>],
    /// Ambient factor of the pre-pass.
    pub ambient: f32,
    /// Accuracy mode of signs and multiplicities.
    pub mode: Accuracy,
    /// Count silhouette edges, side quads and cap triangles per (light, object) (read them with
    /// [`ShadowPass::read_counts`]; costs atomics, so leave it off in timed frames).
    pub count: bool,
    /// Runs of consecutive lights that sample one light with a size (indices into `lights`;
    /// empty: none). In exact mode the pass decides a triangle once for each run of lights with
    /// the same techniques (up to [`MAX_SHARING_GROUP`] lights) when its plane misses their box,
    /// and each edge whose triangles are all so decided once for the run; every light's signs
    /// and records stay exactly its own ([`SharingGroup`]).
    pub sample_groups: &'a [std::ops::Range<usize>],
}

/// Lights per [`SharingGroup`] at most (the edge pass keeps a slot per light of a group in
/// workgroup memory).
pub const MAX_SHARING_GROUP: usize = 64;

/// Consecutive lights `first .. first + count` that the pass extracts together (exact mode):
/// lights of one of [`PassFrame::sample_groups`] with the same techniques for every object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SharingGroup {
    /// The group's first light.
    pub first: usize,
    /// Its number of lights (2 to [`MAX_SHARING_GROUP`]).
    pub count: usize,
}

/// Per-(light, object) counts of one frame, from [`ShadowPass::read_counts`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PassCounts {
    /// `[light * objects + object]`: edges with `m != 0`.
    pub silhouette_edges: Vec<u32>,
    /// `[light * objects + object]`: side quads (`Σ |m|`).
    pub side_quads: Vec<u32>,
    /// `[light * objects + object]`: cap triangles of z-fail objects (`σ ≠ 0`).
    pub cap_triangles: Vec<u32>,
    /// (triangle, light) pairs of exact mode that the filter left to the integer path.
    pub integer_decided: u64,
    /// Per light: z-pass and z-fail side records (the indirect instance counts).
    pub records: Vec<[u32; 2]>,
}

/// Per-(light, object) technique codes of the pass, as uploaded: the edge's or triangle's object
/// is skipped (culled), its sides go to the z-pass list, or to the z-fail list (and it gets
/// caps).
pub mod technique {
    use crate::Technique;

    /// Culled: no sign, no record.
    pub const CULLED: u32 = 0;
    /// Z-pass sides.
    pub const ZPASS: u32 = 1;
    /// Z-fail sides and caps.
    pub const ZFAIL: u32 = 2;

    /// The code of `t`.
    #[must_use]
    pub fn code(t: Technique) -> u32 {
        match t {
            Technique::Culled => CULLED,
            Technique::ZPass => ZPASS,
            Technique::ZFail => ZFAIL,
        }
    }
}

/// The side records of one light, from [`ShadowPass::read_records`]: global edge ids,
/// [`layout::NEGATIVE`] set when `m < 0`, each edge `|m|` times; sorted.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LightRecords {
    /// Records of z-pass objects.
    pub zpass: Vec<u32>,
    /// Records of z-fail objects.
    pub zfail: Vec<u32>,
}

impl LightRecords {
    /// The multiplicity of each of `edges` global edges: the number of its records, negated
    /// for those with [`layout::NEGATIVE`].
    ///
    /// # Panics
    /// Panics if a record names an edge at or past `edges`.
    #[must_use]
    pub fn multiplicities(&self, edges: usize) -> Vec<i32> {
        let mut m = vec![0i32; edges];
        for &x in self.zpass.iter().chain(&self.zfail) {
            let e = (x & !layout::NEGATIVE) as usize;
            m[e] += if x & layout::NEGATIVE != 0 { -1 } else { 1 };
        }
        m
    }
}

/// The pipelines of the pass on one device.
pub struct ShadowPass {
    device: wgpu::Device,
    queue: wgpu::Queue,
    formats: PassFormats,
    filter: ExactFilter,
    depth_clamp: bool,
    timestamps: bool,
    /// The extraction's layouts and compute pipelines.
    extract: pipeline::ExtractPipelines,
    /// The vertex and surface passes.
    world: pipeline::SurfacePipelines,
    /// The render pipelines and their layouts.
    draw: pipeline::DrawPipelines,
    /// Where the lit pass and the pre-pass read the surfaces' vertices.
    surfaces: SurfaceVertices,
}

/// Where the lit pass and the pre-pass read the surfaces' vertices: a vertex buffer the surface
/// pass writes each frame (3 vertices of 56 bytes a triangle: 168 bytes a triangle of device
/// memory, and the fastest draws), or the storage buffers themselves (vertex pulling: no memory
/// of its own, more work per vertex; 3.8 times the frame time of a 10^7-triangle scene on
/// lavapipe). The image is the same either way.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum SurfaceVertices {
    /// The vertex buffer for scenes of at most [`SurfaceVertices::AUTO_MAX_TRIANGLES`]
    /// triangles, vertex pulling beyond (the default).
    #[default]
    Auto,
    /// The vertex buffer wherever the device can hold it.
    Buffer,
    /// Vertex pulling.
    Pull,
}

impl SurfaceVertices {
    /// Triangles up to which [`SurfaceVertices::Auto`] writes the vertex buffer: 2^22, about
    /// 700 MB of surface vertices.
    pub const AUTO_MAX_TRIANGLES: usize = 1 << 22;

    /// The environment variable that sets the choice of the CLI and of [`crate::Renderer`]'s
    /// GPU pipeline: `auto`, `buffer` or `pull`.
    pub const ENV: &'static str = "SHADOWVOL_SURFACE_VERTICES";

    /// The choice `SHADOWVOL_SURFACE_VERTICES` names, [`SurfaceVertices::Auto`] when it is unset.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] naming the variable and the values it takes, for any other
    /// value.
    pub fn from_env() -> Result<Self, RenderError> {
        match std::env::var(Self::ENV).as_deref() {
            Err(_) | Ok("auto") => Ok(Self::Auto),
            Ok("buffer") => Ok(Self::Buffer),
            Ok("pull") => Ok(Self::Pull),
            Ok(other) => Err(RenderError::InvalidInput(format!(
                "{}={other:?}: expected auto, buffer or pull",
                Self::ENV
            ))),
        }
    }

    /// [`SurfaceVertices::Buffer`] or [`SurfaceVertices::Pull`]: what this choice gives a
    /// scene of `tris` triangles.
    #[must_use]
    pub fn resolve(self, tris: usize) -> Self {
        if self.buffer_for(tris) {
            Self::Buffer
        } else {
            Self::Pull
        }
    }

    /// `"buffer"` or `"pulled"`: what this choice gives a scene of `tris` triangles, as the
    /// render JSON's `surface_vertices` names it.
    #[must_use]
    pub fn name_for(self, tris: usize) -> &'static str {
        if self.buffer_for(tris) {
            "buffer"
        } else {
            "pulled"
        }
    }

    /// Whether a scene of `tris` triangles gets the vertex buffer (where the device holds it).
    #[must_use]
    pub fn buffer_for(self, tris: usize) -> bool {
        match self {
            Self::Auto => tris <= Self::AUTO_MAX_TRIANGLES,
            Self::Buffer => true,
            Self::Pull => false,
        }
    }
}

impl std::fmt::Debug for ShadowPass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowPass")
            .field("formats", &self.formats)
            .field("filter", &self.filter)
            .field("depth_clamp", &self.depth_clamp)
            .finish_non_exhaustive()
    }
}

/// The index of `mode`'s pipeline in the per-mode pipeline lists (built in [`Accuracy::ALL`]
/// order, which is the order of the mode codes).
fn mode_index(mode: Accuracy) -> usize {
    mode_code(mode) as usize
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// Which pass a pair of timestamps belongs to.
#[derive(Debug, Clone, Copy)]
enum TimestampSlot {
    Extract,
    Prepass,
    Sides(usize),
    Caps(usize),
    Lit(usize),
}

impl TimestampSlot {
    fn index(self) -> u32 {
        2 * match self {
            TimestampSlot::Extract => 0,
            TimestampSlot::Prepass => 1,
            TimestampSlot::Sides(l) => 2 + 3 * l as u32,
            TimestampSlot::Caps(l) => 3 + 3 * l as u32,
            TimestampSlot::Lit(l) => 4 + 3 * l as u32,
        }
    }
}

fn render_ts(
    fb: &FrameBuffers,
    slot: TimestampSlot,
) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
    fb.queries
        .as_ref()
        .map(|(set, _, _)| wgpu::RenderPassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(slot.index()),
            end_of_pass_write_index: Some(slot.index() + 1),
        })
}

/// What the last [`ShadowPass::update`] set, for the draws.
#[derive(Debug, Clone)]
struct FrameState {
    lights: usize,
    /// The sharing groups of the frame ([`PassFrame::sample_groups`], split).
    groups: Vec<SharingGroup>,
    mode: Accuracy,
    techniques: Vec<Technique>,
    scissors: Vec<Option<[u32; 4]>>,
}

/// A scene uploaded by [`ShadowPass::prepare`], with its per-frame buffers.
pub struct ResidentScene {
    /// Per object, the pixel ids' `[surface, first triangle]` where they are not
    /// `[object, 0]` (a scene drawn in parts); empty: every object is its own surface.
    pub(crate) ids: Vec<[u32; 2]>,
    counts: LayoutCounts,
    /// Per object `(first edge, first triangle, first vertex, first OV slot)`, plus a sentinel.
    bases: Vec<[u32; 4]>,
    /// The extraction's tables, packed as the `wgpu` backend binds them (without the OV vertex
    /// list: this pass's `original` reads each OV through its triangle), with the object of
    /// each global vertex.
    tables: shadowvol_gpu::TableBuffers,
    world: wgpu::Buffer,
    world_out: wgpu::BindGroup,
    /// The indirect arguments of the pending dispatch (`STORAGE | INDIRECT`) and the bind group
    /// through which `resident_pending_args` writes them.
    pending_dispatch: (wgpu::Buffer, wgpu::BindGroup),
    /// The per-frame surface vertex buffer and the bind groups of its chunks with their
    /// triangle counts (`None`: vertex pulling).
    surface: Option<(wgpu::Buffer, Vec<(wgpu::BindGroup, u32)>)>,
    globals: wgpu::Buffer,
    frame: Option<FrameBuffers>,
    state: FrameState,
}

impl ResidentScene {
    /// What the scene holds beyond its edge tables: its per-object bases on the host
    /// (the layout itself is freed once uploaded), and every device buffer (the scene's, the
    /// surface vertices', and those of the last frame's lights).
    #[must_use]
    pub fn bytes(&self) -> PreparedBytes {
        let host = vec_bytes(&self.bases);
        let mut buffers = self.tables.all().to_vec();
        buffers.extend([&self.world, &self.pending_dispatch.0, &self.globals]);
        if let Some((b, _)) = &self.surface {
            buffers.push(b);
        }
        if let Some(f) = &self.frame {
            buffers.extend(f.all());
        }
        PreparedBytes {
            host,
            device: buffers.iter().map(|b| b.size()).sum(),
        }
    }
}

impl std::fmt::Debug for ResidentScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ResidentScene")
            .field("triangles", &self.counts.tris)
            .field("edges", &self.counts.edges)
            .field("objects", &self.counts.objects)
            .finish_non_exhaustive()
    }
}

impl ResidentScene {
    /// Number of global edges uploaded (the stride of the per-edge results).
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.counts.edges
    }

    /// The sharing groups of the last [`ShadowPass::update`] (empty outside exact mode).
    #[must_use]
    pub fn sharing_groups(&self) -> &[SharingGroup] {
        &self.state.groups
    }

    /// How many batches the lights of the last [`ShadowPass::update`] are extracted in: more
    /// than one where their buffers would exceed one storage binding of the device
    /// (`max_storage_buffer_binding_size`); 0 before the first update.
    #[must_use]
    pub fn light_batches(&self) -> usize {
        self.frame.as_ref().map_or(0, |f| {
            f.batches
                .iter()
                .filter(|b| b.lights_of(self.state.lights) > 0)
                .count()
        })
    }

    /// Where the lit pass and the pre-pass read this scene's surface vertices: `"buffer"` (the
    /// surface pass's vertex buffer) or `"pulled"` (vertex pulling; see [`SurfaceVertices`]).
    #[must_use]
    pub fn surface_vertices(&self) -> &'static str {
        if self.surface.is_some() {
            "buffer"
        } else {
            "pulled"
        }
    }
}

/// The sizes of an uploaded [`ResidentLayout`]: all the frames need of it once its arrays are
/// on the device.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LayoutCounts {
    pub objects: usize,
    pub tris: usize,
    pub vertices: usize,
    pub edges: usize,
    /// [`ResidentLayout::capacity`].
    pub capacity: usize,
}

impl LayoutCounts {
    pub(crate) fn of(layout: &ResidentLayout) -> Self {
        Self {
            objects: layout.object_count(),
            tris: layout.tri_count(),
            vertices: layout.vertex_objects.len(),
            edges: layout.tables.edge_count(),
            capacity: layout.capacity(),
        }
    }
}
