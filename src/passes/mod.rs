//! The registry of pass kinds (every kind a graph file may name), the WGSL modules they share,
//! and what they ask of the scene: its shader defs, its features, its GPU copy.

mod gather;
pub mod hit_point_bvh_lbvh;
pub mod hit_point_bvh_sah;
pub mod hit_point_grid;
pub mod hit_points;
pub mod lanes;
pub mod path_trace;
pub mod photon_grid;
pub mod photon_trace;
pub mod ppm;
pub mod pppm;
mod registry;
pub mod resolve;
pub mod rng;
pub mod scene_resources;
pub mod sppm;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use naga_oil::compose::ShaderDefValue;

use crate::gpu::shaders::{ShaderFile, ShaderLibrary, defs_of};
use crate::graph::pass::{PassKind, SceneNeed};
use crate::scene::{Scene, SceneFeatures};
use crate::shader_file;

/// `bundled!("pt")`: the entry of graphs/pt.ron in [`BUNDLED_GRAPHS`].
macro_rules! bundled {
    ($name:literal) => {
        (
            $name,
            concat!("graphs/", $name, ".ron"),
            include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/graphs/",
                $name,
                ".ron"
            )),
        )
    };
}

pub use registry::{NeedTest, Registry};
pub use scene_resources::{PlacementRule, SceneResources, TablePlacement};

/// The built-in pass kinds, in the order `hppm info` lists them ([`Registry::builtin`] holds
/// them, and a program adds its own there).
pub fn builtin_kinds() -> &'static [&'static PassKind] {
    static KINDS: &[&PassKind] = &[
        &path_trace::KIND,
        &hit_point_bvh_sah::KIND,
        &hit_point_bvh_lbvh::KIND,
        &hit_point_grid::KIND,
        &photon_trace::KIND,
        &photon_grid::KIND,
        &sppm::KIND,
        &ppm::KIND,
        &pppm::KIND,
        &resolve::KIND,
    ];
    KINDS
}

/// Importable modules under `shaders/common/`, in dependency order (a module may import only
/// those above it).
pub const COMMON_MODULES: &[ShaderFile] = &[
    shader_file!("shaders/common/rng.wgsl"),
    shader_file!("shaders/common/sampling.wgsl"),
    shader_file!("shaders/common/scene.wgsl"),
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

/// The graphs shipped in `graphs/`, by name (the file name without `.ron`), with the path
/// errors name them by and their text, compiled into the library.
pub const BUNDLED_GRAPHS: &[(&str, &str, &str)] = &[
    bundled!("hybrid"),
    bundled!("pt"),
    bundled!("hybrid_ppm"),
    bundled!("hybrid_pppm"),
    bundled!("hybrid_lbvh"),
    bundled!("hybrid_grid"),
    bundled!("hybrid_all_depths"),
    bundled!("hybrid_first_vertex"),
    bundled!("hybrid_glossy"),
    bundled!("ppm_only"),
];

/// A bundled graph's path (for messages) and text.
pub fn bundled_graph(name: &str) -> Result<(&'static str, &'static str), crate::Error> {
    BUNDLED_GRAPHS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, file, text)| (*file, *text))
        .ok_or_else(|| {
            let names: Vec<&str> = BUNDLED_GRAPHS.iter().map(|g| g.0).collect();
            crate::Error::Other(format!(
                "no bundled graph \"{name}\"; the bundled graphs: {}",
                names.join(", ")
            ))
        })
}

