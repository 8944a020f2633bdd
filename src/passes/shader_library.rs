//! The WGSL the built-in passes compose against: the scene's module, the shared modules of
//! `shaders/common/` with the BSDF units' between them, the shader defs a scene's features set,
//! and the library built from them for one scene.

use std::collections::HashMap;

use naga_oil::compose::ShaderDefValue;

use super::Registry;
use crate::bsdfs::BsdfRegistry;
use crate::gpu::shaders::{ShaderFile, ShaderLibrary, WgslModule, defs_of};
use crate::gpu_scene::TablePlacement;
use crate::scene::{Scene, SceneFeatures};
use crate::shader_file;

/// Importable modules under `shaders/common/` that the BSDFs' WGSL may use, in dependency order
/// (a module may import only those above it).
pub const COMMON_MODULES: &[ShaderFile] = &[
    shader_file!("shaders/common/rng.wgsl"),
    shader_file!("shaders/common/sampling.wgsl"),
    shader_file!("shaders/common/intersection.wgsl"),
    shader_file!("shaders/common/traversal.wgsl"),
    shader_file!("shaders/common/surface.wgsl"),
    shader_file!("shaders/common/pixel_filter.wgsl"),
    shader_file!("shaders/common/signed_filter.wgsl"),
    shader_file!("shaders/common/camera.wgsl"),
    shader_file!("shaders/common/environment.wgsl"),
    // Before lights: a spot's or projector's texture.
    shader_file!("shaders/common/texture.wgsl"),
    shader_file!("shaders/common/lights.wgsl"),
    shader_file!("shaders/common/medium.wgsl"),
];

/// Importable modules under `shaders/common/` that use the BSDFs' (the material dispatch among
/// them), in dependency order.
pub const PATH_MODULES: &[ShaderFile] = &[
    shader_file!("shaders/common/path_step.wgsl"),
    shader_file!("shaders/common/hit_points.wgsl"),
    shader_file!("shaders/common/gather.wgsl"),
    shader_file!("shaders/common/deposit_sums.wgsl"),
    shader_file!("shaders/common/spatial_hash.wgsl"),
    shader_file!("shaders/common/photon_grid.wgsl"),
];

/// Every module the built-in passes import, in dependency order: the scene's bindings, readers
/// and material kinds (`common::scene`), [`COMMON_MODULES`], the BSDFs' modules and the material
/// dispatch generated from `bsdfs`, then [`PATH_MODULES`].
pub fn common_modules(bsdfs: &BsdfRegistry) -> Vec<WgslModule> {
    let files = |files: &'static [ShaderFile]| files.iter().map(|&f| WgslModule::File(f));
    std::iter::once(crate::gpu_scene::wgsl_module(bsdfs))
        .chain(files(COMMON_MODULES))
        .chain(bsdfs.wgsl_modules())
        .chain(files(PATH_MODULES))
        .collect()
}

/// Shader defs that compile in code for scene features other than BSDFs (each BSDF unit names
/// its own); without them that code is left out.
pub const SCENE_DEFS: &[&str] = &[
    "SPHERES",
    "POINT_LIGHTS",
    "SPOT_LIGHTS",
    "PROJECTORS",
    "DIRECTIONAL_LIGHTS",
    "ENVIRONMENT",
    "TEXTURES",
    "FLOAT_TEXELS",
    "NORMAL_MAPS",
    "MEDIA",
    "GRID_MEDIA",
];

/// Every scene def there is with `bsdfs`: [`SCENE_DEFS`] and the BSDF units' defs.
pub fn scene_def_names(bsdfs: &BsdfRegistry) -> Vec<&'static str> {
    SCENE_DEFS.iter().copied().chain(bsdfs.all_defs()).collect()
}

/// The shader defs a scene needs: those of the BSDF units whose kinds its materials use
/// (`DIELECTRIC`, `CONDUCTOR`, `PLASTIC`, `ROUGH_DIELECTRIC`, `BLENDS`, `PRINCIPLED` for hppm's
/// own), `SPHERES` when it has spheres, `POINT_LIGHTS` when it has a point or spot light or a
/// projector, `SPOT_LIGHTS` a spot light, `PROJECTORS` a projector, `DIRECTIONAL_LIGHTS` a
/// directional light, `ENVIRONMENT` a constant or map light, `TEXTURES` when a material or a
/// light has a texture (the scene then has binding 11), `NORMAL_MAPS` a normalmap or bumpmap
/// (with `TEXTURES`), `MEDIA` participating media (common::medium and the medium step), `GRID_MEDIA` one with a grid.
pub fn scene_defs(
    features: &SceneFeatures,
    bsdfs: &BsdfRegistry,
) -> HashMap<String, ShaderDefValue> {
    let present = [
        ("SPHERES", features.spheres),
        ("POINT_LIGHTS", features.point_lights),
        ("SPOT_LIGHTS", features.spot_lights),
        ("PROJECTORS", features.projectors),
        ("DIRECTIONAL_LIGHTS", features.directional_lights),
        ("ENVIRONMENT", features.environment),
        ("TEXTURES", features.textures),
        ("NORMAL_MAPS", features.normal_maps),
        ("MEDIA", features.media),
        ("GRID_MEDIA", features.grid_media),
    ];
    let scene = present.iter().filter(|(_, on)| *on).map(|(name, _)| *name);
    defs_of(scene.chain(bsdfs.defs_for(&features.bsdfs)))
}

/// Shader defs a pass sets for itself from its params (on top of the scene's): `GLOSSY` compiles
/// in the glossy-caustic partition of `path_trace` and `photon_trace` (a `glossy_threshold`
/// above 0 on a scene with microfacet lobes).
pub const PASS_DEFS: &[&str] = &["GLOSSY"];

/// Every scene def set: kernels composed this way contain all the code there is.
pub fn all_scene_defs(bsdfs: &BsdfRegistry) -> HashMap<String, ShaderDefValue> {
    defs_of(scene_def_names(bsdfs))
}

/// The shader library the built-in passes compose against for `scene` on a device with or
/// without float atomics, with its tables bound as `placement` says
/// ([`Registry::shader_library`] for a registry of one's own).
pub fn shader_library(
    float_atomics: bool,
    scene: &Scene,
    placement: &TablePlacement,
) -> Result<ShaderLibrary, crate::Error> {
    Registry::builtin().shader_library(float_atomics, scene, placement)
}
