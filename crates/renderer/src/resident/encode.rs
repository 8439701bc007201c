//! Recording a frame into the caller's encoder: the compute pass, the pre-pass, each light's
//! stencil (sides, caps) and lit passes.

use super::*;
use crate::raster::states;

impl ShadowPass {
    /// Records the frame's compute pass for the inputs last given to [`ShadowPass::update`]: the
    /// vertex pass (camera-relative world positions, which every draw reads), then the reset,
    /// triangle and edge passes (in exact mode, between the last two, the dispatch that decides
    /// the pairs the filter left, with no workgroup when there are none). Record it before the
    /// frame's draws.
    ///
    /// # Panics
    /// Panics if [`ShadowPass::update`] was never called on `rs`.
    pub fn encode_extract(&self, enc: &mut wgpu::CommandEncoder, rs: &ResidentScene) {
        let fb = rs
            .frame
            .as_ref()
            .expect("ShadowPass::update before encode_extract");
        let n_lights = rs.state.lights;
        let objects = rs.counts.objects as u32;
        let max_dim = self
            .device
            .limits()
            .max_compute_workgroups_per_dimension
            .max(1);
        let grid = |items: u32| {
            let groups = items.div_ceil(WORKGROUP).max(1);
            let x = groups.min(max_dim);
            (x, groups.div_ceil(x))
        };
        let slot = TimestampSlot::Extract.index();
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("resident extract"),
            timestamp_writes: fb.queries.as_ref().map(|(set, _, _)| {
                wgpu::ComputePassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(slot),
                    end_of_pass_write_index: Some(slot + 1),
                }
            }),
        });
        // Vertices first: the draws of the frame read their camera-relative positions.
        pass.set_pipeline(&self.world.vertices);
        pass.set_bind_group(0, &fb.v0, &[]);
        pass.set_bind_group(1, &self.world.empty, &[]);
        pass.set_bind_group(2, &rs.world_out, &[]);
        let (x, y) = grid(rs.counts.vertices as u32);
        pass.dispatch_workgroups(x, y, 1);
        if let Some((_, chunks)) = &rs.surface {
            pass.set_pipeline(&self.world.surfaces);
            pass.set_bind_group(0, &fb.s0, &[]);
            for (out, count) in chunks {
                pass.set_bind_group(2, out, &[]);
                let (x, y) = grid(*count);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        let shared = !rs.state.groups.is_empty();
        let mode = mode_index(rs.state.mode);
        for b in fb.batches.iter().filter(|b| b.lights_of(n_lights) > 0) {
            let nb = b.lights_of(n_lights) as u32;
            pass.set_bind_group(0, &b.c0, &[]);
            pass.set_bind_group(1, &b.c1, &[]);
            pass.set_pipeline(&self.extract.reset);
            let total = nb * 8 + 1 + 3 * nb * objects;
            pass.dispatch_workgroups(total.div_ceil(64).max(1), 1, 1);
            // Sharing groups exist only in exact mode; a batch without any of them runs the
            // shared kernels as the plain ones.
            let (x, y) = grid(rs.counts.tris as u32);
            pass.set_pipeline(if shared {
                &self.extract.triangles_shared
            } else {
                &self.extract.triangles[mode]
            });
            pass.dispatch_workgroups(x, y, 1);
            if rs.state.mode == Accuracy::Exact {
                let (args, out) = &rs.pending_dispatch;
                pass.set_pipeline(&self.extract.pending_args);
                pass.set_bind_group(2, out, &[]);
                pass.dispatch_workgroups(1, 1, 1);
                pass.set_pipeline(&self.extract.pending);
                pass.set_bind_group(2, &self.world.empty, &[]);
                pass.dispatch_workgroups_indirect(args, 0);
            }
            let (x, y) = grid(rs.counts.edges as u32);
            pass.set_pipeline(if shared {
                &self.extract.edges_shared
            } else {
                &self.extract.edges[mode]
            });
            pass.dispatch_workgroups(x, y, 1);
        }
    }

    /// Records the depth pre-pass (ambient colour, ids when [`PassFormats::ids`] is set). With
    /// `clear`, colour is cleared to it, ids to 0, depth to 1 and stencil to 0; with `None`
    /// every target is loaded (a later part of a scene drawn in parts, so that the parts'
    /// surfaces meet in one depth buffer).
    ///
    /// # Panics
    /// Panics if [`ShadowPass::update`] was never called on `rs`, or `ids` is given without
    /// [`PassFormats::ids`] (or missing with it).
    pub fn encode_prepass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rs: &ResidentScene,
        color: &wgpu::TextureView,
        ids: Option<&wgpu::TextureView>,
        depth: &wgpu::TextureView,
        clear: Option<wgpu::Color>,
    ) {
        assert_eq!(
            ids.is_some(),
            self.formats.ids.is_some(),
            "ids target matches PassFormats::ids"
        );
        let fb = rs
            .frame
            .as_ref()
            .expect("ShadowPass::update before encode_prepass");
        let mut attachments =
            vec![clear.map_or_else(|| states::loaded(color), |c| states::cleared(color, c))];
        if let Some(ids) = ids {
            attachments.push(clear.map_or_else(
                || states::loaded(ids),
                |_| states::cleared(ids, wgpu::Color::TRANSPARENT),
            ));
        }
        let mut pass = states::begin_prepass(
            enc,
            "resident prepass",
            &attachments,
            depth,
            clear.is_some(),
            render_ts(fb, TimestampSlot::Prepass),
        );
        let tris = rs.counts.tris as u32;
        if tris > 0 {
            pass.set_pipeline(&self.draw.prepass[usize::from(rs.surface.is_some())]);
            if let Some((vertices, _)) = &rs.surface {
                pass.set_vertex_buffer(0, vertices.slice(..));
            }
            // Any batch's bind groups: the pre-pass reads no light.
            let b = &fb.batches[0];
            pass.set_bind_group(0, &b.d0, &[]);
            pass.set_bind_group(1, &b.dl, &[0]);
            pass.draw(0..tris * 3, 0..1);
        }
    }

    /// Records light `light`'s stencil pass into `depth` (depth loaded): z-pass sides, z-fail
    /// sides, then the caps of its z-fail objects, counting from `stencil`:
    /// `wgpu::LoadOp::Clear(0)`, or `Load` for a later part of a scene drawn in parts, so that
    /// every part's volumes count into it.
    ///
    /// # Panics
    /// Panics if `light` is not a light of the last [`ShadowPass::update`].
    pub fn encode_stencil(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rs: &ResidentScene,
        light: usize,
        depth: &wgpu::TextureView,
        stencil: wgpu::LoadOp<u32>,
    ) {
        let (fb, scissor) = light_frame(rs, light, "encode_stencil");
        let empty = scissor.is_some_and(|r| r[2] == 0 || r[3] == 0);
        let (b, local) = fb.batch_of(light);
        let offset = (local as u64 * LIGHT_STRIDE) as u32;
        // Two passes, sides then caps, so that each has its own timestamps; the first starts
        // from `stencil` (cleared, or another part's counts), the second keeps counting.
        let begin = |enc: &mut wgpu::CommandEncoder, label, stencil, slot| {
            let mut pass = states::begin_stencil_pass(
                enc,
                label,
                depth,
                stencil,
                scissor,
                render_ts(fb, slot),
            )
            .forget_lifetime();
            pass.set_bind_group(0, &b.d0, &[]);
            pass.set_bind_group(1, &b.dl, &[offset]);
            pass
        };
        {
            let mut pass = begin(enc, "resident sides", stencil, TimestampSlot::Sides(light));
            if !empty {
                let base = local as u64 * 32;
                pass.set_pipeline(&self.draw.side_zpass);
                pass.draw_indirect(&b.buffers.args, base);
                pass.set_pipeline(&self.draw.side_zfail);
                pass.draw_indirect(&b.buffers.args, base + 16);
            }
        }
        let mut pass = begin(
            enc,
            "resident caps",
            wgpu::LoadOp::Load,
            TimestampSlot::Caps(light),
        );
        if empty {
            return;
        }
        let objects = rs.counts.objects;
        let zfail: Vec<usize> = (0..objects)
            .filter(|&o| rs.state.techniques[light * objects + o] == Technique::ZFail)
            .collect();
        let first = |o: usize| rs.bases[o][FIRST_TRIANGLE];
        let range = |o: usize| (first(o), first(o + 1));
        pass.set_pipeline(&self.draw.cap_ccw);
        for &o in &zfail {
            let (a, b) = range(o);
            if b > a {
                pass.draw(a * 6..b * 6, 0..1);
            }
        }
        pass.set_pipeline(&self.draw.cap_cw);
        for &o in &zfail {
            let (a, b) = range(o);
            if b > a {
                pass.draw(a * 3..b * 3, 0..1);
            }
        }
    }

    /// Records light `light`'s additive lit pass into `color` where the stencil is 0.
    ///
    /// # Panics
    /// Panics if `light` is not a light of the last [`ShadowPass::update`].
    pub fn encode_lit(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rs: &ResidentScene,
        light: usize,
        color: &wgpu::TextureView,
        depth: &wgpu::TextureView,
    ) {
        let (fb, scissor) = light_frame(rs, light, "encode_lit");
        let mut pass = states::begin_lit_pass(
            enc,
            "resident lit",
            color,
            depth,
            scissor,
            render_ts(fb, TimestampSlot::Lit(light)),
        );
        let tris = rs.counts.tris as u32;
        if tris == 0 || scissor.is_some_and(|r| r[2] == 0 || r[3] == 0) {
            return;
        }
        pass.set_pipeline(&self.draw.lit[usize::from(rs.surface.is_some())]);
        if let Some((vertices, _)) = &rs.surface {
            pass.set_vertex_buffer(0, vertices.slice(..));
        }
        pass.set_stencil_reference(0);
        let (b, local) = fb.batch_of(light);
        pass.set_bind_group(0, &b.d0, &[]);
        pass.set_bind_group(1, &b.dl, &[(local as u64 * LIGHT_STRIDE) as u32]);
        pass.draw(0..tris * 3, 0..1);
    }
}

/// The frame buffers of the last [`ShadowPass::update`] of `rs` and the scissor of its light
/// `light`, for the encoder `encoder`.
///
/// # Panics
/// Panics if `light` is not a light of that update, or if there was none.
fn light_frame<'r>(
    rs: &'r ResidentScene,
    light: usize,
    encoder: &str,
) -> (&'r FrameBuffers, Option<[u32; 4]>) {
    assert!(
        light < rs.state.lights,
        "light {light} of {}",
        rs.state.lights
    );
    let fb = rs
        .frame
        .as_ref()
        .unwrap_or_else(|| panic!("ShadowPass::update before {encoder}"));
    (fb, rs.state.scissors[light])
}
