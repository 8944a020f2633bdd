//! `hit_point_bvh_sah`: the hit-point BVH built on the CPU with the surface area heuristic, as
//! the original hybrid report did. Each iteration it reads the hit points back, builds a tree
//! over their current search spheres (one hit point per leaf) and uploads it in the layout the
//! photon pass traverses.

use std::collections::HashMap;

use serde::Deserialize;

use crate::Error;
use crate::graph::pass::{
    ExecCtx, Pass, PassKind, PrepareCtx, Recorder, Resource, ResourceKind, SlotDecl, parse_params,
};
use crate::passes::hit_points::{build_tree, read_hit_points, tree_bytes, tree_bytes_of};

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", ResourceKind::HitPoints),
    SlotDecl::output("tree", ResourceKind::HitPointTree),
];

pub const KIND: PassKind = PassKind {
    name: "hit_point_bvh_sah",
    description: "hit-point BVH built on the CPU (binned SAH), uploaded every iteration",
    slots: SLOTS,
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

#[derive(Default)]
pub struct HitPointBvhSah {
    prepared: Option<(Resource, Resource)>,
}

impl Pass for HitPointBvhSah {
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<HashMap<&'static str, Resource>, Error> {
        let hit_points = ctx.input("hit_points")?.clone();
        let tree = ctx.gpu.create_buffer(
            "hit_point_bvh_sah tree",
            tree_bytes(hit_points.len),
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        )?;
        let tree = Resource::new(ResourceKind::HitPointTree, tree, hit_points.len);
        self.prepared = Some((hit_points, tree.clone()));
        Ok(HashMap::from([("tree", tree)]))
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some((hit_points, tree)) = &self.prepared else {
            return Ok(());
        };
        // Submit this iteration's camera pass; the readback is queued after it and waits for both.
        recorder.submit();
        let points = read_hit_points(ctx.gpu, &hit_points.buffer, hit_points.len)?;
        let nodes = build_tree(&points);
        // Ordered before the rest of the iteration, which is submitted after this write.
        ctx.gpu
            .queue
            .write_buffer(&tree.buffer, 0, &tree_bytes_of(&nodes));
        Ok(())
    }
}
