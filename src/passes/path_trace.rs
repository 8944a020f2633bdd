//! `path_trace`: the camera pass. Traces `samples_per_iteration` paths per pixel with next-event
//! estimation and adds them to the persistent `radiance` accumulator (sum and count per pixel).
//!
//! When its `hit_points` output feeds another node, the first `merge_depth` diffuse vertices of
//! each pixel's first sample become hit points for photon mapping, and the emission that photon
//! mapping will add there (reached through specular vertices) is left out of `radiance`.

use std::collections::HashMap;
use std::sync::atomic::Ordering;

use serde::Deserialize;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::graph::pass::{
    ExecCtx, Pass, PassKind, PassStats, PrepareCtx, Recorder, Resource, ResourceKind, SlotDecl,
    parse_params,
};
use crate::passes::hit_points::{
    DEFAULT_RADIUS_PIXELS, HEADER_BYTES, HIT_POINT_BYTES, HitPointHeader,
};
use crate::passes::resolve_depths;
use crate::scene::gpu_layout::UNBOUNDED;

const SHADER: &str = "shaders/passes/path_trace.wgsl";
const WORKGROUP: u32 = 8;

static SLOTS: &[SlotDecl] = &[
    SlotDecl::output("radiance", ResourceKind::Radiance).persistent(),
    SlotDecl::output("hit_points", ResourceKind::HitPoints).persistent(),
];

pub const KIND: PassKind = PassKind {
    name: "path_trace",
    description: "camera paths with next-event estimation (MIS for area lights)",
    slots: SLOTS,
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    Ok(Box::new(PathTrace::new(parse_params(params)?)))
}

#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PathTraceParams {
    /// Longest path in segments (Mitsuba's rule); `None` takes the scene's.
    pub max_depth: Option<u32>,
    /// Camera samples per pixel in one iteration.
    pub samples_per_iteration: u32,
    /// Depth from which Russian roulette terminates paths; `None` takes the scene's (off unless
    /// the scene asks for it, or its depth is unbounded).
    pub rr_depth: Option<u32>,
    /// Photon-mapped diffuse vertices per path: `1` (SPPM) up to `max` (every diffuse vertex,
    /// as in the original hybrid report). Used only when `hit_points` is connected.
    pub merge_depth: MergeDepth,
    /// Continue paths past photon-mapped vertices (hybrid). `false` stops them there, so path
    /// tracing adds only emission seen directly or through specular surfaces (photon mapping
    /// alone).
    pub trace_beyond: bool,
}

impl Default for PathTraceParams {
    fn default() -> Self {
        Self {
            max_depth: None,
            samples_per_iteration: 1,
            rr_depth: None,
            merge_depth: MergeDepth::Depth(1),
            trace_beyond: true,
        }
    }
}

/// `merge_depth: 2` or `merge_depth: max`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MergeDepth {
    Depth(u32),
    Max,
}

/// Hit-point slots per pixel for `merge_depth: max` when the path depth is unbounded.
const MAX_MERGE_SLOTS: u32 = 16;

impl MergeDepth {
    /// Hit-point slots per pixel: a diffuse vertex needs at least one segment before it and one
    /// after it, so a path of `max_depth` segments has at most `max_depth - 1`.
    pub fn slots(self, max_depth: u32) -> u32 {
        let possible = if max_depth == UNBOUNDED {
            MAX_MERGE_SLOTS
        } else {
            max_depth.saturating_sub(1)
        };
        match self {
            MergeDepth::Depth(d) => d.min(possible),
            MergeDepth::Max => possible,
        }
    }
}

