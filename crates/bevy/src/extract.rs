//! The main world's side: which marked lights the volumes shadow this frame (the others get
//! Bevy's shadow maps back), the casters and receivers by Bevy's rules, and small per-frame
//! inputs, which the render world copies each frame. The scene model is built again only when
//! the candidate casters or their meshes change.

mod objects;

use objects::object_states;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use bevy::asset::{LoadState, RenderAssetUsages};
use bevy::camera::visibility::{RenderLayers, VisibilitySystems};
use bevy::ecs::lifecycle::HookContext;
use bevy::ecs::world::DeferredWorld;
use bevy::light::{NotShadowCaster, SimulationLightSystems, SunDisk};
use bevy::mesh::morph::MeshMorphWeights;
use bevy::mesh::skinning::SkinnedMesh;
use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use bevy::render::camera::TemporalJitter;
use bevy::render::{Extract, ExtractSchedule, RenderApp};
use bevy::transform::TransformSystems;
use shadowvol_mesh_topology::{EdgeTable, Mesh as TopoMesh};
use shadowvol_robust_math::{Accuracy, Light};
use shadowvol_scenes::{Emission, Scene, SceneLight, SpotCone};

use crate::{
    ShadowCaster, ShadowCasters, ShadowVolumeLight, ShadowVolumeStats, ShadowVolumes, Side,
    SoftShadowSamples, MAX_LIGHTS,
};

/// A marked light as the pass and the material see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct VolumeLight {
    /// shadowvol's homogeneous light: position (`w = 1`) or direction towards it (`w = 0`).
    pub light: Light,
    /// The light-table texel: position or direction, `w` = 1 point or spot, 2 directional.
    pub texel: [f32; 4],
    /// Its size ([`SceneLight::radius`]): a disk's radius in world units (point, spot) or an
    /// angular radius in radians (directional); 0 for a light without soft shadows.
    pub radius: f32,
    /// A spot light's axis (where it shines): its disk faces along it.
    pub spot: Option<glam::Vec3>,
    /// How many points sample it: 1 (the light itself) where `radius` is 0.
    pub samples: u32,
}

impl VolumeLight {
    /// shadowvol's light with its size: what [`SceneLight::samples`] samples.
    pub fn scene_light(&self) -> SceneLight {
        let mut l = SceneLight::unit(self.light);
        l.radius = self.radius;
        l.emission = self.spot.map(|direction| Emission {
            color: [1.0; 3],
            intensity: 1.0,
            range: None,
            spot: Some(SpotCone {
                direction,
                inner_cone_angle: 0.0,
                outer_cone_angle: std::f32::consts::FRAC_PI_4,
            }),
        });
        l
    }
}

/// Everything the pass needs from the main world, copied into the render world each frame.
#[derive(Resource, Debug, Clone, Default)]
pub(crate) struct VolumeFrame {
    /// The casters' scene model; `None` while no caster's mesh could be read.
    pub scene: Option<Arc<Scene>>,
    /// Bumped each time `scene` is rebuilt: the render world prepares again when it changes.
    pub generation: u64,
    /// The candidate (entity, mesh) pairs `scene` was built from (loaded or not).
    pub key: Vec<(Entity, AssetId<Mesh>)>,
    /// The candidates' meshes that were not loaded at the last build: built again once one is.
    pending: Vec<AssetId<Mesh>>,
    /// Which entity each scene object is (the candidates whose meshes could be read).
    pub objects: Vec<Entity>,
    /// The casters left out of `scene`, and why: reported every frame until the next build.
    left_out: Vec<String>,
    /// Per scene object: world from object, this frame (the identity where `drawn` is false).
    pub transforms: Vec<glam::Affine3A>,
    /// Per scene object: in the pre-pass this frame (visible, on the camera's layers, with an
    /// invertible transform). The render world parks the others where nothing draws them.
    pub drawn: Vec<bool>,
    /// Per (light, object), light-major: the object casts for that light this frame (drawn,
    /// without `NotShadowCaster`, its `RenderLayers` meeting the light's, as for Bevy's maps).
    pub casts: Vec<bool>,
    /// The lights the volumes shadow this frame, in entity order, at most [`MAX_LIGHTS`].
    pub lights: Vec<VolumeLight>,
    /// The camera that gets the masks, and its mode; `None` in a frame where no camera can.
    pub camera: Option<(Entity, Accuracy)>,
    /// Shared with the render world.
    pub stats: ShadowVolumeStats,
}

