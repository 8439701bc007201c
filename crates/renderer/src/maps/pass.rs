//! The shadow-map passes on the caller's device: the surfaces uploaded once in world space, and
//! per frame only uniforms written; per light its map passes, the optional mask pass into the
//! stencil, and its lit pass reading the map.

use super::fit::{LightMap, MapKind};
use super::MapFilter;
use crate::raster::pipelines::{self, color_target, uniform};
use crate::raster::{
    light_uniform, push_surface, states, Attachments, SurfaceVertex, BACKGROUND, COLOR_FORMAT,
    IDS_FORMAT, LIGHT_STRIDE, VISIBILITY_FORMAT,
};
use crate::{RenderDevice, RenderError};
use glam::Vec3;
use shadowvol_gpu::ErrorScopes;
use shadowvol_scenes::Scene;
use shadowvol_silhouette::{vec_bytes, PreparedBytes};
use std::ops::Range;

/// Byte stride of the per-light map uniforms (`MapU`, 560 bytes, at a 256-byte alignment).
const MAP_STRIDE: u64 = 768;
/// Bytes of one `MapU`.
const MAP_BYTES: u64 = 4 * MAP_WORDS as u64;
use super::resources::{
    bind, light_filter, map_uniform, pcss_texture_entries, queries, texture_entries, MapTextures,
    Queries, MAP_WORDS,
};
use crate::raster::empty_scissor;
use crate::raster::pipelines::uniform_buffer;

mod frame;
mod timings;
pub(crate) use frame::{MapFrame, MapLight};

/// The shadow-map passes' pipelines on one device.
pub(crate) struct MapPass {
    globals_bgl: wgpu::BindGroupLayout,
    light_bgl: wgpu::BindGroupLayout,
    map_bgl: wgpu::BindGroupLayout,
    tex_bgl: wgpu::BindGroupLayout,
    depth_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    prepass: wgpu::RenderPipeline,
    prepass_color: wgpu::RenderPipeline,
    mask: wgpu::RenderPipeline,
    lit: wgpu::RenderPipeline,
    /// The map's visibility into the frame's visibility target (a frame read back).
    visibility: wgpu::RenderPipeline,
    /// The maps' bind group layout under PCSS (a second, filtering sampler).
    pcss_bgl: wgpu::BindGroupLayout,
    pcss_layout: wgpu::PipelineLayout,
    /// PCSS's mask and lit passes, built at the first frame that reads a map with PCSS.
    pcss: Option<PcssPipelines>,
    /// The map passes by slope-scaled bias (the only pipeline state a setting changes).
    depth: Vec<(f32, wgpu::RenderPipeline)>,
    hard: wgpu::Sampler,
    pcf: wgpu::Sampler,
    /// Bilinear, without comparison: PCSS's blocker search reads depths with it.
    linear: wgpu::Sampler,
    timestamps: bool,
}

/// The mask and lit passes that read maps with PCSS (`fs_map_mask_pcss`, `fs_map_lit_pcss`).
struct PcssPipelines {
    mask: wgpu::RenderPipeline,
    lit: wgpu::RenderPipeline,
    visibility: wgpu::RenderPipeline,
}

impl std::fmt::Debug for MapPass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MapPass")
            .field("timestamps", &self.timestamps)
            .finish_non_exhaustive()
    }
}

/// One scene on the device: its surfaces in world space, the frame's uniforms, the maps.
pub(crate) struct MapScene {
    surface: wgpu::Buffer,
    /// Per surface: its vertex range in `surface`.
    ranges: Vec<Range<u32>>,
    /// Vertices of the shadow casters (the first surfaces).
    caster_vertices: u32,
    globals: wgpu::Buffer,
    globals_bg: wgpu::BindGroup,
    /// Light and map uniforms, sized for `slots` lights.
    slots: usize,
    lights: wgpu::Buffer,
    lights_bg: wgpu::BindGroup,
    maps: wgpu::Buffer,
    maps_bg: wgpu::BindGroup,
    textures: Option<MapTextures>,
    queries: Option<Queries>,
}

