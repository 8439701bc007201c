//! What the pipeline targets share: the edge table of an arbitrary small mesh.

use glam::Vec3;
use shadowvol_mesh_topology::{EdgeTable, Mesh};

/// The edge table of the mesh of `positions` and `triangles`, each index taken modulo the
/// vertex count, or `None` where the mesh or its table is refused. `positions` is not empty.
#[allow(dead_code)]
pub fn edge_table(positions: Vec<Vec3>, triangles: &[[u8; 3]]) -> Option<EdgeTable> {
    let n = positions.len() as u32;
    let triangles = triangles
        .iter()
        .map(|t| t.map(|x| u32::from(x) % n))
        .collect();
    EdgeTable::build(&Mesh::new(positions, triangles).ok()?).ok()
}

/// Lets the loader catch the panics of the third-party decoder it guards (Draco, on a corrupted
/// stream; it reports them as errors): libFuzzer's panic hook aborts on every panic, caught or
/// not, so it is wrapped to stay silent while `shadowvol_scenes::in_guarded_decoder()` holds. Any
/// other panic still aborts, as a crash.
#[allow(dead_code)]
pub fn tolerate_guarded_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let abort = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !shadowvol_scenes::in_guarded_decoder() {
                abort(info);
            }
        }));
    });
}

/// Checks what a loaded scene promises: every object's table has finite positions, triangles
/// that index them, and edges within range. `what` names the loader in the message.
#[allow(dead_code)]
pub fn check_loaded(scene: &shadowvol_scenes::Scene, what: &str) {
    for o in &scene.geometry.objects {
        let t = &o.table;
        let n = t.positions.len();
        assert!(
            t.positions.iter().all(|p| p.is_finite()),
            "{what}: object {:?} has a non-finite position",
            o.name
        );
        assert!(
            t.triangles.iter().flatten().chain(t.edges.iter().flatten()).all(|&v| (v as usize) < n),
            "{what}: object {:?} indexes past its {n} positions",
            o.name
        );
    }
}
