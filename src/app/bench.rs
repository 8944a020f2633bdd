//! `hppm bench`: rays/s and samples/s of the path-tracing graph on the bundled Cornell scenes,
//! after a warm-up iteration (lavapipe compiles a pipeline at its first dispatch).

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use crate::gpu::GpuContext;
use crate::graph::{ValidGraph, parse_graph};
use crate::render::{Budget, NodeTime, Renderer};
use crate::{Error, graph, passes};

/// The glass-sphere Cornell box, the hybrid benches' caustic scene.
pub(crate) const GLASS: &str = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
const SCENES: &[&str] = &["scenes/cornell_diffuse.ron", "scenes/cornell_box.ron"];
const SIZE: u32 = 256;

pub struct BenchRow {
    pub scene: String,
    pub spp: u64,
    pub seconds: f64,
    pub rays: u64,
    /// CPU time the hypervisor gave to other guests during the timed run ([`stolen_cpu_seconds`]).
    pub stolen: Option<f64>,
}

impl BenchRow {
    pub fn mrays_per_second(&self) -> f64 {
        self.rays as f64 / self.seconds / 1e6
    }
    pub fn msamples_per_second(&self) -> f64 {
        (self.spp * SIZE as u64 * SIZE as u64) as f64 / self.seconds / 1e6
    }
}

fn measure(
    gpu: &GpuContext,
    scene_path: &Path,
    graph_path: &Path,
    spp: u64,
) -> Result<BenchRow, Error> {
    let scene = crate::loaders::load(scene_path)?;
    let graph = graph::load_graph(graph_path, passes::builtin_kinds())?;
    let mut renderer = Renderer::new(gpu, &scene, graph, SIZE, SIZE, 1)?;
    let never = AtomicBool::new(false);
    renderer.run(
        Budget {
            spp: Some(1),
            seconds: None,
            photons: None,
            target_error: None,
            adaptive: false,
        },
        &never,
        |_, _| {},
    )?;
    let rays_before = renderer.counters()?.get("rays");
    let spp_before = renderer.samples_per_pixel();
    let (summary, stolen) = while_counting_steal(|| {
        renderer.run(
            Budget {
                spp: Some(spp_before + spp),
                seconds: None,
                photons: None,
                target_error: None,
                adaptive: false,
            },
            &never,
            |_, _| {},
        )
    });
    let summary = summary?;
    Ok(BenchRow {
        scene: scene_path.display().to_string(),
        spp: renderer.samples_per_pixel() - spp_before,
        seconds: summary.seconds,
        rays: renderer.counters()?.get("rays") - rays_before,
        stolen,
    })
}

/// Runs `work` and returns what it returned with the CPU seconds stolen meanwhile (`None` where
/// [`stolen_cpu_seconds`] is unknown).
pub fn while_counting_steal<T>(work: impl FnOnce() -> T) -> (T, Option<f64>) {
    let before = stolen_cpu_seconds();
    let result = work();
    let stolen = stolen_cpu_seconds()
        .zip(before)
        .map(|(after, before)| after - before);
    (result, stolen)
}

/// Clock ticks per second of /proc/stat's counters (Linux's USER_HZ, 100 on every architecture
/// it exports to user space).
const PROC_STAT_TICKS_PER_SECOND: f64 = 100.0;

/// CPU seconds the hypervisor has so far given to other guests while this machine's CPUs
/// wanted to run ("steal", the eighth counter of /proc/stat's `cpu` line); `None` off Linux or
/// on a kernel without the counter. On a shared virtual machine it moves timings by tens of
/// percent, so each benchmark row reports what was stolen during it.
pub fn stolen_cpu_seconds() -> Option<f64> {
    steal_from_proc_stat(&std::fs::read_to_string("/proc/stat").ok()?)
}

fn steal_from_proc_stat(stat: &str) -> Option<f64> {
    let line = stat.lines().find(|l| l.starts_with("cpu "))?;
    let ticks: u64 = line.split_whitespace().nth(8)?.parse().ok()?;
    Some(ticks as f64 / PROC_STAT_TICKS_PER_SECOND)
}