impl<'de> Deserialize<'de> for MergeDepth {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        // RON hands a bare identifier such as `max` to generic visitors as a unit value without
        // its name, so read the raw text of the value and look at it.
        use serde::de::Error as _;
        let raw = Box::<ron::value::RawValue>::deserialize(deserializer)?;
        let text = raw.get_ron().trim();
        if text == "max" {
            return Ok(MergeDepth::Max);
        }
        raw.into_rust::<u32>().map(MergeDepth::Depth).map_err(|_| {
            D::Error::custom(format!(
                "merge_depth is a whole number (1, 2, ...) or `max`, got `{text}`"
            ))
        })
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParams {
    sample_base: u32,
    samples_per_iteration: u32,
    seed: u32,
    max_depth: u32,
    rr_depth: u32,
    merge_depth: u32,
    record: u32,
    trace_beyond: u32,
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    counters: wgpu::Buffer,
    width: u32,
    height: u32,
    max_depth: u32,
    rr_depth: u32,
    merge_slots: u32,
    hit_points: Resource,
}

pub struct PathTrace {
    params: PathTraceParams,
    prepared: Option<Prepared>,
}

impl PathTrace {
    pub fn new(params: PathTraceParams) -> Self {
        Self {
            params,
            prepared: None,
        }
    }
}

impl Pass for PathTrace {
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<HashMap<&'static str, Resource>, Error> {
        let gpu = ctx.gpu;
        let pixels = ctx.width as u64 * ctx.height as u64;
        let radiance = gpu.create_buffer(
            "path_trace radiance",
            pixels * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let params = gpu.create_buffer(
            "path_trace params",
            std::mem::size_of::<GpuParams>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let counters = gpu.create_buffer(
            "path_trace counters",
            16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let (max_depth, rr_depth) = resolve_depths(
            self.params.max_depth,
            self.params.rr_depth,
            &ctx.scene.uniform,
        );
        // No consumer, no hit points: the pass is then a plain path tracer that drops nothing.
        let merge_slots = if ctx.consumed.contains("hit_points") {
            self.params.merge_depth.slots(max_depth)
        } else {
            0
        };
        let hit_point_slots = pixels * merge_slots as u64;
        let hit_points = gpu.create_buffer(
            "path_trace hit_points",
            HEADER_BYTES + hit_point_slots.max(1) * HIT_POINT_BYTES,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        // A default the estimator overwrites when it is prepared.
        let header = HitPointHeader::new(
            0.0,
            DEFAULT_RADIUS_PIXELS,
            ctx.scene.uniform.scene_radius,
            merge_slots,
        );
        gpu.queue
            .write_buffer(&hit_points, 0, bytemuck::bytes_of(&header));
        let (layout, bind_group) = bind_buffers(
            &gpu.device,
            "path_trace",
            &[
                (Access::Uniform, &params),
                (Access::ReadWrite, &radiance),
                (Access::ReadWrite, &counters),
                (Access::ReadWrite, &hit_points),
            ],
        );
        let pipeline =
            ctx.shaders
                .compute_pipeline(gpu, SHADER, "main", &[&ctx.scene.layout, &layout])?;
        let hit_points = Resource::new(ResourceKind::HitPoints, hit_points, hit_point_slots);
        self.prepared = Some(Prepared {
            pipeline,
            bind_group,
            params,
            counters,
            width: ctx.width,
            height: ctx.height,
            max_depth,
            rr_depth,
            merge_slots,
            hit_points: hit_points.clone(),
        });
        let radiance = Resource::new(ResourceKind::Radiance, radiance, pixels);
        Ok(HashMap::from([
            ("radiance", radiance),
            ("hit_points", hit_points),
        ]))
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        let record = ctx.iteration == 0 || !p.hit_points.frozen.load(Ordering::Relaxed);
        let spp = self.params.samples_per_iteration;
        let gpu_params = GpuParams {
            sample_base: (ctx.iteration as u32).wrapping_mul(spp),
            samples_per_iteration: spp,
            seed: crate::passes::seed32(ctx.seed),
            max_depth: p.max_depth,
            rr_depth: p.rr_depth,
            merge_depth: p.merge_slots,
            record: record as u32,
            trace_beyond: self.params.trace_beyond as u32,
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&gpu_params));
        recorder.dispatch(
            "path_trace",
            &p.pipeline,
            &ctx.scene.bind_group,
            &p.bind_group,
            [p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1],
        );
        Ok(())
    }

    fn samples_per_iteration(&self) -> u32 {
        self.params.samples_per_iteration
    }

    fn stats(&self, gpu: &GpuContext) -> Result<PassStats, Error> {
        let Some(p) = &self.prepared else {
            return Ok(PassStats::default());
        };
        let c: Vec<u32> = gpu.read_pod(&p.counters, 4)?;
        let wide = |lo: u32, hi: u32| (hi as u64) << 32 | lo as u64;
        Ok(PassStats {
            rays: wide(c[0], c[1]),
            discarded_samples: wide(c[2], c[3]),
            ..Default::default()
        })
    }
}
