//! The whole silhouette pipeline on arbitrary small meshes and lights: topology, then the CPU
//! reference backend in every consistent mode; the closed-chain invariant must hold.
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
    /// Small integer-ish coordinates plus a tiny perturbation, so degeneracies are common.
    verts: Vec<([i8; 3], [u8; 3])>,
    triangles: Vec<[u8; 3]>,
    light: [i8; 3],
    light_w: bool,
    light_jitter: [u8; 3],
}

fn coord(i: i8, j: u8) -> f32 {
    f32::from(i) + f32::from(j) * 2f32.powi(-20)
}

fuzz_target!(|input: Input| {
    if input.verts.is_empty() {
        return;
    }
    let positions: Vec<Vec3> = input
        .verts
        .iter()
        .map(|(i, j)| Vec3::new(coord(i[0], j[0]), coord(i[1], j[1]), coord(i[2], j[2])))
        .collect();
    let Some(table) = common::edge_table(positions, &input.triangles) else {
        return;
    };
    let l = input.light;
    let j = input.light_jitter;
    let w = if input.light_w { 1.0 } else { 0.0 };
    let Ok(light) = Light::new(coord(l[0], j[0]), coord(l[1], j[1]), coord(l[2], j[2]), w) else {
        return;
    };
    let scene = TopologyScene::single(table);
    let mut cpu = CpuBackend::new();
    for mode in [Accuracy::Robust, Accuracy::Ordered, Accuracy::Exact] {
        let (m, _) = extract_once(&mut cpu, &scene, &[light], mode).expect("cpu never fails");
        assert_eq!(
            invariant::open_vertices_scene(&scene, &m, 0),
            0,
            "{mode} opened the chain"
        );
        assert!(m.silhouettes_consistent());
    }
});
