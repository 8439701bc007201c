//! The main world's side: marked casters, lights and camera become shadowvol's scene model
//! (built again only when the casters' meshes change) and small per-frame inputs, which the
//! render world copies each frame.

use std::collections::HashMap;
use std::sync::Arc;

use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use bevy::render::{Extract, ExtractSchedule, RenderApp};
use bevy::transform::TransformSystems;
use shadowvol_mesh_topology::Mesh as TopoMesh;
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::Scene;

use crate::{ShadowCaster, ShadowVolumeLight, ShadowVolumeStats, ShadowVolumes, Side, MAX_LIGHTS};

/// A marked light as the pass and the material see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct VolumeLight {
    /// shadowvol's homogeneous light: position (`w = 1`) or direction towards it (`w = 0`).
    pub light: Light,
    /// The light-table texel: position or direction, `w` = 1 point or spot, 2 directional.
    pub texel: [f32; 4],
}

/// Everything the pass needs from the main world, copied into the render world each frame.
#[derive(Resource, Debug, Clone, Default)]
pub(crate) struct VolumeFrame {
    /// The casters' scene model; `None` until the first caster's mesh is read.
    pub scene: Option<Arc<Scene>>,
    /// Bumped each time `scene` is rebuilt: the render world prepares again when it changes.
    pub generation: u64,
    /// The marked (entity, mesh) pairs `scene` was built from.
    key: Vec<(Entity, AssetId<Mesh>)>,
    /// Which entity each scene object is (the marked casters whose meshes could be read).
    objects: Vec<Entity>,
    /// The casters left out of `scene`, and why: reported every frame until the next build.
    left_out: Vec<String>,
    /// Per scene object: world from object, this frame.
    pub transforms: Vec<glam::Affine3A>,
    /// The marked lights, by entity, at most [`MAX_LIGHTS`].
    pub lights: Vec<VolumeLight>,
    /// The camera that gets the masks, and its mode.
    pub camera: Option<(Entity, Accuracy)>,
    /// Shared with the render world.
    pub stats: ShadowVolumeStats,
}

pub(crate) fn build(app: &mut App) {
    let stats = ShadowVolumeStats::default();
    app.insert_resource(stats.clone())
        .insert_resource(VolumeFrame { stats, ..default() })
        .add_systems(
            PostUpdate,
            (disable_shadow_maps, propagate_casters, gather)
                .chain()
                .after(TransformSystems::Propagate),
        );
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app.add_systems(ExtractSchedule, extract_frame);
    }
}

fn extract_frame(mut commands: Commands, frame: Extract<Res<VolumeFrame>>) {
    commands.insert_resource(frame.clone());
}

/// Marked entities that were just marked or whose children changed.
type NewCasterRoots<'w, 's> = Query<
    'w,
    's,
    Entity,
    (
        With<ShadowCaster>,
        Or<(Added<ShadowCaster>, Changed<Children>)>,
    ),
>;

/// [`ShadowCaster`] on an entity marks the meshes below it too (a glTF scene's root, say), when
/// it is added and whenever the entity's children change.
fn propagate_casters(
    mut commands: Commands,
    roots: NewCasterRoots,
    children: Query<&Children>,
    unmarked: Query<(), (With<Mesh3d>, Without<ShadowCaster>)>,
) {
    for root in &roots {
        for e in children.iter_descendants(root) {
            if unmarked.contains(e) {
                commands.entity(e).insert(ShadowCaster);
            }
        }
    }
}

/// Marked lights draw no Bevy shadow maps: the volumes replace them.
fn disable_shadow_maps(
    mut points: Query<&mut PointLight, With<ShadowVolumeLight>>,
    mut spots: Query<&mut SpotLight, With<ShadowVolumeLight>>,
    mut suns: Query<&mut DirectionalLight, With<ShadowVolumeLight>>,
) {
    for mut l in &mut points {
        if l.shadow_maps_enabled {
            l.shadow_maps_enabled = false;
        }
    }
    for mut l in &mut spots {
        if l.shadow_maps_enabled {
            l.shadow_maps_enabled = false;
        }
    }
    for mut l in &mut suns {
        if l.shadow_maps_enabled {
            l.shadow_maps_enabled = false;
        }
    }
}

type LightKinds<'a> = (
    Option<&'a PointLight>,
    Option<&'a SpotLight>,
    Option<&'a DirectionalLight>,
);

