//! Exploration helper (ignored): artifact counts of every hard scene in every mode.
mod common;
use shadowvol_renderer::{hard, reference};
use shadowvol_robust_math::Accuracy;

#[test]
#[ignore]
fn explore() {
    let Some(mut r) = common::renderer(128, 128, Accuracy::Exact) else {
        return;
    };
    let only = std::env::var("SV_ONLY").ok();
    let mut scenes = vec![
        ("frustum".to_string(), hard::edge_on_frustum()),
        ("bunny".to_string(), hard::bunny_offset(1e4).unwrap()),
        ("sphere".to_string(), hard::uv_sphere_pole(2000)),
    ];
    for n in hard::hard_preset_names() {
        scenes.push((n.clone(), hard::hard_preset(&n).unwrap()));
    }
    for (name, scene) in &scenes {
        if only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        for mode in Accuracy::ALL {
            let mut o = r.options();
            o.mode = mode;
            r.set_options(o);
            let f = r.render(scene).unwrap();
            let c = reference::compare(&f);
            println!(
                "{name} {mode}: artifacts {} differing {} shadow {} ref {} covered {}",
                c.artifact_pixels,
                c.differing_pixels,
                c.shadow_pixels,
                c.reference_shadow_pixels,
                c.covered_pixels
            );
            f.save_png(format!("/tmp/sv_{name}_{mode}.png")).unwrap();
            reference::diff_image(&f, &c)
                .save(format!("/tmp/sv_{name}_{mode}_diff.png"))
                .unwrap();
        }
    }
}

#[test]
#[ignore]
fn explore_sphere_open_vertices() {
    use shadowvol_silhouette::{extract_once, invariant, SceneObject, TopologyScene};
    for tris in [2000usize, 8000, 20000] {
        let s = hard::uv_sphere_pole(tris);
        let table = shadowvol_mesh_topology::EdgeTable::build(&s.objects[0].mesh).unwrap();
        let scene = TopologyScene {
            objects: vec![SceneObject {
                name: "s".into(),
                table: std::sync::Arc::new(table),
                world_from_object: glam::Affine3A::IDENTITY,
            }],
        };
        for mode in Accuracy::ALL {
            let mut cpu = shadowvol_cpu::CpuBackend::new();
            let (m, _) = extract_once(&mut cpu, &scene, &s.lights, mode).unwrap();
            let open = invariant::open_vertices_scene(&scene, &m, 0);
            let sil = m.silhouette(0).len();
            println!(
                "sphere {tris} light {:?} {mode}: open {open}, silhouette edges {sil}",
                s.lights[0]
            );
        }
    }
    let s = hard::bunny_offset(1e4).unwrap();
    let table = shadowvol_mesh_topology::EdgeTable::build(&s.objects[0].mesh).unwrap();
    let scene = TopologyScene {
        objects: vec![SceneObject {
            name: "s".into(),
            table: std::sync::Arc::new(table),
            world_from_object: glam::Affine3A::IDENTITY,
        }],
    };
    for mode in Accuracy::ALL {
        let mut cpu = shadowvol_cpu::CpuBackend::new();
        let (m, _) = extract_once(&mut cpu, &scene, &s.lights, mode).unwrap();
        println!(
            "bunny {mode}: open {}",
            invariant::open_vertices_scene(&scene, &m, 0)
        );
    }
}
