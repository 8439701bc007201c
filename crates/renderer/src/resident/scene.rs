//! Uploads: the scene once ([`ShadowPass::prepare`]), the small per-frame inputs
//! ([`ShadowPass::update`]) and the buffers sized by the number of lights.

use super::*;
use shadowvol_gpu::{Extras, TableBuffers, TablePacking};
use shadowvol_silhouette::gpu::{TableBuffer, TableWriter};
use shadowvol_silhouette::TopologyScene;

/// The optional tables the pass packs: the object of each vertex (for the vertex pass), no OV
/// vertex list (its `original` reads each OV through its triangle).
const EXTRAS: Extras = Extras {
    ov_vertices: false,
    vertex_objects: true,
};

impl ShadowPass {
    /// Uploads `scene` once: every surface's ([`shadowvol_scenes::Scene::surfaces`], casters
    /// then receivers) object-space positions, edges, opposite vertices and triangles, written
    /// in chunks straight from their edge tables ([`ShadowPass::prepare_topology`]). The
    /// transforms are not used here; each frame gives its own ([`PassFrame::transforms`]).
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when the scene is too large to index with `u32`;
    /// [`RenderError::TooLarge`] when the packed tables ([`TablePacking`]) exceed the device's
    /// `max_storage_buffer_binding_size` (the GPU pipeline then uploads the scene in parts).
    pub fn prepare(&self, scene: &shadowvol_scenes::Scene) -> Result<ResidentScene, RenderError> {
        self.prepare_topology(&scene.surface_geometry())
    }

    /// Uploads any topology, its tables in the layout [`ResidentLayout::build`] gives them, but
    /// written in chunks straight from its edge tables: no copy of the scene is made on the
    /// host, and the staging memory stays bounded
    /// ([`TableBuffers::upload`]).
    ///
    /// # Errors
    /// As [`ShadowPass::prepare`].
    pub fn prepare_topology(&self, scene: &TopologyScene) -> Result<ResidentScene, RenderError> {
        let writer = TableWriter::new(scene, layout::NAME)
            .map_err(|e| RenderError::InvalidInput(e.to_string()))?;
        layout::check_edge_count(writer.elements(TableBuffer::Edges))?;
        self.check_tables(&TablePacking::new(&writer, EXTRAS))?;
        let wait = |_| crate::raster::wait(&self.device);
        let tables = TableBuffers::upload(
            &self.device,
            &self.queue,
            &writer,
            wgpu::BufferUsages::empty(),
            EXTRAS,
            wait,
        )?;
        let bases = writer.objects().to_vec();
        let counts = LayoutCounts {
            objects: bases.len() - 1,
            tris: writer.elements(TableBuffer::Triangles),
            vertices: writer.elements(TableBuffer::Positions),
            edges: writer.elements(TableBuffer::Edges),
            capacity: writer.elements(TableBuffer::OvRefs).max(1),
        };
        self.finish_prepare(tables, counts, bases)
    }

    /// Uploads a laid-out scene ([`ResidentLayout::build`] of any topology).
    ///
    /// # Errors
    /// As [`ShadowPass::prepare`].
    pub fn prepare_layout(&self, layout: ResidentLayout) -> Result<ResidentScene, RenderError> {
        let packing = TablePacking::of_layout(&layout.tables, true);
        self.check_tables(&packing)?;
        let words = packing.pack_layout(&layout.tables, &layout.vertex_objects);
        let tables = TableBuffers::from_words(&self.device, &words, packing);
        let counts = LayoutCounts::of(&layout);
        self.finish_prepare(tables, counts, layout.tables.objects)
    }

