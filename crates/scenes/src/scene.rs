//! The scene model: shared meshes with their edge tables and the instances that place them
//! (a [`TopologyScene`], what backends prepare), receivers, lights with their emission, a camera
//! and the effects the scene calls for.
//!
//! Loaders and presets build it once; everything after borrows it: backends prepare
//! [`Scene::geometry`], the renderer's pipelines and plan read [`Scene::surfaces`] and
//! [`Scene::lights`], and the reference reads the same views.

use crate::{Camera, Emission, SceneError};
use glam::{Affine3A, Vec3};
use shadowvol_mesh_topology::{positions_distinct_by, EdgeTable, Mesh};
use shadowvol_robust_math::Light;
use shadowvol_silhouette::{SceneObject, TopologyScene};
use std::path::Path;
use std::sync::Arc;

/// Diffuse colour of every caster (linear RGB): a light grey.
pub const CASTER_ALBEDO: [f32; 3] = [0.8, 0.8, 0.8];

/// Diffuse colour of the receivers a scene adds ([`Scene::set_ground`], [`Scene::add_backdrop`]):
/// a warm grey, so that they read apart from the casters.
pub const RECEIVER_ALBEDO: [f32; 3] = [0.75, 0.72, 0.65];

/// The name of the ground receiver ([`Scene::set_ground`]).
pub const GROUND: &str = "ground";

/// The name of the backdrop receiver ([`Scene::add_backdrop`]).
pub const BACKDROP: &str = "backdrop";

/// A light and what it emits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneLight {
    /// Where it is, homogeneous (`w = 1` point, `w = 0` directional towards the light): the
    /// light every silhouette predicate receives.
    pub light: Light,
    /// glTF `KHR_lights_punctual` colour, intensity, range and cone; `None` for a unit light
    /// (white, no falloff: presets, `--light`, the default key light).
    pub emission: Option<Emission>,
    /// The light's size ([`crate::LightDisk`]): for a point or spot light the radius of a disk
    /// in world units, for a directional light an angular radius in radians (the sun's is about
    /// 0.0047). 0 (the default) is a point light, casting hard shadows.
    pub radius: f32,
}

impl SceneLight {
    /// A unit light (no [`Emission`]) of radius 0.
    #[must_use]
    pub fn unit(light: Light) -> Self {
        Self {
            light,
            emission: None,
            radius: 0.0,
        }
    }

    /// The disk this light's samples lie on, aimed at `aim` (the scene's bounding-box centre,
    /// [`Scene::light_aim`]); `None` for radius 0. See [`crate::LightDisk`].
    #[must_use]
    pub fn disk(&self, aim: Vec3) -> Option<crate::LightDisk> {
        crate::LightDisk::of(self, aim)
    }

    /// `n` point (or directional) lights sampling this light's disk aimed at `aim`
    /// ([`crate::LightDisk::samples`]); the light itself when `n <= 1` or the radius is 0.
    #[must_use]
    pub fn samples(&self, n: u32, aim: Vec3) -> Vec<Light> {
        match self.disk(aim) {
            Some(d) if n > 1 => d.samples(n),
            _ => vec![self.light],
        }
    }
}

/// A surface that is drawn and lit but casts no shadow and has no silhouette: a ground plane or
/// a backdrop. World space (no transform).
#[derive(Debug, Clone)]
pub struct Receiver {
    /// A name for the plan and messages ([`GROUND`], [`BACKDROP`]).
    pub name: String,
    /// Its triangles, welded, in world space.
    pub table: Arc<EdgeTable>,
    /// Diffuse colour, linear RGB in `[0, 1]`.
    pub albedo: [f32; 3],
}

