//! CPU-only: every WGSL file in `shaders/` parses and validates with naga, the modules the backend
//! builds validate with exactly the capabilities they use, and the WGSL constants equal the Rust
//! ones the CPU twin uses.

use naga::valid::{Capabilities, ValidationFlags, Validator};
use shadowvol_robust_math::{F32_FILTER_EPS, F32_FILTER_MAX, F32_FILTER_MIN};
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_wgpu_compute::shaders::{
    self, GPU_F32_INPUT_MAX, GPU_F32_PERM_MIN, GPU_F64_FILTER_EPS,
};
use std::path::PathBuf;

fn shader_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shaders")
}

fn validate(name: &str, source: &str, caps: Capabilities) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| {
        format!(
            "{name}: parse error:\n{}",
            e.emit_to_string_with_path(source, name)
        )
    })?;
    Validator::new(ValidationFlags::all(), caps)
        .validate(&module)
        .map_err(|e| {
            format!(
                "{name}: validation error:\n{}",
                e.emit_to_string_with_path(source, name)
            )
        })?;
    Ok(module)
}

/// The capabilities each of this crate's files needs (and no more).
fn own_caps(name: &str) -> Option<Capabilities> {
    match name {
        "silhouette.wgsl" => Some(Capabilities::empty()),
        "exact_f64.wgsl" => Some(Capabilities::FLOAT64),
        _ => None,
    }
}

#[test]
fn every_wgsl_file_in_shaders_validates() {
    let mut checked = 0;
    let mut failures = Vec::new();
    let entries = std::fs::read_dir(shader_dir()).expect("shaders/ exists");
    for entry in entries {
        let path = entry.expect("readable dir entry").path();
        if path.extension().and_then(|e| e.to_str()) != Some("wgsl") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let source = std::fs::read_to_string(&path).expect("readable shader");
        // Files of other crates (the renderer's) are validated with every capability naga has;
        // ours with exactly what the device is asked for.
        let caps = own_caps(&name).unwrap_or(Capabilities::all());
        if let Err(e) = validate(&name, &source, caps) {
            failures.push(e);
        }
        checked += 1;
    }
    assert!(checked >= 3, "found only {checked} WGSL files");
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn embedded_sources_are_the_files_on_disk() {
    for (name, embedded) in [
        ("silhouette.wgsl", shaders::SILHOUETTE_WGSL),
        ("exact_f64.wgsl", shaders::EXACT_F64_WGSL),
        ("exact_int.wgsl", shaders::EXACT_INT_WGSL),
    ] {
        let on_disk = std::fs::read_to_string(shader_dir().join(name)).expect("file exists");
        assert_eq!(
            on_disk, embedded,
            "{name} differs from the embedded copy (rebuild the crate)"
        );
    }
}

#[test]
fn f32_module_needs_no_capability() {
    let src = shaders::module_source(ExactFilter::F32);
    validate("silhouette (f32 filter)", &src, Capabilities::empty()).unwrap();
}

#[test]
fn f64_module_validates_with_float64_and_fails_without() {
    let src = shaders::module_source(ExactFilter::F64);
    let module = validate("silhouette + exact_f64", &src, Capabilities::FLOAT64).unwrap();
    // The composed module really calls the f64 filter ...
    assert!(src.contains("return filter_f64(a, b, l, o); // @exact-filter"));
    assert!(module
        .functions
        .iter()
        .any(|(_, f)| f.name.as_deref() == Some("filter_f64")));
    // ... and therefore cannot be built without SHADER_F64.
    assert!(validate("silhouette + exact_f64", &src, Capabilities::empty()).is_err());
}

#[test]
fn entry_point_and_mode_override_exist() {
    let module = naga::front::wgsl::parse_str(shaders::SILHOUETTE_WGSL).unwrap();
    let ep = module
        .entry_points
        .iter()
        .find(|e| e.name == shaders::ENTRY_POINT)
        .expect("entry point");
    assert_eq!(ep.stage, naga::ShaderStage::Compute);
    assert_eq!(ep.workgroup_size, [shaders::WORKGROUP_SIZE, 1, 1]);
    assert!(module
        .overrides
        .iter()
        .any(|(_, o)| o.name.as_deref() == Some(shaders::MODE_CONSTANT)));
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
fn wgsl_constants_equal_the_twin_constants() {
    let m = naga::front::wgsl::parse_str(shaders::SILHOUETTE_WGSL).unwrap();
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
    let f = naga::front::wgsl::parse_str(shaders::EXACT_F64_WGSL).unwrap();
    assert_eq!(
        literal(&f, "GPU_F64_FILTER_EPS"),
        naga::Literal::F64(GPU_F64_FILTER_EPS)
    );
}

#[test]
fn device_exact_modules_validate_and_call_orient_int() {
    for (filter, caps) in [
        (ExactFilter::F32, Capabilities::empty()),
        (ExactFilter::F64, Capabilities::FLOAT64),
    ] {
        let src = shaders::module_source_with(filter, true);
        assert!(src.contains("return orient_int(a, b, l, o); // @exact-int"));
        assert!(!src.contains("return UNCERTAIN; // @exact-int"));
        let module = validate("silhouette + exact_int", &src, caps).unwrap();
        assert!(module
            .functions
            .iter()
            .any(|(_, f)| f.name.as_deref() == Some("orient_int")));
        // Without the device fallback the module is the host-resolving one.
        assert_eq!(
            shaders::module_source_with(filter, false),
            shaders::module_source(filter)
        );
    }
}