/// The edge tables of the candidates' meshes, by mesh, kept between builds of the scene: a new
/// build makes tables only for meshes it has not got (new, or changed since), and drops those
/// that no candidate uses any more. A mesh left out in silence (lines or points, not marked)
/// or one that cannot cast is not kept: it is looked at again at each build.
#[derive(Debug, Default)]
pub(crate) struct Tables(HashMap<AssetId<Mesh>, Arc<EdgeTable>>);

/// A marked light's own `shadow_maps_enabled`, from when it was marked: given back when the
/// marker goes.
#[derive(Component, Debug, Clone, Copy)]
pub(crate) struct OwnShadowMaps(bool);

/// This frame's decision, made before Bevy's light systems read `shadow_maps_enabled`.
#[derive(Resource, Debug, Default)]
pub(crate) struct Decision {
    /// The camera that draws volumes, its mode and render layers.
    camera: Option<(Entity, Accuracy, RenderLayers)>,
    /// The lights shadowed with volumes, in entity order.
    lights: Vec<Entity>,
    /// Why other lights fell back to Bevy's shadow maps.
    problems: Vec<String>,
}

pub(crate) fn build(app: &mut App) {
    let stats = ShadowVolumeStats::default();
    app.insert_resource(stats.clone())
        .insert_resource(VolumeFrame { stats, ..default() })
        .init_resource::<Decision>()
        .add_systems(
            PostUpdate,
            (
                settle_lights
                    .after(VisibilitySystems::VisibilityPropagate)
                    .before(VisibilitySystems::CheckVisibility)
                    .before(SimulationLightSystems::UpdateDirectionalLightCascades),
                (propagate_casters, gather)
                    .chain()
                    .after(settle_lights)
                    .after(TransformSystems::Propagate),
            ),
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

/// The `on_remove` hook of [`ShadowVolumeLight`]: the light gets its own `shadow_maps_enabled`
/// back, as it was when it was marked.
pub(crate) fn restore_own_shadow_maps(mut world: DeferredWorld, ctx: HookContext) {
    let e = ctx.entity;
    let Some(&OwnShadowMaps(own)) = world.get::<OwnShadowMaps>(e) else {
        return;
    };
    if let Some(mut l) = world.get_mut::<PointLight>(e) {
        l.shadow_maps_enabled = own;
    }
    if let Some(mut l) = world.get_mut::<SpotLight>(e) {
        l.shadow_maps_enabled = own;
    }
    if let Some(mut l) = world.get_mut::<DirectionalLight>(e) {
        l.shadow_maps_enabled = own;
    }
    world.commands().entity(e).try_remove::<OwnShadowMaps>();
}

type SvCameras<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Camera,
        &'static ShadowVolumes,
        Option<&'static Projection>,
        Has<TemporalJitter>,
        Option<&'static RenderLayers>,
    ),
>;

/// Skinned or morphed meshes that would cast: volumes would cast their bind pose.
type Deformed<'w, 's> = Query<
    'w,
    's,
    (Entity, &'static InheritedVisibility, Has<ShadowCaster>),
    (
        With<Mesh3d>,
        Without<NotShadowCaster>,
        Or<(With<SkinnedMesh>, With<MeshMorphWeights>)>,
    ),
>;

type MarkedLights<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        Option<&'static OwnShadowMaps>,
        Option<&'static mut PointLight>,
        Option<&'static mut SpotLight>,
        Option<&'static mut DirectionalLight>,
    ),
    With<ShadowVolumeLight>,
>;

/// The camera that draws volumes this frame, or why none can.
fn volume_camera(
    cameras: &SvCameras,
    deformed: &Deformed,
    setting: ShadowCasters,
    warned: &mut HashSet<Entity>,
) -> Result<(Entity, Accuracy, RenderLayers), String> {
    let mut cams: Vec<_> = cameras.iter().filter(|c| c.1.is_active).collect();
    cams.sort_by_key(|c| c.0);
    let (e, camera, sv, projection, jittered, layers) = match cams.as_slice() {
        [] => return Err("no active camera has ShadowVolumes".into()),
        [one] => *one,
        more => {
            let list: Vec<String> = more.iter().map(|c| c.0.to_string()).collect();
            return Err(format!(
                "{} active cameras have ShadowVolumes ({}); volumes draw for one view only",
                more.len(),
                list.join(", ")
            ));
        }
    };
    match projection {
        Some(Projection::Orthographic(_)) => {
            return Err(
                "the ShadowVolumes camera is orthographic; shadow volumes support \
                        perspective cameras only"
                    .into(),
            )
        }
        Some(Projection::Custom(_)) => {
            return Err(
                "the ShadowVolumes camera has a custom projection; shadow volumes \
                        support Bevy's perspective projection only"
                    .into(),
            )
        }
        _ => {}
    }
    if camera.sub_camera_view.is_some() {
        return Err(
            "the ShadowVolumes camera's projection is off-centre (a sub-view): \
                    shadow volumes need a centred perspective projection"
                .into(),
        );
    }
    if jittered {
        return Err(
            "the ShadowVolumes camera has TemporalJitter (TAA's sub-pixel jitter): \
                    the one-sample mask would not line up with the jittered image; remove \
                    TemporalJitter and TemporalAntiAliasing from that camera"
                .into(),
        );
    }
    let mut skinned: Vec<Entity> = deformed
        .iter()
        .filter(|(_, v, marked)| v.get() && (*marked || setting == ShadowCasters::AllMeshes))
        .map(|(e, _, _)| e)
        .collect();
    if !skinned.is_empty() {
        skinned.sort();
        let list: Vec<String> = skinned.iter().map(ToString::to_string).collect();
        let list = list.join(", ");
        if skinned.iter().any(|e| warned.insert(*e)) {
            warn!(
                "shadowvol: mesh {list} is skinned or morphed; shadow volumes would cast its \
                 bind pose, so the marked lights use Bevy's shadow maps while it is visible \
                 (give it NotShadowCaster to keep the volumes)"
            );
        }
        return Err(format!(
            "skinned or morphed caster {list}: volumes would cast its bind pose"
        ));
    }
    Ok((e, sv.mode, layers.cloned().unwrap_or_default()))
}

/// Decides which marked lights the volumes shadow this frame: the first [`MAX_LIGHTS`] by
/// entity, when one camera can draw them. Every other marked light gets Bevy's shadow maps for
/// this frame, and the reason goes to the stats (logged once). Runs before Bevy's light systems
/// read `shadow_maps_enabled`, so the maps are drawn in this very frame.
#[allow(clippy::too_many_arguments)]
fn settle_lights(
    mut commands: Commands,
    mut decision: ResMut<Decision>,
    stats: Res<ShadowVolumeStats>,
    setting: Res<ShadowCasters>,
    cameras: SvCameras,
    deformed: Deformed,
    mut lights: MarkedLights,
    mut warned: Local<HashSet<Entity>>,
) {
    decision.problems.clear();
    decision.lights.clear();
    let camera = volume_camera(&cameras, &deformed, *setting, &mut warned);
    // After a failure on the device the camera stays, with no volume light: the render world
    // tries the pass again (pre-pass only) and clears its error when it works.
    let refusal = match (&camera, stats.render_error()) {
        (Err(e), _) => Some(e.clone()),
        (Ok(_), Some(e)) => Some(format!("the pass failed in the last frame ({e})")),
        (Ok(_), None) => None,
    };
    if let Some(e) = &refusal {
        if !lights.is_empty() {
            decision
                .problems
                .push(format!("{e}; the marked lights use Bevy's shadow maps"));
        }
    }
    decision.camera = camera.ok();
    let allowed = refusal.is_none();
    let mut marked: Vec<_> = lights.iter_mut().collect();
    marked.sort_by_key(|l| l.0);
    if allowed && marked.len() > MAX_LIGHTS {
        let rest: Vec<String> = marked[MAX_LIGHTS..]
            .iter()
            .map(|l| l.0.to_string())
            .collect();
        decision.problems.push(format!(
            "{} lights have ShadowVolumeLight; the first {MAX_LIGHTS} are shadowed with \
             volumes, the others ({}) with Bevy's shadow maps",
            marked.len(),
            rest.join(", ")
        ));
    }
    for (i, (entity, own, point, spot, sun)) in marked.into_iter().enumerate() {
        let volumes = allowed && i < MAX_LIGHTS;
        let current = point
            .as_ref()
            .map(|l| l.shadow_maps_enabled)
            .or(spot.as_ref().map(|l| l.shadow_maps_enabled))
            .or(sun.as_ref().map(|l| l.shadow_maps_enabled));
        let Some(current) = current else {
            decision.problems.push(format!(
                "light {entity} has ShadowVolumeLight but no PointLight, SpotLight or \
                 DirectionalLight"
            ));
            continue;
        };
        if own.is_none() {
            commands.entity(entity).insert(OwnShadowMaps(current));
        }
        if volumes {
            decision.lights.push(entity);
        }
        let wanted = !volumes;
        if let Some(mut l) = point.filter(|l| l.shadow_maps_enabled != wanted) {
            l.shadow_maps_enabled = wanted;
        }
        if let Some(mut l) = spot.filter(|l| l.shadow_maps_enabled != wanted) {
            l.shadow_maps_enabled = wanted;
        }
        if let Some(mut l) = sun.filter(|l| l.shadow_maps_enabled != wanted) {
            l.shadow_maps_enabled = wanted;
        }
    }
}

type LightKinds<'a> = (
    Option<&'a PointLight>,
    Option<&'a SpotLight>,
    Option<&'a DirectionalLight>,
);

