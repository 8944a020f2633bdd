//! `path_trace`: the camera pass. Traces `samples_per_iteration` paths per pixel with next-event
//! estimation and adds them to the persistent `radiance` accumulator (sum and count per pixel).

use std::collections::HashMap;

use serde::Deserialize;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::graph::pass::{
    ExecCtx, Pass, PassKind, PassStats, PrepareCtx, Resource, ResourceKind, SlotDecl, parse_params,
};
use crate::scene::gpu_layout::UNBOUNDED;

const SHADER: &str = "shaders/passes/path_trace.wgsl";
const WORKGROUP: u32 = 8;

static SLOTS: &[SlotDecl] = &[SlotDecl::output("radiance", ResourceKind::Radiance).persistent()];

pub const KIND: PassKind = PassKind {
    name: "path_trace",
    description: "camera paths with next-event estimation (MIS for area lights)",
    slots: SLOTS,
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    Ok(Box::new(PathTrace::new(parse_params(params)?)))
}

/// Depth at which Russian roulette starts when a path's depth is unbounded and no other start is
/// given (Mitsuba's default `rr_depth`).
const DEFAULT_RR_DEPTH: u32 = 5;

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
}

impl Default for PathTraceParams {
    fn default() -> Self {
        Self {
            max_depth: None,
            samples_per_iteration: 1,
            rr_depth: None,
        }
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
    _pad: [u32; 3],
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

    /// Depth limits after applying the graph's overrides to the scene's integrator settings.
    fn depths(&self, scene_max_depth: u32, scene_rr_depth: u32) -> (u32, u32) {
        let max_depth = self.params.max_depth.unwrap_or(scene_max_depth);
        let mut rr_depth = self.params.rr_depth.unwrap_or(scene_rr_depth);
        if max_depth == UNBOUNDED && rr_depth == UNBOUNDED {
            rr_depth = DEFAULT_RR_DEPTH;
        }
        (max_depth, rr_depth)
    }
}

/// Splits a 64-bit seed into the 32 bits the kernel hashes, keeping both halves' entropy.
fn seed32(seed: u64) -> u32 {
    (seed ^ (seed >> 32)) as u32
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
        let (layout, bind_group) = bind_buffers(
            &gpu.device,
            "path_trace",
            &[
                (Access::Uniform, &params),
                (Access::ReadWrite, &radiance),
                (Access::ReadWrite, &counters),
            ],
        );
        let pipeline =
            ctx.shaders
                .compute_pipeline(gpu, SHADER, "main", &[&ctx.scene.layout, &layout])?;
        let (max_depth, rr_depth) =
            self.depths(ctx.scene.uniform.max_depth, ctx.scene.uniform.rr_depth);
        self.prepared = Some(Prepared {
            pipeline,
            bind_group,
            params,
            counters,
            width: ctx.width,
            height: ctx.height,
            max_depth,
            rr_depth,
        });
        let resource = Resource {
            kind: ResourceKind::Radiance,
            buffer: std::sync::Arc::new(radiance),
            len: pixels,
        };
        Ok(HashMap::from([("radiance", resource)]))
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, encoder: &mut wgpu::CommandEncoder) {
        let Some(p) = &self.prepared else { return };
        let spp = self.params.samples_per_iteration;
        let gpu_params = GpuParams {
            sample_base: (ctx.iteration as u32).wrapping_mul(spp),
            samples_per_iteration: spp,
            seed: seed32(ctx.seed),
            max_depth: p.max_depth,
            rr_depth: p.rr_depth,
            _pad: [0; 3],
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&gpu_params));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("path_trace"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&p.pipeline);
        pass.set_bind_group(0, &ctx.scene.bind_group, &[]);
        pass.set_bind_group(1, &p.bind_group, &[]);
        pass.dispatch_workgroups(p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1);
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
        })
    }
}
