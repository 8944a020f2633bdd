//! `hppm bench --hybrid`: the figures of the hybrid (BENCHMARKS.md): per-node time and photon
//! segments/s, the CPU hit-point BVH build per 1M hit points, part of the report's workload
//! (`bench_seed`) for pt / ppm_only / hybrid, and relMSE after equal wall-clock budgets
//! against the Mitsuba references in tests/refs.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use glam::Vec3;

use crate::Error;
use crate::app::bench::{
    GLASS, graph_with, node_ms, run_iterations, stolen_cell, while_counting_steal,
};
use crate::gpu::GpuContext;
use crate::image::Image;
use crate::passes::hit_points::{GpuHitPoint, build_tree};
use crate::render::{Budget, Renderer};

const POINT_LIGHT: &str = "tests/refs/scenes/point_light_caustic/scene.xml";
const GRAPHS: &[&str] = &["graphs/pt.ron", "graphs/hybrid.ron", "graphs/ppm_only.ron"];

pub struct HybridBenchOptions<'a> {
    pub adapter: Option<&'a str>,
    /// Wall-clock budgets for the equal-time table (empty: skip it).
    pub seconds: Vec<f64>,
    /// Iterations of the 512x512 workload actually run (its 512 spp are extrapolated).
    pub workload_iterations: u64,
}

/// Milliseconds per iteration of each node, and photon segments per second.
fn node_table(gpu: &GpuContext, locate: fn(&str) -> PathBuf) -> Result<String, Error> {
    let mut out = String::from(
        "| scene | graph | photons/iteration | node times per iteration (ms) | photon Msegments/s |\n|---|---|---|---|---|\n",
    );
    for scene_path in [GLASS, POINT_LIGHT] {
        let scene = crate::loaders::load(&locate(scene_path))?;
        for graph_path in ["graphs/hybrid.ron", "graphs/ppm_only.ron"] {
            let graph = graph_with(&locate(graph_path), None)?;
            let (w, h) = (scene.camera.width, scene.camera.height);
            let mut r = Renderer::new(gpu, &scene, graph, w, h, 1)?;
            run_iterations(&mut r, 2)?;
            let before = r.counters()?;
            r.enable_profiling()?;
            let iterations = 8;
            run_iterations(&mut r, iterations)?;
            let after = r.counters()?;
            let times = r.node_times();
            let photon_seconds: f64 = times
                .iter()
                .filter(|t| t.kind == "photon_trace")
                .map(|t| t.wall_seconds)
                .sum();
            let segments = after.get("photon_segments") - before.get("photon_segments");
            let nodes = node_ms(&times, iterations, 1);
            out.push_str(&format!(
                "| {} | {} | {} | {} | {:.2} |\n",
                short(scene_path),
                graph_path,
                r.photons_per_iteration(),
                nodes,
                segments as f64 / photon_seconds.max(1e-9) / 1e6
            ));
        }
    }
    Ok(out)
}

/// "node ms, node ms, ...": each node's wall milliseconds per iteration over `iterations`, with
/// `decimals` decimals, in schedule order.
fn short(scene_path: &str) -> &str {
    scene_path
        .trim_end_matches("/scene.xml")
        .rsplit('/')
        .next()
        .unwrap_or(scene_path)
}

