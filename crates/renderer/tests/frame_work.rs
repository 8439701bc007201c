//! A frame's host work once a scene is prepared. The GPU pipeline writes small inputs only: a
//! frame allocates as much on the host for a sphere of 80,000 triangles as for one of 320. The
//! host pipeline keeps its surfaces, buffers and silhouettes from frame to frame: a second frame
//! of a still scene allocates less than its silhouette's sides take, so nothing of the scene
//! (surfaces, multiplicities, volumes) is built, copied or uploaded again.
//!
//! Its own test binary: it counts every allocation of the process with a global allocator.
mod common;

use glam::{Affine3A, Vec3};
use shadowvol_renderer::{Camera, RenderOptions, Renderer, Scene};
use shadowvol_robust_math::Light;
use shadowvol_test_support::{main, Outcome};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

main!(
    gpu_pipeline_frames_allocate_the_same_for_small_and_large_scenes,
    host_pipeline_still_frames_allocate_less_than_their_silhouette_sides
);

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

/// Held by each test for its whole run: the counters are the process's, and the harness runs
/// tests on several threads.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

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
    let _alone = one_at_a_time();
    let opts = RenderOptions::new(96, 96);
    let (mut small, mut large) = (scene(320), scene(80_000));
    let mut gpu = common::gpu_renderer(opts)?;
    let (gs, gs_calls) = per_frame(&mut gpu, &mut small);
    let mut gpu = common::gpu_renderer(opts)?;
    let (gl, gl_calls) = per_frame(&mut gpu, &mut large);
    eprintln!(
        "per frame: gpu pipeline {gs} B in {gs_calls} allocations (320 triangles), {gl} B in \
         {gl_calls} (80,000)"
    );
    // The GPU pipeline writes the same small inputs whatever the scene's size.
    assert!(
        gl <= gs + gs / 4 + 4096 && gl_calls <= gs_calls + gs_calls / 4 + 16,
        "GPU pipeline: {gs} B in {gs_calls} allocations per frame for 320 triangles, {gl} B in \
         {gl_calls} for 80,000"
    );
    Ok(())
}

/// Bytes of volume vertices (4 `f32`s each) that `plan`'s side quads take: 6 vertices a quad
/// (a directional light's side triangles take 3, and are counted as 6 here too: no light of
/// this test is directional).
fn side_bytes(plan: &[shadowvol_renderer::PlanEntry]) -> u64 {
    let quads: usize = plan.iter().map(|e| e.side_quads).sum();
    (quads * 6 * std::mem::size_of::<[f32; 4]>()) as u64
}

/// Bytes allocated by one [`Renderer::render_timed`] of `scene`.
fn timed_frame_bytes(r: &mut Renderer, scene: &Scene) -> u64 {
    let b0 = BYTES.load(Ordering::Relaxed);
    r.render_timed(scene).expect("frame");
    BYTES.load(Ordering::Relaxed) - b0
}

fn host_pipeline_still_frames_allocate_less_than_their_silhouette_sides() -> Outcome {
    let _alone = one_at_a_time();
    let opts = RenderOptions::new(96, 96);
    let (small, large) = (scene(320), scene(80_000));
    let mut host = common::renderer_with(opts)?;
    let first = host.render(&large).expect("first frame");
    let sides = side_bytes(&first.report.plan);
    assert!(sides > 0, "the sphere casts a shadow");
    drop(first);
    let second = timed_frame_bytes(&mut host, &large);
    let later = timed_frame_bytes(&mut host, &large);
    let mut host_small = common::renderer_with(opts)?;
    host_small.render(&small).expect("first frame");
    timed_frame_bytes(&mut host_small, &small);
    let later_small = timed_frame_bytes(&mut host_small, &small);
    eprintln!(
        "host pipeline, still frames of 80,000 triangles: the second allocates {second} B, a \
         later one {later} B (320 triangles: {later_small} B); the first frame's silhouette \
         sides take {sides} B"
    );
    // Surfaces (15 MB of vertices), multiplicities (480 kB) or volumes built again would each
    // allocate at least the sides' bytes.
    assert!(
        second < sides,
        "host pipeline: the second still frame of 80,000 triangles allocates {second} B, not \
         less than the first frame's silhouette sides ({sides} B)"
    );
    assert!(
        later <= later_small + later_small / 4 + 4096,
        "host pipeline: a still frame allocates {later} B for 80,000 triangles, {later_small} B \
         for 320"
    );
    Ok(())
}