impl Receiver {
    /// A square of two triangles centred at `centre`, facing `normal`, of half-size `half`.
    ///
    /// # Panics
    /// Never for finite inputs: four distinct finite corners always make a table.
    #[must_use]
    pub fn plane(name: &str, centre: Vec3, normal: Vec3, half: f32) -> Self {
        let n = normal.normalize_or(Vec3::Y);
        let helper = if n.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
        let u = n.cross(helper).normalize() * half;
        let v = n.cross(u);
        let mesh = Mesh {
            positions: vec![
                centre - u - v,
                centre + u - v,
                centre + u + v,
                centre - u + v,
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        Self {
            name: name.to_owned(),
            table: Arc::new(EdgeTable::build(&mesh).expect("a finite square")),
            albedo: RECEIVER_ALBEDO,
        }
    }
}

/// One drawn surface of a scene, as [`Scene::surfaces`] lists them: the casters in
/// [`Scene::geometry`] order, then the receivers. Its index in that list is the object id of
/// the renderer's per-pixel ids and of the plan.
#[derive(Debug, Clone, Copy)]
pub struct Surface<'a> {
    /// The object's or receiver's name.
    pub name: &'a str,
    /// Its welded triangles in object space.
    pub table: &'a Arc<EdgeTable>,
    /// World from object (the identity for receivers).
    pub world_from_object: Affine3A,
    /// Diffuse colour, linear RGB.
    pub albedo: [f32; 3],
    /// False for receivers, and for every object when [`Effects::shadows`] is off.
    pub casts_shadows: bool,
}

impl Surface<'_> {
    /// The table's positions in world space, each transformed in `f32` with [`apply_f32`]: the
    /// positions every pipeline draws and the reference casts against.
    #[must_use]
    pub fn world_positions(&self) -> Vec<Vec3> {
        self.table
            .positions
            .iter()
            .map(|&p| apply_f32(&self.world_from_object, p))
            .collect()
    }

    /// Vertex `v` of [`Surface::world_positions`], alone (the same bits).
    ///
    /// # Panics
    /// Panics if `v` is out of range.
    #[must_use]
    pub fn world_position(&self, v: u32) -> Vec3 {
        apply_f32(&self.world_from_object, self.table.positions[v as usize])
    }
}

/// The effects a scene calls for; the renderer plans its passes from these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effects {
    /// Cast stencil shadow volumes from every light (false: lighting only).
    pub shadows: bool,
    /// Ambient light level in `[0, 1]` that shadowed pixels keep.
    pub ambient: f32,
    /// The objects never move: silhouettes can be cached while the lights stand still.
    pub static_geometry: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Self {
            shadows: true,
            ambient: 0.2,
            static_geometry: true,
        }
    }
}

/// A scene: shared meshes with their edge tables placed by instances, receivers, lights, an
/// optional camera and the effects it calls for.
///
/// Load one from a file with [`Scene::load`], build a preset with [`crate::preset`], or either
/// with [`Scene::from_name_or_path`]; build one by hand with [`Scene::add_mesh`] and
/// [`Scene::add_object`].
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// A name for reports (the preset name or the file name).
    pub name: String,
    /// The casters: each object (instance) an edge table in object space and its
    /// world-from-object transform; instances of one mesh share one `Arc<EdgeTable>`. Objects
    /// are in file order (glTF: depth-first node order). This is what backends prepare.
    pub geometry: TopologyScene,
    /// Surfaces that receive shadows but cast none (ground, backdrop), drawn after the casters.
    pub receivers: Vec<Receiver>,
    /// The lights, each with its emission.
    pub lights: Vec<SceneLight>,
    /// The camera, if the scene has one.
    pub camera: Option<Camera>,
    /// What the renderer should simulate.
    pub effects: Effects,
}

