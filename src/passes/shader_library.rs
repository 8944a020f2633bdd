//! The WGSL the built-in passes compose against: the shared modules of `shaders/common/`, the
//! shader defs a scene's features set, and the library built from them for one scene.

use std::collections::HashMap;

use naga_oil::compose::ShaderDefValue;

use super::Registry;
use crate::gpu::shaders::{ShaderFile, ShaderLibrary, WgslModule, defs_of};
use crate::gpu_scene::TablePlacement;
use crate::scene::{Scene, SceneFeatures};
use crate::shader_file;

/// Importable modules under `shaders/common/`, in dependency order (a module may import only
/// those above it); [`common_modules`] puts the scene's own (`common::scene`) before them.
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
    shader_file!("shaders/common/fresnel.wgsl"),
    shader_file!("shaders/common/microfacet.wgsl"),
    shader_file!("shaders/common/bsdf.wgsl"),
    shader_file!("shaders/common/conductor.wgsl"),
    shader_file!("shaders/common/plastic.wgsl"),
    shader_file!("shaders/common/rough_dielectric.wgsl"),
    shader_file!("shaders/common/principled.wgsl"),
    shader_file!("shaders/common/principled_thin.wgsl"),
    shader_file!("shaders/common/normal_map.wgsl"),
    shader_file!("shaders/common/blend.wgsl"),
    shader_file!("shaders/common/material.wgsl"),
    shader_file!("shaders/common/scatter.wgsl"),
    shader_file!("shaders/common/hit_points.wgsl"),
    shader_file!("shaders/common/gather.wgsl"),
    shader_file!("shaders/common/deposit_sums.wgsl"),
    shader_file!("shaders/common/spatial_hash.wgsl"),
    shader_file!("shaders/common/photon_grid.wgsl"),
];

/// Every module the built-in passes import, in dependency order: the scene's bindings and
/// readers (`common::scene`, [`crate::gpu_scene::wgsl_module`]), then [`COMMON_MODULES`].
pub fn common_modules() -> Vec<WgslModule> {
    std::iter::once(crate::gpu_scene::wgsl_module())
        .chain(COMMON_MODULES.iter().map(|&file| WgslModule::File(file)))
        .collect()
}

/// Shader defs that compile in code for scene features; without them that code is left out.
pub const SCENE_DEFS: &[&str] = &[
    "DIELECTRIC",
    "SPHERES",
    "POINT_LIGHTS",
    "SPOT_LIGHTS",
    "PROJECTORS",
    "DIRECTIONAL_LIGHTS",
    "ENVIRONMENT",
    "CONDUCTOR",
    "PLASTIC",
    "ROUGH_DIELECTRIC",
    "TEXTURES",
    "FLOAT_TEXELS",
    "NORMAL_MAPS",
    "BLENDS",
    "PRINCIPLED",
];

/// The shader defs a scene needs: `DIELECTRIC` when a shape has a smooth or thin dielectric
/// BSDF, `CONDUCTOR` a conductor with a Fresnel term (smooth or rough), `PLASTIC` a plastic
/// (smooth or rough), `ROUGH_DIELECTRIC` a rough dielectric, `SPHERES` when it has spheres,
/// `POINT_LIGHTS` when it has a point or spot light or a projector, `SPOT_LIGHTS` a spot light,
/// `PROJECTORS` a projector, `DIRECTIONAL_LIGHTS` a directional light, `ENVIRONMENT` a constant
/// or map light, `TEXTURES` when a material or a light has a texture (the
/// scene then has binding 11), `NORMAL_MAPS` a normalmap or bumpmap (with `TEXTURES`), `BLENDS`
/// a blendbsdf, mask or null BSDF, `PRINCIPLED` a principled BSDF.
pub fn scene_defs(features: &SceneFeatures) -> HashMap<String, ShaderDefValue> {
    let present = [
        ("DIELECTRIC", features.dielectric),
        ("CONDUCTOR", features.conductor),
        ("PLASTIC", features.plastic),
        ("ROUGH_DIELECTRIC", features.rough_dielectric),
        ("SPHERES", features.spheres),
        ("POINT_LIGHTS", features.point_lights),
        ("SPOT_LIGHTS", features.spot_lights),
        ("PROJECTORS", features.projectors),
        ("DIRECTIONAL_LIGHTS", features.directional_lights),
        ("ENVIRONMENT", features.environment),
        ("TEXTURES", features.textures),
        ("NORMAL_MAPS", features.normal_maps),
        ("BLENDS", features.blends),
        ("PRINCIPLED", features.principled),
    ];
    defs_of(present.iter().filter(|(_, on)| *on).map(|(name, _)| *name))
}

/// Shader defs a pass sets for itself from its params (on top of the scene's): `GLOSSY` compiles
/// in the glossy-caustic partition of `path_trace` and `photon_trace` (a `glossy_threshold`
/// above 0 on a scene with microfacet lobes).
pub const PASS_DEFS: &[&str] = &["GLOSSY"];

/// Every scene def set: kernels composed this way contain all the code there is.
pub fn all_scene_defs() -> HashMap<String, ShaderDefValue> {
    defs_of(SCENE_DEFS.iter().copied())
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
