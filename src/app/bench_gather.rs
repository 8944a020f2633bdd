//! `hppm bench --gather`: the hit-point structures side by side, each as its graph node runs it
//! (build, then the gather of one iteration's photon hits into deposits), waited for: the BVH
//! built on the CPU (`hit_point_bvh_sah`: readback, SAH build, upload), the BVH built on the GPU
//! (`hit_point_bvh_lbvh`, full build and refit-only) and the hash grid (`hit_point_grid`), for
//! hit points spread over the glass Cornell box's surfaces (as a camera pass at that many pixels
//! would record them) and the caustic photon hits of one photon pass.

use std::path::PathBuf;
use std::time::Instant;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::radix_sort::RadixSort;
use crate::gpu::shaders::ShaderLibrary;
use crate::gpu_scene::SceneResources;
use crate::gpu_scene::layout::GpuScene;
use crate::graph::exec::{Standalone, Wiring};
use crate::graph::pass::{Pass, PassKind, Resource, Shared};
use crate::passes;
use crate::passes::hit_points::{GpuHitPoint, HIT_POINTS, HitPointsHeader, PHOTON_HITS};
use crate::passes::photon_trace::{PhotonMode, PhotonTrace, PhotonTraceParams};
use crate::scene::Scene;

const GLASS: &str = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
/// 128^2, 512^2 and 1024^2 pixels' worth of hit points.
const SIZES: &[u32] = &[16_384, 262_144, 1_048_576];
const PHOTONS: u32 = 1 << 18;
const REPEATS: usize = 3;

/// The glass Cornell box on the device, shared as a render shares it.
struct Bench<'a> {
    gpu: &'a GpuContext,
    shared: Shared,
    shaders: ShaderLibrary,
}