/// The marked lights as [`gather`] reads them: where, which kind, layers, and the sun's size.
type VolumeLights<'w, 's> = Query<
    'w,
    's,
    (
        &'static GlobalTransform,
        LightKinds<'static>,
        Option<&'static RenderLayers>,
        Option<&'static SunDisk>,
    ),
    With<ShadowVolumeLight>,
>;

/// A candidate caster: its mesh, transform, visibility, layers, whether it opts out of
/// casting (`NotShadowCaster`: it still receives), and whether it is marked.
type Candidates<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Mesh3d,
        &'static GlobalTransform,
        &'static InheritedVisibility,
        Option<&'static RenderLayers>,
        Has<NotShadowCaster>,
        Has<ShadowCaster>,
    ),
    (Without<SkinnedMesh>, Without<MeshMorphWeights>),
>;

/// Reads the casters and the decided lights into [`VolumeFrame`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather(
    mut frame: ResMut<VolumeFrame>,
    decision: Res<Decision>,
    setting: Res<ShadowCasters>,
    casters: Candidates,
    lights: VolumeLights,
    samples: Res<SoftShadowSamples>,
    meshes: Res<Assets<Mesh>>,
    server: Option<Res<AssetServer>>,
    mut events: MessageReader<AssetEvent<Mesh>>,
    mut tables: Local<Tables>,
) {
    let stats = frame.stats.clone();
    let mut problems = decision.problems.clone();
    frame.camera = decision.camera.as_ref().map(|(e, m, _)| (*e, *m));

    let mut candidates: Vec<CandidateItem<'_>> = casters
        .iter()
        .filter(|c| c.6 || *setting == ShadowCasters::AllMeshes)
        .collect();
    candidates.sort_by_key(|c| c.0);
    let key: Vec<_> = candidates.iter().map(|c| (c.0, c.1.id())).collect();
    // A mesh changed in place (or loaded again) has its table made again, at the next build.
    let touched: Vec<AssetId<Mesh>> = events
        .read()
        .filter_map(|ev| match ev {
            AssetEvent::Modified { id } | AssetEvent::LoadedWithDependencies { id } => Some(*id),
            _ => None,
        })
        .collect();
    for id in &touched {
        tables.0.remove(id);
    }
    let changed = touched.iter().any(|id| key.iter().any(|(_, m)| m == id));
    let arrived = frame.pending.iter().any(|id| meshes.contains(*id));
    if key != frame.key || changed || arrived {
        let built = build_scene(
            &candidates,
            &meshes,
            *setting == ShadowCasters::Marked,
            &mut tables,
        );
        let live = tables.0.len();
        stats.with(|s| {
            s.tables_built += built.made;
            s.tables = live;
        });
        frame.scene = (!built.objects.is_empty()).then(|| Arc::new(built.scene));
        frame.generation += 1;
        frame.pending = key
            .iter()
            .map(|k| k.1)
            .filter(|id| !meshes.contains(*id))
            .collect();
        frame.key = key;
        frame.objects = built.objects;
        frame.left_out = built.left_out;
    }
    problems.extend(frame.left_out.iter().cloned());
    if let Some(server) = &server {
        for (e, m) in &frame.key {
            if matches!(server.get_load_state(*m), Some(LoadState::Failed(_))) {
                problems.push(format!(
                    "caster {e}: its mesh failed to load; it casts nothing"
                ));
            }
        }
    }
    let (casts, their_layers) = object_states(&mut frame, &candidates, &decision);
    let everywhere = RenderLayers::default();
    frame.lights.clear();
    let mut per_light = Vec::with_capacity(decision.lights.len() * frame.objects.len());
    for &entity in &decision.lights {
        let Ok((t, kinds, light_layers, disk)) = lights.get(entity) else {
            continue;
        };
        let (point, spot, sun) = kinds;
        let light = volume_light(t, point.is_some() || spot.is_some(), sun.is_some()).map(|l| {
            with_size(l, t, kinds, disk, samples.per_light()).unwrap_or_else(|e| {
                problems.push(format!("light {entity}: {e}"));
                l
            })
        });
        match light {
            Ok(l) => {
                frame.lights.push(l);
                let light_layers = light_layers.unwrap_or(&everywhere);
                per_light.extend(
                    casts
                        .iter()
                        .zip(&their_layers)
                        .map(|(&c, o)| c && o.intersects(light_layers)),
                );
            }
            Err(e) => problems.push(format!("light {entity}: {e}")),
        }
    }
    frame.casts = per_light;
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
        // Not `t.back()`: its `Dir3` asserts a unit vector (a panic in debug builds) and a zero
        // scale has none. A zero axis gives the light error below instead.
        (
            Vec3::from(t.affine().matrix3.z_axis).normalize_or_zero(),
            0.0,
            2.0,
        )
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
        radius: 0.0,
        spot: None,
        samples: 1,
    })
}