    /// The scene uploaded: its frame-independent buffers beside `tables`.
    fn finish_prepare(
        &self,
        tables: TableBuffers,
        counts: LayoutCounts,
        bases: Vec<[u32; 4]>,
    ) -> Result<ResidentScene, RenderError> {
        let (world, world_out) = self.world_positions(counts.vertices)?;
        let pending_dispatch = self.pending_dispatch();
        let surface = self.surface_vertices(counts.tris);
        // Frees the uploads' staging memory before the next part is laid out.
        crate::raster::finish_uploads(&self.device, &self.queue)?;
        Ok(ResidentScene {
            ids: Vec::new(),
            counts,
            bases,
            tables,
            world,
            world_out,
            pending_dispatch,
            surface,
            globals: self.uniform_buffer("resident globals", 96),
            frame: None,
            state: FrameState {
                lights: 0,
                groups: Vec::new(),
                mode: Accuracy::Exact,
                techniques: Vec::new(),
                scissors: Vec::new(),
            },
        })
    }

    /// [`RenderError::TooLarge`] when the scene's packed tables exceed one storage binding.
    fn check_tables(&self, packing: &TablePacking) -> Result<(), RenderError> {
        let limits = self.device.limits();
        let max = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        packing
            .check(layout::NAME, max)
            .map_err(RenderError::TooLarge)
    }

