//! `sppm` (default estimator): stochastic progressive photon mapping (Hachisuka & Jensen 2009).
//! Every iteration the camera pass regenerates the hit points; per pixel and photon-mapped
//! depth this node keeps N, R and tau across iterations and merges each iteration's deposits
//! with the update of design.md section 2. Its `radiance` output is the photon-mapped radiance
//! (w = 1). `ppm` (src/passes/ppm.rs) runs the same merge on hit points it keeps.

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
use crate::passes::hit_points::{DEFAULT_RADIUS_PIXELS, HitPointHeader, read_hit_points};

const SHADER: &str = "shaders/passes/merge.wgsl";
const WORKGROUP: u32 = 8;
/// Bytes of one slot's N, tau and photon total (`SlotStats` in merge.wgsl).
const SLOT_STATS_BYTES: u64 = 32;

pub(crate) static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", ResourceKind::HitPoints),
    SlotDecl::input("deposits", ResourceKind::Deposits),
    SlotDecl::output("radiance", ResourceKind::Radiance).persistent(),
];

pub const KIND: PassKind = PassKind {
    name: "sppm",
    description: "stochastic progressive photon mapping: per-pixel N, R, tau over iterations",
    slots: SLOTS,
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    Ok(Box::new(Merge::new(MergeParams::parse(params)?, false)))
}

#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MergeParams {
    /// Fraction of new photons kept in N each iteration (Hachisuka et al.'s alpha), in (0, 1).
    pub alpha: f32,
    /// Initial radius in scene units; `None`: `radius_pixels` pixel footprints at each hit point.
    pub initial_radius: Option<f32>,
    /// Initial radius in pixel footprints (the width of a pixel at the hit point's distance).
    pub radius_pixels: f32,
}

impl MergeParams {
    /// Parses and range-checks the params; an error points at the params in the graph file.
    pub fn parse(text: &str) -> Result<Self, ron::error::SpannedError> {
        let params: MergeParams = parse_params(text)?;
        let problem = if !(params.alpha > 0.0 && params.alpha < 1.0) {
            Some(format!("alpha must lie in (0, 1), got {}", params.alpha))
        } else if params
            .initial_radius
            .is_some_and(|r| !(r.is_finite() && r > 0.0))
        {
            Some("initial_radius must be a positive finite number".to_string())
        } else if !(params.radius_pixels.is_finite() && params.radius_pixels > 0.0) {
            Some("radius_pixels must be a positive finite number".to_string())
        } else {
            None
        };
        match problem {
            None => Ok(params),
            Some(message) => {
                let start = ron::error::Position { line: 1, col: 1 };
                Err(ron::error::SpannedError {
                    code: ron::Error::Message(message),
                    span: ron::error::Span { start, end: start },
                })
            }
        }
    }
}

impl Default for MergeParams {
    fn default() -> Self {
        Self {
            alpha: 0.7,
            initial_radius: None,
            radius_pixels: DEFAULT_RADIUS_PIXELS,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParams {
    alpha: f32,
    inv_iterations: f32,
    slots_per_pixel: u32,
    width: u32,
    height: u32,
    _pad: [u32; 3],
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    stats: wgpu::Buffer,
    hit_points: Resource,
    slots: u64,
    slots_per_pixel: u32,
    width: u32,
    height: u32,
}

/// The merge shared by `sppm` and `ppm`; `keep_hit_points` makes it `ppm`.
pub struct Merge {
    params: MergeParams,
    keep_hit_points: bool,
    prepared: Option<Prepared>,
}

impl Merge {
    pub fn new(params: MergeParams, keep_hit_points: bool) -> Self {
        Self {
            params,
            keep_hit_points,
            prepared: None,
        }
    }

    /// Per slot: tau (RGB), N, and the exact photon total. Reads back; for tests and reports.
    pub fn slot_stats(&self, gpu: &GpuContext) -> Result<Vec<SlotStats>, Error> {
        let Some(p) = &self.prepared else {
            return Ok(Vec::new());
        };
        let words: Vec<[u32; 8]> = gpu.read_pod(&p.stats, p.slots as usize)?;
        let hit_points = read_hit_points(gpu, &p.hit_points.buffer, p.slots)?;
        Ok(words
            .iter()
            .zip(&hit_points)
            .map(|(w, hp)| {
                // The kernel keeps tau / R^2 (merge.wgsl says why).
                let r2 = hp.radius * hp.radius;
                SlotStats {
                    tau: [0, 1, 2].map(|c| f32::from_bits(w[c]) * r2),
                    n: f32::from_bits(w[3]),
                    photons: (w[5] as u64) << 32 | w[4] as u64,
                    discarded: w[6],
                }
            })
            .collect())
    }
}

/// One hit-point slot's progressive statistics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlotStats {
    pub tau: [f32; 3],
    pub n: f32,
    pub photons: u64,
    pub discarded: u32,
}

impl Pass for Merge {
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<HashMap<&'static str, Resource>, Error> {
        let gpu = ctx.gpu;
        let hit_points = ctx.input("hit_points")?;
        let deposits = ctx.input("deposits")?;
        let pixels = ctx.width as u64 * ctx.height as u64;
        let slots_per_pixel = (hit_points.len / pixels.max(1)) as u32;
        let header = HitPointHeader::new(
            self.params.initial_radius.unwrap_or(0.0),
            self.params.radius_pixels,
            ctx.scene.uniform.scene_radius,
            slots_per_pixel,
        );
        gpu.queue
            .write_buffer(&hit_points.buffer, 0, bytemuck::bytes_of(&header));
        if self.keep_hit_points {
            hit_points.frozen.store(true, Ordering::Relaxed);
        }
        let radiance = gpu.create_buffer(
            "merge radiance",
            pixels * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let stats = gpu.create_buffer(
            "merge slot stats",
            hit_points.len.max(1) * SLOT_STATS_BYTES,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let params = gpu.create_buffer(
            "merge params",
            std::mem::size_of::<GpuParams>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let (layout, bind_group) = bind_buffers(
            &gpu.device,
            "merge",
            &[
                (Access::Uniform, &params),
                (Access::ReadWrite, &hit_points.buffer),
                (Access::ReadWrite, &deposits.buffer),
                (Access::ReadWrite, &stats),
                (Access::ReadWrite, &radiance),
            ],
        );
        let pipeline =
            ctx.shaders
                .compute_pipeline(gpu, SHADER, "main", &[&ctx.scene.layout, &layout])?;
        self.prepared = Some(Prepared {
            pipeline,
            bind_group,
            params,
            stats,
            hit_points: hit_points.clone(),
            slots: hit_points.len,
            slots_per_pixel,
            width: ctx.width,
            height: ctx.height,
        });
        let radiance = Resource::new(ResourceKind::Radiance, radiance, pixels);
        Ok(HashMap::from([("radiance", radiance)]))
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        let gpu_params = GpuParams {
            alpha: self.params.alpha,
            inv_iterations: (1.0 / (ctx.iteration as f64 + 1.0)) as f32,
            slots_per_pixel: p.slots_per_pixel,
            width: p.width,
            height: p.height,
            _pad: [0; 3],
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&gpu_params));
        recorder.dispatch(
            "merge",
            &p.pipeline,
            &ctx.scene.bind_group,
            &p.bind_group,
            [p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1],
        );
        Ok(())
    }

    fn stats(&self, gpu: &GpuContext) -> Result<PassStats, Error> {
        let discarded = self
            .slot_stats(gpu)?
            .iter()
            .map(|s| s.discarded as u64)
            .sum();
        Ok(PassStats {
            discarded_samples: discarded,
            ..Default::default()
        })
    }
}
