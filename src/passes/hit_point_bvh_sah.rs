//! `hit_point_bvh_sah`: the hit-point BVH built on the CPU with the surface area heuristic, as
//! the original hybrid report did, and the BVH gather over it. Each iteration it reads the hit
//! points back, builds a tree over their current search spheres (one hit point per leaf),
//! uploads it in the layout the gather traverses, and gathers this iteration's photon hits
//! into `deposits`.

use serde::Deserialize;

use crate::Error;
use crate::gpu::binding::Access;
use crate::graph::pass::{
    ExecCtx, Pass, PassKind, PrepareCtx, Recorder, Resource, Size, SlotDecl, parse_params,
};
use crate::passes::gather::{BVH_GATHER, Gather};
use crate::passes::hit_points::{
    DEPOSITS, HIT_POINT_TREE, HIT_POINTS, PHOTON_HITS, build_tree, tree_bytes_of, tree_nodes,
};

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", HIT_POINTS),
    SlotDecl::input("photon_hits", PHOTON_HITS),
    SlotDecl::output("deposits", DEPOSITS, Size::LikeInput("hit_points")),
    SlotDecl::output("tree", HIT_POINT_TREE, Size::Computed),
];

pub const KIND: PassKind = PassKind {
    name: "hit_point_bvh_sah",
    description: "hit-point BVH built on the CPU (binned SAH) every iteration; BVH gather",
    slots: SLOTS,
    shaders: &[BVH_GATHER],
    layouts: &[],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let _: SahParams = parse_params(params)?;
    Ok(Box::new(HitPointBvhSah::default()))
}

/// No parameters yet; declared so that unknown ones are rejected.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct SahParams {}

struct Prepared {
    hit_points: Resource,
    tree: Resource,
    gather: Gather,
}

#[derive(Default)]
pub struct HitPointBvhSah {
    prepared: Option<Prepared>,
}

impl Pass for HitPointBvhSah {
    fn output_len(&self, _slot: &str, ctx: &PrepareCtx<'_>) -> Result<u64, Error> {
        Ok(tree_nodes(ctx.input("hit_points")?.len))
    }

    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let tree = ctx.output("tree")?.clone();
        let gather = Gather::new(
            &ctx,
            "hit_point_bvh_sah gather",
            &BVH_GATHER,
            "main",
            &[(Access::Read, &tree.buffer)],
        )?;
        self.prepared = Some(Prepared {
            hit_points: ctx.input("hit_points")?.clone(),
            tree,
            gather,
        });
        Ok(())
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        // Submit this iteration's camera pass; the readback is queued after it and waits for both.
        recorder.submit();
        let points = p.hit_points.read(ctx.gpu)?;
        let nodes = build_tree(&points);
        // Ordered before the rest of the iteration, which is submitted after this write.
        ctx.gpu
            .queue
            .write_buffer(&p.tree.buffer, 0, &tree_bytes_of(&nodes));
        p.gather.record(recorder, "hit_point_bvh_sah gather");
        Ok(())
    }
}
