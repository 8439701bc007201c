//! CPU-only: every shader source in `shaders/` is valid, as production builds it. The one
//! validator of the workspace's shaders (OpenCL C in `kernels/` is built by the `opencl` crate's
//! device tests).
//!
//! * WGSL: every module the crates build (`shadowvol_gpu::shaders`, the renderer's
//!   raster shader and GPU-resident pass, `shadowvol_viewer::shaders`), composed by the crates'
//!   own functions, parses and validates with naga under the capabilities its device is asked
//!   for; and every `shaders/*.wgsl` file appears whole in at least one of them, so a file that
//!   no validated module includes fails the test.
//! * GLSL: every `shaders/*.{vert,geom,frag,comp}` compiles with `glslangValidator` once per
//!   SPIR-V file `cargo xtask shaders` makes of it, with the same definitions: the job list is
//!   xtask's own (`xtask/src/shaders.rs`, included below). Without glslangValidator the test is
//!   ignored with the reason, and fails under `CI=true`.
//! * WESL: `shaders/bevy_mask.wesl`, the Bevy plugin's material shader, imports Bevy's own PBR
//!   modules, so only Bevy's composer can validate it: `crates/bevy`'s headless test does (a
//!   broken shader draws nothing there, and the test fails). Here it must only exist, be named
//!   `bevy_*` and be read by that crate.
//! * Nothing else lives in `shaders/`: a file that is neither WGSL, the Bevy plugin's WESL, a
//!   GLSL stage nor the SPIR-V of a job fails the test.
//!
//! This test lives in the workspace test crate because that crate already depends on every crate
//! that builds shaders (through the CLI), so it sees the production compositions without a new
//! dependency edge, and `cargo test --workspace` runs it on every machine (no GPU needed).

// Only the job list and the compile command are used here (and xtask's own unit tests, which
// are not test functions in this harness-less binary, leave their imports unused).
#[allow(dead_code, unused_imports)]
#[path = "../xtask/src/shaders.rs"]
mod xtask_shaders;

use naga::valid::{Capabilities, ValidationFlags, Validator};
use shadowvol_gpu::shaders;
use shadowvol_renderer::resident;
use shadowvol_silhouette::gpu::ExactFilter;
use shadowvol_test_support::{main, skip, Outcome};
use shadowvol_viewer::shaders as viewer;
use std::path::{Path, PathBuf};

main!(
    every_wgsl_module_validates_as_composed,
    every_wgsl_file_is_in_a_validated_module,
    f64_modules_need_float64,
    every_glsl_source_compiles_for_each_spirv_file,
    shaders_holds_only_shader_sources_and_their_spirv,
);

/// One WGSL module as a crate builds it.
struct Module {
    /// Which crate builds it, and from what.
    name: String,
    /// The composed source.
    source: String,
    /// The capabilities its device is asked for (and no more).
    caps: Capabilities,
}

fn module(name: &str, source: impl Into<String>, caps: Capabilities) -> Module {
    Module {
        name: name.to_owned(),
        source: source.into(),
        caps,
    }
}

/// The capabilities a module with `filter` needs: `FLOAT64` for the `f64` filter only.
fn caps(filter: ExactFilter) -> Capabilities {
    match filter {
        ExactFilter::F64 => Capabilities::FLOAT64,
        ExactFilter::F32 => Capabilities::empty(),
    }
}

/// Every WGSL module production builds, composed by the crates' own functions.
fn modules() -> Vec<Module> {
    let mut all = Vec::new();
    for filter in [ExactFilter::F32, ExactFilter::F64] {
        let f = filter.name();
        for device_exact in [false, true] {
            all.push(module(
                &format!(
                    "wgpu-compute silhouette ({f} filter, exact {})",
                    if device_exact {
                        "on the device"
                    } else {
                        "on the host"
                    }
                ),
                shaders::module_source_with(filter, device_exact),
                caps(filter),
            ));
        }
        all.push(module(
            &format!("renderer resident extract ({f} filter)"),
            resident::extract_source(filter),
            caps(filter),
        ));
    }
    all.push(module(
        "renderer raster (shaders/render_raster.wgsl)",
        shadowvol_renderer::raster::RASTER_WGSL,
        Capabilities::empty(),
    ));
    all.push(module(
        "renderer resident draw",
        resident::draw_source(),
        Capabilities::empty(),
    ));
    all.push(module(
        "renderer shadow maps",
        shadowvol_renderer::maps::maps_source(),
        Capabilities::empty(),
    ));
    all.push(module(
        "renderer stencil bits (shaders/render_stencil_bits.wgsl)",
        shadowvol_renderer::raster::STENCIL_BITS_WGSL,
        Capabilities::empty(),
    ));
    all.push(module(
        "renderer soft lights (shaders/render_soft.wgsl)",
        shadowvol_renderer::raster::SOFT_WGSL,
        Capabilities::empty(),
    ));
    all.push(module(
        "viewer blit",
        viewer::BLIT_WGSL,
        Capabilities::empty(),
    ));
    all.push(module(
        "viewer volumes",
        viewer::VOLUMES_WGSL,
        Capabilities::empty(),
    ));
    // The Bevy plugin (outside the workspace) includes this file whole, as its resolve module.
    all.push(module(
        "bevy mask resolve (crates/bevy/src/render.rs)",
        include_str!("../shaders/bevy_mask_resolve.wgsl"),
        Capabilities::empty(),
    ));
    all
}

