//! Scenes for shadowvol: loaders (glTF 2.0, OBJ, STL, PLY), procedural meshes, and the paper's presets.
//!
//! * [`Scene`]: the one scene model. Its [`geometry`](Scene::geometry) holds the casters: shared
//!   meshes, each welded once into an [`EdgeTable`](shadowvol_mesh_topology::EdgeTable), and the
//!   objects (instances) that place them with a world transform; it is the
//!   [`TopologyScene`](shadowvol_silhouette::TopologyScene) backends prepare, borrowed, never
//!   converted. Beside it: [`Receiver`]s (a ground, a backdrop), [`SceneLight`]s (each light
//!   with its [`Emission`]), a camera and the [`Effects`] the scene calls for. Load one with
//!   [`Scene::load`] (`.gltf`, `.glb`, `.obj`, `.stl`, `.ply`), build a preset with [`preset`],
//!   or either with [`Scene::from_name_or_path`]. [`Scene::surfaces`] lists what is drawn;
//!   [`Scene::baked_table`] merges everything into one world-space table, transforms applied in
//!   `f32` on the host.
//! * [`gltf_load`]: glTF loading with node transforms, shared meshes, cameras and
//!   `KHR_lights_punctual`, validating accessor contents; [`obj`], [`stl`], [`ply`]: OBJ, STL
//!   (ASCII and binary) and PLY (ASCII and binary) loading.
//! * [`export_glb`]: writes any scene as binary glTF that other tools can open.
//! * [`procedural`]: UV spheres and icospheres with an exact triangle count, Loop subdivision,
//!   the "town".
//! * [`shapes`]: small exact shapes (tetrahedron, box, planar grid, ...), bit-identical on every
//!   platform, and the deterministic [`Rng`](shapes::Rng).
//! * [`hard`]: the hard cases (edge-on triangles, lights at vertices, non-manifold books, ...)
//!   that the conformance tests run on every backend.
//! * [`presets`](mod@presets): `bunnies-10-individual`, `bunnies-10-baked`, `spheres-10-individual`,
//!   `spheres-10-baked`, `sphere-1m`, `sphere-100k`, `spheres-100x10k`, `spheres-100x1k`,
//!   `town` and `hard-<case>` for every case of [`hard::cases`].
//!
//! ```
//! use shadowvol_scenes::{preset, Scene};
//!
//! let scene = preset("spheres-100x1k")?;
//! assert_eq!(scene.geometry.objects.len(), 100);
//! assert_eq!(scene.triangle_count(), 100 * 1_000);
//! // One edge table, shared by the 100 instances.
//! let first = &scene.geometry.objects[0].table;
//! assert!(scene.geometry.objects.iter().all(|o| std::sync::Arc::ptr_eq(&o.table, first)));
//! assert_eq!(scene.baked_table()?.triangles.len(), 100_000);
//! # Ok::<(), shadowvol_scenes::SceneError>(())
//! ```

mod camera;
mod disk;
pub mod emission;
mod glb_write;
pub mod gltf_load;
pub mod hard;
mod load;
pub mod meshopt_view;
pub mod obj;
pub mod ply;
pub mod presets;
pub mod procedural;
mod scene;
pub mod shapes;
pub mod staging;
pub mod stl;

pub use camera::{box_centre_radius, Camera, InvalidCamera};
pub use disk::{LightDisk, GOLDEN_ANGLE};
pub use emission::{Emission, SpotCone};
pub use glb_write::{export_glb, glb_container, to_glb};
pub use gltf_load::{
    in_guarded_decoder, load_gltf, load_gltf_mesh, load_gltf_slice, load_gltf_slice_with_notes,
};
pub use presets::{is_preset, preset, preset_names, presets, PresetInfo, PresetSize};
pub use scene::{
    apply_f32, mesh_bounds, points_bounds, transformed, Effects, Receiver, Scene, SceneLight,
    Surface, BACKDROP, CASTER_ALBEDO, GROUND, RECEIVER_ALBEDO,
};

use shadowvol_mesh_topology::MeshError;

/// Errors from loading, building or exporting a scene. Each names the file and what in it is
/// wrong (node, mesh, primitive, accessor, element; or line for OBJ).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A glTF file is malformed or unsupported.
    #[error("{file}: {context}: {message}")]
    Gltf {
        /// The file (or source name).
        file: String,
        /// Where: `document`, `buffers`, or `node N 'name', mesh M, primitive P, accessor A
        /// (POSITION)` and so on.
        context: String,
        /// What is wrong.
        message: String,
    },
    /// An OBJ file is malformed (the error names the file and line).
    #[error(transparent)]
    Obj(#[from] obj::LoadError),
    /// A mesh is invalid (non-finite position, index out of range, too large).
    #[error("{what}: {source}")]
    Mesh {
        /// Which mesh (object name or what was being built).
        what: String,
        /// The mesh error.
        source: MeshError,
    },
    /// An STL file is malformed (the error names the file and the line or facet).
    #[error("{file}: {location}: {message}")]
    Stl {
        /// The file (or source name).
        file: String,
        /// Where: `line N` (ASCII), `facet T (byte B)` (binary) or `header`.
        location: String,
        /// What is wrong.
        message: String,
    },
    /// A PLY file is malformed (the error names the file and the line or element).
    #[error("{file}: {location}: {message}")]
    Ply {
        /// The file (or source name).
        file: String,
        /// Where: `line N`, `header`, `payload`, or `element vertex I` / `element face F`.
        location: String,
        /// What is wrong.
        message: String,
    },
    /// A scene name is neither a preset nor a file with a known extension.
    #[error(
        "unknown scene '{name}': not a .gltf/.glb/.obj/.stl/.ply file and not a preset \
         (presets: {known})"
    )]
    UnknownPreset {
        /// The name given.
        name: String,
        /// The preset names, comma separated.
        known: String,
    },
    /// The file extension is not one of `.gltf`, `.glb`, `.obj`, `.stl`, `.ply`.
    #[error("{path}: unsupported scene format (expected .gltf, .glb, .obj, .stl or .ply)")]
    UnsupportedFormat {
        /// The path given.
        path: String,
    },
    /// A light's radius is out of range ([`SceneLight::radius`]).
    #[error("light {light}: {message}")]
    LightRadius {
        /// The light's index in [`Scene::lights`].
        light: usize,
        /// What is wrong, with the value.
        message: String,
    },
    /// The scene cannot be encoded as glTF.
    #[error("cannot export: {message}")]
    Export {
        /// Why.
        message: String,
    },
}
