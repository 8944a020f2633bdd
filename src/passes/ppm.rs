//! `ppm`: progressive photon mapping as first published (Hachisuka et al. 2008). The hit points
//! of the first camera pass are kept (its `hit_points` input is declared kept, so the camera
//! pass records them once) and only photon passes repeat; the merge is the same as `sppm`'s
//! (src/passes/sppm.rs). Path tracing, when the graph has it, still adds a sample per pixel
//! every iteration.

use crate::graph::pass::{IMAGE, Pass, PassKind, Size, SlotDecl};
use crate::passes::hit_points::{DEPOSITS, HIT_POINT_RADII, HIT_POINTS, KERNEL_BIAS};
use crate::passes::sppm::{Merge, MergeParams, PARAMS_LAYOUT, SHADER, STATS_LAYOUT};

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", HIT_POINTS).kept().exclusive(),
    SlotDecl::input("deposits", DEPOSITS),
    SlotDecl::output("radiance", IMAGE, Size::Pixels),
    SlotDecl::output("radii", HIT_POINT_RADII, Size::LikeInput("hit_points"))
        .persistent()
        .required(),
    SlotDecl::output(KERNEL_BIAS, IMAGE, Size::Pixels),
];

pub const KIND: PassKind = PassKind {
    name: "ppm",
    description: "progressive photon mapping: hit points of one camera pass, photon passes repeat",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: &[PARAMS_LAYOUT, STATS_LAYOUT],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    Ok(Box::new(Merge::new(MergeParams::parse(params)?)))
}
