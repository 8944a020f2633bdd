//! `hppm bench --seed-workload`: the workload of the report this project started from (a glass
//! Cornell box at 512x512, 512 camera samples per pixel and 2M photons in all, 4,096 per
//! iteration), rendered whole by `pt`, `ppm_only` and `hybrid`, so that any machine gives its
//! figures in one command: whole-run seconds, per-node milliseconds per iteration, rays/s.
//! `scale` renders that fraction of the samples and photons (a slow machine can run a part;
//! the image size stays the report's).

use std::path::PathBuf;

use crate::Error;
use crate::app::bench::{
    GLASS, graph_with, node_ms, run_iterations, stolen_cell, while_counting_steal,
};
use crate::gpu::GpuContext;
use crate::render::Renderer;

/// The report's image, samples per pixel, and photons per iteration (2M over 512 iterations).
const SIZE: u32 = 512;
const SPP: u64 = 512;
const PHOTONS_PER_ITERATION: u64 = 4096;
const GRAPHS: &[&str] = &["graphs/pt.ron", "graphs/ppm_only.ron", "graphs/hybrid.ron"];
/// Iterations profiled node by node after the timed run (profiling waits for every node, so
/// the timed run is not profiled).
const PROFILED_ITERATIONS: u64 = 2;

pub struct SeedWorkloadOptions<'a> {
    pub adapter: Option<&'a str>,
    /// Fraction of the report's samples and photons to render, in (0, 1].
    pub scale: f64,
}

/// Iterations (one camera sample per pixel each) the scaled workload takes: at least one.
pub fn iterations(scale: f64) -> Result<u64, Error> {
    if !(scale > 0.0 && scale <= 1.0) {
        return Err(Error::Other(format!(
            "--scale must lie in (0, 1] (the fraction of the report's 512 spp to render), got {scale}"
        )));
    }
    Ok(((SPP as f64 * scale).round() as u64).max(1))
}

/// Renders the workload with each graph and returns the table as Markdown.
pub fn run(
    options: &SeedWorkloadOptions<'_>,
    locate: fn(&str) -> PathBuf,
) -> Result<String, Error> {
    let iterations = iterations(options.scale)?;
    let gpu = GpuContext::new(options.adapter)?;
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    Ok(format!(
        "\n### The report's workload, adapter: {} (host: {cores} CPU cores)\n\n{}",
        gpu.adapter_label(),
        table(&gpu, locate, iterations)?
    ))
}

/// The workload's table for `iterations` camera samples per pixel (512 is the whole workload).
pub fn table(
    gpu: &GpuContext,
    locate: fn(&str) -> PathBuf,
    iterations: u64,
) -> Result<String, Error> {
    let scene = crate::loaders::load(&locate(GLASS))?;
    let mut out = format!(
        "Glass Cornell box (`{GLASS}`), {SIZE}x{SIZE}, {iterations} spp and {} photons \
         ({PHOTONS_PER_ITERATION} per iteration; the report's whole workload is {SPP} spp). Whole \
         run after one warm-up iteration (pipelines compile at their first dispatch); node times \
         from {PROFILED_ITERATIONS} more iterations, each node waited for on its own.\n\n\
         | graph | whole run (s) | s/iteration | Mrays/s (camera rays + photon segments) | node ms/iteration | stolen CPU s |\n\
         |---|---|---|---|---|---|\n",
        iterations * PHOTONS_PER_ITERATION,
    );
    for graph_path in GRAPHS {
        // The report's photon count replaces the default of one photon per pixel.
        let graph = graph_with(
            &locate(graph_path),
            Some((
                "(mode: ",
                &format!("(photons_per_iteration: {PHOTONS_PER_ITERATION}, mode: "),
            )),
        )?;
        let mut r = Renderer::new(gpu, &scene, graph, SIZE, SIZE, 1)?;
        run_iterations(&mut r, 1)?;
        // Camera rays and photon segments alike: both are rays cast through the scene.
        let cast = |r: &Renderer<'_>| -> Result<u64, Error> {
            let c = r.counters()?;
            Ok(c.get("rays") + c.get("photon_segments"))
        };
        let rays_before = cast(&r)?;
        let (seconds, stolen) = while_counting_steal(|| run_iterations(&mut r, iterations));
        let seconds = seconds?;
        let rays = cast(&r)? - rays_before;
        r.enable_profiling()?;
        run_iterations(&mut r, PROFILED_ITERATIONS)?;
        let nodes = node_ms(&r.node_times(), PROFILED_ITERATIONS, 0);
        out.push_str(&format!(
            "| {graph_path} | {seconds:.1} | {:.3} | {:.2} | {} | {} |\n",
            seconds / iterations as f64,
            rays as f64 / seconds.max(1e-9) / 1e6,
            nodes,
            stolen_cell(stolen)
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_picks_a_part_of_the_512_samples() {
        assert_eq!(iterations(1.0).ok(), Some(512));
        assert_eq!(iterations(0.125).ok(), Some(64));
        assert_eq!(iterations(1e-6).ok(), Some(1));
        assert!(iterations(0.0).is_err());
        assert!(iterations(1.5).is_err());
        assert!(iterations(f64::NAN).is_err());
    }
}
