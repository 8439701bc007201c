//! The footprint rule on a real raster: a soup of triangles each in a plane through its point
//! light (as written; `f32` rounding leaves each plane a hair off the light, so each casts a
//! shadow wedge far narrower than a pixel). The exact volumes shadow the odd pixel centre the
//! raster rounds into a wedge; the reference shadows no centre, and with the footprint rule
//! counts no artifact. Every pixel the rule moves lies within a pixel of a wedge, measured here
//! by projecting the soup onto the floor in `f64`. (The geometric count, with no 1/255
//! threshold, keeps the raster's z-fighting on the soup's own faces, each edge-on to the light:
//! the crate README of `shadowvol-reference` explains that count.) Skips visibly without a GPU
//! adapter.

mod common;
#[path = "../src/shot.rs"]
mod shot;

use glam::{Affine3A, DVec2, DVec3, Vec3};
use shadowvol_mesh_topology::Mesh;
use shadowvol_reference::{self as reference, Rule};
use shadowvol_renderer::{Accuracy, Camera, Light, RenderError, RenderOptions, Renderer, Scene};
use shadowvol_test_support::shapes::{distance_to_triangles, Lcg};
use shadowvol_test_support::{main, Outcome};
use std::fmt::Write as _;

main!(
    a_soup_through_its_light_leaves_no_artifact_pixel,
    json_counts_the_pixels_the_footprint_rule_moved
);

const LIGHT: [f32; 3] = [0.37, 6.1, -0.23];

/// `n` triangles over y = 0, each with one edge on a line through the light (in `f64`, before
/// the vertices are rounded to `f32`).
fn soup(n: usize) -> Vec<[Vec3; 3]> {
    let mut rng = Lcg(54);
    let l = Vec3::from(LIGHT).as_dvec3();
    (0..n)
        .map(|_| {
            let p0 = DVec3::new(
                rng.next_f64() * 6.0 - 3.0,
                0.5 + rng.next_f64() * 2.5,
                rng.next_f64() * 6.0 - 3.0,
            );
            let p1 = p0 + (p0 - l) * (0.05 + 0.1 * rng.next_f64());
            let d = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            );
            [p0, p1, p0 + d * 0.8].map(|p| p.as_vec3())
        })
        .collect()
}

/// The soup's shadows on the floor y = 0, projected from the light in `f64` (x, z).
fn wedges(soup: &[[Vec3; 3]]) -> Vec<[DVec2; 3]> {
    let l = Vec3::from(LIGHT).as_dvec3();
    soup.iter()
        .map(|t| {
            t.map(|v| {
                let v = v.as_dvec3();
                let p = l + (v - l) * (l.y / (l.y - v.y));
                DVec2::new(p.x, p.z)
            })
        })
        .collect()
}

