//! The renderer is backend-agnostic: in exact mode the `simd` backend's multiplicities are
//! bit-identical to the `cpu` backend's, so the stencil (shadow) masks must be identical too.
mod common;

use shadowvol_renderer::{hard, RenderOptions, Renderer};
use shadowvol_robust_math::Accuracy;
use shadowvol_test_support::{main, Outcome};

main!(simd_and_cpu_give_identical_stencils_in_exact_mode);

fn simd_and_cpu_give_identical_stencils_in_exact_mode() -> Outcome {
    let mut cpu = common::renderer(96, 96, Accuracy::Exact)?;
    let simd = shadowvol_simd::create_backend().expect("the simd backend always starts");
    let mut simd = Renderer::host(simd, RenderOptions::new(96, 96)).unwrap();
    let scenes = [
        hard::edge_on_frustum().unwrap(),
        hard::bunny_offset(1e4).unwrap(),
        hard::hard_preset("hard-multi-object-transforms").unwrap(),
        hard::hard_preset("hard-book-4").unwrap(),
    ];
    for scene in &scenes {
        let a = cpu.render(scene).unwrap();
        let b = simd.render(scene).unwrap();
        assert_eq!(
            a.image.as_ref().unwrap().stencil,
            b.image.as_ref().unwrap().stencil,
            "{}",
            a.report.explain()
        );
        assert_eq!(
            a.image.as_ref().unwrap().rgba,
            b.image.as_ref().unwrap().rgba
        );
        assert!(
            a.image
                .as_ref()
                .unwrap()
                .stencil
                .iter()
                .flatten()
                .any(|&s| s != 0),
            "the scene has shadows"
        );
    }
    Ok(())
}
