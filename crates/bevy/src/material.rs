//! The material side: the `StandardMaterial` extension that reads the mask, the two textures it
//! binds, and the systems that give casters that material and size the mask to the camera.

use std::collections::HashMap;

use bevy::asset::io::embedded::EmbeddedAssetRegistry;
use bevy::asset::RenderAssetUsages;
use bevy::image::TextureFormatPixelInfo as _;
use bevy::pbr::{ExtendedMaterial, MaterialExtension};
use bevy::prelude::*;
use bevy::render::render_resource::{
    AsBindGroup, Extent3d, TextureDimension, TextureFormat, TextureUsages, TextureViewDescriptor,
    TextureViewDimension,
};
use bevy::shader::ShaderRef;

use crate::extract::VolumeFrame;
use crate::{ShadowVolumes, MAX_LIGHTS};

/// The extension's binding of the mask (binding 100) and of the light table (101); the
/// `StandardMaterial` keeps its own bindings below 100.
#[derive(Asset, AsBindGroup, Reflect, Debug, Clone)]
pub struct ShadowMask {
    /// The screen-space mask, `R16Float`, one layer per marked light: the share of the light
    /// that reaches the pixel, 1 lit, 0 in shadow, `k / N` in a soft light's penumbra.
    #[texture(100, dimension = "2d_array", sample_type = "float", filterable = false)]
    pub mask: Handle<Image>,
    /// Per marked light, one `Rgba32Float` texel: the light's position (`w = 1`, point and spot)
    /// or its direction towards the light (`w = 2`, directional); `w = 0` marks an unused slot.
    #[texture(101, sample_type = "float", filterable = false)]
    pub lights: Handle<Image>,
}

/// The material of every caster: Bevy's `StandardMaterial` with each marked light's shadow
/// factor taken from the mask. The plugin puts it in place of a caster's
/// `MeshMaterial3d<StandardMaterial>` and keeps it equal to that material when it changes; a
/// mesh that stops being a candidate caster gets its `StandardMaterial` back.
pub type ShadowVolumeMaterial = ExtendedMaterial<StandardMaterial, ShadowMask>;

/// The extension's fragment shader, `shaders/bevy_mask.wesl` (WESL, as Bevy 0.20's own shaders:
/// it imports `bevy_pbr`'s lighting): an embedded asset, as Bevy's own shaders are, at this
/// path of the `embedded://` source.
const MASK_SHADER: &str = "shadowvol_bevy/bevy_mask.wesl";

impl MaterialExtension for ShadowMask {
    fn fragment_shader() -> ShaderRef {
        ShaderRef::Path(format!("embedded://{MASK_SHADER}").into())
    }
}

/// A caster's own `StandardMaterial`, kept while the plugin's copy is in its place.
#[derive(Component, Debug, Clone)]
pub(crate) struct SwappedFrom(Handle<StandardMaterial>);

/// The mask and the light table, one pair for the [`ShadowVolumes`] camera.
#[derive(Resource, Debug, Clone)]
pub(crate) struct MaskTextures {
    pub mask: Handle<Image>,
    pub lights: Handle<Image>,
    /// The mask's size in pixels. Kept here: the image lives on the GPU only, so the main
    /// world's copy is gone once uploaded.
    size: (u32, u32),
}

/// Each base material's extended copy, by the base's id.
#[derive(Resource, Debug, Default)]
struct Swapped(HashMap<AssetId<StandardMaterial>, Handle<ShadowVolumeMaterial>>);

pub(crate) fn build(app: &mut App) {
    // The shader as an embedded asset (what `embedded_asset!` does, for a file outside `src`).
    match app.world().get_resource::<EmbeddedAssetRegistry>() {
        Some(registry) => registry.insert_asset(
            std::path::PathBuf::from(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../shaders/bevy_mask.wesl"
            )),
            std::path::Path::new(MASK_SHADER),
            include_bytes!("../../../shaders/bevy_mask.wesl").as_slice(),
        ),
        None => error!(
            "shadowvol: ShadowVolumesPlugin needs Bevy's asset plugin (DefaultPlugins, added \
             before it); the casters will not draw"
        ),
    }
    app.add_plugins(MaterialPlugin::<ShadowVolumeMaterial>::default())
        .init_resource::<Swapped>()
        .add_systems(PreStartup, make_textures)
        .add_systems(
            PostUpdate,
            (swap_materials.after(crate::extract::gather), size_mask),
        );
}