/// `l` with Bevy's size of the light, where its soft shadows are on: a point or spot light's
/// `radius` (world units) with `soft_shadows_enabled`; a directional light's angular radius,
/// half its `SunDisk`'s angular diameter (`SunDisk::EARTH` without one), where its
/// `soft_shadow_size` is `Some` (that value is the maps' filter size, which has no unit; see
/// the crate's README). Sampled by `samples` points.
///
/// # Errors
/// A size that is not one: negative or not finite, or an angle of a quarter turn or more.
fn with_size(
    mut l: VolumeLight,
    t: &GlobalTransform,
    (point, spot, sun): LightKinds,
    disk: Option<&SunDisk>,
    samples: u32,
) -> Result<VolumeLight, String> {
    let radius = if let Some(p) = point {
        if p.soft_shadows_enabled {
            p.radius
        } else {
            0.0
        }
    } else if let Some(s) = spot {
        if s.soft_shadows_enabled {
            let axis = Vec3::from(t.affine().matrix3.z_axis).normalize_or_zero();
            l.spot = Some(glam::Vec3::from((-axis).to_array()));
            s.radius
        } else {
            0.0
        }
    } else if sun.is_some_and(|d| d.soft_shadow_size.is_some()) {
        0.5 * disk.map_or(SunDisk::EARTH.angular_size, |d| d.angular_size)
    } else {
        0.0
    };
    let quarter = std::f32::consts::FRAC_PI_2;
    if !radius.is_finite() || radius < 0.0 || (sun.is_some() && radius >= quarter) {
        return Err(format!(
            "its size {radius} is not one (a radius of at least 0 in world units, or for a \
             directional light an angular radius under a quarter turn); its shadow is hard"
        ));
    }
    if radius > 0.0 && samples > 1 {
        l.radius = radius;
        l.samples = samples;
    } else {
        l.spot = None;
    }
    Ok(l)
}