impl Scene {
    /// An empty scene named `name`.
    #[must_use]
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            ..Self::default()
        }
    }

    /// Welds `mesh` and builds its edge table, to be placed by [`Scene::add_object`] (once per
    /// instance).
    ///
    /// # Errors
    /// [`SceneError::Mesh`] naming `what` if the mesh is invalid (non-finite position, index
    /// out of range) or too large for the available memory.
    pub fn add_mesh(&mut self, what: &str, mesh: &Mesh) -> Result<Arc<EdgeTable>, SceneError> {
        EdgeTable::build(mesh)
            .map(Arc::new)
            .map_err(|source| SceneError::Mesh {
                what: what.to_owned(),
                source,
            })
    }

    /// [`Scene::add_mesh`], consuming `mesh` ([`EdgeTable::build_owned`]: the mesh is freed
    /// while the table is built, so the two are not held at once).
    ///
    /// # Errors
    /// As [`Scene::add_mesh`].
    pub fn add_mesh_owned(&mut self, what: &str, mesh: Mesh) -> Result<Arc<EdgeTable>, SceneError> {
        EdgeTable::build_owned(mesh)
            .map(Arc::new)
            .map_err(|source| SceneError::Mesh {
                what: what.to_owned(),
                source,
            })
    }

    /// Adds an object: `table` (from [`Scene::add_mesh`], possibly shared) placed by
    /// `transform` (world from object, invertible).
    pub fn add_object(
        &mut self,
        name: impl Into<String>,
        table: Arc<EdgeTable>,
        transform: Affine3A,
    ) {
        self.geometry.objects.push(SceneObject {
            name: name.into(),
            table,
            world_from_object: transform,
        });
    }

    /// A scene of one object, `mesh` at the identity, named `name`.
    ///
    /// # Errors
    /// As [`Scene::add_mesh`].
    pub fn single(name: impl Into<String>, mesh: &Mesh) -> Result<Self, SceneError> {
        let mut scene = Self::new(name);
        let table = scene.add_mesh(&scene.name.clone(), mesh)?;
        scene.add_object(scene.name.clone(), table, Affine3A::IDENTITY);
        Ok(scene)
    }

    /// [`Scene::single`], consuming `mesh`, which is freed while its table is built
    /// ([`Scene::add_mesh_owned`]).
    ///
    /// # Errors
    /// As [`Scene::single`].
    pub fn single_owned(name: impl Into<String>, mesh: Mesh) -> Result<Self, SceneError> {
        let mut scene = Self::new(name);
        let table = scene.add_mesh_owned(&scene.name.clone(), mesh)?;
        scene.add_object(scene.name.clone(), table, Affine3A::IDENTITY);
        Ok(scene)
    }

    /// Adds unit lights (no [`Emission`]).
    pub fn add_unit_lights(&mut self, lights: impl IntoIterator<Item = Light>) {
        self.lights.extend(lights.into_iter().map(SceneLight::unit));
    }

    /// The lights' homogeneous positions, in order: what silhouette backends take.
    #[must_use]
    pub fn light_positions(&self) -> Vec<Light> {
        self.lights.iter().map(|l| l.light).collect()
    }

    /// Every drawn surface: the casters in [`Scene::geometry`] order, then the receivers. The
    /// position in this list is the surface's object id.
    pub fn surfaces(&self) -> impl ExactSizeIterator<Item = Surface<'_>> + Clone + '_ {
        let casts = self.effects.shadows;
        let n = self.geometry.objects.len();
        (0..n + self.receivers.len()).map(move |i| match self.geometry.objects.get(i) {
            Some(o) => Surface {
                name: &o.name,
                table: &o.table,
                world_from_object: o.world_from_object,
                albedo: CASTER_ALBEDO,
                casts_shadows: casts,
            },
            None => {
                let r = &self.receivers[i - n];
                Surface {
                    name: &r.name,
                    table: &r.table,
                    world_from_object: Affine3A::IDENTITY,
                    albedo: r.albedo,
                    casts_shadows: false,
                }
            }
        })
    }

    /// Heap bytes of every edge table the scene holds, casters' and receivers', each shared
    /// table once ([`EdgeTable::heap_bytes`]).
    #[must_use]
    pub fn table_bytes(&self) -> u64 {
        let casters = self.geometry.objects.iter().map(|o| &o.table);
        let tables = casters.chain(self.receivers.iter().map(|r| &r.table));
        shadowvol_mesh_topology::unique_arc_bytes(tables, EdgeTable::heap_bytes)
    }

    /// Every surface ([`Scene::surfaces`] order) as a topology: the casters with their
    /// transforms, then the receivers at the identity. The tables are shared, not copied; what
    /// a renderer lays out once to draw every surface.
    #[must_use]
    pub fn surface_geometry(&self) -> TopologyScene {
        TopologyScene {
            objects: self
                .surfaces()
                .map(|s| SceneObject {
                    name: s.name.to_owned(),
                    table: Arc::clone(s.table),
                    world_from_object: s.world_from_object,
                })
                .collect(),
        }
    }

    /// Total number of input triangles over all objects (instances counted each time;
    /// receivers not counted).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.geometry
            .objects
            .iter()
            .map(|o| o.table.stats.triangles)
            .sum()
    }

    /// Total number of input vertices over all objects (instances counted each time).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.geometry
            .objects
            .iter()
            .map(|o| o.table.stats.vertices)
            .sum()
    }

    /// The height of the ground receiver, if the scene has one.
    #[must_use]
    pub fn ground_y(&self) -> Option<f32> {
        self.receivers
            .iter()
            .find(|r| r.name == GROUND)
            .and_then(|r| r.table.positions.first())
            .map(|p| p.y)
    }

    /// Sets the ground: `Some(y)` places a horizontal receiver plane at height `y` (facing
    /// `+Y`) under the casters (centred on their vertices' world bounds, three bounding
    /// diameters across); `None` removes it. It is not
    /// an object: it casts nothing and is not part of silhouette extraction.
    pub fn set_ground(&mut self, y: Option<f32>) {
        self.receivers.retain(|r| r.name != GROUND);
        let casters = self
            .geometry
            .objects
            .iter()
            .filter_map(|o| world_bounds(&o.table.positions, o.world_from_object))
            .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)));
        if let (Some(y), Some((lo, hi))) = (y, casters) {
            let (c, r) = crate::box_centre_radius(lo, hi);
            let half = (2.0 * r).max(1e-3) * 3.0;
            self.receivers.push(Receiver::plane(
                GROUND,
                Vec3::new(c.x, y, c.z),
                Vec3::Y,
                half,
            ));
        }
    }

    /// Adds a receiver plane behind the scene as seen from the first light, so that shadows
    /// have somewhere to fall (used for the `hard-*` scenes, which have no ground). Does
    /// nothing without lights or vertices.
    pub fn add_backdrop(&mut self) {
        let (Some(light), Some((lo, hi))) = (self.lights.first(), self.surface_bounds()) else {
            return;
        };
        let (c, r) = crate::box_centre_radius(lo, hi);
        let r = r.max(1e-3);
        let l = light.light.to_array();
        let away = if l[3] == 0.0 {
            -Vec3::new(l[0], l[1], l[2])
        } else {
            c - Vec3::new(l[0], l[1], l[2]) / l[3]
        };
        let away = away.normalize_or(Vec3::NEG_Y);
        self.receivers.push(Receiver::plane(
            BACKDROP,
            c + away * (r * 1.5),
            -away,
            r * 6.0,
        ));
    }

    /// World-space bounds `(min, max)` of every surface's vertices (casters and receivers),
    /// each transformed in `f32`; `None` without vertices.
    #[must_use]
    pub fn surface_bounds(&self) -> Option<(Vec3, Vec3)> {
        self.surfaces()
            .filter_map(|s| world_bounds(&s.table.positions, s.world_from_object))
            .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)))
    }

    /// All objects merged into one world-space edge table: each object's transform applied to
    /// its welded positions in `f32` (with [`apply_f32`]), the objects concatenated in order
    /// and welded again. Vertex names (and [`EdgeTable::vertex_names`]) are *input* indices in
    /// the concatenation of the objects' input vertices, so vertex `i` of object `k` is named
    /// `(input vertices of objects before k) + i`, exactly as if the input meshes had been
    /// transformed and concatenated before welding (the CLI's numbering). Triangle sources are
    /// input triangle indices in the same way. One object at the identity is returned as is.
    ///
    /// # Errors
    /// [`SceneError::Mesh`] if the result is too large for `u32` indexing or for the memory.
    pub fn baked_table(&self) -> Result<Arc<EdgeTable>, SceneError> {
        if let [o] = self.geometry.objects.as_slice() {
            if o.world_from_object == Affine3A::IDENTITY {
                return Ok(Arc::clone(&o.table));
            }
            let mut table = EdgeTable::clone(&o.table);
            if move_table(&mut table, &o.world_from_object) {
                return Ok(Arc::new(table));
            }
        }
        self.rebuilt_table()
    }

    /// [`Scene::baked_table`], consuming the scene: a single object's table is moved rather
    /// than copied where nothing else shares it, so that the scene's table and the baked one
    /// are not held at once (the command line's path for a mesh argument).
    ///
    /// # Errors
    /// As [`Scene::baked_table`].
    pub fn into_baked_table(mut self) -> Result<Arc<EdgeTable>, SceneError> {
        if self.geometry.objects.len() == 1 {
            let o = self.geometry.objects.pop().expect("one object");
            if o.world_from_object == Affine3A::IDENTITY {
                return Ok(o.table);
            }
            let mut table = Arc::try_unwrap(o.table).unwrap_or_else(|shared| (*shared).clone());
            if move_table(&mut table, &o.world_from_object) {
                return Ok(Arc::new(table));
            }
            self.geometry.objects.push(SceneObject {
                table: Arc::new(table),
                ..o
            });
            return self.rebuilt_table();
        }
        self.baked_table()
    }

    /// The general path of [`Scene::baked_table`]: every object transformed into one mesh,
    /// welded and tabled again.
    fn rebuilt_table(&self) -> Result<Arc<EdgeTable>, SceneError> {
        let what = || format!("baked mesh of scene '{}'", self.name);
        let welded: usize = self
            .geometry
            .objects
            .iter()
            .map(|o| o.table.positions.len())
            .sum();
        let kept: usize = self
            .geometry
            .objects
            .iter()
            .map(|o| o.table.triangles.len())
            .sum();
        let mut mesh = Mesh {
            positions: Vec::with_capacity(welded),
            triangles: Vec::with_capacity(kept),
        };
        // Per vertex of `mesh`: its input name; per triangle: its input index.
        let mut names: Vec<u32> = Vec::with_capacity(welded);
        let mut sources: Vec<u32> = Vec::with_capacity(kept);
        let (mut input_vertices, mut input_triangles, mut degenerate) = (0u64, 0u64, 0usize);
        for o in &self.geometry.objects {
            let t = &o.table;
            let base = mesh.positions.len() as u32;
            let offset =
                u32::try_from(input_vertices).map_err(|_| too_large(what(), input_vertices))?;
            let tri_offset =
                u32::try_from(input_triangles).map_err(|_| too_large(what(), input_triangles))?;
            mesh.positions.extend(
                t.positions
                    .iter()
                    .map(|&p| apply_f32(&o.world_from_object, p)),
            );
            names.extend(t.vertex_names.iter().map(|n| offset + n));
            mesh.triangles
                .extend(t.triangles.iter().map(|tri| tri.map(|v| base + v)));
            sources.extend(t.triangle_sources.iter().map(|s| tri_offset + s));
            input_vertices += t.stats.vertices as u64;
            input_triangles += t.stats.triangles as u64;
            degenerate += t.stats.degenerate_triangles;
        }
        if u32::try_from(input_vertices).is_err() || u32::try_from(input_triangles).is_err() {
            return Err(too_large(what(), input_vertices.max(input_triangles)));
        }
        let mut baked = EdgeTable::build(&mesh).map_err(|source| SceneError::Mesh {
            what: what(),
            source,
        })?;
        // Names grow with the vertex index of `mesh` (within an object compact ids follow names,
        // and objects follow each other), so a group's smallest index carries its smallest name.
        baked.vertex_names = std::mem::take(&mut baked.vertex_names).map(|n| names[n as usize]);
        baked.triangle_sources =
            std::mem::take(&mut baked.triangle_sources).map(|s| sources[s as usize]);
        baked.stats.vertices = input_vertices as usize;
        baked.stats.triangles = input_triangles as usize;
        baked.stats.degenerate_triangles += degenerate;
        Ok(Arc::new(baked))
    }

    /// This scene with all objects baked into one object (identity transform, see
    /// [`Scene::baked_table`]), keeping receivers, lights, camera and effects.
    ///
    /// # Errors
    /// As [`Scene::baked_table`].
    pub fn baked(&self) -> Result<Self, SceneError> {
        let table = self.baked_table()?;
        let mut geometry = TopologyScene::default();
        geometry.objects.push(SceneObject {
            name: format!("{} (baked)", self.name),
            table,
            world_from_object: Affine3A::IDENTITY,
        });
        Ok(Self {
            geometry,
            ..self.clone()
        })
    }

    /// The point a light with a size faces ([`SceneLight::disk`]): the centre of
    /// [`Scene::surface_bounds`], the origin for a scene without vertices.
    #[must_use]
    pub fn light_aim(&self) -> Vec3 {
        self.surface_bounds()
            .map_or(Vec3::ZERO, |(lo, hi)| (lo + hi) * 0.5)
    }

    /// Sets every light's radius ([`SceneLight::radius`]) to `radius`.
    ///
    /// # Errors
    /// [`SceneError::LightRadius`] when `radius` is negative or not finite, or not under a
    /// quarter turn (π/2) for a directional light.
    pub fn set_light_radius(&mut self, radius: f32) -> Result<(), SceneError> {
        for (i, l) in self.lights.iter_mut().enumerate() {
            crate::disk::check_radius(l.light, radius)
                .map_err(|message| SceneError::LightRadius { light: i, message })?;
            l.radius = radius;
        }
        Ok(())
    }

    /// World-space axis-aligned bounds `(min, max)` of all objects' vertices (each object's
    /// box corners transformed), or `None` for a scene without vertices. Receivers are not
    /// included.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        (0..self.geometry.objects.len())
            .filter_map(|i| self.object_bounds(i))
            .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)))
    }

    /// World-space bounds of object `i` (its table's box corners transformed), `None` when it
    /// has no vertices or there is no object `i`.
    #[must_use]
    pub fn object_bounds(&self, i: usize) -> Option<(Vec3, Vec3)> {
        let o = self.geometry.objects.get(i)?;
        let (lo, hi) = points_bounds(&o.table.positions)?;
        let mut min = Vec3::splat(f32::INFINITY);
        let mut max = Vec3::splat(f32::NEG_INFINITY);
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let w = o.world_from_object.transform_point3(c);
            min = min.min(w);
            max = max.max(w);
        }
        Some((min, max))
    }

    /// The scene's camera, or one framing its bounds (from `+x+y+z`-ish) when it has none.
    /// `None` only for a scene without vertices and without camera.
    #[must_use]
    pub fn camera_or_default(&self) -> Option<Camera> {
        self.camera.or_else(|| {
            self.bounds()
                .map(|(lo, hi)| Camera::framing(lo, hi, Vec3::new(0.6, 0.5, 1.0)))
        })
    }
}

