//! The registry of pass kinds: every kind a graph file may name.

pub mod hit_point_bvh_lbvh;
pub mod hit_point_bvh_sah;
pub mod hit_points;
pub mod path_trace;
pub mod photon_trace;
pub mod ppm;
pub mod resolve;
pub mod sppm;

use crate::graph::pass::PassKind;

/// All pass kinds, in the order `hppm info` lists them.
pub fn registry() -> &'static [PassKind] {
    static KINDS: &[PassKind] = &[
        path_trace::KIND,
        hit_point_bvh_sah::KIND,
        hit_point_bvh_lbvh::KIND,
        photon_trace::KIND,
        sppm::KIND,
        ppm::KIND,
        resolve::KIND,
    ];
    KINDS
}

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
