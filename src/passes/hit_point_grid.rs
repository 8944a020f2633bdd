//! `hit_point_grid`: a uniform hash grid over the hit points' search spheres, built on the GPU
//! every iteration with no readback, and the gather over it (Hachisuka & Jensen 2010, "Parallel
//! Progressive Photon Mapping on GPUs"; pbrt-v4's SPPM). It takes the same inputs and gives the
//! same `deposits` as the BVH nodes, so a graph swaps one for the other in one line.
//!
//! Where the BVHs pay for a sort or a CPU build and a tree walk per photon, the grid costs two
//! passes over the hit points and one list walk per photon: each iteration the kernels find the
//! largest current radius (an atomic max on its f32 bits), choose a cell edge of a little over
//! twice that, so that a sphere's box overlaps at most 2 cells per axis, and push each hit point
//! onto the list of every bucket its box's cells (at most 8) hash to, skipping a bucket it is
//! already in so that no photon is deposited twice. A photon then needs only the list of its own
//! cell's bucket. The cell edge follows the radii, so the grid stays tight as `sppm` shrinks
//! them; the cost is a cell at least as wide as the widest sphere, so very uneven radii put many
//! small spheres in one cell. The cell and rounding rules are in
//! shaders/passes/hit_point_grid.wgsl.

use std::sync::Arc;

use serde::Deserialize;

use crate::Error;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::dispatch::workgroup_grid;
use crate::gpu::layout::StructLayout;
use crate::gpu::shaders::ShaderFile;
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{
    ExecCtx, Pass, PassKind, PrepareCtx, Recorder, ResourceKind, Size, SlotDecl, parse_params,
};
use crate::passes::gather::Gather;
use crate::passes::hit_points::{DEPOSITS, HIT_POINTS, PHOTON_HITS};
use crate::{shader_file, struct_layout};

const SHADER: ShaderFile = shader_file!("shaders/passes/hit_point_grid.wgsl");
/// `WORKGROUP_SIZE` in shaders/gpu/dispatch.wgsl.
const WORKGROUP: u32 = 256;

/// Cells a hit point's box overlaps at most (2 per axis), each with its own entry.
pub const CELLS_PER_HIT_POINT: u64 = 8;
/// Most hit-point slots the kernels index: entries (8 per slot) and bucket heads (at most 4 per
/// slot) share one u32-indexed array.
pub const MAX_SLOTS: u64 = 1 << 28;

/// What the build kernels found this iteration; precedes the words of a grid buffer. Mirrors
/// `GridInfo` in shaders/passes/hit_point_grid.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GridInfo {
    /// Largest padded search radius of a hit point in the grid.
    pub max_radius: f32,
    /// Largest |coordinate| plus padded radius of a hit point in the grid.
    pub magnitude: f32,
    /// Hit points in the grid.
    pub valid: u32,
    /// List entries pushed (a hit point's cells that hash to distinct buckets).
    pub inserted: u32,
    /// Boxes that spanned more than 2 cells on an axis and lost cells: 0 unless the cell rule
    /// is broken.
    pub clipped: u32,
    /// Cell edge in scene units, from the scene's `bounds_min`.
    pub cell: f32,
    pub inv_cell: f32,
    pub _pad: u32,
}

pub const GRID_INFO_BYTES: u64 = std::mem::size_of::<GridInfo>() as u64;

/// `GridUniform` in the shader: what the kernels index by, fixed when the node is prepared.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct GridUniform {
    slots: u32,
    bucket_mask: u32,
    buckets: u32,
    _pad: u32,
}

/// The structs above against their WGSL twins.
const LAYOUTS: &[StructLayout] = &[
    struct_layout!(GridUniform => "GridUniform" in SHADER, { slots, bucket_mask, buckets }),
    struct_layout!(GridInfo => "GridInfo" in SHADER, {
        max_radius, magnitude, valid, inserted, clipped, cell, inv_cell
    }),
];

/// The grid: a `GridInfo`, then u32 words, `bucket_count(slots)` list heads followed by
/// `CELLS_PER_HIT_POINT` entry links per slot. A head or link is an entry index + 1 (0: end of
/// list); entry `e` belongs to hit point `e / 8`. Its length is in words.
pub const HIT_POINT_GRID: ResourceKind = ResourceKind::new("hit_point_grid", GRID_INFO_BYTES, 4);

/// List heads for `slots` hit-point slots: a power of two (the hash keeps the low bits) of at
/// least twice the slots, so that buckets hold few cells' lists each.
pub fn bucket_count(slots: u64) -> u64 {
    (2 * slots.max(1)).next_power_of_two()
}