fn soup_mesh(tris: &[[Vec3; 3]]) -> Mesh {
    Mesh {
        positions: tris.iter().flatten().copied().collect(),
        triangles: (0..tris.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect(),
    }
}

/// A floor y = 0 of two triangles, half-size 8.
fn floor() -> Mesh {
    let s = 8.0;
    Mesh {
        positions: vec![
            Vec3::new(-s, 0.0, -s),
            Vec3::new(-s, 0.0, s),
            Vec3::new(s, 0.0, s),
            Vec3::new(s, 0.0, -s),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

fn a_soup_through_its_light_leaves_no_artifact_pixel() -> Outcome {
    let tris = soup(400);
    let mut scene = Scene::new("soup");
    for (name, mesh) in [("floor", floor()), ("soup", soup_mesh(&tris))] {
        let table = scene.add_mesh(name, &mesh).expect("valid mesh");
        scene.add_object(name, table, Affine3A::IDENTITY);
    }
    scene.add_unit_lights([Light::point(Vec3::from(LIGHT))]);
    scene.camera = Some(Camera::look_at(
        Vec3::new(1.0, 9.0, 7.0),
        Vec3::new(0.0, 0.0, 0.0),
    ));
    scene.effects.ambient = 0.1;
    let size = 128;
    let mut opts = RenderOptions::new(size, size);
    opts.mode = Accuracy::Exact;
    let mut r = match Renderer::gpu(opts) {
        Ok(r) => r,
        Err(RenderError::NoAdapter(why) | RenderError::Unsupported(why)) => {
            return Err(shadowvol_test_support::skip(format!(
                "no GPU adapter for the GPU pipeline ({why}); install Mesa lavapipe"
            )))
        }
        Err(e) => panic!("renderer failed to start: {e}"),
    };
    let frame = r.render(&scene).expect("a frame");
    let shot = shot::shot(&frame, &scene).expect("a frame read back");
    let before = reference::compare_with(&shot, Rule::Neighbourhood);
    let after = reference::compare(&shot);
    eprintln!(
        "soup of 400 at {size}²: reference shadows {} centres; artifact pixels {} by the 3×3 \
         rule, {} with the footprint rule ({} moved); geometric {} -> {}",
        after.reference_shadow_pixels,
        before.artifact_pixels,
        after.artifact_pixels,
        after.footprint_boundary_pixels,
        before.geometric_artifact_pixels,
        after.geometric_artifact_pixels
    );
    assert_eq!(after.reference_shadow_pixels, 0);
    assert!(
        after.footprint_boundary_pixels > 0,
        "the raster rounds no centre into a wedge: the test shows nothing"
    );
    assert_eq!(after.artifact_pixels, 0, "{:?}", after.footprint_moved);
    assert_eq!(
        before.artifact_pixels,
        after.artifact_pixels + after.footprint_boundary_pixels
    );

    // Every moved pixel is on the floor, within a pixel of a wedge.
    let points = reference::surface_points(&shot);
    let w = size as usize;
    let on_floor = |i: usize| shot.ids[i][0] == 1;
    let wedges = wedges(&tris);
    let mut report = String::new();
    for &i in &after.footprint_moved {
        assert!(on_floor(i), "pixel {i} is not on the floor");
        let p = points[i].expect("covered").position;
        let width = [i + 1, i + w]
            .iter()
            .filter(|&&j| j < w * w && on_floor(j))
            .map(|&j| (points[j].expect("covered").position - p).length())
            .fold(f64::INFINITY, f64::min);
        let d = distance_to_triangles(DVec2::new(p.x, p.z), &wedges);
        let _ = write!(report, " {:.3}", d / width);
        assert!(d < width, "pixel {i}: {d} from a wedge, a pixel is {width}");
    }
    eprintln!("distance to the nearest wedge, in pixels:{report}");
    Ok(())
}

/// `render --reference --format json` reports the pixels the footprint rule moved, and
/// `artifact_pixels` plus that count is the count by the 3×3 rule alone.
fn json_counts_the_pixels_the_footprint_rule_moved() -> Outcome {
    let dir = std::env::temp_dir().join(format!("shadowvol-footprint-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("soup.obj");
    let mut text = String::new();
    for t in soup(400) {
        for v in t {
            let _ = writeln!(text, "v {:e} {:e} {:e}", v.x, v.y, v.z);
        }
    }
    for k in 0..400 {
        let _ = writeln!(text, "f {} {} {}", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    }
    std::fs::write(&obj, text).unwrap();
    let light = format!("--light={},{},{},1", LIGHT[0], LIGHT[1], LIGHT[2]);
    let (v, _) = common::json_ok(&[
        "render",
        obj.to_str().unwrap(),
        &light,
        "--mode",
        "exact",
        "--size",
        "128x128",
        "--reference",
        "--out",
        dir.join("soup.png").to_str().unwrap(),
        "--format",
        "json",
    ])?;
    let n = |k: &str| v[k].as_u64().unwrap_or_else(|| panic!("{k}: {v}"));
    eprintln!(
        "render soup.obj: artifact {}, footprint {}, boundary {}, geometric {} (footprint {})",
        n("artifact_pixels"),
        n("footprint_boundary_pixels"),
        n("boundary_pixels"),
        n("geometric_artifact_pixels"),
        n("geometric_footprint_boundary_pixels")
    );
    assert_eq!(n("reference_shadow_pixels"), 0);
    assert_eq!(n("artifact_pixels"), 0);
    assert!(n("footprint_boundary_pixels") <= n("boundary_pixels"));
    Ok(())
}