/// A mask of `width × height` pixels and [`MAX_LIGHTS`] layers, drawn by the pass and sampled by
/// the material; it lives on the GPU only.
fn mask_image(width: u32, height: u32) -> Image {
    let mut image = Image::new_uninit(
        Extent3d {
            width: width.max(1),
            height: height.max(1),
            depth_or_array_layers: MAX_LIGHTS as u32,
        },
        TextureDimension::D2,
        TextureFormat::R16Float,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage =
        TextureUsages::TEXTURE_BINDING | TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC;
    image.texture_view_descriptor = Some(TextureViewDescriptor {
        dimension: Some(TextureViewDimension::D2Array),
        ..default()
    });
    image
}

fn make_textures(mut commands: Commands, mut images: ResMut<Assets<Image>>) {
    let format = TextureFormat::Rgba32Float;
    let texel = format.pixel_size().unwrap_or(16);
    let mut lights = Image::new(
        Extent3d {
            width: MAX_LIGHTS as u32,
            height: 1,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        vec![0; texel * MAX_LIGHTS],
        format,
        RenderAssetUsages::RENDER_WORLD,
    );
    lights.texture_descriptor.usage |= TextureUsages::COPY_DST;
    commands.insert_resource(MaskTextures {
        mask: images.add(mask_image(1, 1)),
        lights: images.add(lights),
        size: (1, 1),
    });
}

/// Gives every candidate caster (see [`crate::ShadowCasters`]; not skinned or morphed) with a
/// `StandardMaterial` the extended copy of it, keeps the copies equal to their bases when a base
/// changes, and gives an entity that is no longer a candidate its own material back.
#[allow(clippy::too_many_arguments)]
fn swap_materials(
    mut commands: Commands,
    frame: Res<VolumeFrame>,
    plain: Query<(Entity, &MeshMaterial3d<StandardMaterial>)>,
    swapped_entities: Query<(Entity, &SwappedFrom)>,
    mut events: MessageReader<AssetEvent<StandardMaterial>>,
    standard: Res<Assets<StandardMaterial>>,
    mut extended: ResMut<Assets<ShadowVolumeMaterial>>,
    mut swapped: ResMut<Swapped>,
    textures: Option<Res<MaskTextures>>,
) {
    let Some(textures) = textures else { return };
    for event in events.read() {
        if let AssetEvent::Modified { id } = event {
            if let (Some(copy), Some(base)) = (swapped.0.get(id), standard.get(*id)) {
                if let Some(mut m) = extended.get_mut(copy) {
                    m.base = base.clone();
                }
            }
        }
    }
    let receivers: std::collections::HashSet<Entity> = frame.key.iter().map(|k| k.0).collect();
    for (entity, from) in &swapped_entities {
        if !receivers.contains(&entity) {
            commands
                .entity(entity)
                .remove::<(MeshMaterial3d<ShadowVolumeMaterial>, SwappedFrom)>()
                .insert(MeshMaterial3d(from.0.clone()));
        }
    }
    for (entity, material) in &plain {
        if !receivers.contains(&entity) {
            continue;
        }
        let id = material.id();
        let Some(base) = standard.get(id) else {
            continue; // not loaded yet
        };
        let handle = swapped
            .0
            .entry(id)
            .or_insert_with(|| {
                extended.add(ShadowVolumeMaterial {
                    base: base.clone(),
                    extension: ShadowMask {
                        mask: textures.mask.clone(),
                        lights: textures.lights.clone(),
                    },
                })
            })
            .clone();
        commands
            .entity(entity)
            .remove::<MeshMaterial3d<StandardMaterial>>()
            .insert((MeshMaterial3d(handle), SwappedFrom(material.0.clone())));
    }
}

/// Keeps the mask the size of the [`ShadowVolumes`] camera's viewport, in physical pixels. A new
/// size is a new image, given to every material: a material re-prepared with a new image waits
/// for it to reach the GPU, where one whose image changed in place could keep the old texture.
fn size_mask(
    cameras: Query<(Entity, &Camera), With<ShadowVolumes>>,
    textures: Option<ResMut<MaskTextures>>,
    mut images: ResMut<Assets<Image>>,
    mut materials: ResMut<Assets<ShadowVolumeMaterial>>,
) {
    let Some(mut textures) = textures else { return };
    let Some((_, camera)) = cameras.iter().min_by_key(|(e, _)| *e) else {
        return;
    };
    let Some(size) = camera.physical_viewport_size() else {
        return;
    };
    let wanted = (size.x.max(1), size.y.max(1));
    if textures.size == wanted {
        return;
    }
    textures.size = wanted;
    textures.mask = images.add(mask_image(wanted.0, wanted.1));
    for (_, m) in materials.iter_mut() {
        m.extension.mask = textures.mask.clone();
    }
}
