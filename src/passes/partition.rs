//! The light-transport partition as the passes declare it (docs/design.md section 1): the path
//! classes the transport check counts, the scene needs of photon passes, the glossy threshold's
//! rules and the path-length rules a node's overrides resolve to.

use crate::gpu_scene::SceneResources;
use crate::graph::pass::SceneNeed;
use crate::passes::PASS_DEFS;

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
    scene: &crate::gpu_scene::layout::GpuSceneUniform,
) -> (u32, u32) {
    use crate::gpu_scene::layout::UNBOUNDED;
    let max_depth = max_depth.unwrap_or(scene.max_depth);
    let mut rr_depth = rr_depth.unwrap_or(scene.rr_depth);
    if max_depth == UNBOUNDED && rr_depth == UNBOUNDED {
        rr_depth = DEFAULT_RR_DEPTH;
    }
    (max_depth, rr_depth)
}
