//! Times the soft reference on a preset with a ground, the pixels' surfaces found by ray casting
//! (no renderer needed).
//!
//! `cargo run --release -p shadowvol-reference --example soft_reference -- [SCENE] [SIZE]
//! [RADIUS]`: `SCENE` a preset (default `bunny-subdivided`), `SIZE` the image's width and height
//! (default 256), `RADIUS` every light's radius as a share of the casters' bounding radius for
//! point lights, or in radians for directional ones (default 0.1). Prints the time and the
//! pixels' classes for the first light.

use glam::{DVec3, DVec4};
use shadowvol_reference::{visibility_reference, Bvh, Shot};
use shadowvol_scenes::{box_centre_radius, preset};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("bunny-subdivided", String::as_str);
    let size: u32 = args.get(1).map_or(Ok(256), |s| s.parse())?;
    let share: f32 = args.get(2).map_or(Ok(0.1), |s| s.parse())?;
    let mut scene = preset(name)?;
    let (lo, hi) = scene.bounds().ok_or("the scene has no vertices")?;
    if scene.ground_y().is_none() {
        scene.set_ground(Some(lo.y));
    }
    if scene.lights.is_empty() {
        return Err("the scene has no light".into());
    }
    let (_, bound_r) = box_centre_radius(lo, hi);
    let radius = if scene.lights[0].light.to_array()[3] == 0.0 {
        share
    } else {
        share * bound_r
    };
    scene.set_light_radius(radius)?;
    let camera = scene.camera_or_default().ok_or("no camera")?;
    println!(
        "{name}: {} triangles, light {:?}, radius {radius}, {size}²",
        scene.triangle_count(),
        scene.lights[0].light.to_array()
    );

    // The pixels' surfaces by ray casting every surface (casters and receivers).
    let t = Instant::now();
    let n = (size * size) as usize;
    let (rgba, stencil, colors) = (
        vec![0u8; 4 * n],
        vec![vec![0u8; n]; scene.lights.len()],
        vec![[1.0f32; 3]; scene.lights.len()],
    );
    let empty_ids = vec![[0u32; 2]; n];
    let probe = Shot::new(
        &scene, camera, size, size, &rgba, &empty_ids, &stencil, &colors,
    );
    let mut tris = Vec::new();
    let mut owner = Vec::new();
    for (si, obj) in probe.triangles().iter().enumerate() {
        for (ti, t) in obj.iter().enumerate() {
            tris.push(t.map(|p| p.as_dvec3()));
            owner.push([si as u32 + 1, ti as u32]);
        }
    }
    let bvh = Bvh::build(tris);
    let inv = camera.view_proj_f64(1.0).inverse();
    let eye = camera.eye.as_dvec3();
    let ids: Vec<[u32; 2]> = (0..n)
        .map(|i| {
            let (x, y) = (
                (i as u32 % size) as f64 + 0.5,
                (i as u32 / size) as f64 + 0.5,
            );
            let s = f64::from(size);
            let p = inv * DVec4::new(x / s * 2.0 - 1.0, 1.0 - y / s * 2.0, 0.5, 1.0);
            let dir: DVec3 = p.truncate() / p.w - eye;
            bvh.closest_hit(eye, dir).map_or([0, 0], |(k, _)| owner[k])
        })
        .collect();
    println!("ids by ray casting: {:.2?}", t.elapsed());

    let shot = Shot::new(&scene, camera, size, size, &rgba, &ids, &stencil, &colors);
    let disk = scene.lights[0]
        .disk(scene.light_aim())
        .ok_or("the light has no disk")?;
    let t = Instant::now();
    let reference = visibility_reference(&shot, 0, &disk);
    let took = t.elapsed();
    let covered: Vec<_> = reference.pixels.iter().flatten().collect();
    let count = |f: &dyn Fn(&&shadowvol_reference::Visibility) -> bool| {
        covered.iter().filter(|v| f(v)).count()
    };
    let penumbra = count(&|v| v.is_penumbra());
    let (lit, umbra) = (count(&|v| v.is_lit()), count(&|v| v.is_umbra()));
    let max_casters = covered.iter().map(|v| v.casters).max().unwrap_or(0);
    let mean_casters =
        covered.iter().map(|v| f64::from(v.casters)).sum::<f64>() / covered.len().max(1) as f64;
    let max_edges = covered.iter().map(|v| v.edges).max().unwrap_or(0);
    println!(
        "soft reference: {took:.2?} on {} threads; covered {}, lit {lit}, umbra {umbra}, \
         penumbra {penumbra}, undecided {}; largest bound {:e}; casters per pixel mean {mean_casters:.1}, \
         max {max_casters}; edges max {max_edges}",
        rayon::current_num_threads(),
        covered.len(),
        covered.len() - lit - umbra - penumbra,
        reference.max_bound(),
    );
    if let Some((i, v)) = reference
        .pixels
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.map(|v| (i, v)))
        .max_by(|a, b| a.1.bound.total_cmp(&b.1.bound))
    {
        println!(
            "largest bound at pixel ({}, {}): {v:?}",
            i as u32 % size,
            i as u32 / size
        );
    }
    Ok(())
}