/// Reads the marked entities into [`VolumeFrame`].
#[allow(clippy::too_many_arguments)]
fn gather(
    mut frame: ResMut<VolumeFrame>,
    casters: Query<(Entity, &Mesh3d, &GlobalTransform), With<ShadowCaster>>,
    lights: Query<(Entity, &GlobalTransform, LightKinds), With<ShadowVolumeLight>>,
    cameras: Query<(Entity, &ShadowVolumes)>,
    meshes: Res<Assets<Mesh>>,
    mut events: MessageReader<AssetEvent<Mesh>>,
) {
    let stats = frame.stats.clone();
    let mut problems = Vec::new();

    let mut cams: Vec<_> = cameras.iter().collect();
    cams.sort_by_key(|(e, _)| *e);
    frame.camera = cams.first().map(|(e, s)| (*e, s.mode));
    if cams.len() > 1 {
        problems.push(format!(
            "{} cameras have ShadowVolumes; only the first, {}, gets shadow volumes",
            cams.len(),
            cams[0].0
        ));
    }

    let mut marked: Vec<_> = casters.iter().collect();
    marked.sort_by_key(|(e, _, _)| *e);
    let key: Vec<_> = marked.iter().map(|(e, m, _)| (*e, m.id())).collect();
    let changed = events.read().any(|ev| match ev {
        AssetEvent::Modified { id } | AssetEvent::LoadedWithDependencies { id } => {
            key.iter().any(|(_, m)| m == id)
        }
        _ => false,
    });
    if key != frame.key || changed || frame.scene.is_none() && !key.is_empty() {
        if let Some(built) = build_scene(&marked, &meshes) {
            frame.scene = Some(Arc::new(built.scene));
            frame.generation += 1;
            frame.key = key;
            frame.objects = built.objects;
            frame.left_out = built.left_out;
        } // else a mesh is still loading: try again next frame
    }
    problems.extend(frame.left_out.iter().cloned());
    // Per object of the current scene; an object whose entity is gone while its rebuild waits
    // is collapsed to a point, which casts nothing.
    let by_entity: HashMap<Entity, &GlobalTransform> =
        marked.iter().map(|&(e, _, t)| (e, t)).collect();
    let transforms = frame
        .objects
        .iter()
        .map(|k| {
            by_entity
                .get(k)
                .map_or(glam::Affine3A::ZERO, |t| to_affine(t))
        })
        .collect();
    frame.transforms = transforms;

    let mut marked_lights: Vec<_> = lights.iter().collect();
    marked_lights.sort_by_key(|(e, _, _)| *e);
    if marked_lights.len() > MAX_LIGHTS {
        problems.push(format!(
            "{} lights have ShadowVolumeLight; the first {MAX_LIGHTS} are shadowed",
            marked_lights.len()
        ));
    }
    frame.lights.clear();
    for (entity, t, (point, spot, sun)) in marked_lights.into_iter().take(MAX_LIGHTS) {
        match volume_light(t, point.is_some() || spot.is_some(), sun.is_some()) {
            Ok(l) => frame.lights.push(l),
            Err(e) => problems.push(format!("light {entity}: {e}")),
        }
    }
    if problems.is_empty() {
        stats.clear(Side::Main);
    } else {
        stats.fail(Side::Main, problems.join("; "));
    }
}

/// One marked light: a point or spot light at its translation, or a directional light shining
/// along its forward axis (towards the light: its back axis).
fn volume_light(
    t: &GlobalTransform,
    positional: bool,
    directional: bool,
) -> Result<VolumeLight, String> {
    let (v, w, kind) = if directional {
        (t.back().as_vec3(), 0.0, 2.0)
    } else if positional {
        (t.translation(), 1.0, 1.0)
    } else {
        return Err(
            "has ShadowVolumeLight but no PointLight, SpotLight or DirectionalLight".into(),
        );
    };
    let light = Light::new(v.x, v.y, v.z, w).map_err(|e| e.to_string())?;
    Ok(VolumeLight {
        light,
        texel: [v.x, v.y, v.z, kind],
    })
}

/// Bevy's transform (glam 0.33) as shadowvol's (glam 0.34), column by column.
fn to_affine(t: &GlobalTransform) -> glam::Affine3A {
    glam::Affine3A::from_cols_array(&t.affine().to_cols_array())
}

/// The scene model of the marked casters, the entity of each object, and the casters left out.
struct Built {
    scene: Scene,
    objects: Vec<Entity>,
    left_out: Vec<String>,
}

/// The scene model of the marked casters: one edge table per distinct mesh, one object per
/// entity. A caster whose mesh cannot be read is left out, with the reason; the others are
/// built. `None` while a mesh is not loaded yet.
fn build_scene(
    casters: &[(Entity, &Mesh3d, &GlobalTransform)],
    meshes: &Assets<Mesh>,
) -> Option<Built> {
    let mut built = Built {
        scene: Scene::new("bevy"),
        objects: Vec::new(),
        left_out: Vec::new(),
    };
    let mut tables = HashMap::new();
    for (entity, mesh, t) in casters {
        let id = mesh.id();
        if let std::collections::hash_map::Entry::Vacant(slot) = tables.entry(id) {
            let m = meshes.get(id)?;
            slot.insert(to_topology(m).and_then(|topo| {
                built
                    .scene
                    .add_mesh_owned(&format!("{id}"), topo)
                    .map_err(|e| e.to_string())
            }));
        }
        match &tables[&id] {
            Ok(table) => {
                let name = format!("{entity}");
                built.scene.add_object(name, table.clone(), to_affine(t));
                built.objects.push(*entity);
            }
            Err(e) => built
                .left_out
                .push(format!("caster {entity} is left out: {e}")),
        }
    }
    Some(built)
}

/// A Bevy mesh's positions and triangles, checked: a triangle list with `Float32x3` positions
/// and in-range indices (none: consecutive triples).
pub(crate) fn to_topology(m: &Mesh) -> Result<TopoMesh, String> {
    if m.primitive_topology() != PrimitiveTopology::TriangleList {
        return Err(format!(
            "its mesh is a {:?}; shadow volumes need a triangle list",
            m.primitive_topology()
        ));
    }
    let positions: Vec<glam::Vec3> = match m.attribute(Mesh::ATTRIBUTE_POSITION) {
        Some(VertexAttributeValues::Float32x3(p)) => {
            p.iter().map(|&v| glam::Vec3::from(v)).collect()
        }
        Some(_) => return Err("its positions are not Float32x3".into()),
        None => {
            return Err("its mesh has no positions in the main world (keep \
                        RenderAssetUsages::MAIN_WORLD on casters' meshes)"
                .into())
        }
    };
    let indices: Vec<u32> = match m.indices() {
        Some(Indices::U16(i)) => i.iter().map(|&i| u32::from(i)).collect(),
        Some(Indices::U32(i)) => i.clone(),
        None => (0..positions.len() as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(format!(
            "its mesh has {} indices, not a multiple of 3",
            indices.len()
        ));
    }
    let triangles = indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    TopoMesh::new(positions, triangles).map_err(|e| e.to_string())
}
