//! Lists every preset with its size and how long it took to generate.
//!
//! `cargo run --release -p shadowvol-scenes --example presets`

fn main() -> Result<(), shadowvol_scenes::SceneError> {
    for info in shadowvol_scenes::presets() {
        if info.size.is_some() {
            // 10^7 triangles and more: run them alone (`shadowvol silhouette sphere-10m`).
            println!(
                "{:28} (not generated here)  {}",
                info.name, info.description
            );
            continue;
        }
        let t = std::time::Instant::now();
        let scene = shadowvol_scenes::preset(&info.name)?;
        let dt = t.elapsed();
        println!(
            "{:28} {:4} objects {:9} triangles {:2} lights  {:8.1} ms  {}",
            info.name,
            scene.geometry.objects.len(),
            scene.triangle_count(),
            scene.lights.len(),
            dt.as_secs_f64() * 1e3,
            info.description
        );
    }
    Ok(())
}
