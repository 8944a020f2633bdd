//! Checks any BSDF unit can run on itself, hppm's own and a program's alike: its WGSL against its
//! CPU model on random direction pairs ([`gpu_against_cpu`]), its sampler against its pdf
//! ([`chi_square`]), and its energy ([`furnace`]). Each returns measurements; the caller's test
//! states the bound it holds them to.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu_scene::{GpuScene, SceneResources};
use crate::passes::Registry;
use crate::scene::Scene;
use crate::scene::bsdf::{Bsdf, Mode};

/// xorshift64*: a seeded stream of test directions and random numbers.
#[derive(Debug, Clone)]
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u32(&mut self) -> u32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 32) as u32
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    /// A uniform direction on the sphere.
    pub fn direction(&mut self) -> Vec3 {
        uniform_sphere(Vec2::new(self.unit(), self.unit()))
    }
}

/// The unit square mapped uniformly onto the sphere.
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Incident directions the statistical checks use: near normal, 53 and 78 degrees off, and
/// one from below for a BSDF that transmits.
pub fn incident_directions(transmits: bool) -> Vec<Vec3> {
    let mut dirs: Vec<Vec3> = [0.95f32, 0.6, 0.2]
        .iter()
        .map(|&z| Vec3::new((1.0 - z * z).sqrt() * 0.8, (1.0 - z * z).sqrt() * 0.6, z))
        .collect();
    if transmits {
        dirs.push(Vec3::new(0.3, -0.4, -(1.0f32 - 0.25).sqrt()));
    }
    dirs
}

/// A chi-square test of a sampler against its pdf.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChiSquare {
    pub chi2: f64,
    pub dof: f64,
    /// Wilson and Hilferty's normal approximation of the upper tail: the statistic's z-score.
    pub z: f64,
}

/// `samples` directions sampled from `wi`, histogrammed over 20 x 40 cells of (cos theta, phi)
/// (equal solid angle) plus one cell for delta and failed samples, against the pdf integrated
/// over each cell (32 x 32 points: the peaked anisotropic lobes need them); cells expecting under
/// 5 are pooled. A pdf that is not the sampler's (a missing lobe probability, a Jacobian off by
/// a factor) gives a large z, which MIS would turn into bias.
pub fn chi_square(bsdf: &Bsdf, wi: Vec3, samples: usize, rng: &mut Rng) -> ChiSquare {
    const ZB: usize = 20;
    const PB: usize = 40;
    const SUB: usize = 32;
    let mut observed = vec![0.0f64; ZB * PB + 1];
    for _ in 0..samples {
        let u1 = rng.unit();
        let u2 = Vec2::new(rng.unit(), rng.unit());
        let cell = match bsdf.sample(wi, u1, u2, Mode::Radiance) {
            Some(s) if !s.delta => {
                let z = ((s.wo.z + 1.0) * 0.5 * ZB as f32).clamp(0.0, ZB as f32 - 1.0) as usize;
                let phi = s.wo.y.atan2(s.wo.x).rem_euclid(2.0 * std::f32::consts::PI);
                let ph = ((phi / (2.0 * std::f32::consts::PI)) * PB as f32).min(PB as f32 - 1.0)
                    as usize;
                z * PB + ph
            }
            _ => ZB * PB,
        };
        observed[cell] += 1.0;
    }
    let mut expected = vec![0.0f64; ZB * PB + 1];
    let cell_area = (2.0 / ZB as f64) * (2.0 * std::f64::consts::PI / PB as f64);
    for z in 0..ZB {
        for ph in 0..PB {
            let mut sum = 0.0f64;
            for a in 0..SUB {
                for c in 0..SUB {
                    let cz = -1.0 + (z as f64 + (a as f64 + 0.5) / SUB as f64) * 2.0 / ZB as f64;
                    let cp =
                        (ph as f64 + (c as f64 + 0.5) / SUB as f64) * 2.0 * std::f64::consts::PI
                            / PB as f64;
                    let r = (1.0 - cz * cz).max(0.0).sqrt();
                    let wo = Vec3::new((r * cp.cos()) as f32, (r * cp.sin()) as f32, cz as f32);
                    sum += bsdf.pdf(wi, wo) as f64;
                }
            }
            expected[z * PB + ph] = sum / (SUB * SUB) as f64 * cell_area * samples as f64;
        }
    }
    let continuous: f64 = expected[..ZB * PB].iter().sum();
    expected[ZB * PB] = (samples as f64 - continuous).max(0.0);
    let (mut chi2, mut dof) = (0.0f64, 0.0f64);
    let (mut pool_o, mut pool_e) = (0.0f64, 0.0f64);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1.0;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(5.0);
        dof += 1.0;
    }
    let k = 2.0 / (9.0 * (dof - 1.0).max(1.0));
    let z = ((chi2 / (dof - 1.0).max(1.0)).powf(1.0 / 3.0) - (1.0 - k)) / k.sqrt();
    ChiSquare { chi2, dof, z }
}

