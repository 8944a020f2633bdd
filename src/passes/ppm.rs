//! `ppm`: progressive photon mapping as first published (Hachisuka et al. 2008). The hit points
//! of the first camera pass are kept (the camera pass stops rewriting them) and only photon
//! passes repeat; the merge is the same as `sppm`'s (src/passes/sppm.rs). Path tracing, when the
//! graph has it, still adds a sample per pixel every iteration.

use crate::graph::pass::{Pass, PassKind};
use crate::passes::sppm::{Merge, MergeParams, SLOTS};

pub const KIND: PassKind = PassKind {
    name: "ppm",
    description: "progressive photon mapping: hit points of one camera pass, photon passes repeat",
    slots: SLOTS,
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    Ok(Box::new(Merge::new(MergeParams::parse(params)?, true)))
}