impl MapScene {
    /// Device bytes the scene keeps: the surface vertices, the uniforms, the maps (4 bytes a
    /// texel: every cascade layer of the 2-D map and the 6 cube faces) and the timestamp
    /// buffers; the host keeps only the surfaces' ranges.
    pub(crate) fn bytes(&self) -> PreparedBytes {
        let mut device: u64 = [&self.surface, &self.globals, &self.lights, &self.maps]
            .iter()
            .map(|b| b.size())
            .sum();
        if let Some(t) = &self.textures {
            let texels = |size: u32, layers: usize| u64::from(size).pow(2) * layers as u64;
            device +=
                4 * (texels(t.size_2d, t.layers_2d.len()) + texels(t.size_cube, t.faces.len()));
        }
        if let Some(q) = &self.queries {
            device += q.resolve.size() + q.read.size();
        }
        PreparedBytes {
            host: vec_bytes(&self.ranges),
            device,
        }
    }
}

impl MapPass {
    /// The pipelines on `rd`.
    ///
    /// # Errors
    /// [`RenderError::Device`] when a shader or pipeline fails to build.
    pub(crate) fn new(rd: &RenderDevice) -> Result<Self, RenderError> {
        let device = &rd.device;
        let scope = ErrorScopes::push(device);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shaders/render_maps.wgsl"),
            source: wgpu::ShaderSource::Wgsl(super::maps_source().into()),
        });
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let globals_bgl = pipelines::bind_group_layout(device, "globals", &[uniform(0, vf, false)]);
        let light_bgl = pipelines::bind_group_layout(device, "light", &[uniform(0, vf, true)]);
        let map_bgl = pipelines::bind_group_layout(device, "map", &[uniform(0, vf, true)]);
        let tex_bgl = pipelines::bind_group_layout(device, "map textures", &texture_entries());
        let layout = pipelines::pipeline_layout(
            device,
            "maps",
            &[&globals_bgl, &light_bgl, &map_bgl, &tex_bgl],
        );
        let pcss_bgl =
            pipelines::bind_group_layout(device, "map textures (pcss)", &pcss_texture_entries());
        let pcss_layout = pipelines::pipeline_layout(
            device,
            "maps (pcss)",
            &[&globals_bgl, &light_bgl, &map_bgl, &pcss_bgl],
        );
        let depth_layout =
            pipelines::pipeline_layout(device, "map depth", &[&globals_bgl, &light_bgl, &map_bgl]);
        let surface_layout = [Some(states::surface_layout())];
        let make = pipelines::RenderPipelines {
            device,
            layout: &layout,
            module: &module,
            depth: rd.depth_format,
        };
        let prepass = make.prepass(
            "map prepass",
            "vs_map_surface",
            &surface_layout,
            "fs_prepass",
            &[
                color_target(COLOR_FORMAT, None),
                color_target(IDS_FORMAT, None),
            ],
        );
        let prepass_color = make.prepass(
            "map prepass (colour)",
            "vs_map_surface",
            &surface_layout,
            "fs_prepass_color",
            &[color_target(COLOR_FORMAT, None)],
        );
        let surface = |label, depth, fs, targets: &[Option<wgpu::ColorTargetState>]| {
            make.surface(label, "vs_map_surface", &surface_layout, depth, fs, targets)
        };
        let mask = surface(
            "map mask",
            states::map_mask_depth(rd.depth_format),
            "fs_map_mask",
            &[],
        );
        let lit = surface(
            "map lit",
            states::map_lit_depth(rd.depth_format),
            "fs_map_lit",
            &[color_target(COLOR_FORMAT, Some(states::additive()))],
        );
        let visibility = surface(
            "map visibility",
            states::map_lit_depth(rd.depth_format),
            "fs_map_visibility",
            &[color_target(VISIBILITY_FORMAT, None)],
        );
        if let Some(err) = scope.pop() {
            return Err(RenderError::Device(format!("map pipelines: {err}")));
        }
        let sampler = |label, filter, compare| {
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some(label),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                address_mode_w: wgpu::AddressMode::ClampToEdge,
                mag_filter: filter,
                min_filter: filter,
                compare,
                ..Default::default()
            })
        };
        let greater_equal = Some(wgpu::CompareFunction::GreaterEqual);
        Ok(Self {
            hard: sampler("map hard", wgpu::FilterMode::Nearest, greater_equal),
            pcf: sampler("map pcf", wgpu::FilterMode::Linear, greater_equal),
            linear: sampler("map pcss search", wgpu::FilterMode::Linear, None),
            pcss_bgl,
            pcss_layout,
            pcss: None,
            globals_bgl,
            light_bgl,
            map_bgl,
            tex_bgl,
            depth_layout,
            module,
            prepass,
            prepass_color,
            mask,
            lit,
            visibility,
            depth: Vec::new(),
            timestamps: device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
        })
    }

    /// The map pass with slope-scaled bias `slope`, built on first use.
    fn depth_pipeline(&mut self, device: &wgpu::Device, slope: f32) -> usize {
        if let Some(i) = self.depth.iter().position(|(s, _)| *s == slope) {
            return i;
        }
        let make = pipelines::RenderPipelines {
            device,
            layout: &self.depth_layout,
            module: &self.module,
            depth: wgpu::TextureFormat::Depth32Float,
        };
        let primitive = wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        };
        let pipeline = make.create(
            "map depth",
            "vs_map_depth",
            &[Some(states::surface_layout())],
            primitive,
            states::map_depth(slope),
            None,
        );
        self.depth.push((slope, pipeline));
        self.depth.len() - 1
    }

    /// Builds PCSS's mask and lit passes on first use.
    ///
    /// # Errors
    /// [`RenderError::Unsupported`] on OpenGL, which samples a texture with one sampler only
    /// (PCSS reads each map with the comparison sampler and a bilinear one); [`RenderError::Device`]
    /// when the device rejects them.
    fn pcss_pipelines(&mut self, rd: &RenderDevice) -> Result<(), RenderError> {
        if self.pcss.is_some() {
            return Ok(());
        }
        if rd.adapter.get_info().backend == wgpu::Backend::Gl {
            return Err(RenderError::Unsupported(
                "--map-filter pcss on OpenGL: PCSS reads each shadow map with two samplers (a \
                 comparison for the filter, a bilinear one for the blocker search), and OpenGL \
                 samples a texture with one only (Bevy's WebGL 2 build skips the blocker search); \
                 use a Vulkan, Metal or DX12 adapter, or --map-filter pcf"
                    .to_owned(),
            ));
        }
        let device = &rd.device;
        let scope = ErrorScopes::push(device);
        let make = pipelines::RenderPipelines {
            device,
            layout: &self.pcss_layout,
            module: &self.module,
            depth: rd.depth_format,
        };
        let surface_layout = [Some(states::surface_layout())];
        let mask = make.surface(
            "map mask (pcss)",
            "vs_map_surface",
            &surface_layout,
            states::map_mask_depth(rd.depth_format),
            "fs_map_mask_pcss",
            &[],
        );
        let lit = make.surface(
            "map lit (pcss)",
            "vs_map_surface",
            &surface_layout,
            states::map_lit_depth(rd.depth_format),
            "fs_map_lit_pcss",
            &[color_target(COLOR_FORMAT, Some(states::additive()))],
        );
        let visibility = make.surface(
            "map visibility (pcss)",
            "vs_map_surface",
            &surface_layout,
            states::map_lit_depth(rd.depth_format),
            "fs_map_visibility_pcss",
            &[color_target(VISIBILITY_FORMAT, None)],
        );
        if let Some(err) = scope.pop() {
            return Err(RenderError::Device(format!(
                "map pipelines for --map-filter pcss: {err}"
            )));
        }
        self.pcss = Some(PcssPipelines {
            mask,
            lit,
            visibility,
        });
        Ok(())
    }

    /// Uploads `scene`'s surfaces in world space.
    ///
    /// # Errors
    /// [`RenderError::TooLarge`](crate::RenderError::TooLarge) when the surfaces' vertices
    /// exceed the device's `max_buffer_size`.
    pub(crate) fn prepare(
        &self,
        device: &wgpu::Device,
        scene: &Scene,
    ) -> Result<MapScene, crate::RenderError> {
        let mut vertices = Vec::new();
        let mut ranges = Vec::new();
        let mut caster_vertices = 0;
        for (i, s) in scene.surfaces().enumerate() {
            let start = vertices.len() as u32;
            push_surface(
                &mut vertices,
                i,
                s.table,
                &s.world_positions(),
                s.albedo,
                Vec3::ZERO,
            );
            ranges.push(start..vertices.len() as u32);
            if s.casts_shadows {
                caster_vertices = vertices.len() as u32;
            }
        }
        if vertices.is_empty() {
            vertices.push(bytemuck::Zeroable::zeroed());
        }
        let surface = crate::raster::vertex_buffer(
            device,
            "map surfaces",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::COPY_DST,
        )?;
        let globals = uniform_buffer(device, "map globals", 96);
        let globals_bg = bind(device, &self.globals_bgl, &globals, 96);
        let (lights, lights_bg, maps, maps_bg) = self.light_buffers(device, 1);
        Ok(MapScene {
            surface,
            ranges,
            caster_vertices,
            globals,
            globals_bg,
            slots: 1,
            lights,
            lights_bg,
            maps,
            maps_bg,
            textures: None,
            queries: None,
        })
    }

    fn light_buffers(
        &self,
        device: &wgpu::Device,
        slots: usize,
    ) -> (wgpu::Buffer, wgpu::BindGroup, wgpu::Buffer, wgpu::BindGroup) {
        let lights = uniform_buffer(device, "map lights", slots as u64 * LIGHT_STRIDE);
        let lights_bg = bind(device, &self.light_bgl, &lights, 96);
        let maps = uniform_buffer(device, "map uniforms", slots as u64 * MAP_STRIDE);
        let maps_bg = bind(device, &self.map_bgl, &maps, MAP_BYTES);
        (lights, lights_bg, maps, maps_bg)
    }

    /// Rewrites the world vertices of `surface` (it moved) from its new `positions`.
    pub(crate) fn update_surface(
        &self,
        queue: &wgpu::Queue,
        ms: &MapScene,
        surface: usize,
        s: &shadowvol_scenes::Surface<'_>,
        positions: &[Vec3],
    ) {
        let mut v = Vec::new();
        push_surface(&mut v, surface, s.table, positions, s.albedo, Vec3::ZERO);
        let offset =
            u64::from(ms.ranges[surface].start) * std::mem::size_of::<SurfaceVertex>() as u64;
        if !v.is_empty() {
            queue.write_buffer(&ms.surface, offset, bytemuck::cast_slice(&v));
        }
    }

    /// Writes the frame's uniforms and makes the maps and timestamps the frame needs.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] for a map larger than the device's 2-D texture limit.
    pub(crate) fn update(
        &mut self,
        rd: &RenderDevice,
        ms: &mut MapScene,
        frame: &MapFrame<'_>,
    ) -> Result<(), RenderError> {
        let device = &rd.device;
        let n = frame.lights.len();
        if n > ms.slots {
            let (l, lb, m, mb) = self.light_buffers(device, n);
            (ms.lights, ms.lights_bg, ms.maps, ms.maps_bg, ms.slots) = (l, lb, m, mb, n);
            ms.queries = None;
        }
        let mut globals = [0f32; 24];
        globals[..16].copy_from_slice(&frame.view_proj.to_cols_array());
        globals[20] = frame.ambient;
        rd.queue
            .write_buffer(&ms.globals, 0, bytemuck::cast_slice(&globals));
        let mut light_bytes = vec![0u8; ms.slots * LIGHT_STRIDE as usize];
        let mut map_bytes = vec![0u8; ms.slots * MAP_STRIDE as usize];
        for (i, l) in frame.lights.iter().enumerate() {
            let v = light_uniform(l.light, l.color, l.emission.as_ref());
            let o = i * LIGHT_STRIDE as usize;
            light_bytes[o..o + 64].copy_from_slice(bytemuck::cast_slice(&v));
            let filter = light_filter(frame.filter, l.map.as_ref());
            let u = map_uniform(l.map.as_ref(), frame.eye, filter);
            let o = i * MAP_STRIDE as usize;
            map_bytes[o..o + MAP_BYTES as usize].copy_from_slice(bytemuck::cast_slice(&u));
        }
        if n == 0 {
            let u = map_uniform(None, frame.eye, frame.filter);
            map_bytes[..MAP_BYTES as usize].copy_from_slice(bytemuck::cast_slice(&u));
        }
        rd.queue.write_buffer(&ms.lights, 0, &light_bytes);
        rd.queue.write_buffer(&ms.maps, 0, &map_bytes);
        let size = |kind: MapKind| {
            frame
                .lights
                .iter()
                .filter_map(|l| {
                    l.map
                        .filter(|m| (m.kind == MapKind::Cube) == (kind == MapKind::Cube))
                })
                .map(|m| m.size)
                .max()
                .unwrap_or(1)
        };
        let (s2, sc) = (size(MapKind::Directional), size(MapKind::Cube));
        let limit = device.limits().max_texture_dimension_2d;
        if s2.max(sc) > limit {
            return Err(RenderError::InvalidInput(format!(
                "a shadow map of {} texels a side exceeds the device's max_texture_dimension_2d \
                 {limit}; give a smaller --map-size",
                s2.max(sc)
            )));
        }
        let layers = frame
            .lights
            .iter()
            .filter_map(|l| l.map.map(|m| m.cascades))
            .max()
            .unwrap_or(1)
            .max(1);
        if !ms.textures.as_ref().is_some_and(|t| {
            t.size_2d == s2 && t.layers_2d.len() == layers as usize && t.size_cube == sc
        }) {
            ms.textures = None;
            ms.textures = Some(self.textures(device, (s2, layers), sc));
        }
        for l in frame.lights.iter().filter_map(|l| l.map) {
            self.depth_pipeline(device, l.bias.slope);
        }
        if frame
            .lights
            .iter()
            .any(|l| light_filter(frame.filter, l.map.as_ref()) == MapFilter::Pcss)
        {
            self.pcss_pipelines(rd)?;
        }
        if self.timestamps && ms.queries.is_none() {
            ms.queries = Some(queries(device, ms.slots));
        }
        Ok(())
    }

    /// The 2-D map (`size_2d` texels, `layers` layers: one per cascade) and the cube map.
    fn textures(
        &self,
        device: &wgpu::Device,
        (size_2d, layers): (u32, u32),
        size_cube: u32,
    ) -> MapTextures {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let map = |label, size, layers| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: size,
                    height: size,
                    depth_or_array_layers: layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Depth32Float,
                usage,
                view_formats: &[],
            })
        };
        let t2 = map("shadow map", size_2d, layers);
        let tc = map("shadow cube map", size_cube, 6);
        let layer_views = |t: &wgpu::Texture, n: u32| -> Vec<wgpu::TextureView> {
            (0..n)
                .map(|layer| {
                    t.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: layer,
                        array_layer_count: Some(1),
                        ..Default::default()
                    })
                })
                .collect()
        };
        let view_2d = t2.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let layers_2d = layer_views(&t2, layers);
        let faces = layer_views(&tc, 6);
        let cube = tc.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::Cube),
            ..Default::default()
        });
        // The maps and one comparison sampler, of the frame's filter (OpenGL samples a texture
        // with one sampler only); PCSS adds a bilinear sampler for its blocker search.
        fn entries<'a>(
            view_2d: &'a wgpu::TextureView,
            cube: &'a wgpu::TextureView,
            sampler: &'a wgpu::Sampler,
        ) -> [wgpu::BindGroupEntry<'a>; 3] {
            [
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(view_2d),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(cube),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
            ]
        }
        let bind_group = |label, layout, entries: &[wgpu::BindGroupEntry<'_>]| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries,
            })
        };
        let bind_groups = [
            bind_group(
                "map textures",
                &self.tex_bgl,
                &entries(&view_2d, &cube, &self.hard),
            ),
            bind_group(
                "map textures",
                &self.tex_bgl,
                &entries(&view_2d, &cube, &self.pcf),
            ),
        ];
        let [maps, cube_map, compare] = entries(&view_2d, &cube, &self.pcf);
        let search = wgpu::BindGroupEntry {
            binding: 3,
            resource: wgpu::BindingResource::Sampler(&self.linear),
        };
        let pcss = bind_group(
            "map textures (pcss)",
            &self.pcss_bgl,
            &[maps, cube_map, compare, search],
        );
        MapTextures {
            size_2d,
            size_cube,
            layers_2d,
            faces,
            bind_groups,
            pcss,
        }
    }

    /// Records the frame: the pre-pass, then per light its map passes, its mask pass (where the
    /// frame's stencil is read back) and its lit pass. Returns which timestamp pairs it wrote.
    pub(crate) fn record(
        &self,
        enc: &mut wgpu::CommandEncoder,
        ms: &MapScene,
        frame: &MapFrame<'_>,
        target: &Attachments<'_>,
    ) -> Vec<bool> {
        let mut written = vec![false; 1 + 3 * frame.lights.len()];
        let Some(tex) = ms.textures.as_ref() else {
            return written;
        };
        // The pre-pass reads no map; its layout is the hard and PCF passes'.
        let maps = tex.bind_group(light_filter(frame.filter, None));
        written[0] = true;
        let q = |slot: usize, begin: bool, end: bool| {
            if !(begin || end) {
                return None;
            }
            ms.queries
                .as_ref()
                .map(|q| wgpu::RenderPassTimestampWrites {
                    query_set: &q.set,
                    beginning_of_pass_write_index: begin.then_some(2 * slot as u32),
                    end_of_pass_write_index: end.then_some(2 * slot as u32 + 1),
                })
        };
        let all = 0..ms.ranges.last().map_or(0, |r| r.end);
        {
            let ids = target
                .ids
                .map(|v| states::cleared(v, wgpu::Color::TRANSPARENT));
            let mut color = vec![states::cleared(target.color, BACKGROUND)];
            color.extend(ids);
            let mut pass = states::begin_prepass(
                enc,
                "map prepass",
                &color,
                target.depth_stencil,
                true,
                q(0, true, true),
            );
            if !all.is_empty() {
                let pipeline = if target.ids.is_some() {
                    &self.prepass
                } else {
                    &self.prepass_color
                };
                pass.set_pipeline(pipeline);
                self.bind_surface(&mut pass, ms, 0, Some(maps));
                pass.draw(all.clone(), 0..1);
            }
        }
        for (li, l) in frame.lights.iter().enumerate() {
            let slot = 1 + 3 * li;
            written[slot] = l.map.is_some();
            written[slot + 1] = target.reads_stencil();
            written[slot + 2] = true;
            if let Some(map) = &l.map {
                self.record_map(enc, ms, tex, li, map, |first, last| q(slot, first, last));
            }
            let drawn = l.map.is_some() && !empty_scissor(l.scissor) && !all.is_empty();
            // Each light's own filter: under PCSS a light of size 0 is read with PCF.
            let (mask, lit, visible, light_maps) =
                match (light_filter(frame.filter, l.map.as_ref()), &self.pcss) {
                    (MapFilter::Pcss, Some(p)) => (
                        &p.mask,
                        &p.lit,
                        &p.visibility,
                        tex.bind_group(MapFilter::Pcss),
                    ),
                    (MapFilter::Pcss, None) => (&self.mask, &self.lit, &self.visibility, maps),
                    (f, _) => (&self.mask, &self.lit, &self.visibility, tex.bind_group(f)),
                };
            if target.reads_stencil() {
                let mut pass = states::begin_stencil_pass(
                    enc,
                    "map mask",
                    target.depth_stencil,
                    wgpu::LoadOp::Clear(0),
                    l.scissor,
                    q(slot + 1, true, true),
                );
                if drawn {
                    pass.set_pipeline(mask);
                    pass.set_stencil_reference(1);
                    self.bind_surface(&mut pass, ms, li, Some(light_maps));
                    pass.draw(all.clone(), 0..1);
                }
            }
            target.after_stencil(enc, li);
            if let Some(soft) = target.soft.filter(|s| s.reads_back()) {
                // The map's visibility, 1 where no surface or no map, read back for the reference.
                let mut pass = soft.begin_visibility(enc, "map visibility", target.depth_stencil);
                if drawn {
                    pass.set_pipeline(visible);
                    self.bind_surface(&mut pass, ms, li, Some(light_maps));
                    pass.draw(all.clone(), 0..1);
                }
                drop(pass);
                soft.copy_visibility(enc, li);
            }
            let mut pass = states::begin_lit_pass(
                enc,
                "map lit",
                target.color,
                target.depth_stencil,
                l.scissor,
                q(slot + 2, true, true),
            );
            if !empty_scissor(l.scissor) && !all.is_empty() {
                pass.set_pipeline(lit);
                self.bind_surface(&mut pass, ms, li, Some(light_maps));
                pass.draw(all.clone(), 0..1);
            }
        }
        written
    }

    /// Light `li`'s map passes: each face cleared to 0 (farthest), then the casters.
    fn record_map<'q>(
        &self,
        enc: &mut wgpu::CommandEncoder,
        ms: &MapScene,
        tex: &MapTextures,
        li: usize,
        map: &LightMap,
        timestamps: impl Fn(bool, bool) -> Option<wgpu::RenderPassTimestampWrites<'q>>,
    ) {
        let pipeline = self
            .depth
            .iter()
            .find(|(s, _)| *s == map.bias.slope)
            .map(|(_, p)| p)
            .expect("built in update");
        let faces: Vec<&wgpu::TextureView> = match map.kind {
            MapKind::Cube => tex.faces.iter().collect(),
            _ => tex.layers_2d.iter().take(map.cascades as usize).collect(),
        };
        let last = faces.len() - 1;
        for (face, view) in faces.into_iter().enumerate() {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timestamps(face == 0, face == last),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if ms.caster_vertices > 0 {
                pass.set_pipeline(pipeline);
                self.bind_surface(&mut pass, ms, li, None);
                pass.draw(0..ms.caster_vertices, face as u32..face as u32 + 1);
            }
        }
    }

    /// Binds the surfaces, the globals, light `li`'s uniforms and (but in the map passes) the
    /// maps.
    fn bind_surface(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        ms: &MapScene,
        li: usize,
        tex: Option<&wgpu::BindGroup>,
    ) {
        pass.set_bind_group(0, &ms.globals_bg, &[]);
        pass.set_bind_group(1, &ms.lights_bg, &[(li as u64 * LIGHT_STRIDE) as u32]);
        pass.set_bind_group(2, &ms.maps_bg, &[(li as u64 * MAP_STRIDE) as u32]);
        if let Some(t) = tex {
            pass.set_bind_group(3, t, &[]);
        }
        pass.set_vertex_buffer(0, ms.surface.slice(..));
    }
}
