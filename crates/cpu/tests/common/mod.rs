//! Shared helpers of the CPU backend's tests: the big-integer reference multiplicities.
#![allow(dead_code)]

#[path = "../../../robust-math/tests/oracle/mod.rs"]
pub mod oracle;

use shadowvol_mesh_topology::EdgeTable;
use shadowvol_silhouette::{object_lights, Light, Multiplicities, TopologyScene};

/// Reference multiplicities of the whole scene, light-major like [`Multiplicities`], computed
/// with the big-integer oracle only (no `shadowvol-robust-math` predicate involved) on the
/// object-space `f32` lights every backend receives.
pub fn reference(scene: &TopologyScene, lights: &[Light]) -> Vec<Vec<i32>> {
    let obj_lights = object_lights(scene.transforms(), lights);
    (0..lights.len())
        .map(|l| {
            scene
                .objects
                .iter()
                .enumerate()
                .flat_map(|(i, o)| table_reference(&o.table, obj_lights[i][l]))
                .collect()
        })
        .collect()
}

/// Reference multiplicities of one table for one object-space light.
pub fn table_reference(table: &EdgeTable, light: [f32; 4]) -> Vec<i32> {
    let positions: Vec<[f32; 3]> = table.positions.iter().map(|p| p.to_array()).collect();
    table
        .edges
        .iter()
        .enumerate()
        .map(|(e, &[a, b])| {
            let ovs: Vec<u32> = table.ovs_of(e).collect();
            oracle::multiplicity(&positions, a, b, &ovs, light)
        })
        .collect()
}

/// Panics with the first differing edge (object, edge names, values) if `m` differs from `want`.
pub fn assert_equals_reference(
    what: &str,
    scene: &TopologyScene,
    m: &Multiplicities,
    want: &[Vec<i32>],
) {
    assert_eq!(m.light_count(), want.len(), "{what}: light count");
    let offsets = scene.edge_offsets();
    for (l, w) in want.iter().enumerate() {
        let got = m.values(l);
        assert_eq!(got.len(), w.len(), "{what}: edge count");
        if let Some(e) = (0..w.len()).find(|&e| got[e] != w[e]) {
            let obj = offsets.iter().rposition(|&o| o <= e).unwrap();
            let local = e - offsets[obj];
            let names = scene.objects[obj].table.edge_names(local);
            panic!(
                "{what}: light {l}, object {obj}, edge {local} {names:?}: backend m = {}, oracle m = {}",
                got[e], w[e]
            );
        }
    }
}
