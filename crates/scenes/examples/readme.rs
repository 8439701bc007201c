//! The example of README.md: a preset, a GLB round trip, exact silhouettes.
//!
//! `cargo run -p shadowvol-scenes --example readme`

use shadowvol_cpu::CpuBackend;
use shadowvol_scenes::{export_glb, load_gltf, preset};
use shadowvol_silhouette::{extract_once, invariant, Accuracy};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A preset: 100 instances of one 1,000-triangle icosphere, one point light.
    let scene = preset("spheres-100x1k")?;
    assert_eq!(scene.triangle_count(), 100_000);

    // Write it as glTF and read it back: the same scene, bit for bit.
    let path = std::env::temp_dir().join("spheres-100x1k.glb");
    export_glb(&scene, &path)?;
    let loaded = load_gltf(&path)?;
    assert_eq!(loaded.light_positions(), scene.light_positions());

    // Exact silhouettes of the loaded scene on the reference backend: the chains close.
    let (m, _) = extract_once(
        &mut CpuBackend::new(),
        &loaded.geometry,
        &loaded.light_positions(),
        Accuracy::Exact,
    )?;
    assert_eq!(invariant::open_vertices_scene(&loaded.geometry, &m, 0), 0);
    println!("{} silhouette edges", m.silhouette(0).len());
    Ok(())
}