    /// The world positions that the vertex pass writes each frame, and its output bind group.
    fn world_positions(
        &self,
        vertices: usize,
    ) -> Result<(wgpu::Buffer, wgpu::BindGroup), RenderError> {
        let max = self.device.limits().max_storage_buffer_binding_size;
        let world_bytes = 16 * vertices.max(1) as u64;
        if world_bytes > max {
            return Err(RenderError::TooLarge(format!(
                "the scene's world positions take {world_bytes} bytes; the device binds at most {max} (max_storage_buffer_binding_size)"
            )));
        }
        let world = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("world positions"),
            size: world_bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let world_out = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident vertices out"),
            layout: &self.extract.v2,
            entries: &[entry(0, &world)],
        });
        Ok((world, world_out))
    }

    /// Exact mode's pending-dispatch arguments and the bind group that writes them.
    fn pending_dispatch(&self) -> (wgpu::Buffer, wgpu::BindGroup) {
        let dispatch = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resident pending dispatch"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let pending_out = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident pending dispatch"),
            layout: &self.extract.v2,
            entries: &[entry(0, &dispatch)],
        });
        (dispatch, pending_out)
    }

    /// The surface vertex buffer of `tris` triangles and its chunks' bind groups, or `None`
    /// (vertex pulling: [`SurfaceVertices`] chose it, or the buffer exceeds the device's
    /// largest).
    fn surface_vertices(&self, tris: usize) -> Option<(wgpu::Buffer, Vec<(wgpu::BindGroup, u32)>)> {
        if !self.surfaces.buffer_for(tris) {
            return None;
        }
        // The surface vertices (3 `SurfaceVertex` per triangle) where the buffer fits the device;
        // the surface pass writes them in chunks that each fit one storage binding.
        let per_tri = 3 * std::mem::size_of::<crate::raster::SurfaceVertex>() as u64;
        let surface_bytes = per_tri * tris as u64;
        let limits = self.device.limits();
        let max = limits.max_storage_buffer_binding_size;
        let align = u64::from(limits.min_storage_buffer_offset_alignment.max(1));
        // Triangles per chunk: fits a binding, and chunk offsets stay aligned.
        let step = align / gcd(align, per_tri);
        let chunk = (max / per_tri) / step * step;
        if !(surface_bytes > 0 && surface_bytes <= limits.max_buffer_size && chunk > 0) {
            return None;
        }
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("surface vertices"),
            size: surface_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
            mapped_at_creation: false,
        });
        let tris = tris as u64;
        let chunks = (0..tris.div_ceil(chunk))
            .map(|c| {
                let first = c * chunk;
                let count = chunk.min(tris - first);
                let group = self.surface_chunk(&buffer, first, count, per_tri);
                (group, count as u32)
            })
            .collect();
        Some((buffer, chunks))
    }

    /// The bind group through which the surface pass writes `count` triangles from `first`.
    fn surface_chunk(
        &self,
        buffer: &wgpu::Buffer,
        first: u64,
        count: u64,
        per_tri: u64,
    ) -> wgpu::BindGroup {
        let base = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("resident surfaces chunk"),
                contents: bytemuck::cast_slice(&[first as u32, count as u32, 0, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resident surfaces out"),
            layout: &self.world.s2,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer,
                        offset: first * per_tri,
                        size: std::num::NonZeroU64::new(count * per_tri),
                    }),
                },
                entry(2, &base),
            ],
        })
    }

    /// A uniform buffer of `size` bytes that the host writes each frame.
    pub(super) fn uniform_buffer(&self, label: &str, size: u64) -> wgpu::Buffer {
        crate::raster::pipelines::uniform_buffer(&self.device, label, size)
    }

    /// Writes one frame's inputs (object-space lights, techniques, camera-relative transforms,
    /// per-light uniforms), growing the per-light buffers when there are more lights than before.
    ///
    /// # Errors
    /// [`RenderError::InvalidInput`] when a slice's length does not match the scene or the lights,
    /// an object-space light is not finite, or the per-light buffers would exceed the device's
    /// `max_storage_buffer_binding_size`.
    pub fn update(&self, rs: &mut ResidentScene, f: &PassFrame<'_>) -> Result<(), RenderError> {
        check_frame_lengths(rs, f)?;
        let n = f.lights.len();
        let slots = n.max(1);
        if rs.frame.as_ref().is_none_or(|b| b.lights < slots) {
            rs.frame = Some(self.frame_buffers(rs, slots)?);
        }
        let fb = rs.frame.as_ref().expect("allocated above");
        let groups = groups::sharing_groups(f, rs.counts.objects, fb.per_batch)?;
        let lights = object_space_lights(f)?;
        let q = &self.queue;
        q.write_buffer(
            &fb.objects,
            0,
            bytemuck::cast_slice(&object_rows(f, &rs.bases, &rs.ids)),
        );
        self.write_globals(rs, f);
        for b in fb.batches.iter().filter(|b| b.lights_of(n) > 0) {
            let nb = b.lights_of(n);
            self.write_batch(rs, b, f, &lights, b.groups(&groups, nb));
            let uniforms = light_uniforms(rs, f, (b.first, nb), b.groups(&groups, nb));
            q.write_buffer(&b.buffers.light_u, 0, &uniforms);
        }
        rs.state = FrameState {
            lights: n,
            groups,
            mode: f.mode,
            techniques: f.techniques.to_vec(),
            scissors: f.scissors.to_vec(),
        };
        Ok(())
    }

    /// Writes batch `b`'s inputs: its object-space lights (`lights[object * n + light]` of the
    /// frame's `n`), their extrusion points, the plan's technique codes, the extraction's
    /// parameters, and its sharing groups' words and boxes after the codes and the lights.
    fn write_batch(
        &self,
        rs: &ResidentScene,
        b: &batch::Batch,
        f: &PassFrame<'_>,
        lights: &[[f32; 4]],
        groups: &[SharingGroup],
    ) {
        let (objects, n) = (rs.counts.objects, f.lights.len());
        let nb = b.lights_of(n);
        let q = &self.queue;
        let mut bl: Vec<[f32; 4]> = (0..objects)
            .flat_map(|o| &lights[o * n + b.first..o * n + b.first + nb])
            .copied()
            .collect();
        let points = light_points(&bl, objects, nb);
        q.write_buffer(&b.buffers.light_points, 0, bytemuck::cast_slice(&points));
        let local: Vec<SharingGroup> = groups
            .iter()
            .map(|g| SharingGroup {
                first: g.first - b.first,
                count: g.count,
            })
            .collect();
        bl.extend(groups::group_boxes(&local, &bl, nb, objects));
        if bl.is_empty() {
            bl.push([0.0; 4]);
        }
        q.write_buffer(&b.buffers.lights, 0, bytemuck::cast_slice(&bl));
        let rows = &f.techniques[b.first * objects..(b.first + nb) * objects];
        let mut codes: Vec<u32> = rows.iter().map(|&t| technique::code(t)).collect();
        let culled = |j: usize| {
            let row = &rows[j * objects..(j + 1) * objects];
            row.iter().all(|&t| t == Technique::Culled)
        };
        codes.extend(groups::group_words(&local, nb, culled));
        q.write_buffer(&b.buffers.technique, 0, bytemuck::cast_slice(&codes));
        let (edges, tris) = (rs.counts.edges as u32, rs.counts.tris as u32);
        let params = [edges, nb as u32, 0, tris, 0, objects as u32, 0, 0];
        q.write_buffer(&b.params, 0, bytemuck::cast_slice(&params));
        let capacity = rs.counts.capacity as u32;
        let rparams = [objects as u32, capacity, u32::from(f.count), 0];
        q.write_buffer(&b.rparams, 0, bytemuck::cast_slice(&rparams));
    }

    /// Writes the globals of the camera moved to the origin.
    fn write_globals(&self, rs: &ResidentScene, f: &PassFrame<'_>) {
        let rel_cam = Camera {
            eye: glam::Vec3::ZERO,
            target: f.camera.target - f.camera.eye,
            ..*f.camera
        };
        let mut globals = [0f32; 24];
        globals[..16].copy_from_slice(&rel_cam.view_proj(f.aspect).to_cols_array());
        globals[20] = f.ambient;
        self.queue
            .write_buffer(&rs.globals, 0, bytemuck::cast_slice(&globals));
    }
}

