//! The registry of pass kinds: every kind a graph file may name.

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
        photon_trace::KIND,
        sppm::KIND,
        ppm::KIND,
        resolve::KIND,
    ];
    KINDS
}

/// Splits a 64-bit seed into the 32 bits a kernel hashes, keeping both halves' entropy.
pub(crate) fn seed32(seed: u64) -> u32 {
    (seed ^ (seed >> 32)) as u32
}
