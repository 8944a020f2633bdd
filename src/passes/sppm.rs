//! `sppm` (default estimator): stochastic progressive photon mapping (Hachisuka & Jensen 2009).
//! Every iteration the camera pass regenerates the hit points; per pixel and photon-mapped
//! depth this node keeps N, R and tau across iterations and merges each iteration's deposits
//! with the update of docs/design.md section 2. Its `radiance` output is the photon-mapped radiance
//! (w = 1), its `kernel_bias` output that estimate's bias from its kernel (docs/error-estimate.md);
//! its `radii` output, the radius of every hit-point slot after its rule, is state it
//! owns and the camera pass reads in the next iteration. `ppm` (src/passes/ppm.rs) runs the same
//! merge on hit points it keeps.

use serde::Deserialize;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::shaders::ShaderFile;
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{
    Counters, ExecCtx, IMAGE, Pass, PassKind, PrepareCtx, Recorder, Resource, Size, SlotDecl,
    params_error, parse_params,
};
use crate::passes::hit_points::{
    DEFAULT_RADIUS_PIXELS, DEPOSITS, HIT_POINT_RADII, HIT_POINTS, KERNEL_BIAS, RadiusRule,
};
use crate::shader_file;

pub(crate) const SHADER: ShaderFile = shader_file!("shaders/passes/merge.wgsl");
const WORKGROUP: u32 = 8;
/// One slot's N, tau and photon total (`SlotStats` in merge.wgsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuSlotStats {
    tau_per_r2: [f32; 3],
    n: f32,
    tau_carry: [f32; 3],
    discarded: u32,
    inner_per_r2: [f32; 3],
    photons_low: u32,
    photons_high: u32,
    _pad: [u32; 3],
}

const SLOT_STATS_BYTES: u64 = std::mem::size_of::<GpuSlotStats>() as u64;

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", HIT_POINTS).exclusive(),
    SlotDecl::input("deposits", DEPOSITS),
    SlotDecl::output("radiance", IMAGE, Size::Pixels),
    SlotDecl::output("radii", HIT_POINT_RADII, Size::LikeInput("hit_points"))
        .persistent()
        .required(),
    SlotDecl::output(KERNEL_BIAS, IMAGE, Size::Pixels),
];

/// `MergeUniform` against its namesake in the shader.
pub(crate) const PARAMS_LAYOUT: crate::gpu::layout::StructLayout = crate::struct_layout!(MergeUniform => "MergeUniform" in SHADER, {
    alpha, inv_iterations, slots_per_pixel, width, height, one
});

/// `GpuSlotStats` against `SlotStats` in the shader.
pub(crate) const STATS_LAYOUT: crate::gpu::layout::StructLayout = crate::struct_layout!(GpuSlotStats => "SlotStats" in SHADER, {
    tau_per_r2, n, tau_carry, discarded, inner_per_r2, photons_low, photons_high
});

pub const KIND: PassKind = PassKind {
    name: "sppm",
    description: "stochastic progressive photon mapping: per-pixel N, R, tau over iterations",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: &[PARAMS_LAYOUT, STATS_LAYOUT],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    Ok(Box::new(Merge::new(MergeParams::parse(params)?)))
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
        } else if !(params.radius_pixels > 0.0 && params.radius_pixels <= MAX_RADIUS_PIXELS) {
            // A radius of many pixels gathers every photon into every hit point: hours per
            // iteration, and a blurred caustic.
            Some(format!(
                "radius_pixels must lie in (0, {MAX_RADIUS_PIXELS}], got {}",
                params.radius_pixels
            ))
        } else {
            None
        };
        match problem {
            None => Ok(params),
            Some(message) => Err(params_error(message)),
        }
    }
}

/// Largest first search radius in pixel footprints.
pub const MAX_RADIUS_PIXELS: f32 = 64.0;

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
struct MergeUniform {
    alpha: f32,
    inv_iterations: f32,
    slots_per_pixel: u32,
    width: u32,
    height: u32,
    /// 1.0: keeps the shader compiler from folding the compensated sum away (merge.wgsl).
    one: f32,
    _pad: [u32; 2],
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    scene: wgpu::BindGroup,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    stats: wgpu::Buffer,
    radii: Resource,
    slots: u64,
    slots_per_pixel: u32,
    width: u32,
    height: u32,
}

