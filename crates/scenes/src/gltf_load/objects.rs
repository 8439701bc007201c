//! The second phase of a load: each mesh's edge table, built after the file's buffers are
//! freed, and the scene objects of the nodes that use it.
//!
//! The walk reads every mesh into a [`Mesh`] and records each node that uses one as a
//! [`PendingObject`]. Only then are the buffers dropped and the tables built, one mesh at a time,
//! each mesh freed as its table is built: the file's bytes, the read meshes and the tables are
//! never all held at once. The objects, their notes and their errors come in the walk's order.

use crate::scene::{apply_f32, Scene};
use crate::SceneError;
use glam::Affine3A;
use shadowvol_mesh_topology::{EdgeTable, Mesh};
use std::collections::HashMap;
use std::sync::Arc;

/// A node with a mesh, recorded by the walk.
pub(super) struct PendingObject {
    /// How messages name the node (`node 3 'wheel'`).
    pub(super) label: String,
    /// The object's name in the scene.
    pub(super) name: String,
    /// The glTF mesh index.
    pub(super) mesh: usize,
    /// The mesh as read, on the first node that uses it; `None` on the nodes that share it.
    pub(super) read: Option<Mesh>,
    /// The node's world transform.
    pub(super) world: Affine3A,
    /// How many notes the walk had written when it reached the node: where the node's own note
    /// (a mesh without triangles) goes.
    pub(super) note_at: usize,
}

/// Builds the tables of `pending`'s meshes and adds their objects to `scene`, in order; a node
/// whose mesh has no triangles is skipped with a note, inserted into `notes` where the walk
/// reached it.
///
/// # Errors
/// [`SceneError::Mesh`] when a mesh's table cannot be built, [`SceneError::Gltf`] when a node's
/// transform takes a vertex past `f32`'s range.
pub(super) fn add_objects(
    source_name: &str,
    pending: Vec<PendingObject>,
    scene: &mut Scene,
    notes: &mut Vec<String>,
) -> Result<(), SceneError> {
    let mut tables: HashMap<usize, Arc<EdgeTable>> = HashMap::new();
    let mut own_notes: Vec<(usize, String)> = Vec::new();
    for mut o in pending {
        let table = match (o.read.take(), tables.get(&o.mesh)) {
            (Some(mesh), _) => {
                // The mesh is freed as its table is built.
                let t = EdgeTable::build_owned(mesh).map_err(|source| SceneError::Mesh {
                    what: format!("{source_name}: {}, mesh {}", o.label, o.mesh),
                    source,
                })?;
                let t = Arc::new(t);
                tables.insert(o.mesh, Arc::clone(&t));
                t
            }
            (None, Some(t)) => Arc::clone(t),
            (None, None) => {
                return Err(gltf_error(
                    source_name,
                    format!("{}, mesh {}", o.label, o.mesh),
                    "the mesh was not read before its first use (a loader bug)",
                ))
            }
        };
        if table.stats.triangles == 0 {
            own_notes.push((
                o.note_at,
                format!(
                    "{source_name}: {}: mesh {} has no triangles, the node is skipped",
                    o.label, o.mesh
                ),
            ));
            continue;
        }
        check_world_range(source_name, &o, &table)?;
        scene.add_object(o.name, table, o.world);
    }
    merge_notes(notes, own_notes);
    Ok(())
}

/// A finite transform can still scale finite positions past `f32`'s range: the first vertex it
/// does is an error.
fn check_world_range(
    source_name: &str,
    o: &PendingObject,
    table: &EdgeTable,
) -> Result<(), SceneError> {
    let overflow = table.positions.iter().enumerate().find_map(|(v, &p)| {
        let w = apply_f32(&o.world, p).to_array();
        (0..3).find(|&k| !w[k].is_finite()).map(|k| (v, k, w[k]))
    });
    match overflow {
        None => Ok(()),
        Some((v, k, value)) => {
            let axis = ['x', 'y', 'z'][k];
            Err(gltf_error(
                source_name,
                format!("{}, mesh {}", o.label, o.mesh),
                format!(
                    "vertex {v}: in world space, coordinate {axis} is {value}, but positions \
                     must be finite (the world transform takes it past the f32 range)"
                ),
            ))
        }
    }
}

/// Inserts each `(at, note)` of `own` (ascending `at`) after the first `at` notes of `notes`.
fn merge_notes(notes: &mut Vec<String>, own: Vec<(usize, String)>) {
    if own.is_empty() {
        return;
    }
    let walk = std::mem::take(notes);
    let mut walk = walk.into_iter().enumerate().peekable();
    for (at, note) in own {
        while let Some((_, n)) = walk.next_if(|(i, _)| *i < at) {
            notes.push(n);
        }
        notes.push(note);
    }
    notes.extend(walk.map(|(_, n)| n));
}

fn gltf_error(source_name: &str, context: String, message: impl Into<String>) -> SceneError {
    SceneError::Gltf {
        file: source_name.to_owned(),
        context,
        message: message.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::merge_notes;

    #[test]
    fn notes_are_merged_where_the_walk_reached_them() {
        let mut notes: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let own = vec![
            (0, "x".to_owned()),
            (2, "y".to_owned()),
            (2, "z".to_owned()),
        ];
        merge_notes(&mut notes, own);
        assert_eq!(notes, ["x", "a", "b", "y", "z", "c"]);
        let mut notes: Vec<String> = vec!["a".to_owned()];
        merge_notes(&mut notes, vec![(1, "x".to_owned())]);
        assert_eq!(notes, ["a", "x"]);
    }
}