impl Bench<'_> {
    fn prepare(
        &self,
        kind: &PassKind,
        pass: &mut dyn Pass,
        inputs: &[(&'static str, &Resource)],
        wiring: &Wiring,
    ) -> Result<Standalone, Error> {
        let (gpu, shaders, shared) = (self.gpu, &self.shaders, &self.shared);
        Standalone::prepare(gpu, shaders, shared, (128, 128), kind, pass, inputs, wiring)
    }

    /// Median milliseconds of REPEATS iterations after a warm-up one (pipeline compilation).
    fn median_ms(&self, run: &Standalone, pass: &mut dyn Pass) -> Result<f64, Error> {
        run.run(self.gpu, pass, 0, 1)?;
        let mut times = Vec::with_capacity(REPEATS);
        for i in 0..REPEATS {
            let start = Instant::now();
            run.run(self.gpu, pass, 1 + i as u64, 1)?;
            times.push(start.elapsed().as_secs_f64() * 1e3);
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
    let header = HitPointsHeader {
        slots_per_pixel: 1,
        _pad: [0; 3],
    };
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(points));
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let buffer = gpu.create_buffer_init("bench hit points", &bytes, usage)?;
    Ok(Resource::new(HIT_POINTS, buffer, points.len() as u64))
}

/// One photon pass's caustic photon hits (PHOTONS photons), kept for every structure.
fn photon_hits(bench: &Bench<'_>) -> Result<Resource, Error> {
    let mut photons = PhotonTrace::new(PhotonTraceParams {
        mode: PhotonMode::Caustic,
        photons_per_iteration: Some(PHOTONS),
        ..Default::default()
    });
    let kind = &passes::photon_trace::KIND;
    let run = bench.prepare(kind, &mut photons, &[], &Wiring::default())?;
    run.run(bench.gpu, &mut photons, 0, 1)?;
    Ok(run.output("photon_hits")?.clone())
}

/// Milliseconds of one run of a structure node over `hit_points` and `photon_hits`.
fn node_ms(
    bench: &Bench<'_>,
    kind: &PassKind,
    inputs: &[(&'static str, &Resource)],
    wiring: &Wiring,
) -> Result<f64, Error> {
    let mut pass =
        (kind.construct)("()").map_err(|e| Error::Other(format!("{}: {e}", kind.name)))?;
    let run = bench.prepare(kind, &mut *pass, inputs, wiring)?;
    bench.median_ms(&run, &mut *pass)
}

/// The structures compared, in table order.
const STRUCTURES: &[&PassKind] = &[
    &passes::hit_point_bvh_sah::KIND,
    &passes::hit_point_bvh_lbvh::KIND,
    &passes::hit_point_grid::KIND,
];

/// Whether `kind` has a cheaper path for kept hit points worth its own column.
fn refits(kind: &PassKind) -> bool {
    kind.name == passes::hit_point_bvh_lbvh::KIND.name
}

/// One table row at `count` hit points: per structure its build alone (no photon hits), its
/// build + gather, and for the LBVH its refit + gather with kept hit points.
fn row(
    bench: &Bench<'_>,
    scene: &Scene,
    photon_hits: &Resource,
    count: u32,
) -> Result<String, Error> {
    let points = surface_hit_points(scene, count);
    let hit_points = hit_point_resource(bench.gpu, &points)?;
    drop(points);
    // Zeroed, so it holds no hit: the gather then only launches and returns.
    let no_hits = Resource::allocate(
        bench.gpu,
        "bench no photon hits",
        PHOTON_HITS,
        photon_hits.len,
    )?;
    let with_hits = [("hit_points", &hit_points), ("photon_hits", photon_hits)];
    let without = [("hit_points", &hit_points), ("photon_hits", &no_hits)];
    let kept = Wiring {
        kept_inputs: vec!["hit_points"],
        ..Default::default()
    };
    let mut line = format!("| {count} |");
    for kind in STRUCTURES {
        let build = node_ms(bench, kind, &without, &Wiring::default())?;
        let full = node_ms(bench, kind, &with_hits, &Wiring::default())?;
        line.push_str(&format!(" {build:.0} | {full:.0} |"));
        if refits(kind) {
            let refit = node_ms(bench, kind, &with_hits, &kept)?;
            line.push_str(&format!(" {refit:.0} |"));
        }
    }
    line.push('\n');
    Ok(line)
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

/// Runs the hit-point structure benchmark and returns it as Markdown.
pub fn run(adapter: Option<&str>, locate: fn(&str) -> PathBuf) -> Result<String, Error> {
    let gpu = GpuContext::new(adapter)?;
    let scene = crate::loaders::load(&locate(GLASS))?;
    let mut shared = Shared::default();
    let resources = SceneResources::for_adapter(&gpu, &GpuScene::new(&scene, 128, 128)?)?;
    let shaders = passes::shader_library(gpu.has_float_atomics(), &scene, &resources.placement)?;
    shared.insert(resources);
    let bench = Bench {
        gpu: &gpu,
        shared,
        shaders,
    };
    let photon_hits = photon_hits(&bench)?;
    let hits: Vec<u32> = gpu.read_pod(&photon_hits.buffer, 1)?;
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut header = String::from("| hit points |");
    let mut rule = String::from("|---|");
    for kind in STRUCTURES {
        header.push_str(&format!(" {0} build | {0} build + gather |", kind.name));
        rule.push_str("---|---|");
        if refits(kind) {
            header.push_str(&format!(
                " {} refit + gather (kept hit points) |",
                kind.name
            ));
            rule.push_str("---|");
        }
    }
    let mut out = format!(
        "\n### hit-point structures, adapter: {} (host: {cores} CPU cores)\n\n\
         Hit points on the glass Cornell box's surfaces; milliseconds per node run, each waited \
         for (median of {REPEATS} after a warm-up): its build alone (no photon hits), and its \
         build then the gather of {} caustic photon hits from {PHOTONS} photons.\n\n{header}\n{rule}\n",
        gpu.adapter_label(),
        hits[0]
    );
    let mut not_run = String::new();
    for &count in SIZES {
        match row(&bench, &scene, &photon_hits, count) {
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
