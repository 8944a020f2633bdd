//! `hit_point_bvh_lbvh`: the hit-point BVH built on the GPU every iteration, with no readback: a
//! linear BVH (Morton codes, GPU radix sort, Karras 2012 hierarchy, bottom-up refit; see
//! shaders/passes/lbvh.wgsl) in the same layout as `hit_point_bvh_sah`'s, gathered by the same
//! BVH gather, so the two nodes are interchangeable in a graph. Every hit-point slot gets a
//! leaf; slots without a hit point get empty boxes, which traversal never enters.
//!
//! While the hit points keep their positions (their producer keeps them for `ppm`, which only
//! shrinks radii), the tree's shape stays valid, so after the first build only the refit runs,
//! with the current radii.

use serde::Deserialize;

use crate::Error;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::dispatch::workgroup_grid;
use crate::gpu::radix_sort::RadixSort;
use crate::gpu::shaders::ShaderFile;
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{
    ExecCtx, Pass, PassKind, PrepareCtx, Recorder, Size, SlotDecl, parse_params,
};
use crate::passes::gather::{BVH_GATHER, Gather};
use crate::passes::hit_points::{DEPOSITS, HIT_POINT_TREE, HIT_POINTS, PHOTON_HITS, tree_nodes};
use crate::shader_file;

const SHADER: ShaderFile = shader_file!("shaders/passes/lbvh.wgsl");
/// `WORKGROUP_SIZE` in shaders/gpu/dispatch.wgsl.
const WORKGROUP: u32 = 256;

/// `LbvhUniform` in the shader (the graph file's params are `LbvhParams`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LbvhUniform {
    /// Hit-point slots (leaves).
    count: u32,
    _pad: [u32; 3],
}

const PARAMS_LAYOUT: crate::gpu::layout::StructLayout =
    crate::struct_layout!(LbvhUniform => "LbvhUniform" in SHADER, { count });

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", HIT_POINTS),
    SlotDecl::input("photon_hits", PHOTON_HITS),
    SlotDecl::output("deposits", DEPOSITS, Size::LikeInput("hit_points")),
    // Kept across iterations: a refit needs the shape of the last full build.
    SlotDecl::output("tree", HIT_POINT_TREE, Size::Computed).persistent(),
];

pub const KIND: PassKind = PassKind {
    name: "hit_point_bvh_lbvh",
    description: "hit-point BVH built on the GPU (Morton codes, radix sort, Karras); BVH gather",
    slots: SLOTS,
    shaders: &[SHADER, BVH_GATHER, crate::gpu::radix_sort::SHADER],
    layouts: &[PARAMS_LAYOUT],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let params: LbvhParams = parse_params(params)?;
    Ok(Box::new(HitPointBvhLbvh::new(params)))
}

/// When to skip the sort and hierarchy and only recompute bounds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
pub enum RefitOnly {
    /// After the first build, whenever the hit points' producer keeps them.
    #[default]
    Auto,
    /// Rebuild every iteration.
    Never,
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LbvhParams {
    pub refit_only: RefitOnly,
}

/// How many times the pass built the tree from scratch and how many times it only refit it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BuildCounts {
    pub full: u64,
    pub refit: u64,
}

struct Pipelines {
    morton_codes: wgpu::ComputePipeline,
    emit_hierarchy: wgpu::ComputePipeline,
    reset_bounds: wgpu::ComputePipeline,
    refit: wgpu::ComputePipeline,
    finish_bounds: wgpu::ComputePipeline,
}

struct Prepared {
    /// The hit points' producer keeps them (written once; only radii change).
    kept: bool,
    scene: wgpu::BindGroup,
    gather: Gather,
    /// Leaves (hit-point slots).
    count: u32,
    keys: wgpu::Buffer,
    values: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pipelines: Pipelines,
    sort: RadixSort,
}

pub struct HitPointBvhLbvh {
    params: LbvhParams,
    prepared: Option<Prepared>,
    builds: BuildCounts,
}

impl HitPointBvhLbvh {
    pub fn new(params: LbvhParams) -> Self {
        Self {
            params,
            prepared: None,
            builds: BuildCounts::default(),
        }
    }

    pub fn builds(&self) -> BuildCounts {
        self.builds
    }

    /// A full build is needed first, and whenever the hit points may have moved.
    fn needs_full_build(&self, kept: bool) -> bool {
        self.builds.full == 0 || self.params.refit_only == RefitOnly::Never || !kept
    }
}

/// Leaf count as the kernels index it (i32 sorted positions in the hierarchy kernel).
fn leaf_count(len: u64) -> Result<u32, Error> {
    u32::try_from(len)
        .ok()
        .filter(|&n| n < i32::MAX as u32 / 2)
        .ok_or_else(|| {
            Error::Other(format!(
                "hit_point_bvh_lbvh: {len} hit-point slots are more than the builder indexes"
            ))
        })
}