/// Words of a grid over `slots` hit-point slots.
pub fn grid_words(slots: u64) -> u64 {
    bucket_count(slots) + CELLS_PER_HIT_POINT * slots
}

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", HIT_POINTS),
    SlotDecl::input("photon_hits", PHOTON_HITS),
    SlotDecl::output("deposits", DEPOSITS, Size::LikeInput("hit_points")),
    // Persistent only so that the graph does not zero the entry links every iteration: the
    // node resets the info and heads itself, and a link is written before any list reaches it.
    SlotDecl::output("grid", HIT_POINT_GRID, Size::Computed).persistent(),
];

pub const KIND: PassKind = PassKind {
    name: "hit_point_grid",
    description: "uniform hash grid over hit points built on the GPU every iteration; grid gather",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: LAYOUTS,
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let _: GridParams = parse_params(params)?;
    Ok(Box::new(HitPointGrid::default()))
}

/// No parameters: the cell edge follows the radii and the table the slot count. Declared so
/// that unknown ones are rejected.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct GridParams {}

struct Pipelines {
    bounds: wgpu::ComputePipeline,
    setup: wgpu::ComputePipeline,
    insert: wgpu::ComputePipeline,
}

struct Prepared {
    scene: wgpu::BindGroup,
    bind_group: wgpu::BindGroup,
    pipelines: Pipelines,
    gather: Gather,
    grid: Arc<wgpu::Buffer>,
    /// Hit-point slots.
    slots: u32,
    /// Bytes of the info and heads, which every build starts from zero.
    reset_bytes: u64,
}

#[derive(Default)]
pub struct HitPointGrid {
    prepared: Option<Prepared>,
}

fn slot_count(len: u64) -> Result<u32, Error> {
    u32::try_from(len)
        .ok()
        .filter(|&n| u64::from(n) <= MAX_SLOTS)
        .ok_or_else(|| {
            Error::Other(format!(
                "hit_point_grid: {len} hit-point slots are more than the grid indexes \
                 (at most {MAX_SLOTS})"
            ))
        })
}

impl Pass for HitPointGrid {
    fn output_len(&self, _slot: &str, ctx: &PrepareCtx<'_>) -> Result<u64, Error> {
        let slots = slot_count(ctx.input("hit_points")?.len)?;
        Ok(grid_words(slots.into()))
    }

    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        let hit_points = ctx.input("hit_points")?;
        let photon_hits = ctx.input("photon_hits")?;
        let deposits = ctx.output("deposits")?;
        let grid = ctx.output("grid")?;
        let slots = slot_count(hit_points.len)?;
        // Below 2^30 by MAX_SLOTS, so it fits the kernels' u32.
        let buckets = bucket_count(slots.into()) as u32;
        let params = gpu.create_buffer_init(
            "hit_point_grid params",
            bytemuck::bytes_of(&GridUniform {
                slots,
                bucket_mask: buckets - 1,
                buckets,
                _pad: 0,
            }),
            wgpu::BufferUsages::UNIFORM,
        )?;
        // The gather's bindings and the grid's, in the gather's order: the build kernels share
        // the gather's shader file, whose bindings 0-2 come from common::gather.
        let (layout, bind_group) = bind_buffers(
            gpu,
            "hit_point_grid build",
            &[
                (Access::Read, &hit_points.buffer),
                (Access::Read, &photon_hits.buffer),
                (Access::ReadWrite, &deposits.buffer),
                (Access::Uniform, &params),
                (Access::ReadWrite, &grid.buffer),
            ],
        );
        let pipeline = |entry| {
            ctx.shaders
                .compute_pipeline(gpu, &SHADER, entry, &[&scene.layout, &layout])
        };
        let pipelines = Pipelines {
            bounds: pipeline("bounds")?,
            setup: pipeline("setup")?,
            insert: pipeline("insert")?,
        };
        let gather = Gather::new(
            &ctx,
            "hit_point_grid gather",
            &SHADER,
            "main",
            &[
                (Access::Uniform, &params),
                (Access::ReadWrite, &grid.buffer),
            ],
        )?;
        self.prepared = Some(Prepared {
            scene: scene.bind_group.clone(),
            bind_group,
            pipelines,
            gather,
            grid: grid.buffer.clone(),
            slots,
            reset_bytes: GRID_INFO_BYTES + 4 * u64::from(buckets),
        });
        Ok(())
    }

    fn execute(&mut self, _ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        if p.slots == 0 {
            return Ok(());
        }
        let groups = [&p.scene, &p.bind_group];
        let per_slot = workgroup_grid(p.slots.div_ceil(WORKGROUP));
        recorder
            .encoder()
            .clear_buffer(&p.grid, 0, Some(p.reset_bytes));
        recorder.dispatch(
            "hit_point_grid bounds",
            &p.pipelines.bounds,
            &groups,
            per_slot,
        );
        recorder.dispatch(
            "hit_point_grid setup",
            &p.pipelines.setup,
            &groups,
            [1, 1, 1],
        );
        recorder.dispatch(
            "hit_point_grid insert",
            &p.pipelines.insert,
            &groups,
            per_slot,
        );
        p.gather.record(recorder, "hit_point_grid gather");
        Ok(())
    }
}
