//! The map passes' device resources: the uniform layout of `MapU`, the map textures and their
//! bind group layout, the timestamp queries, and small binding helpers.

use super::fit::{LightMap, MapKind};
use super::MapFilter;
use glam::Vec3;

/// `MapU.mode.x` of a light without a map (nothing casts): visibility 1.
pub(super) const NO_MAP: u32 = 3;

/// The 2-D map and the cube map (one each, reused light after light), with their bind group.
pub(super) struct MapTextures {
    pub(super) size_2d: u32,
    pub(super) size_cube: u32,
    /// The 2-D map's layers as render targets (one per cascade; spot maps use the first).
    pub(super) layers_2d: Vec<wgpu::TextureView>,
    /// The cube's 6 faces as render targets, layer order +X, -X, +Y, -Y, +Z, -Z.
    pub(super) faces: Vec<wgpu::TextureView>,
    /// The maps with the comparison sampler of each filter: `[hard, pcf]`.
    pub(super) bind_groups: [wgpu::BindGroup; 2],
    /// The maps for PCSS ([`pcss_texture_entries`]): PCF's comparison sampler and a bilinear
    /// one for the blocker search.
    pub(super) pcss: wgpu::BindGroup,
}

impl MapTextures {
    /// The bind group that reads the maps with `filter`'s sampler.
    pub(super) fn bind_group(&self, filter: MapFilter) -> &wgpu::BindGroup {
        match filter {
            MapFilter::Hard => &self.bind_groups[0],
            MapFilter::Pcf => &self.bind_groups[1],
            MapFilter::Pcss => &self.pcss,
        }
    }
}

/// The filter a light's map is read with in a frame of `filter`: PCSS reads a light of size 0
/// with PCF, as Bevy reads a light without a soft shadow size with its normal filter.
pub(super) fn light_filter(filter: MapFilter, map: Option<&LightMap>) -> MapFilter {
    match (filter, map) {
        (MapFilter::Pcss, Some(m)) if m.soft_shadow_size > 0.0 => MapFilter::Pcss,
        (MapFilter::Pcss, _) => MapFilter::Pcf,
        (f, _) => f,
    }
}

/// Timestamps: pairs for the pre-pass, then per light its map passes, mask pass and lit pass.
pub(super) struct Queries {
    pub(super) set: wgpu::QuerySet,
    pub(super) resolve: wgpu::Buffer,
    pub(super) read: wgpu::Buffer,
    pub(super) lights: usize,
}

/// `u32`s of one `MapU`.
pub(super) const MAP_WORDS: usize = 140;

/// The `MapU` of a light read with `filter` ([`light_filter`]): face matrices, eye, mode, bias,
/// axis, cascades and PCSS sizes.
pub(super) fn map_uniform(
    map: Option<&LightMap>,
    eye: Vec3,
    filter: MapFilter,
) -> [u32; MAP_WORDS] {
    let mut u = [0u32; MAP_WORDS];
    let f = |x: f32| x.to_bits();
    let (kind, size) = match map {
        Some(m) => {
            for (k, vp) in m.view_proj.iter().enumerate() {
                for (j, x) in vp.to_cols_array().iter().enumerate() {
                    u[16 * k + j] = f(*x);
                }
            }
            let kind = match m.kind {
                MapKind::Directional => 0,
                MapKind::Spot => 1,
                MapKind::Cube => 2,
            };
            (kind, m.size)
        }
        None => (NO_MAP, 1),
    };
    u[96..99].copy_from_slice(&[f(eye.x), f(eye.y), f(eye.z)]);
    u[100] = kind;
    u[101] = match filter {
        MapFilter::Hard => 0,
        MapFilter::Pcf => 1,
        MapFilter::Pcss => 2,
    };
    u[102] = size;
    if let Some(m) = map {
        u[104] = f(m.bias.depth);
        u[105] = f(m.normal_offset);
        u[106] = f(m.near);
        u[108..111].copy_from_slice(&[f(m.axis.x), f(m.axis.y), f(m.axis.z)]);
        u[103] = m.cascades;
        for k in 0..4 {
            u[112 + k] = f(m.cascade_far[k]);
            u[116 + k] = f(m.cascade_offset[k]);
        }
        u[120] = f(m.soft_shadow_size);
        for (k, c) in m.cascade_soft.iter().enumerate() {
            for (j, x) in c.iter().enumerate() {
                u[124 + 4 * k + j] = f(*x);
            }
        }
    }
    u
}

pub(super) fn texture_entries() -> [wgpu::BindGroupLayoutEntry; 3] {
    let fs = wgpu::ShaderStages::FRAGMENT;
    let texture = |binding, view_dimension| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: fs,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Depth,
            view_dimension,
            multisampled: false,
        },
        count: None,
    };
    let sampler = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: fs,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
        count: None,
    };
    [
        texture(0, wgpu::TextureViewDimension::D2Array),
        texture(1, wgpu::TextureViewDimension::Cube),
        sampler(2),
    ]
}

/// [`texture_entries`] and, for the PCSS blocker search, a filtering sampler (binding 3).
pub(super) fn pcss_texture_entries() -> [wgpu::BindGroupLayoutEntry; 4] {
    let [t2, tc, cmp] = texture_entries();
    [
        t2,
        tc,
        cmp,
        wgpu::BindGroupLayoutEntry {
            binding: 3,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        },
    ]
}

/// A bind group of `buffer`'s first `size` bytes (the window a dynamic offset moves).
pub(super) fn bind(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffer: &wgpu::Buffer,
    size: u64,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("maps"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset: 0,
                size: std::num::NonZeroU64::new(size),
            }),
        }],
    })
}

pub(super) fn queries(device: &wgpu::Device, lights: usize) -> Queries {
    let count = 2 * (1 + 3 * lights) as u32;
    Queries {
        set: device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("map timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count,
        }),
        resolve: device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("map timestamps resolve"),
            size: 256 * (1 + 3 * lights) as u64,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }),
        read: device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("map timestamps read"),
            size: 256 * (1 + 3 * lights) as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }),
        lights,
    }
}