/// A table cell for stolen CPU seconds: two decimals, or `–` where unknown.
pub fn stolen_cell(stolen: Option<f64>) -> String {
    stolen.map_or_else(|| "–".to_string(), |s| format!("{s:.2}"))
}

/// Runs the benchmark, prints a Markdown table and optionally appends it to `write`.
pub fn run(
    adapter: Option<&str>,
    spp: u64,
    write: Option<&Path>,
    locate: fn(&str) -> PathBuf,
) -> Result<(), Error> {
    let gpu = GpuContext::new(adapter)?;
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut table = format!(
        "\n### path_trace, {SIZE}x{SIZE}, {spp} spp, adapter: {} (host: {cores} CPU cores)\n\n\
         | scene | spp | seconds | Mrays/s | Msamples/s | CPU s stolen |\n\
         |---|---|---|---|---|---|\n",
        gpu.adapter_label()
    );
    for scene_path in SCENES {
        let row = measure(&gpu, &locate(scene_path), &locate("graphs/pt.ron"), spp)?;
        table.push_str(&format!(
            "| {} | {} | {:.2} | {:.2} | {:.3} | {} |\n",
            scene_path,
            row.spp,
            row.seconds,
            row.mrays_per_second(),
            row.msamples_per_second(),
            stolen_cell(row.stolen)
        ));
    }
    print!("{table}");
    if let Some(path) = write {
        append_markdown(path, &table)?;
    }
    Ok(())
}

/// Appends `text` to the Markdown file at `path` (created if missing), by writing the whole
/// file anew and renaming it into place: an interrupted append leaves the old file.
pub fn append_markdown(path: &Path, text: &str) -> Result<(), Error> {
    let old = match std::fs::read_to_string(path) {
        Ok(old) => old,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(source) => {
            return Err(Error::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    crate::image::write_file_atomically(path, (old + text).as_bytes())
}

/// A graph file with `replace` applied to its text (to set a param for one measurement).
pub(crate) fn graph_with(path: &Path, replace: Option<(&str, &str)>) -> Result<ValidGraph, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = match replace {
        Some((from, to)) => text.replace(from, to),
        None => text,
    };
    Ok(parse_graph(path, &text, passes::builtin_kinds())?)
}

pub(crate) fn run_iterations(renderer: &mut Renderer<'_>, iterations: u64) -> Result<f64, Error> {
    let never = AtomicBool::new(false);
    let target = renderer.samples_per_pixel() + iterations * renderer.spp_per_iteration().max(1);
    let budget = Budget {
        spp: Some(target),
        ..Default::default()
    };
    Ok(renderer.run(budget, &never, |_, _| {})?.seconds)
}

/// Milliseconds per iteration of each node, as a table cell.
pub(crate) fn node_ms(times: &[NodeTime], iterations: u64, decimals: usize) -> String {
    let per_iteration = |t: &NodeTime| t.wall_seconds / iterations.max(1) as f64 * 1e3;
    times
        .iter()
        .map(|t| format!("{} {:.decimals$}", t.name, per_iteration(t)))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Would catch reading the wrong counter (iowait, guest) or the wrong unit.
    #[test]
    fn steal_is_the_eighth_counter_of_the_cpu_line_in_ticks() {
        let stat = "cpu  142374 12 9263 118036 716 0 177 13345 0 0\n\
                    cpu0 71000 6 4600 59000 350 0 90 6700 0 0\n\
                    intr 1 2 3\n";
        assert_eq!(steal_from_proc_stat(stat), Some(133.45));
        assert_eq!(steal_from_proc_stat("cpu  1 2 3 4\n"), None);
        assert_eq!(steal_from_proc_stat("intr 1 2 3\n"), None);
        assert_eq!(stolen_cell(None), "–");
        assert_eq!(stolen_cell(Some(0.256)), "0.26");
    }
}