/// The frame's object-space lights, `[object * light_count + light]`, through the one shared
/// conversion (f64, rounded once), as every backend does.
///
/// # Errors
/// [`RenderError::InvalidInput`] naming the object when a light is not finite in its space.
fn object_space_lights(f: &PassFrame<'_>) -> Result<Vec<[f32; 4]>, RenderError> {
    let mut lights: Vec<[f32; 4]> = Vec::with_capacity(f.transforms.len() * f.lights.len());
    for (oi, &t) in f.transforms.iter().enumerate() {
        for light in f.lights {
            let l = object_light(t, light.light);
            if !l.iter().all(|v| v.is_finite()) {
                return Err(RenderError::InvalidInput(format!(
                    "object {oi}: the light in object space {l:?} is not finite"
                )));
            }
            lights.push(l);
        }
    }
    Ok(lights)
}

/// Checks that the frame's per-object and per-light slices match the scene and lights.
fn check_frame_lengths(rs: &ResidentScene, f: &PassFrame<'_>) -> Result<(), RenderError> {
    let objects = rs.counts.objects;
    let n_lights = f.lights.len();
    let check = |what: &str, got: usize, want: usize| {
        if got == want {
            Ok(())
        } else {
            Err(RenderError::InvalidInput(format!(
                "GPU pipeline frame: {got} {what}, expected {want}"
            )))
        }
    };
    check("transforms", f.transforms.len(), objects)?;
    check("albedos", f.albedo.len(), objects)?;
    check("techniques", f.techniques.len(), objects * n_lights)?;
    check("light colours", f.colors.len(), n_lights)?;
    check("scissors", f.scissors.len(), n_lights)
}

/// Per object: its camera-relative transform rows, its albedo, and its first triangle, pixel
/// ids and first edge.
fn object_rows(f: &PassFrame<'_>, bases: &[[u32; 4]], ids: &[[u32; 2]]) -> Vec<[u32; 4]> {
    // Camera-relative transforms composed in f64 and rounded once, so large world
    // coordinates keep their precision near the eye.
    let eye = f.camera.eye.as_dvec3();
    let mut objs: Vec<[u32; 4]> = Vec::with_capacity(f.transforms.len() * 5);
    for (oi, t) in f.transforms.iter().enumerate() {
        let d = DAffine3::from_cols(
            t.matrix3.x_axis.as_dvec3(),
            t.matrix3.y_axis.as_dvec3(),
            t.matrix3.z_axis.as_dvec3(),
            t.translation.as_dvec3() - eye,
        );
        let m = d.matrix3;
        for r in 0..3 {
            let row = m.row(r);
            let v = [
                row.x as f32,
                row.y as f32,
                row.z as f32,
                d.translation[r] as f32,
            ];
            objs.push(v.map(f32::to_bits));
        }
        let a = f.albedo[oi];
        objs.push([a[0], a[1], a[2], 1.0].map(f32::to_bits));
        let [surface, first] = ids.get(oi).copied().unwrap_or([oi as u32, 0]);
        let b = bases[oi];
        objs.push([b[FIRST_TRIANGLE], surface + 1, first, b[FIRST_EDGE]]);
    }
    if objs.is_empty() {
        objs.push([0; 4]);
    }
    objs
}