/// Input vertices or triangles of a bake beyond `u32` numbering.
/// Moves `table`'s positions by `t` ([`apply_f32`]) when that makes the table a rebuild would
/// make: every moved position finite and no two of them equal (then welding keeps every vertex,
/// in the same order, and the triangles, edges and names stay as they are). Returns false, and
/// leaves the table as it was, otherwise.
///
/// The moved positions are checked as they are computed and written only once they pass, so the
/// move holds no second copy of them.
fn move_table(table: &mut EdgeTable, t: &Affine3A) -> bool {
    let moved = |i: usize| apply_f32(t, table.positions[i]);
    let n = table.positions.len();
    let ok = (0..n).all(|i| moved(i).is_finite()) && positions_distinct_by(n, moved);
    if ok {
        for p in &mut table.positions {
            *p = apply_f32(t, *p);
        }
    }
    ok
}

fn too_large(what: String, count: u64) -> SceneError {
    SceneError::Mesh {
        what,
        source: shadowvol_mesh_topology::MeshError::TooLarge {
            what: "input vertices or triangles",
            count,
            limit: u64::from(u32::MAX),
        },
    }
}

/// Bounds of `points` transformed by `t` in `f32`; `None` for no points.
fn world_bounds(points: &[Vec3], t: Affine3A) -> Option<(Vec3, Vec3)> {
    let first = apply_f32(&t, *points.first()?);
    Some(points.iter().fold((first, first), |(lo, hi), &p| {
        let w = apply_f32(&t, p);
        (lo.min(w), hi.max(w))
    }))
}

