//! CPU-only: how `shaders` composes the backend's WGSL module, its entry points and overrides,
//! and the WGSL constants equal the Rust ones the CPU twin uses. (Validation of every module is
//! the workspace's `tests/shaders.rs`.)

use shadowvol_gpu::shaders::{
    self, GPU_F32_INPUT_MAX, GPU_F32_PERM_MIN, GPU_F64_FILTER_EPS, TOUCH,
};
use shadowvol_robust_math::{F32_FILTER_EPS, F32_FILTER_MAX, F32_FILTER_MIN};
use shadowvol_silhouette::gpu::ExactFilter;

fn parse(name: &str, source: &str) -> naga::Module {
    naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string_with_path(source, name)))
}

fn has_function(module: &naga::Module, name: &str) -> bool {
    module
        .functions
        .iter()
        .any(|(_, f)| f.name.as_deref() == Some(name))
}

fn has_override(module: &naga::Module, name: &str) -> bool {
    module
        .overrides
        .iter()
        .any(|(_, o)| o.name.as_deref() == Some(name))
}

#[test]
fn the_f64_module_calls_the_f64_filter() {
    let src = shaders::module_source(ExactFilter::F64);
    assert!(src.contains("return filter_f64(a, b, l, o); // @exact-filter"));
    assert!(has_function(
        &parse("silhouette + exact_f64", &src),
        "filter_f64"
    ));
    let f32 = shaders::module_source(ExactFilter::F32);
    assert_eq!(f32, shaders::SILHOUETTE_WGSL);
    assert!(!has_function(&parse("silhouette", &f32), "filter_f64"));
}

#[test]
fn entry_points_and_overrides_exist() {
    let module = parse("silhouette", shaders::SILHOUETTE_WGSL);
    for entry in [
        shaders::ENTRY_POINT,
        shaders::TRIANGLE_ENTRY_POINT,
        shaders::RESOLVE_ENTRY_POINT,
    ] {
        let ep = module
            .entry_points
            .iter()
            .find(|e| e.name == entry)
            .unwrap_or_else(|| panic!("entry point {entry}"));
        assert_eq!(ep.stage, naga::ShaderStage::Compute);
        assert_eq!(ep.workgroup_size, [shaders::WORKGROUP_SIZE, 1, 1]);
    }
    assert!(has_override(&module, shaders::MODE_CONSTANT));
    assert!(has_override(&module, shaders::TOUCH_SIGNS_CONSTANT));
    assert!(has_override(&module, shaders::OV_VERTICES_CONSTANT));
    assert!(has_override(&module, shaders::SINGLE_OBJECT_CONSTANT));
    let exact = parse(
        "silhouette + exact_int",
        &shaders::module_source_with(ExactFilter::F32, true),
    );
    assert!(has_override(&exact, shaders::DEFER_INT_CONSTANT));
}

fn literal(module: &naga::Module, name: &str) -> naga::Literal {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("constant {name} not found"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(l) => l,
        ref other => panic!("constant {name} is not a literal: {other:?}"),
    }
}

#[test]
fn wgsl_constants_equal_the_rust_constants() {
    let m = parse("silhouette", shaders::SILHOUETTE_WGSL);
    assert_eq!(
        literal(&m, "F32_FILTER_EPS"),
        naga::Literal::F32(F32_FILTER_EPS)
    );
    assert_eq!(
        literal(&m, "F32_FILTER_MIN"),
        naga::Literal::F32(F32_FILTER_MIN)
    );
    assert_eq!(
        literal(&m, "F32_FILTER_MAX"),
        naga::Literal::F32(F32_FILTER_MAX)
    );
    assert_eq!(
        literal(&m, "F32_PERM_MIN"),
        naga::Literal::F32(GPU_F32_PERM_MIN)
    );
    assert_eq!(
        literal(&m, "F32_INPUT_MAX_BITS"),
        naga::Literal::U32(GPU_F32_INPUT_MAX.to_bits())
    );
    assert_eq!(
        literal(&m, "WORKGROUP_SIZE"),
        naga::Literal::U32(shaders::WORKGROUP_SIZE)
    );
    assert_eq!(literal(&m, "TOUCH"), naga::Literal::I32(TOUCH));
    let f = parse("exact_f64", shaders::EXACT_F64_WGSL);
    assert_eq!(
        literal(&f, "GPU_F64_FILTER_EPS"),
        naga::Literal::F64(GPU_F64_FILTER_EPS)
    );
}

#[test]
fn device_exact_modules_call_orient_int() {
    for filter in [ExactFilter::F32, ExactFilter::F64] {
        let src = shaders::module_source_with(filter, true);
        assert!(src.contains("return orient_int(a, b, l, o); // @exact-int"));
        assert!(!src.contains("return UNCERTAIN; // @exact-int"));
        assert!(has_function(
            &parse("silhouette + exact_int", &src),
            "orient_int"
        ));
        // Without the device fallback the module is the host-resolving one.
        assert_eq!(
            shaders::module_source_with(filter, false),
            shaders::module_source(filter)
        );
    }
}