/// A mean with its standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub mean: f64,
    pub error: f64,
}

/// What a white furnace measures of a BSDF from one incident direction (red channel, photons'
/// importance mode, which conserves energy across a refraction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Furnace {
    /// The mean sample weight: the directional albedo, at most 1 for a BSDF that makes no light.
    pub albedo: Estimate,
    /// The same over non-delta samples only.
    pub continuous_albedo: Estimate,
    /// The integral of `eval` over the sphere (uniform directions), which the continuous albedo
    /// must equal when sample weights are eval / pdf.
    pub eval_integral: Estimate,
}

/// The white furnace of `bsdf` seen from `wi`, `samples` samples each of its sampler and of
/// uniform directions for `eval`.
pub fn furnace(bsdf: &Bsdf, wi: Vec3, samples: usize, rng: &mut Rng) -> Furnace {
    let (mut albedo, mut albedo2, mut smooth, mut smooth2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let (mut integral, mut integral2) = (0.0f64, 0.0f64);
    for _ in 0..samples {
        let u = Vec2::new(rng.unit(), rng.unit());
        if let Some(s) = bsdf.sample(wi, rng.unit(), u, Mode::Importance) {
            let w = s.weight.x as f64;
            albedo += w;
            albedo2 += w * w;
            if !s.delta {
                smooth += w;
                smooth2 += w * w;
            }
        }
        let wo = rng.direction();
        let v = bsdf.eval(wi, wo, Mode::Importance).x as f64 * 4.0 * std::f64::consts::PI;
        integral += v;
        integral2 += v * v;
    }
    let n = samples as f64;
    let estimate = |s: f64, s2: f64| Estimate {
        mean: s / n,
        error: ((s2 / n - (s / n).powi(2)).max(0.0) / n).sqrt(),
    };
    Furnace {
        albedo: estimate(albedo, albedo2),
        continuous_albedo: estimate(smooth, smooth2),
        eval_integral: estimate(integral, integral2),
    }
}

/// One direction pair a material's WGSL is evaluated and sampled at.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug)]
struct Query {
    wi: [f32; 3],
    material: u32,
    wo: [f32; 3],
    u1: f32,
    u2: [f32; 2],
    radiance: u32,
    _pad: u32,
}

/// What the WGSL answered: its eval and pdf at (wi, wo), and its sample from (wi, u1, u2).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug)]
struct Answer {
    value: [f32; 3],
    pdf: f32,
    wo: [f32; 3],
    s_pdf: f32,
    weight: [f32; 3],
    flags: u32,
}

const KERNEL: &str = r#"
#import common::scene::materials
#import common::material::{material_eval, material_sample}

struct Query {
    wi: vec3<f32>,
    material: u32,
    wo: vec3<f32>,
    u1: f32,
    u2: vec2<f32>,
    radiance: u32,
    pad: u32,
}

struct Answer {
    value: vec3<f32>,
    pdf: f32,
    wo: vec3<f32>,
    s_pdf: f32,
    weight: vec3<f32>,
    flags: u32,
}

@group(1) @binding(0) var<storage, read> queries: array<Query>;
@group(1) @binding(1) var<storage, read_write> answers: array<Answer>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&queries) {
        return;
    }
    let q = queries[id.x];
    let m = materials[q.material];
    let e = material_eval(m, q.wi, q.wo, q.radiance != 0u);
    let s = material_sample(m, q.wi, q.u1, q.u2, q.radiance != 0u);
    answers[id.x] = Answer(e.value, e.pdf, s.wo, s.pdf, s.weight, select(0u, 1u, s.valid) | select(0u, 2u, s.delta));
}
"#;

/// How a material's WGSL compared with its CPU model.
#[derive(Debug, Clone, Default)]
pub struct GpuAgreement {
    /// Pairs evaluated.
    pub evals: usize,
    /// Each pair whose eval or pdf differs beyond the relative tolerance, described.
    pub eval_failures: Vec<String>,
    /// Samples both sides drew (with a non-zero weight).
    pub samples_compared: usize,
    /// Samples whose direction, weight or delta flag differ, or that one side drew and the other
    /// did not. A random number within a few ulps of a lobe's threshold, or a grazing direction,
    /// may fall either way in f32 on the two sides: a handful is rounding, more is a difference.
    pub sample_mismatches: usize,
    /// Queries in all.
    pub queries: usize,
}