fn create_pipelines(
    ctx: &PrepareCtx<'_>,
    scene: &wgpu::BindGroupLayout,
    layout: &wgpu::BindGroupLayout,
) -> Result<Pipelines, Error> {
    let pipeline = |entry| {
        ctx.shaders
            .compute_pipeline(ctx.gpu, &SHADER, entry, &[scene, layout])
    };
    Ok(Pipelines {
        morton_codes: pipeline("morton_codes")?,
        emit_hierarchy: pipeline("emit_hierarchy")?,
        reset_bounds: pipeline("reset_bounds")?,
        refit: pipeline("refit")?,
        finish_bounds: pipeline("finish_bounds")?,
    })
}

impl Pass for HitPointBvhLbvh {
    fn output_len(&self, _slot: &str, ctx: &PrepareCtx<'_>) -> Result<u64, Error> {
        Ok(tree_nodes(ctx.input("hit_points")?.len))
    }

    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        let hit_points = ctx.input("hit_points")?;
        let tree = ctx.output("tree")?;
        let count = leaf_count(hit_points.len)?;
        let storage = wgpu::BufferUsages::STORAGE;
        // The shape, and so the node count, depends only on the number of slots.
        let node_count = (2 * count).saturating_sub(1);
        gpu.queue.write_buffer(
            &tree.buffer,
            0,
            bytemuck::cast_slice(&[node_count, 0, 0, 0]),
        );
        let words = |n: u64| n.max(1) * 4;
        let keys = gpu.create_buffer("lbvh keys", words(count as u64), storage)?;
        let values = gpu.create_buffer("lbvh values", words(count as u64), storage)?;
        let node_slots = gpu.create_buffer("lbvh node slots", words(2 * count as u64), storage)?;
        let parents = gpu.create_buffer("lbvh parents", words(2 * count as u64), storage)?;
        let params = LbvhUniform {
            count,
            _pad: [0; 3],
        };
        let params = gpu.create_buffer_init(
            "lbvh params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let (layout, bind_group) = bind_buffers(
            gpu,
            "hit_point_bvh_lbvh",
            &[
                (Access::Uniform, &params),
                (Access::Read, &hit_points.buffer),
                (Access::ReadWrite, &keys),
                (Access::ReadWrite, &values),
                (Access::ReadWrite, &tree.buffer),
                (Access::ReadWrite, &node_slots),
                (Access::ReadWrite, &parents),
            ],
        );
        let pipelines = create_pipelines(&ctx, &scene.layout, &layout)?;
        let sort = RadixSort::new(gpu, ctx.shaders)?;
        let gather = Gather::new(
            &ctx,
            "hit_point_bvh_lbvh gather",
            &BVH_GATHER,
            "main",
            &[(Access::Read, &tree.buffer)],
        )?;
        self.prepared = Some(Prepared {
            kept: ctx.kept_inputs.contains("hit_points"),
            scene: scene.bind_group.clone(),
            gather,
            count,
            keys,
            values,
            bind_group,
            pipelines,
            sort,
        });
        self.builds = BuildCounts::default();
        Ok(())
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let full = match &self.prepared {
            Some(p) if p.count > 0 => self.needs_full_build(p.kept),
            _ => return Ok(()),
        };
        let Some(p) = &mut self.prepared else {
            return Ok(());
        };
        let scene = &p.scene;
        let per_leaf = workgroup_grid(p.count.div_ceil(WORKGROUP));
        let per_internal = workgroup_grid((p.count - 1).div_ceil(WORKGROUP));
        if full {
            let codes = &p.pipelines.morton_codes;
            recorder.dispatch(
                "lbvh morton codes",
                codes,
                &[scene, &p.bind_group],
                per_leaf,
            );
            p.sort
                .record(ctx.gpu, recorder.encoder(), &p.keys, &p.values, p.count)?;
            let emit = &p.pipelines.emit_hierarchy;
            recorder.dispatch(
                "lbvh hierarchy",
                emit,
                &[scene, &p.bind_group],
                per_internal,
            );
            self.builds.full += 1;
        } else {
            self.builds.refit += 1;
        }
        // Three dispatches because only whole dispatches are ordered (see refit in
        // shaders/passes/lbvh.wgsl).
        let bounds = [
            ("lbvh reset bounds", &p.pipelines.reset_bounds, per_internal),
            ("lbvh refit", &p.pipelines.refit, per_leaf),
            (
                "lbvh finish bounds",
                &p.pipelines.finish_bounds,
                per_internal,
            ),
        ];
        for (label, pipeline, grid) in bounds {
            recorder.dispatch(label, pipeline, &[scene, &p.bind_group], grid);
        }
        p.gather.record(recorder, "hit_point_bvh_lbvh gather");
        Ok(())
    }
}
