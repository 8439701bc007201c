//! Differential fuzzing of the `simd` backend against the `cpu` reference on arbitrary small
//! meshes (several objects' worth of near-degenerate coordinates, non-manifold edges, welded
//! duplicates) and several lights in one call: exact mode must be bit-identical to `cpu`, and
//! robust and ordered must keep every chain closed. Lane tails, light batching and thread
//! splitting are what this exercises beyond the `pipeline` target.
#![no_main]
use arbitrary::Arbitrary;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use shadowvol_cpu::CpuBackend;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_silhouette::{extract_once, invariant, TopologyScene};

mod common;

#[derive(Arbitrary, Debug)]
struct Input {
    /// Small integer coordinates plus a tiny perturbation (2^-20 steps), or a scale exponent
    /// that takes them far from 1 (tiny or huge, subnormal included).
    verts: Vec<([i8; 3], [u8; 3])>,
    scale_exp: i8,
    triangles: Vec<[u8; 3]>,
    lights: Vec<([i8; 3], [u8; 3], bool)>,
}

fn coord(i: i8, j: u8, scale: f32) -> f32 {
    (f32::from(i) + f32::from(j) * 2f32.powi(-20)) * scale
}

fuzz_target!(|input: Input| {
    if input.verts.is_empty() || input.lights.is_empty() || input.lights.len() > 16 {
        return;
    }
    let scale = 2f32.powi(i32::from(input.scale_exp).clamp(-140, 100));
    let positions: Vec<Vec3> = input
        .verts
        .iter()
        .map(|(i, j)| {
            Vec3::new(
                coord(i[0], j[0], scale),
                coord(i[1], j[1], scale),
                coord(i[2], j[2], scale),
            )
        })
        .collect();
    let Some(table) = common::edge_table(positions, &input.triangles) else {
        return;
    };
    let lights: Vec<Light> = input
        .lights
        .iter()
        .filter_map(|(l, j, point)| {
            let w = if *point { 1.0 } else { 0.0 };
            Light::new(
                coord(l[0], j[0], scale),
                coord(l[1], j[1], scale),
                coord(l[2], j[2], scale),
                w,
            )
            .ok()
        })
        .collect();
    if lights.is_empty() {
        return;
    }
    let scene = TopologyScene::single(table);
    let mut cpu = CpuBackend::new();
    let mut simd = shadowvol_simd::create_backend().expect("simd starts on any x86-64/aarch64");
    let (reference, _) =
        extract_once(&mut cpu, &scene, &lights, Accuracy::Exact).expect("cpu never fails");
    let (exact, _) =
        extract_once(simd.as_mut(), &scene, &lights, Accuracy::Exact).expect("simd exact");
    assert_eq!(
        exact.all_values(),
        reference.all_values(),
        "simd exact != cpu exact"
    );
    assert!(exact.silhouettes_consistent());
    for mode in [Accuracy::Robust, Accuracy::Ordered] {
        let (m, _) = extract_once(simd.as_mut(), &scene, &lights, mode).expect("simd");
        for l in 0..lights.len() {
            assert_eq!(
                invariant::open_vertices_scene(&scene, &m, l),
                0,
                "simd {mode} opened the chain for light {l}"
            );
        }
        assert!(m.silhouettes_consistent());
    }
});
