//! What the pipeline targets share: the edge table of an arbitrary small mesh.

use glam::Vec3;
use shadowvol_mesh_topology::{EdgeTable, Mesh};

/// The edge table of the mesh of `positions` and `triangles`, each index taken modulo the
/// vertex count, or `None` where the mesh or its table is refused. `positions` is not empty.
pub fn edge_table(positions: Vec<Vec3>, triangles: &[[u8; 3]]) -> Option<EdgeTable> {
    let n = positions.len() as u32;
    let triangles = triangles
        .iter()
        .map(|t| t.map(|x| u32::from(x) % n))
        .collect();
    EdgeTable::build(&Mesh::new(positions, triangles).ok()?).ok()
}