/// The merge shared by `sppm` and `ppm` (which differ in their slots: `ppm` keeps its input).
pub struct Merge {
    params: MergeParams,
    prepared: Option<Prepared>,
}

impl Merge {
    pub fn new(params: MergeParams) -> Self {
        Self {
            params,
            prepared: None,
        }
    }

    /// Per slot: tau (RGB), N, and the exact photon total. Reads back; for tests and reports.
    pub fn slot_stats(&self, gpu: &GpuContext) -> Result<Vec<SlotStats>, Error> {
        let Some(p) = &self.prepared else {
            return Ok(Vec::new());
        };
        let stats: Vec<GpuSlotStats> = gpu.read_pod(&p.stats, p.slots as usize)?;
        let radii: Vec<f32> = p.radii.read(gpu)?;
        Ok(stats
            .iter()
            .zip(&radii)
            .map(|(s, radius)| {
                // The kernel keeps tau / R^2 (merge.wgsl says why).
                let r2 = radius * radius;
                SlotStats {
                    tau: s.tau_per_r2.map(|t| t * r2),
                    n: s.n,
                    photons: (s.photons_high as u64) << 32 | s.photons_low as u64,
                    discarded: s.discarded,
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
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        let hit_points = ctx.input("hit_points")?;
        let deposits = ctx.input("deposits")?;
        let radiance = ctx.output("radiance")?;
        let radii = ctx.output("radii")?;
        let kernel_bias = ctx.output(KERNEL_BIAS)?;
        let slots_per_pixel = (hit_points.len / ctx.pixels().max(1)) as u32;
        let rule = RadiusRule::new(
            self.params.initial_radius.unwrap_or(0.0),
            self.params.radius_pixels,
            scene.uniform.scene_radius,
        );
        gpu.queue
            .write_buffer(&radii.buffer, 0, bytemuck::bytes_of(&rule));
        let stats = gpu.create_buffer(
            "merge slot stats",
            hit_points.len.max(1) * SLOT_STATS_BYTES,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let params = gpu.create_buffer(
            "merge params",
            std::mem::size_of::<MergeUniform>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let (layout, bind_group) = bind_buffers(
            gpu,
            "merge",
            &[
                (Access::Uniform, &params),
                (Access::Read, &hit_points.buffer),
                (Access::ReadWrite, &deposits.buffer),
                (Access::ReadWrite, &stats),
                (Access::ReadWrite, &radiance.buffer),
                (Access::ReadWrite, &radii.buffer),
                (Access::ReadWrite, &kernel_bias.buffer),
            ],
        );
        let pipeline =
            ctx.shaders
                .compute_pipeline(gpu, &SHADER, "main", &[&scene.layout, &layout])?;
        self.prepared = Some(Prepared {
            pipeline,
            scene: scene.bind_group.clone(),
            bind_group,
            params,
            stats,
            radii: radii.clone(),
            slots: hit_points.len,
            slots_per_pixel,
            width: ctx.width,
            height: ctx.height,
        });
        Ok(())
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        let gpu_params = MergeUniform {
            alpha: self.params.alpha,
            inv_iterations: (1.0 / (ctx.iteration as f64 + 1.0)) as f32,
            slots_per_pixel: p.slots_per_pixel,
            width: p.width,
            height: p.height,
            one: 1.0,
            _pad: [0; 2],
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&gpu_params));
        recorder.dispatch(
            "merge",
            &p.pipeline,
            &[&p.scene, &p.bind_group],
            [p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1],
        );
        Ok(())
    }

    fn state(&self) -> Vec<(&'static str, &wgpu::Buffer)> {
        self.prepared
            .iter()
            .map(|p| ("slot_stats", &p.stats))
            .collect()
    }

    fn shard_refusal(&self) -> Option<&'static str> {
        Some(
            "its per-pixel N, R and tau depend on every earlier iteration, so renders of \
             disjoint iterations are not parts of one render and their images cannot be summed \
             (graphs/hybrid_pppm.ron's pppm estimator can)",
        )
    }

    fn counters(&self, gpu: &GpuContext) -> Result<Counters, Error> {
        let discarded = self
            .slot_stats(gpu)?
            .iter()
            .map(|s| s.discarded as u64)
            .sum();
        Ok(Counters::of(&[("discarded_samples", discarded)]))
    }
}
