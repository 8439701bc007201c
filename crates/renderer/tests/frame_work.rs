//! The GPU pipeline's per-frame host work is writing small inputs only: once a scene is prepared,
//! a frame allocates as much on the host for a sphere of 80,000 triangles as for one of 320, so
//! nothing of the scene is converted, copied or uploaded per frame. The host pipeline, which
//! builds its surfaces and volumes on the host every frame, shows the counter can tell.
//!
//! Its own test binary: it counts every allocation of the process with a global allocator.
mod common;

use glam::{Affine3A, Vec3};
use shadowvol_renderer::{Camera, RenderOptions, Renderer, Scene};
use shadowvol_robust_math::Light;
use shadowvol_test_support::{main, Outcome};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

main!(gpu_pipeline_frames_allocate_the_same_for_small_and_large_scenes);

/// Bytes and calls of every allocation in the process.
struct Counting;

static BYTES: AtomicU64 = AtomicU64::new(0);
static CALLS: AtomicU64 = AtomicU64::new(0);

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        BYTES.fetch_add(layout.size() as u64, Ordering::Relaxed);
        CALLS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        BYTES.fetch_add(new_size as u64, Ordering::Relaxed);
        CALLS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A sphere of `triangles` over a floor, one point light, seen from above.
fn scene(triangles: usize) -> Scene {
    let sphere = shadowvol_scenes::procedural::icosphere(triangles, 1.0);
    let mut s = common::scene_of(
        vec![
            ("floor", common::floor(5.0, 2), Affine3A::IDENTITY),
            ("sphere", sphere, Affine3A::from_translation(Vec3::Y * 1.5)),
        ],
        &[Light::point(Vec3::new(2.0, 6.0, 1.0))],
        Camera::look_at(Vec3::new(4.0, 6.0, 7.0), Vec3::ZERO),
        0.15,
    );
    s.effects.ambient = 0.15;
    s
}

/// Allocated bytes and calls per frame over 8 frames of `scene` with the light moving on a
/// circle (so every frame re-extracts), after 3 frames of warm-up.
fn per_frame(r: &mut Renderer, scene: &mut Scene) -> (u64, u64) {
    let mut frame = |k: u32| {
        let a = k as f32 * 0.1;
        scene.lights[0].light = Light::point(Vec3::new(2.0 * a.cos(), 6.0, 2.0 * a.sin()));
        r.render_timed(scene).expect("frame");
    };
    for k in 0..3 {
        frame(k);
    }
    let (b0, c0) = (BYTES.load(Ordering::Relaxed), CALLS.load(Ordering::Relaxed));
    for k in 3..11 {
        frame(k);
    }
    let (b1, c1) = (BYTES.load(Ordering::Relaxed), CALLS.load(Ordering::Relaxed));
    ((b1 - b0) / 8, (c1 - c0) / 8)
}

fn gpu_pipeline_frames_allocate_the_same_for_small_and_large_scenes() -> Outcome {
    let opts = RenderOptions::new(96, 96);
    let (mut small, mut large) = (scene(320), scene(80_000));
    let mut gpu = common::gpu_renderer(opts)?;
    let (gs, gs_calls) = per_frame(&mut gpu, &mut small);
    let mut gpu = common::gpu_renderer(opts)?;
    let (gl, gl_calls) = per_frame(&mut gpu, &mut large);
    let mut host = common::renderer_with(opts)?;
    let (hs, _) = per_frame(&mut host, &mut small);
    let mut host = common::renderer_with(opts)?;
    let (hl, _) = per_frame(&mut host, &mut large);
    eprintln!(
        "per frame: gpu pipeline {gs} B in {gs_calls} allocations (320 triangles), {gl} B in \
         {gl_calls} (80,000); host pipeline {hs} B, {hl} B"
    );
    // The host pipeline rebuilds surfaces (and volumes) every frame: 250 times the triangles,
    // far more bytes. The counter sees per-frame work that grows with the scene.
    assert!(hl > 20 * hs, "host pipeline: {hs} B then {hl} B per frame");
    // The GPU pipeline writes the same small inputs whatever the scene's size.
    assert!(
        gl <= gs + gs / 4 + 4096 && gl_calls <= gs_calls + gs_calls / 4 + 16,
        "GPU pipeline: {gs} B in {gs_calls} allocations per frame for 320 triangles, {gl} B in \
         {gl_calls} for 80,000"
    );
    Ok(())
}