/// Evaluates and samples, through the generated material dispatch (`common::material`), the
/// front BSDF of every material of `scene` (loaded with `registry`'s BSDFs) whose kind the
/// dispatch handles, at `pairs` random direction pairs each (both radiance and importance
/// mode; below the surface too where it transmits), and compares each with the model's CPU
/// eval and pdf at relative tolerance `tolerance` (sample weights at 1.5 times it). Catches a WGSL port that differs from
/// the reference: a sign, a swapped argument, a wrong slot of the GPU record, a missing
/// dispatch entry.
pub fn gpu_against_cpu(
    gpu: &GpuContext,
    registry: &Registry,
    scene: &Scene,
    pairs: usize,
    tolerance: f32,
    rng: &mut Rng,
) -> Result<GpuAgreement, Error> {
    let gpu_scene = GpuScene::with_bsdfs(scene, 4, 4, registry.bsdfs())?;
    let resources = SceneResources::for_adapter(gpu, &gpu_scene)?;
    let shaders = registry.shader_library(gpu.has_float_atomics(), scene, &resources.placement)?;
    let module = shaders.compose_source("hppm::testing::bsdf (kernel)", KERNEL)?;
    let dispatched = |b: &Bsdf| {
        registry
            .bsdfs()
            .kind(b.kind())
            .is_some_and(|(_, k)| k.eval.is_some() || k.sample.is_some())
    };
    let mut queries = Vec::new();
    for (index, m) in scene.materials.iter().enumerate() {
        if !dispatched(&m.bsdf) {
            continue;
        }
        let lower = m.bsdf.transmits();
        for i in 0..pairs {
            let mut wi = rng.direction();
            if !lower && i % 5 != 0 {
                wi.z = wi.z.abs();
            }
            let mut wo = rng.direction();
            if !lower && i % 5 != 1 {
                wo.z = wo.z.abs();
            }
            queries.push(Query {
                wi: wi.to_array(),
                material: index as u32,
                wo: wo.to_array(),
                u1: rng.unit(),
                u2: [rng.unit(), rng.unit()],
                radiance: (i % 2) as u32,
                _pad: 0,
            });
        }
    }
    let answers = run_kernel(gpu, &resources, module, &queries)?;
    let mut report = GpuAgreement {
        queries: queries.len(),
        ..GpuAgreement::default()
    };
    let close = |a: f32, b: f32, rel: f32| (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-5;
    let close3 = |a: Vec3, b: Vec3, rel: f32| (0..3).all(|i| close(a[i], b[i], rel));
    // A sample's weight is eval / pdf: half as much again of rounding.
    let weight_tolerance = 1.5 * tolerance;
    for (q, a) in queries.iter().zip(&answers) {
        let bsdf = &scene.materials[q.material as usize].bsdf;
        let mode = if q.radiance != 0 {
            Mode::Radiance
        } else {
            Mode::Importance
        };
        let (wi, wo) = (Vec3::from_array(q.wi), Vec3::from_array(q.wo));
        let f = bsdf.eval(wi, wo, mode);
        let pdf = bsdf.pdf(wi, wo);
        report.evals += 1;
        if !close3(Vec3::from_array(a.value), f, tolerance) || !close(a.pdf, pdf, tolerance) {
            report.eval_failures.push(format!(
                "material {} ({}): GPU eval {:?} pdf {} but CPU {f} {pdf} (wi {wi}, wo {wo})",
                q.material,
                bsdf.kind(),
                a.value,
                a.pdf
            ));
        }
        let s = bsdf
            .sample(wi, q.u1, Vec2::from_array(q.u2), mode)
            .filter(|s| s.weight.max_element() > 0.0);
        let valid = a.flags & 1 != 0 && Vec3::from_array(a.weight).max_element() > 0.0;
        match s {
            Some(s) if valid => {
                report.samples_compared += 1;
                if Vec3::from_array(a.wo).dot(s.wo) < 0.9995
                    || !close3(Vec3::from_array(a.weight), s.weight, weight_tolerance)
                    || (a.flags & 2 != 0) != s.delta
                {
                    report.sample_mismatches += 1;
                }
            }
            None if !valid => {}
            _ => report.sample_mismatches += 1,
        }
    }
    Ok(report)
}

/// Runs the query kernel over `queries` with the scene bound as group 0.
fn run_kernel(
    gpu: &GpuContext,
    resources: &SceneResources,
    module: wgpu::naga::Module,
    queries: &[Query],
) -> Result<Vec<Answer>, Error> {
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let query_buffer = gpu.create_buffer_init("queries", bytemuck::cast_slice(queries), storage)?;
    let answer_bytes = (queries.len().max(1) * size_of::<Answer>()) as u64;
    let answer_buffer = gpu.create_buffer("answers", answer_bytes, storage)?;
    let (layout, group) = bind_buffers(
        gpu,
        "bsdf check",
        &[
            (Access::Read, &query_buffer),
            (Access::ReadWrite, &answer_buffer),
        ],
    );
    let shader = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("bsdf check"),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(module)),
        });
    let pipeline_layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("bsdf check"),
            bind_group_layouts: &[Some(&resources.layout), Some(&layout)],
            immediate_size: 0,
        });
    let pipeline = gpu
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("bsdf check"),
            layout: Some(&pipeline_layout),
            module: &shader,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &resources.bind_group, &[]);
        pass.set_bind_group(1, &group, &[]);
        pass.dispatch_workgroups((queries.len() as u32).div_ceil(64), 1, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.check_errors()?;
    Ok(gpu.read_pod(&answer_buffer, queries.len())?)
}
