//! `pppm`: probabilistic progressive photon mapping (Knaus & Zwicker 2011). No per-pixel photon
//! statistics: every iteration is an independent density estimate at that iteration's hit
//! points, with one global radius schedule r_i^2 = r_1^2 prod_{k<i} (k + alpha) / (k + 1)
//! indexed by the global iteration number i (1-based; iteration index g = i - 1 in the code),
//! and the caustic image is the mean of the estimates. Its `radiance` output holds per pixel the
//! sum of the estimates and their count, so renders of disjoint iterations (shards, a resumed
//! render) sum to one render's image. r_1 is the rule of `sppm` (`initial_radius`, else
//! `radius_pixels` footprints at each hit point); the schedule scales it. The `radii` output
//! carries only that rule, with the scale for the next iteration, to the camera pass. Its
//! `kernel_bias` output sums each estimate's bias from its kernel in the same way
//! (docs/error-estimate.md).

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::shaders::ShaderFile;
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{
    Counters, ExecCtx, IMAGE, Pass, PassKind, PrepareCtx, Recorder, Size, SlotDecl,
};
use crate::passes::hit_points::{DEPOSITS, HIT_POINT_RADII, HIT_POINTS, KERNEL_BIAS, RadiusRule};
use crate::passes::sppm::MergeParams;
use crate::shader_file;

const SHADER: ShaderFile = shader_file!("shaders/passes/pppm.wgsl");
const WORKGROUP: u32 = 8;

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("hit_points", HIT_POINTS),
    SlotDecl::input("deposits", DEPOSITS),
    SlotDecl::output("radiance", IMAGE, Size::Pixels).persistent(),
    SlotDecl::output("radii", HIT_POINT_RADII, Size::LikeInput("hit_points"))
        .persistent()
        .required(),
    SlotDecl::output(KERNEL_BIAS, IMAGE, Size::Pixels).persistent(),
];

/// `PppmUniform` against its namesake in the shader.
const PARAMS_LAYOUT: crate::gpu::layout::StructLayout = crate::struct_layout!(PppmUniform => "PppmUniform" in SHADER, {
    width, height, slots_per_pixel, next_scale
});

pub const KIND: PassKind = PassKind {
    name: "pppm",
    description: "probabilistic progressive photon mapping: one global radius schedule, the mean of independent estimates",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: &[PARAMS_LAYOUT],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    // The same params as sppm's, with the same meaning: alpha, and the first radius's rule.
    Ok(Box::new(Pppm::new(MergeParams::parse(params)?)))
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PppmUniform {
    width: u32,
    height: u32,
    slots_per_pixel: u32,
    next_scale: f32,
}

/// r_g^2 / r_1^2 for global iteration index `g` (0-based, so iteration g + 1 of the paper):
/// prod_{k=1}^{g} (k + alpha) / (k + 1), kept in f64 and advanced factor by factor in one order
/// whatever the schedule, so shards and resumed renders compute the very same radii.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadiusSchedule {
    alpha: f64,
    at: u64,
    ratio: f64,
}

impl RadiusSchedule {
    pub fn new(alpha: f64) -> Self {
        Self {
            alpha,
            at: 0,
            ratio: 1.0,
        }
    }

    /// r_g^2 / r_1^2. Iteration indices must not decrease between calls (a render only moves
    /// forward); an earlier one restarts the product from 0.
    pub fn ratio_at(&mut self, g: u64) -> f64 {
        if g < self.at {
            *self = Self::new(self.alpha);
        }
        while self.at < g {
            self.at += 1;
            let k = self.at as f64;
            self.ratio *= (k + self.alpha) / (k + 1.0);
        }
        self.ratio
    }

    /// The factor on r_1 at iteration index `g`.
    pub fn scale_at(&mut self, g: u64) -> f32 {
        self.ratio_at(g).sqrt() as f32
    }
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    scene: wgpu::BindGroup,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    discarded: wgpu::Buffer,
    slots_per_pixel: u32,
    width: u32,
    height: u32,
}

pub struct Pppm {
    params: MergeParams,
    schedule: RadiusSchedule,
    prepared: Option<Prepared>,
}

impl Pppm {
    pub fn new(params: MergeParams) -> Self {
        let schedule = RadiusSchedule::new(params.alpha as f64);
        Self {
            params,
            schedule,
            prepared: None,
        }
    }
}