/// CPU SAH build of the hit-point tree over 1M random hit points (median of 3).
fn bvh_build_table() -> String {
    let mut state = 12345u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let points: Vec<GpuHitPoint> = (0..1_000_000)
        .map(|i| GpuHitPoint {
            position: Vec3::new(next(), next(), next()).to_array(),
            pixel: i,
            normal: [0.0, 1.0, 0.0],
            radius: 0.002 + 0.004 * next(),
            wo: [0.0, 1.0, 0.0],
            depth: 1,
            weight: [1.0; 3],
            footprint: 0.002,
        })
        .collect();
    let mut times: Vec<f64> = (0..3)
        .map(|_| {
            let start = Instant::now();
            let nodes = build_tree(&points);
            std::hint::black_box(nodes);
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    format!(
        "| hit points | CPU SAH build (ms, median of 3, one thread) |\n|---|---|\n| 1,000,000 | {:.0} |\n",
        times[1]
    )
}

/// Pixels where the point-light composite reference is exact (the camera sees the plane).
fn plane_mask(locate: fn(&str) -> PathBuf) -> Result<Vec<bool>, Error> {
    let specular = Image::read_exr(&locate(
        "tests/refs/images/point_light_caustic_primary_specular.exr",
    ))?;
    Ok(specular
        .pixels
        .iter()
        .map(|p| p.iter().all(|&c| c == 0.0))
        .collect())
}

fn equal_time_table(
    gpu: &GpuContext,
    locate: fn(&str) -> PathBuf,
    budgets: &[f64],
) -> Result<String, Error> {
    let mut out = String::from(
        "| scene (reference) | graph | seconds | iterations | photons | relMSE | CPU s stolen |\n\
         |---|---|---|---|---|---|---|\n",
    );
    let mask = plane_mask(locate)?;
    let cases = [
        (GLASS, "tests/refs/images/cornell_glass_sphere.exr", false),
        (
            POINT_LIGHT,
            "tests/refs/images/point_light_caustic_composite.exr",
            true,
        ),
    ];
    for (scene_path, reference_path, masked) in cases {
        let scene = crate::loaders::load(&locate(scene_path))?;
        let reference = Image::read_exr(&locate(reference_path))?;
        if masked {
            // Mitsuba's converged path tracer misses the caustic: no budget gets it below this.
            let path_only = Image::read_exr(&locate("tests/refs/images/point_light_caustic.exr"))?;
            out.push_str(&format!(
                "| {} (composite, plane pixels) | Mitsuba 3 `path`, converged reference | any | | | {:.5} | |\n",
                short(scene_path),
                path_only.relmse_where(&reference, |i| mask[i])?
            ));
        }
        for graph_path in GRAPHS {
            for &seconds in budgets {
                let graph = graph_with(&locate(graph_path), None)?;
                let (w, h) = (scene.camera.width, scene.camera.height);
                let mut r = Renderer::new(gpu, &scene, graph, w, h, 1)?;
                // Warm-up outside the clock (lavapipe compiles pipelines at first dispatch),
                // then a fresh renderer so the image holds only timed iterations.
                run_iterations(&mut r, 1)?;
                drop(r);
                let graph = graph_with(&locate(graph_path), None)?;
                let mut r = Renderer::new(gpu, &scene, graph, w, h, 7)?;
                let never = AtomicBool::new(false);
                let budget = Budget {
                    seconds: Some(seconds),
                    ..Default::default()
                };
                let (summary, stolen) = while_counting_steal(|| r.run(budget, &never, |_, _| {}));
                let summary = summary?;
                let image = r.image()?;
                let error = if masked {
                    image.relmse_where(&reference, |i| mask[i])?
                } else {
                    image.relmse(&reference)?
                };
                out.push_str(&format!(
                    "| {}{} | {graph_path} | {:.1} | {} | {} | {error:.5} | {} |\n",
                    short(scene_path),
                    if masked {
                        " (composite, plane pixels)"
                    } else {
                        ""
                    },
                    summary.seconds,
                    summary.iterations,
                    summary.photons,
                    stolen_cell(stolen),
                ));
            }
        }
    }
    Ok(out)
}

/// Runs the hybrid benchmarks and returns them as Markdown.
pub fn run(options: &HybridBenchOptions<'_>, locate: fn(&str) -> PathBuf) -> Result<String, Error> {
    let gpu = GpuContext::new(options.adapter)?;
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut out = format!(
        "\n### hybrid, adapter: {} (host: {cores} CPU cores)\n\n",
        gpu.adapter_label()
    );
    out.push_str("Per-node time (each node waited for on its own), 128x128:\n\n");
    out.push_str(&node_table(&gpu, locate)?);
    out.push_str("\nHit-point BVH:\n\n");
    out.push_str(&bvh_build_table());
    out.push_str(
        "\nThe report's workload, in part (`hppm bench --seed-workload` runs it whole):\n\n",
    );
    out.push_str(&crate::app::bench_seed::table(
        &gpu,
        locate,
        options.workload_iterations,
    )?);
    if !options.seconds.is_empty() {
        out.push_str("\nEqual time, 128x128, relMSE against Mitsuba 3:\n\n");
        out.push_str(&equal_time_table(&gpu, locate, &options.seconds)?);
    }
    Ok(out)
}