/// The text of the graph file at `name_or_path`, or, where there is no such file, of the
/// bundled graph it names: by name (`hybrid`) or by its path in hppm's repository
/// (`graphs/hybrid.ron`, which a program run away from the repository is still given). Returns
/// the path errors name with the text.
pub fn read_graph(name_or_path: &Path) -> Result<(PathBuf, String), crate::Error> {
    let missing = match std::fs::read_to_string(name_or_path) {
        Ok(text) => return Ok((name_or_path.to_path_buf(), text)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => e,
        Err(e) => {
            return Err(crate::Error::Other(format!(
                "{}: {e}",
                name_or_path.display()
            )));
        }
    };
    let bundled = BUNDLED_GRAPHS
        .iter()
        .find(|(name, file, _)| name_or_path == Path::new(name) || name_or_path.ends_with(file));
    match bundled {
        Some((_, file, text)) => Ok((PathBuf::from(file), text.to_string())),
        None => {
            let names: Vec<&str> = BUNDLED_GRAPHS.iter().map(|g| g.0).collect();
            Err(crate::Error::Other(format!(
                "{}: {missing} (nor is it a bundled graph: {})",
                name_or_path.display(),
                names.join(", ")
            )))
        }
    }
}

/// Classes of light paths for the partition check (graph/transport.rs), relative to a camera
/// path's photon-mapped vertices (its first `merge_depth` diffuse vertices, docs/design.md section
/// 1). A hybrid counts each exactly once: the camera pass all but `CAUSTIC`, the photon pass
/// and estimator `CAUSTIC`.
pub mod paths {
    use crate::graph::transport::PathClasses;

    /// Paths with no photon-mapped vertex: emission seen directly or through specular vertices,
    /// and everything when no vertex is photon-mapped.
    pub const UNMERGED: u32 = 1;
    /// Light reaching a photon-mapped vertex straight from the light (`L D`).
    pub const DIRECT: u32 = 2;
    /// Light reaching a photon-mapped vertex through specular vertices only (`L S+ D`).
    pub const CAUSTIC: u32 = 4;
    /// Light reaching a photon-mapped vertex after another diffuse vertex (`L ... D D`), except
    /// `DEEP_CAUSTIC`.
    pub const INDIRECT: u32 = 8;
    /// Caustics (`L S+ D`) at the diffuse vertices past a camera path's photon-mapped ones (all
    /// of them when it has none): path traced, or looked up in a `photon_grid`.
    pub const DEEP_CAUSTIC: u32 = 16;
    pub const ALL: u32 = UNMERGED | DIRECT | CAUSTIC | INDIRECT | DEEP_CAUSTIC;

    pub const CLASSES: PathClasses<'static> = PathClasses {
        all: ALL,
        names: &[
            "paths without a photon-mapped vertex",
            "direct light at photon-mapped vertices (L D)",
            "caustics at photon-mapped vertices (L S+ D)",
            "indirect light at photon-mapped vertices (L ... D D)",
            "caustics at diffuse vertices past the photon-mapped ones (L S+ D ... D E)",
        ],
    };
}

/// Checks a `glossy_threshold` param: a roughness (alpha), finite and not negative.
pub(crate) fn check_glossy_threshold(threshold: f32) -> Result<(), ron::error::SpannedError> {
    if threshold.is_finite() && threshold >= 0.0 {
        return Ok(());
    }
    Err(crate::graph::pass::params_error(format!(
        "glossy_threshold is a roughness (alpha) of 0 or more, got {threshold} (0: only delta \
         lobes are specular)"
    )))
}

/// Whether a pass with `glossy_threshold` needs the glossy code (`GLOSSY`) on this scene: only
/// where some lobe could fall below the threshold.
pub(crate) fn glossy_defs(threshold: f32, scene: &SceneResources) -> &'static [&'static str] {
    if scene.smoothest_microfacet < threshold {
        PASS_DEFS
    } else {
        &[]
    }
}

/// A path-length rule as the partition check compares them.
pub(crate) fn depth_rule(max_depth: Option<u32>) -> crate::graph::transport::Depth {
    use crate::graph::transport::Depth;
    max_depth.map_or(Depth::Scene, Depth::Segments)
}

/// A surface with a delta lobe (mirror, smooth or thin dielectric, smooth conductor, plastic's
/// coating): caustic photons need one to become caustic photons.
pub const SPECULAR_SURFACE: SceneNeed = SceneNeed {
    name: "specular_surface",
    description: "specular (delta: mirror, smooth dielectric or conductor, plastic) surface",
    glossy_below: 0.0,
};

/// A surface with a delta lobe or a microfacet lobe smoother than `glossy_below` (the pass's
/// `glossy_threshold`): such a glossy lobe can make a caustic too.
pub const SPECULAR_OR_GLOSSY_SURFACE: SceneNeed = SceneNeed {
    name: "specular_or_glossy_surface",
    description: "specular (delta) surface or glossy one (microfacet: rough conductor, \
                  dielectric, plastic) smoother than the glossy_threshold",
    glossy_below: 0.0,
};

/// Depth at which Russian roulette starts when a path's depth is unbounded and no other start is
/// given (Mitsuba's default `rr_depth`).
const DEFAULT_RR_DEPTH: u32 = 5;

/// (max_depth, rr_depth) after a node's overrides are applied to the scene's integrator
/// settings. With both unbounded, Russian roulette starts at `DEFAULT_RR_DEPTH`, so that every
/// path ends.
pub(crate) fn resolve_depths(
    max_depth: Option<u32>,
    rr_depth: Option<u32>,
    scene: &crate::scene::gpu_layout::GpuSceneUniform,
) -> (u32, u32) {
    use crate::scene::gpu_layout::UNBOUNDED;
    let max_depth = max_depth.unwrap_or(scene.max_depth);
    let mut rr_depth = rr_depth.unwrap_or(scene.rr_depth);
    if max_depth == UNBOUNDED && rr_depth == UNBOUNDED {
        rr_depth = DEFAULT_RR_DEPTH;
    }
    (max_depth, rr_depth)
}

/// Splits a 64-bit seed into the 32 bits a kernel hashes, keeping both halves' entropy.
pub(crate) fn seed32(seed: u64) -> u32 {
    (seed ^ (seed >> 32)) as u32
}
