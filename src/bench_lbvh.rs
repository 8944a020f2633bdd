//! `hppm bench --lbvh`: the hit-point BVH built on the CPU (`hit_point_bvh_sah`: readback, SAH
//! build, upload) against the GPU (`hit_point_bvh_lbvh`: full build and refit-only), each waited
//! for, and the photon pass traversing either tree, for 1M and 10M hit points spread over the
//! glass Cornell box's surfaces (as a camera pass at that many pixels would record them).

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Instant;

use crate::gpu::GpuContext;
use crate::gpu::radix_sort::RadixSort;
use crate::graph::pass::{ExecCtx, Pass, PrepareCtx, Recorder, Resource, ResourceKind};
use crate::passes::hit_point_bvh_lbvh::{HitPointBvhLbvh, LbvhParams};
use crate::passes::hit_point_bvh_sah::HitPointBvhSah;
use crate::passes::hit_points::{GpuHitPoint, HitPointHeader};
use crate::passes::photon_trace::{PhotonMode, PhotonTrace, PhotonTraceParams};
use crate::render::SceneResources;
use crate::scene::Scene;
use crate::scene::gpu_layout::GpuScene;
use crate::shaders::ShaderLibrary;
use crate::{Error, scene};

const GLASS: &str = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
const SIZES: &[u32] = &[1_000_000, 2_000_000, 10_000_000];
const PHOTONS: u32 = 1 << 16;
const REPEATS: usize = 3;

/// One pass at a time on the glass Cornell box's shared resources.
struct Bench<'a> {
    gpu: &'a GpuContext,
    scene: SceneResources,
    shaders: ShaderLibrary,
}

impl Bench<'_> {
    fn prepare(
        &self,
        pass: &mut dyn Pass,
        inputs: &[(&'static str, &Resource)],
    ) -> Result<HashMap<&'static str, Resource>, Error> {
        pass.prepare(PrepareCtx {
            gpu: self.gpu,
            scene: &self.scene,
            shaders: &self.shaders,
            inputs: inputs.iter().map(|(s, r)| (*s, (*r).clone())).collect(),
            consumed: HashSet::new(),
            width: 128,
            height: 128,
        })
    }

    /// Seconds for one iteration of `pass`, submitted and waited for.
    fn time(&self, pass: &mut dyn Pass, iteration: u64) -> Result<f64, Error> {
        let ctx = ExecCtx {
            gpu: self.gpu,
            scene: &self.scene,
            iteration,
            seed: 1,
        };
        let start = Instant::now();
        let mut recorder = Recorder::new(self.gpu);
        pass.execute(&ctx, &mut recorder)?;
        recorder.flush()?;
        Ok(start.elapsed().as_secs_f64())
    }

    /// Median milliseconds of REPEATS iterations after a warm-up one (pipeline compilation).
    fn median_ms(&self, pass: &mut dyn Pass) -> Result<f64, Error> {
        self.time(pass, 0)?;
        let mut times = Vec::with_capacity(REPEATS);
        for i in 0..REPEATS {
            times.push(self.time(pass, 1 + i as u64)? * 1e3);
        }
        times.sort_by(f64::total_cmp);
        Ok(times[REPEATS / 2])
    }
}

/// `count` hit points on the scene's triangles (uniform per triangle, then per area), facing
/// the scene's centre, with radii of about a pixel footprint at 1000x1000.
fn surface_hit_points(scene: &Scene, count: u32) -> Vec<GpuHitPoint> {
    let (lo, hi) = scene.bounds();
    let centre = lo.lerp(hi, 0.5);
    let radius = 1e-3 * (hi - lo).length();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    };
    let triangles = &scene.triangles;
    (0..count)
        .map(|i| {
            let t = &triangles[(next() * triangles.len() as f32) as usize % triangles.len()];
            let (mut u, mut v) = (next(), next());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = t.v[0] + u * (t.v[1] - t.v[0]) + v * (t.v[2] - t.v[0]);
            let mut normal = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalize_or_zero();
            if normal.dot(centre - p) < 0.0 {
                normal = -normal;
            }
            GpuHitPoint {
                position: p.to_array(),
                pixel: i,
                normal: normal.to_array(),
                radius: radius * (0.5 + next()),
                wo: normal.to_array(),
                depth: 1,
                weight: [1.0; 3],
                footprint: radius,
            }
        })
        .collect()
}

fn hit_point_resource(gpu: &GpuContext, points: &[GpuHitPoint]) -> Result<Resource, Error> {
    let header = HitPointHeader::new(0.0, 1.0, 1.0, 1);
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(points));
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let buffer = gpu.create_buffer_init("bench hit points", &bytes, usage)?;
    Ok(Resource::new(
        ResourceKind::HitPoints,
        buffer,
        points.len() as u64,
    ))
}