/// Per light of a batch (`first .. first + nb`, with its sharing `groups`): camera-relative
/// light, colour and emission, draw ranges, first point, and where its group's shared signs
/// start (plus 1; 0 outside a group) in the batch's buffers.
fn light_uniforms(
    rs: &ResidentScene,
    f: &PassFrame<'_>,
    (first, nb): (usize, usize),
    groups: &[SharingGroup],
) -> Vec<u8> {
    let objects = rs.counts.objects;
    let capacity = rs.counts.capacity as u32;
    let tri_count = rs.counts.tris as u32;
    let mut light_bytes = vec![0u8; nb * LIGHT_STRIDE as usize];
    for j in 0..nb {
        let light = &f.lights[first + j];
        let l = crate::raster::relative_light(light.light.to_array(), f.camera.eye);
        let v = crate::raster::light_uniform(l, f.colors[first + j], light.emission.as_ref());
        let draw = [
            j as u32 * capacity,
            capacity,
            j as u32 * tri_count,
            u32::from(l[3] != 0.0),
        ];
        let o = j * LIGHT_STRIDE as usize;
        light_bytes[o..o + 64].copy_from_slice(bytemuck::cast_slice(&v));
        light_bytes[o + 64..o + 80].copy_from_slice(bytemuck::cast_slice(&draw));
        let shared = groups
            .iter()
            .position(|g| (g.first..g.first + g.count).contains(&(first + j)))
            .map_or(0, |k| (nb + k) as u32 * tri_count + 1);
        let first_point = [(j * objects) as u32, shared, 0, 0];
        light_bytes[o + 80..o + 96].copy_from_slice(bytemuck::cast_slice(&first_point));
    }
    light_bytes
}

/// The draws' extrusion inputs, `[light * object_count + object]`, two `[f32; 4]` each, from the
/// object-space lights `ol[object * n_lights + light]` of `objects` objects: for a point light (`w > 0`) the point
/// `P = L.xyz / w`, evaluated in `f64` and split into `f32` `hi` and `lo = P − hi`, as `(hi, w)`
/// and `(lo, 0)`; for a directional light `(L.xyz, 0)` and zeros. The vertex shader extrudes
/// object-space vertex `p` along `(p − hi) − lo`, whose first difference is exact where `p`
/// is near `P` (Sterbenz), so a vertex a hair from the light still extrudes the right way,
/// where `w·p − L.xyz` in `f32` rounds to noise. At least one pair, so the buffer is never
/// empty.
#[must_use]
pub(crate) fn light_points(ol: &[[f32; 4]], objects: usize, n_lights: usize) -> Vec<[f32; 4]> {
    let mut out = vec![[0.0f32; 4]; 2 * (objects * n_lights).max(1)];
    for oi in 0..objects {
        for li in 0..n_lights {
            let l = &ol[oi * n_lights + li];
            let k = 2 * (li * objects + oi);
            let w = f64::from(l[3]);
            if w == 0.0 {
                out[k] = [l[0], l[1], l[2], 0.0];
                continue;
            }
            let p = [l[0], l[1], l[2]].map(|c| f64::from(c) / w);
            let hi = p.map(|c| c as f32);
            let lo = [0, 1, 2].map(|i| (p[i] - f64::from(hi[i])) as f32);
            out[k] = [hi[0], hi[1], hi[2], l[3]];
            out[k + 1] = [lo[0], lo[1], lo[2], 0.0];
        }
    }
    out
}
