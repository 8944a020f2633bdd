//! The gather half of a hit-point structure node: for each photon hit a kernel invocation adds
//! the photon to the hit points whose sphere contains it (several hits in turn per invocation
//! on CPU adapters, `lanes`). Every structure's gather kernel binds hit
//! points, photon hits and deposits first (shaders/common/gather.wgsl), then its own resources.

use crate::Error;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::dispatch::workgroup_grid;
use crate::gpu::shaders::ShaderFile;
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{PrepareCtx, Recorder};
use crate::passes::lanes::items_per_invocation;
use crate::shader_file;

/// The BVH gather, shared by the SAH and LBVH builders (their trees have one layout).
pub const BVH_GATHER: ShaderFile = shader_file!("shaders/passes/gather_bvh.wgsl");

/// `WORKGROUP_SIZE` in shaders/gpu/dispatch.wgsl.
const WORKGROUP: u64 = 256;

pub struct Gather {
    pipeline: wgpu::ComputePipeline,
    scene: wgpu::BindGroup,
    bind_group: wgpu::BindGroup,
    grid: [u32; 3],
}

impl Gather {
    /// The gather `entry` of `shader` over the node's `hit_points` and `photon_hits` inputs
    /// into its `deposits` output, with `structure` bound from binding 3 on.
    pub fn new(
        ctx: &PrepareCtx<'_>,
        label: &str,
        shader: &ShaderFile,
        entry: &str,
        structure: &[(Access, &wgpu::Buffer)],
    ) -> Result<Self, Error> {
        let scene = ctx.shared.get::<SceneResources>()?;
        let hit_points = ctx.input("hit_points")?;
        let photon_hits = ctx.input("photon_hits")?;
        let deposits = ctx.output("deposits")?;
        let mut entries = vec![
            (Access::Read, &*hit_points.buffer),
            (Access::Read, &*photon_hits.buffer),
            (Access::ReadWrite, &*deposits.buffer),
        ];
        entries.extend_from_slice(structure);
        let (layout, bind_group) = bind_buffers(ctx.gpu, label, &entries);
        let pipeline =
            ctx.shaders
                .compute_pipeline(ctx.gpu, shader, entry, &[&scene.layout, &layout])?;
        let hits = u32::try_from(photon_hits.len).unwrap_or(u32::MAX);
        // At most half of u32's range of invocations, so that the kernels' stride (the grid's
        // invocations, rows padded) stays a u32.
        let per_invocation = items_per_invocation(ctx.gpu.info.device_type, hits, 1, u32::MAX / 2);
        let groups = photon_hits
            .len
            .div_ceil(per_invocation as u64)
            .div_ceil(WORKGROUP)
            .max(1);
        let groups = u32::try_from(groups).map_err(|_| {
            Error::Other(format!(
                "{label}: {} photon hits are more than one dispatch can gather",
                photon_hits.len
            ))
        })?;
        Ok(Self {
            pipeline,
            scene: scene.bind_group.clone(),
            bind_group,
            grid: workgroup_grid(groups),
        })
    }

    pub fn record(&self, recorder: &mut Recorder<'_>, label: &str) {
        recorder.dispatch(
            label,
            &self.pipeline,
            &[&self.scene, &self.bind_group],
            self.grid,
        );
    }
}
