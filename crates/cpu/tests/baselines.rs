//! The seeds' baseline algorithms against exact mode: on closed manifold meshes with lights in
//! general position, each returns exactly the edges with `m != 0` of `Accuracy::Exact`.

use glam::Vec3;
use shadowvol_cpu::baselines::{Baseline, BaselineError, ClosedMesh};
use shadowvol_cpu::extract_table;
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use shadowvol_robust_math::Accuracy;
use shadowvol_test_support::shapes::uv_sphere_y;

fn tetrahedron() -> Mesh {
    shadowvol_test_support::shapes::tetrahedron(1.0)
}

/// UV sphere of radius 1, outward winding, poles as fans (pole valence = `segments`).
fn uv_sphere(rings: u32, segments: u32) -> Mesh {
    uv_sphere_y(rings, segments, 1.0)
}

/// A torus (genus 1, every vertex valence 6): closed, manifold, not convex, so silhouettes have
/// several loops.
fn torus(major: u32, minor: u32) -> Mesh {
    let mut p = Vec::new();
    for i in 0..major {
        let u = std::f32::consts::TAU * i as f32 / major as f32;
        for j in 0..minor {
            let v = std::f32::consts::TAU * j as f32 / minor as f32;
            let r = 1.0 + 0.35 * v.cos();
            p.push(Vec3::new(r * u.cos(), 0.35 * v.sin(), r * u.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % major) * minor + (j % minor);
    let mut t = Vec::new();
    for i in 0..major {
        for j in 0..minor {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1));
            t.push([a, c, d]);
            t.push([a, d, b]);
        }
    }
    Mesh::new(p, t).unwrap()
}

fn lights() -> Vec<[f32; 4]> {
    vec![
        [3.1, 4.7, -2.3, 1.0],
        [-0.31, 1.13, 0.47, 0.0],
        [0.77, -2.9, 1.61, 1.0],
        [0.41, 0.05, 0.23, 1.0], // inside the sphere and the torus hole region
    ]
}

fn exact_silhouette(table: &EdgeTable, light: [f32; 4]) -> Vec<u32> {
    let mut m = vec![0; table.edges.len()];
    extract_table(table, light, Accuracy::Exact, &mut m);
    // Closed manifold: m is -2, 0 or 2.
    assert!(m.iter().all(|&x| x == 0 || x.abs() == 2));
    m.iter()
        .enumerate()
        .filter(|(_, &x)| x != 0)
        .map(|(e, _)| e as u32)
        .collect()
}

fn check(name: &str, mesh: &Mesh, hash8_fits: bool) {
    let table = EdgeTable::build(mesh).unwrap();
    let closed = ClosedMesh::new(&table).unwrap();
    let mut nonempty = 0;
    for light in lights() {
        let exact = exact_silhouette(&table, light);
        nonempty += usize::from(!exact.is_empty());
        for which in [
            Baseline::TwoStep,
            Baseline::Classic,
            Baseline::FastHash { columns: 64 },
            Baseline::FastHash { columns: 8 },
            Baseline::Connectivity,
        ] {
            match closed.run(which, light) {
                Ok(edges) => assert_eq!(
                    edges,
                    exact,
                    "{name}: {} disagrees with exact for light {light:?}",
                    which.name()
                ),
                Err(BaselineError::HashRowFull { columns: 8, .. }) if !hash8_fits => {}
                Err(e) => panic!("{name}: {} failed: {e}", which.name()),
            }
        }
    }
    assert!(nonempty >= 2, "{name}: the lights must produce silhouettes");
}

#[test]
fn tetrahedron_agrees_with_exact() {
    check("tetrahedron", &tetrahedron(), true);
}

#[test]
fn sphere_agrees_with_exact() {
    // Pole valence 7 (< 8 columns) and 40 (the 8-column table may overflow at the poles).
    check("sphere 9x7", &uv_sphere(9, 7), true);
    check("sphere 24x40", &uv_sphere(24, 40), false);
}

#[test]
fn torus_agrees_with_exact() {
    check("torus", &torus(48, 20), true);
}

#[test]
fn hash_table_overflow_is_an_error_naming_the_vertex() {
    // A pole of valence 40 with the light straight above it: all 40 fan triangles are lit.
    // Ordered so that the even fan triangles come first, 20 edges of the pole are open at once
    // and the pole's row of an 8-column table overflows.
    let mut mesh = uv_sphere(12, 40);
    // The first 80 triangles alternate north fan (s = 0..40) and south fan.
    let north: Vec<[u32; 3]> = mesh.triangles[..80].iter().step_by(2).copied().collect();
    let south = mesh.triangles[..80].iter().skip(1).step_by(2).copied();
    let mut reordered: Vec<[u32; 3]> = north.iter().step_by(2).copied().collect();
    reordered.extend(north.iter().skip(1).step_by(2));
    reordered.extend(south);
    reordered.extend_from_slice(&mesh.triangles[80..]);
    mesh.triangles = reordered;
    let table = EdgeTable::build(&mesh).unwrap();
    let closed = ClosedMesh::new(&table).unwrap();
    let light = [0.01, 10.0, 0.02, 1.0];
    let err = closed.fast_hash(light, 8).unwrap_err();
    assert!(
        matches!(err, BaselineError::HashRowFull { columns: 8, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("row of vertex"));
    assert_eq!(
        closed.fast_hash(light, 64).unwrap(),
        exact_silhouette(&table, light)
    );
    assert_eq!(
        closed.fast_hash(light, 0).unwrap_err(),
        BaselineError::NoColumns
    );
}

#[test]
fn open_or_misoriented_meshes_are_rejected() {
    // Open: a single triangle.
    let open =
        EdgeTable::build(&Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap())
            .unwrap();
    let err = ClosedMesh::new(&open).unwrap_err();
    assert!(
        matches!(err, BaselineError::NotClosedManifold { triangles: 1, .. }),
        "{err}"
    );
    // Misoriented: flip one face of the tetrahedron.
    let mut m = tetrahedron();
    m.triangles[2] = [1, 3, 2];
    let t = EdgeTable::build(&m).unwrap();
    let err = ClosedMesh::new(&t).unwrap_err();
    assert!(matches!(err, BaselineError::NotOriented { .. }), "{err}");
    assert!(err.to_string().contains("same direction"));
}