/// Parses and validates `source`; the error names the module and shows the source location.
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

/// The workspace's `shaders/` folder.
fn shader_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders")
}

/// The files of `shaders/` as `(name, path)`, sorted.
fn shader_files() -> Vec<(String, PathBuf)> {
    let mut files: Vec<(String, PathBuf)> = std::fs::read_dir(shader_dir())
        .expect("shaders/ exists")
        .map(|e| e.expect("a readable entry").path())
        .filter(|p| p.is_file())
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), p))
        .collect();
    files.sort();
    files
}

fn every_wgsl_module_validates_as_composed() {
    let failures: Vec<String> = modules()
        .iter()
        .filter_map(|m| validate(&m.name, &m.source, m.caps).err())
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

fn every_wgsl_file_is_in_a_validated_module() {
    let modules = modules();
    let mut wgsl = 0;
    let mut uncovered = Vec::new();
    for (name, path) in shader_files() {
        if !name.ends_with(".wgsl") {
            continue;
        }
        wgsl += 1;
        let text = std::fs::read_to_string(&path).expect("a readable shader");
        if !modules.iter().any(|m| m.source.contains(&text)) {
            uncovered.push(name);
        }
    }
    assert!(wgsl > 0, "no WGSL file found in {}", shader_dir().display());
    assert!(
        uncovered.is_empty(),
        "WGSL files in shaders/ that no validated module includes whole (add the module that \
         builds them to modules() in tests/shaders.rs, or rebuild if they changed): {}",
        uncovered.join(", ")
    );
}

/// The `f64` modules really contain the `f64` filter: without `FLOAT64` they do not validate.
fn f64_modules_need_float64() {
    for m in modules().iter().filter(|m| m.caps == Capabilities::FLOAT64) {
        validate(&m.name, &m.source, m.caps).unwrap();
        assert!(
            validate(&m.name, &m.source, Capabilities::empty()).is_err(),
            "{} validates without FLOAT64: it does not contain the f64 filter",
            m.name
        );
    }
}

fn every_glsl_source_compiles_for_each_spirv_file() -> Outcome {
    if std::process::Command::new("glslangValidator")
        .arg("--version")
        .output()
        .is_err()
    {
        return Err(skip(
            "glslangValidator is not installed (Debian/Ubuntu: apt-get install glslang-tools)",
        ));
    }
    let jobs = xtask_shaders::jobs(&shader_dir()).expect("the shader jobs");
    assert!(!jobs.is_empty(), "no GLSL shader found");
    let tmp = std::env::temp_dir().join(format!("shadowvol-shaders-test-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).expect("a temporary folder");
    let failures: Vec<String> = jobs
        .iter()
        .enumerate()
        .filter_map(|(i, job)| xtask_shaders::compile(job, &tmp.join(format!("{i}.spv"))).err())
        .collect();
    let _ = std::fs::remove_dir_all(&tmp);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    Ok(())
}

fn shaders_holds_only_shader_sources_and_their_spirv() {
    let jobs = xtask_shaders::jobs(&shader_dir()).expect("the shader jobs");
    let stray: Vec<String> = shader_files()
        .into_iter()
        .filter(|(name, path)| {
            let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
            let bevy_wesl = ext == "wesl" && name.starts_with("bevy_") && bevy_reads(name);
            let source = ext == "wgsl" || bevy_wesl || xtask_shaders::STAGES.contains(&ext);
            let spirv = jobs
                .iter()
                .any(|j| j.output.file_name() == Some(std::ffi::OsStr::new(name)));
            !source && !spirv
        })
        .map(|(name, _)| name)
        .collect();
    assert!(
        stray.is_empty(),
        "files in shaders/ that are neither WGSL, the Bevy plugin's WESL, a GLSL stage nor the \
         SPIR-V of a `cargo xtask shaders` job: {}",
        stray.join(", ")
    );
}

/// Whether a file of `crates/bevy/src` includes `shaders/NAME`.
fn bevy_reads(name: &str) -> bool {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../crates/bevy/src");
    std::fs::read_dir(&src).is_ok_and(|dir| {
        dir.flatten().any(|f| {
            std::fs::read_to_string(f.path())
                .is_ok_and(|text| text.contains(&format!("shaders/{name}\")")))
        })
    })
}