/// Bevy's transform (glam 0.33) as shadowvol's (glam 0.34), column by column.
fn to_affine(t: &GlobalTransform) -> glam::Affine3A {
    glam::Affine3A::from_cols_array(&t.affine().to_cols_array())
}

/// The scene model of the candidate casters, the entity of each object, and the casters left
/// out.
struct Built {
    scene: Scene,
    objects: Vec<Entity>,
    left_out: Vec<String>,
    /// Edge tables made for this build (the others came from [`Tables`]).
    made: u64,
}

/// The scene model of the candidate casters: one edge table per distinct mesh, one object per
/// entity. A caster whose mesh cannot be read is left out, with the reason (where it is not
/// marked, in [`ShadowCasters::AllMeshes`], a mesh of lines or points is left out in silence);
/// the others are built. A mesh not loaded yet is skipped: a new build comes when it loads.
/// Edge tables come from `cache` where it has them; only the other meshes' are made, and the
/// tables of meshes no candidate uses any more are dropped from it.
fn build_scene(
    casters: &[CandidateItem<'_>],
    meshes: &Assets<Mesh>,
    marked_only: bool,
    cache: &mut Tables,
) -> Built {
    let mut built = Built {
        scene: Scene::new("bevy"),
        objects: Vec::new(),
        left_out: Vec::new(),
        made: 0,
    };
    let used: HashSet<AssetId<Mesh>> = casters.iter().map(|c| c.1.id()).collect();
    cache.0.retain(|id, _| used.contains(id));
    let mut tables: HashMap<AssetId<Mesh>, Option<Result<Arc<EdgeTable>, String>>> = HashMap::new();
    for &(entity, mesh, t, _, _, _, marked) in casters {
        let id = mesh.id();
        if let std::collections::hash_map::Entry::Vacant(slot) = tables.entry(id) {
            if let Some(table) = cache.0.get(&id) {
                slot.insert(Some(Ok(table.clone())));
            } else {
                let Some(m) = meshes.get(id) else {
                    continue; // not loaded (yet): skipped, the others are built
                };
                let quiet = !marked_only
                    && !marked
                    && m.primitive_topology() != PrimitiveTopology::TriangleList;
                let table = (!quiet).then(|| {
                    to_topology(m).and_then(|topo| {
                        built
                            .scene
                            .add_mesh_owned(&format!("{id}"), topo)
                            .map_err(|e| e.to_string())
                    })
                });
                if let Some(Ok(table)) = &table {
                    cache.0.insert(id, table.clone());
                    built.made += 1;
                }
                slot.insert(table);
            }
        }
        match tables.get(&id) {
            Some(Some(Ok(table))) => {
                let name = format!("{entity}");
                built.scene.add_object(name, table.clone(), to_affine(t));
                built.objects.push(entity);
            }
            Some(Some(Err(e))) => built
                .left_out
                .push(format!("caster {entity} is left out: {e}")),
            Some(None) | None => {}
        }
    }
    built
}

/// One item of [`Candidates`].
type CandidateItem<'a> = (
    Entity,
    &'a Mesh3d,
    &'a GlobalTransform,
    &'a InheritedVisibility,
    Option<&'a RenderLayers>,
    bool,
    bool,
);

/// A Bevy mesh's positions and triangles, checked: a triangle list with `Float32x3` positions
/// and in-range indices (none: consecutive triples).
pub(crate) fn to_topology(m: &Mesh) -> Result<TopoMesh, String> {
    if !m.asset_usage.contains(RenderAssetUsages::MAIN_WORLD) {
        return Err(
            "its mesh lives in the render world only (RenderAssetUsages::RENDER_WORLD); \
                    casters need RenderAssetUsages::MAIN_WORLD too"
                .into(),
        );
    }
    if m.primitive_topology() != PrimitiveTopology::TriangleList {
        return Err(format!(
            "its mesh is a {:?}; shadow volumes need a triangle list",
            m.primitive_topology()
        ));
    }
    let unreadable = |e| format!("its mesh cannot be read in the main world: {e}");
    let positions: Vec<glam::Vec3> = match m
        .try_attribute_option(Mesh::ATTRIBUTE_POSITION)
        .map_err(unreadable)?
    {
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
    let indices: Vec<u32> = match m.try_indices_option().map_err(unreadable)? {
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