impl Pass for Pppm {
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        let hit_points = ctx.input("hit_points")?;
        let deposits = ctx.input("deposits")?;
        let radiance = ctx.output("radiance")?;
        let radii = ctx.output("radii")?;
        let kernel_bias = ctx.output(KERNEL_BIAS)?;
        let slots_per_pixel = (hit_points.len / ctx.pixels().max(1)) as u32;
        // The camera pass runs before this node in every iteration, so the first iteration's
        // scale is set here; each dispatch then leaves the next one's.
        let rule = RadiusRule {
            scale: self.schedule.scale_at(ctx.first_iteration),
            ..RadiusRule::new(
                self.params.initial_radius.unwrap_or(0.0),
                self.params.radius_pixels,
                scene.uniform.scene_radius,
            )
        };
        gpu.queue
            .write_buffer(&radii.buffer, 0, bytemuck::bytes_of(&rule));
        let params = gpu.create_buffer(
            "pppm params",
            std::mem::size_of::<PppmUniform>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let discarded = gpu.create_buffer(
            "pppm discarded",
            4,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let (layout, bind_group) = bind_buffers(
            gpu,
            "pppm",
            &[
                (Access::Uniform, &params),
                (Access::Read, &hit_points.buffer),
                (Access::ReadWrite, &deposits.buffer),
                (Access::ReadWrite, &radiance.buffer),
                (Access::ReadWrite, &radii.buffer),
                (Access::ReadWrite, &discarded),
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
            discarded,
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
        let gpu_params = PppmUniform {
            width: p.width,
            height: p.height,
            slots_per_pixel: p.slots_per_pixel,
            next_scale: self.schedule.scale_at(ctx.next_iteration),
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&gpu_params));
        recorder.dispatch(
            "pppm",
            &p.pipeline,
            &[&p.scene, &p.bind_group],
            [p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1],
        );
        Ok(())
    }

    fn state(&self) -> Vec<(&'static str, &wgpu::Buffer)> {
        self.prepared
            .iter()
            .map(|p| ("discarded", &p.discarded))
            .collect()
    }

    fn counters(&self, gpu: &GpuContext) -> Result<Counters, Error> {
        let Some(p) = &self.prepared else {
            return Ok(Counters::default());
        };
        let discarded: Vec<u32> = gpu.read_pod(&p.discarded, 1)?;
        Ok(Counters::of(&[("discarded_samples", discarded[0] as u64)]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ln Gamma(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error near 1e-15).
    fn ln_gamma(x: f64) -> f64 {
        const C: [f64; 9] = [
            0.999_999_999_999_809_9,
            676.520_368_121_885_1,
            -1_259.139_216_722_402_8,
            771.323_428_777_653_1,
            -176.615_029_162_140_6,
            12.507_343_278_686_905,
            -0.138_571_095_265_720_12,
            9.984_369_578_019_572e-6,
            1.505_632_735_149_311_6e-7,
        ];
        if x < 0.5 {
            let pi = std::f64::consts::PI;
            return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
        }
        let x = x - 1.0;
        let mut a = C[0];
        let t = x + 7.5;
        for (i, c) in C.iter().enumerate().skip(1) {
            a += c / (x + i as f64);
        }
        0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
    }

    /// The schedule against its closed form: prod_{k=1}^{g} (k + a)/(k + 1)
    /// = Gamma(g + 1 + a) / (Gamma(1 + a) Gamma(g + 2)), to 1e-8 relative up to 10^6
    /// iterations, for any order of visits (a shard's stride, a resumed render's jump). Would
    /// catch an off-by-one in the index (the ratio at g is the one at g +- 1 times a factor
    /// near 1 - (1 - a)/g: 3e-7 off at g = 10^6, 3e-2 at g = 10), a factor (k + a)/(k + 1)
    /// written the other way up, or a schedule that depends on the path taken to g.
    #[test]
    fn radius_schedule_matches_the_closed_form() {
        for alpha in [0.5, 2.0 / 3.0, 0.7, 0.9] {
            let closed = |g: u64| {
                let g = g as f64;
                (ln_gamma(g + 1.0 + alpha) - ln_gamma(1.0 + alpha) - ln_gamma(g + 2.0)).exp()
            };
            let mut forward = RadiusSchedule::new(alpha);
            assert_eq!(forward.ratio_at(0), 1.0, "r_1 is the first radius");
            for g in [1u64, 2, 3, 10, 100, 1_000, 10_000, 100_000, 1_000_000] {
                let ratio = forward.ratio_at(g);
                let fresh = RadiusSchedule::new(alpha).ratio_at(g);
                assert_eq!(ratio, fresh, "alpha {alpha}, g {g}: path-independent");
                let expected = closed(g);
                // The closed form differences ln Gamma values near 10^7 at g = 10^6, which
                // leaves it about 1e-9 of its own (measured 1.1e-10 at 10^5).
                assert!(
                    (ratio / expected - 1.0).abs() < 1e-8,
                    "alpha {alpha}, g {g}: {ratio} vs closed form {expected}"
                );
            }
            // Exact first steps: r_2^2 = r_1^2 (1 + a)/2, r_3^2 = r_2^2 (2 + a)/3.
            let mut s = RadiusSchedule::new(alpha);
            assert!((s.ratio_at(1) - (1.0 + alpha) / 2.0).abs() < 1e-15);
            assert!((s.ratio_at(2) - (1.0 + alpha) * (2.0 + alpha) / 6.0).abs() < 1e-15);
            // Going back restarts the product rather than returning a later radius.
            assert!((s.ratio_at(1) - (1.0 + alpha) / 2.0).abs() < 1e-15);
        }
    }
}