/// Milliseconds of the photon pass (PHOTONS caustic photons) traversing `tree`.
fn photon_ms(bench: &Bench<'_>, hit_points: &Resource, tree: &Resource) -> Result<f64, Error> {
    let mut photons = PhotonTrace::new(PhotonTraceParams {
        mode: PhotonMode::Caustic,
        photons_per_iteration: Some(PHOTONS),
        ..Default::default()
    });
    bench.prepare(
        &mut photons,
        &[("hit_points", hit_points), ("hit_point_tree", tree)],
    )?;
    bench.median_ms(&mut photons)
}

/// One table row: SAH build, photon pass on its tree, LBVH build, refit, photon pass on it.
fn row(bench: &Bench<'_>, scene: &Scene, count: u32) -> Result<String, Error> {
    let points = surface_hit_points(scene, count);
    let hit_points = hit_point_resource(bench.gpu, &points)?;
    drop(points);
    let mut sah = HitPointBvhSah::default();
    let sah_tree = bench.prepare(&mut sah, &[("hit_points", &hit_points)])?["tree"].clone();
    let sah_ms = bench.median_ms(&mut sah)?;
    let sah_photon_ms = photon_ms(bench, &hit_points, &sah_tree)?;
    drop((sah, sah_tree));
    let mut lbvh = HitPointBvhLbvh::new(LbvhParams::default());
    let lbvh_tree = bench.prepare(&mut lbvh, &[("hit_points", &hit_points)])?["tree"].clone();
    let lbvh_ms = bench.median_ms(&mut lbvh)?;
    let lbvh_photon_ms = photon_ms(bench, &hit_points, &lbvh_tree)?;
    hit_points.frozen.store(true, Ordering::Relaxed);
    let refit_ms = bench.median_ms(&mut lbvh)?;
    Ok(format!(
        "| {count} | {sah_ms:.0} | {lbvh_ms:.0} | {refit_ms:.0} | {sah_photon_ms:.0} | {lbvh_photon_ms:.0} |\n"
    ))
}

/// Median milliseconds of the radix sort alone on `count` pseudo-random pairs, waited for.
fn sort_ms(bench: &Bench<'_>, count: u32) -> Result<f64, Error> {
    let gpu = bench.gpu;
    let keys: Vec<u32> = (0..count)
        .map(|i| i.wrapping_mul(2_654_435_761) >> 2)
        .collect();
    let storage = wgpu::BufferUsages::STORAGE;
    let key_buffer = gpu.create_buffer_init("bench keys", bytemuck::cast_slice(&keys), storage)?;
    let value_buffer =
        gpu.create_buffer_init("bench values", bytemuck::cast_slice(&keys), storage)?;
    let mut sort = RadixSort::new(gpu, &bench.shaders)?;
    let mut times = Vec::with_capacity(REPEATS + 1);
    for _ in 0..=REPEATS {
        let start = Instant::now();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        sort.record(gpu, &mut encoder, &key_buffer, &value_buffer, count)?;
        gpu.queue.submit([encoder.finish()]);
        gpu.wait()?;
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    // The first sort compiles the pipelines.
    times.remove(0);
    times.sort_by(f64::total_cmp);
    Ok(times[REPEATS / 2])
}

/// Runs the hit-point BVH benchmark and returns it as Markdown.
pub fn run(adapter: Option<&str>, locate: fn(&str) -> PathBuf) -> Result<String, Error> {
    let gpu = GpuContext::new(adapter)?;
    let scene = scene::load(&locate(GLASS))?;
    let bench = Bench {
        gpu: &gpu,
        scene: SceneResources::upload(&gpu, &GpuScene::new(&scene, 128, 128))?,
        shaders: ShaderLibrary::new(gpu.has_float_atomics(), crate::shaders::scene_defs(&scene)),
    };
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut out = format!(
        "\n### hit-point BVH, adapter: {} (host: {cores} CPU cores)\n\n\
         Hit points on the glass Cornell box's surfaces; milliseconds per build, each waited \
         for (median of {REPEATS} after a warm-up); photon pass: {PHOTONS} caustic photons \
         traversing the tree.\n\n\
         | hit points | CPU SAH (readback + build + upload) | GPU LBVH build | GPU LBVH refit only | photon pass, SAH tree | photon pass, LBVH tree |\n\
         |---|---|---|---|---|---|\n",
        gpu.adapter_label()
    );
    let mut not_run = String::new();
    for &count in SIZES {
        match row(&bench, &scene, count) {
            Ok(line) => out.push_str(&line),
            Err(e) => not_run.push_str(&format!("\n{count} hit points not run: {e}\n")),
        }
        // A failed allocation leaves its error for the next check; start the next size clean.
        let _ = gpu.check_errors();
    }
    out.push_str(&not_run);
    out.push_str("\nThe radix sort alone (8 passes of 4 bits, u32 keys and values):\n\n");
    out.push_str("| pairs | GPU radix sort (ms) |\n|---|---|\n");
    for &count in SIZES {
        match sort_ms(&bench, count) {
            Ok(ms) => out.push_str(&format!("| {count} | {ms:.0} |\n")),
            Err(e) => out.push_str(&format!("| {count} | not run: {e} |\n")),
        }
        let _ = gpu.check_errors();
    }
    Ok(out)
}