/// Applies a world-from-object transform to one point in `f32`: the one definition used by
/// [`Scene::baked_table`], the glTF loader, the renderer and the reference, so world positions
/// are reproducible bit for bit.
#[inline]
#[must_use]
pub fn apply_f32(t: &Affine3A, p: Vec3) -> Vec3 {
    t.transform_point3(p)
}

/// `mesh` with `t` applied to every position in `f32` (triangles unchanged). The identity leaves
/// positions bit-identical.
#[must_use]
pub fn transformed(mesh: &Mesh, t: &Affine3A) -> Mesh {
    if *t == Affine3A::IDENTITY {
        return mesh.clone();
    }
    Mesh {
        positions: mesh.positions.iter().map(|&p| apply_f32(t, p)).collect(),
        triangles: mesh.triangles.clone(),
    }
}

/// Axis-aligned bounds of a mesh's positions, `None` when it has none.
#[must_use]
pub fn mesh_bounds(mesh: &Mesh) -> Option<(Vec3, Vec3)> {
    points_bounds(&mesh.positions)
}

/// Axis-aligned bounds of `points`, `None` when empty.
#[must_use]
pub fn points_bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    )
}

pub(crate) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One object of `mesh` placed by `t`.
    fn one(mesh: &Mesh, t: Affine3A) -> Scene {
        let mut scene = Scene::new("test");
        let table = scene.add_mesh("mesh", mesh).unwrap();
        scene.add_object("mesh", table, t);
        scene
    }

    #[test]
    fn a_moved_table_is_the_table_a_rebuild_makes() {
        let mesh = crate::procedural::uv_sphere(2000, 1.5);
        let t = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.0, 2.0, 0.5),
            glam::Quat::from_rotation_y(0.3),
            Vec3::new(3.0, -1.0, 2.0),
        );
        let scene = one(&mesh, t);
        let rebuilt = scene.rebuilt_table().unwrap();
        assert!(move_table(
            &mut EdgeTable::clone(&scene.geometry.objects[0].table),
            &t
        ));
        assert_eq!(*scene.baked_table().unwrap(), *rebuilt);
        assert_eq!(*scene.into_baked_table().unwrap(), *rebuilt);
    }

    #[test]
    fn positions_that_meet_when_moved_are_welded_by_a_rebuild() {
        // Two vertices one ulp apart at x = 1 land on one f32 once moved by 2^30.
        let next = f32::from_bits(1.0f32.to_bits() + 1);
        let mesh = Mesh {
            positions: vec![
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(next, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, 1.0),
            ],
            triangles: vec![[0, 2, 3], [1, 3, 2], [0, 1, 2]],
        };
        let t = Affine3A::from_translation(Vec3::new(1_073_741_824.0, 0.0, 0.0));
        let scene = one(&mesh, t);
        let table = EdgeTable::clone(&scene.geometry.objects[0].table);
        let mut unchanged = table.clone();
        assert!(!move_table(&mut unchanged, &t), "two vertices meet");
        assert_eq!(
            unchanged, table,
            "a refused move leaves the table as it was"
        );
        let rebuilt = scene.rebuilt_table().unwrap();
        assert!(rebuilt.positions.len() < table.positions.len());
        assert_eq!(*scene.baked_table().unwrap(), *rebuilt);
        assert_eq!(*scene.into_baked_table().unwrap(), *rebuilt);
    }
}
