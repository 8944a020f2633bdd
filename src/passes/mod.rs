//! The pass kinds a graph file may name, one file each, and the registry that holds them
//! (`registry.rs`); the WGSL they share and the defs a scene sets (`shader_library.rs`); the
//! light-transport partition they declare (`partition.rs`); the scene on the GPU
//! (`scene_resources.rs`).

mod gather;
pub mod hit_point_bvh_lbvh;
pub mod hit_point_bvh_sah;
pub mod hit_point_grid;
pub mod hit_points;
pub mod lanes;
pub mod partition;
pub mod path_trace;
pub mod photon_grid;
pub mod photon_trace;
pub mod ppm;
pub mod pppm;
mod registry;
pub mod resolve;
pub mod rng;

mod shader_library;
pub mod sppm;

use crate::graph::pass::PassKind;

pub use partition::{SPECULAR_OR_GLOSSY_SURFACE, SPECULAR_SURFACE, paths};
pub(crate) use partition::{check_glossy_threshold, depth_rule, glossy_defs, resolve_depths};
pub use registry::{NeedTest, Registry};

pub use shader_library::{
    COMMON_MODULES, PASS_DEFS, PATH_MODULES, SCENE_DEFS, all_scene_defs, common_modules,
    scene_def_names, scene_defs, shader_library,
};

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

/// Splits a 64-bit seed into the 32 bits a kernel hashes, keeping both halves' entropy.
pub(crate) fn seed32(seed: u64) -> u32 {
    (seed ^ (seed >> 32)) as u32
}
