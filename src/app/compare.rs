//! `hppm compare`: error against run time for several graphs on one scene and one adapter.
//! Each graph renders for the same wall budget; at log-spaced moments the clock stops, the image
//! is read back, its error estimated without a reference (docs/error-estimate.md) and, when a
//! reference is given, measured against it (relMSE, RMSE, MAE), then the clock resumes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use crate::Error;
#[cfg(feature = "cli")]
use crate::app::plot::{self, Series, SeriesStyle};
use crate::gpu::GpuContext;
use crate::image::{ErrorMetrics, Image, Provenance};
use crate::render::{Budget, NodeTime, Renderer, auto};

/// What to compare (the command line's arguments).
pub struct CompareOptions {
    /// The pass kinds the graphs are validated against and rendered with.
    pub registry: crate::passes::Registry,
    pub scene: PathBuf,
    /// Mitsuba `-D name=value` scene parameters.
    pub defines: Vec<(String, String)>,
    /// Without one only the estimated error is reported.
    pub reference: Option<PathBuf>,
    pub graphs: Vec<PathBuf>,
    pub seconds: f64,
    pub snapshots: usize,
    pub seed: u64,
    /// CSV of another renderer's (seconds, relmse, label) rows to plot beside ours.
    pub peer: Option<PathBuf>,
    /// Image whose zero pixels are the ones measured.
    pub mask: Option<PathBuf>,
    pub out: PathBuf,
    pub profile: bool,
    /// Render size; default: the scene's film.
    pub size: Option<(u32, u32)>,
}

/// One row of `errors.csv`.
#[derive(Debug, Clone)]
pub struct Snapshot {
    pub index: usize,
    pub seconds: f64,
    pub iterations: u64,
    pub spp: u64,
    pub photons: u64,
    /// Against the reference, when there is one.
    pub metrics: Option<ErrorMetrics>,
    /// The render's own estimate (none before two iterations).
    pub estimated: Option<Estimated>,
}

/// The parts of an error estimate a snapshot keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimated {
    pub relmse: f64,
    pub variance: f64,
    pub bias: f64,
}

/// One graph's run.
pub struct GraphRun {
    /// The graph file's stem (made unique).
    pub label: String,
    pub snapshots: Vec<Snapshot>,
    /// Least-squares slope of log relMSE against log seconds (-1 is an unbiased estimator's rate).
    pub slope: Option<f64>,
    pub node_times: Vec<NodeTime>,
    pub profiled_iterations: u64,
}

/// A peer renderer's measurement (`--peer`).
#[derive(Debug, Clone, PartialEq)]
pub struct PeerPoint {
    pub seconds: f64,
    pub relmse: f64,
    pub label: String,
}

pub struct CompareReport {
    pub runs: Vec<GraphRun>,
    pub peers: Vec<PeerPoint>,
    pub errors_csv: PathBuf,
    pub plot: Option<PathBuf>,
    pub profile_csv: Option<PathBuf>,
}

/// `n` moments from `total / 100` to `total`, evenly spaced in log time.
pub fn snapshot_times(total: f64, n: usize) -> Vec<f64> {
    if n <= 1 {
        return vec![total];
    }
    (0..n)
        .map(|k| total * 10f64.powf(-2.0 * (n - 1 - k) as f64 / (n - 1) as f64))
        .collect()
}

/// Least-squares slope of ln y against ln x over the points where both are positive; `None`
/// with fewer than two such points or no spread in x.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return None;
    }
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 1e-12).then(|| sxy / sxx)
}

/// Reads `seconds,relmse,label` rows; a header before the first row, blank lines and `#`
/// comments are skipped.
pub fn read_peer_csv(path: &Path) -> Result<Vec<PeerPoint>, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_peer_csv(path, &text)
}

pub fn parse_peer_csv(path: &Path, text: &str) -> Result<Vec<PeerPoint>, Error> {
    let mut points = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        let header = points.is_empty() && line.starts_with("seconds");
        if line.is_empty() || line.starts_with('#') || header {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let number = |k: usize| {
            fields
                .get(k)
                .and_then(|f| f.parse::<f64>().ok())
                .filter(|v| v.is_finite() && *v > 0.0)
        };
        let (Some(seconds), Some(relmse)) = (number(0), number(1)) else {
            return Err(Error::Other(format!(
                "{}:{}:1: expected `seconds,relmse,label` with positive numbers, got {line:?}",
                path.display(),
                i + 1
            )));
        };
        let label = fields.get(2).filter(|l| !l.is_empty()).unwrap_or(&"peer");
        points.push(PeerPoint {
            seconds,
            relmse,
            label: label.to_string(),
        });
    }
    Ok(points)
}

/// Which pixels a mask EXR keeps: those zero in every channel. An error when its size differs
/// from the renders' or it keeps nothing.
pub fn read_mask(path: &Path, width: u32, height: u32) -> Result<Vec<bool>, Error> {
    let image = Image::read_exr(path)?;
    if (image.width, image.height) != (width, height) {
        return Err(Error::Other(format!(
            "{}: the mask is {}x{} but the renders are {width}x{height}",
            path.display(),
            image.width,
            image.height
        )));
    }
    let keep: Vec<bool> = image.pixels.iter().map(|p| *p == [0.0; 3]).collect();
    if !keep.iter().any(|&k| k) {
        return Err(Error::Other(format!(
            "{}: no pixel of the mask is zero, so nothing would be measured",
            path.display()
        )));
    }
    Ok(keep)
}

/// Graph file stems, with `-2`, `-3` ... appended where two files share one.
fn labels(graphs: &[PathBuf]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for g in graphs {
        let stem = g
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "graph".into());
        let mut label = stem.clone();
        let mut k = 2;
        while out.contains(&label) {
            label = format!("{stem}-{k}");
            k += 1;
        }
        out.push(label);
    }
    out
}

/// Runs the comparison and writes `errors.csv`, each graph's final image, `errors.png` and,
/// with profiling, `profile.csv` into `options.out`. `progress` gets a line per step,
/// `snapshot` each graph's label and image at each snapshot (read back off the clock, so a
/// live view costs the measurement nothing).
pub fn compare(
    gpu: &GpuContext,
    options: &CompareOptions,
    cancel: &AtomicBool,
    mut progress: impl FnMut(&str),
    mut snapshot: impl FnMut(&str, &Image),
) -> Result<CompareReport, Error> {
    if !(options.seconds.is_finite() && options.seconds > 0.0) {
        return Err(Error::Other(format!(
            "the time per graph must be a positive number of seconds, got {}",
            options.seconds
        )));
    }
    if options.graphs.is_empty() {
        return Err(Error::Other("give at least one graph".into()));
    }
    let scene = crate::loaders::load_reporting(
        &options.scene,
        &options.defines,
        options.registry.bsdfs(),
        |w| eprintln!("warning: {w}"),
    )?;
    let (width, height) = options
        .size
        .unwrap_or((scene.camera.width, scene.camera.height));
    let reference = match &options.reference {
        Some(path) => {
            let reference = Image::read_exr(path)?;
            if (reference.width, reference.height) != (width, height) {
                return Err(Error::Other(format!(
                    "{}: the reference is {}x{} but the renders are {width}x{height} (set the render size)",
                    path.display(),
                    reference.width,
                    reference.height
                )));
            }
            Some(reference)
        }
        None => None,
    };
    let keep = match &options.mask {
        Some(path) => Some(read_mask(path, width, height)?),
        None => None,
    };
    let peers = match &options.peer {
        Some(path) => read_peer_csv(path)?,
        None => Vec::new(),
    };
    // Load every graph before rendering any, so a typo fails in a second, not after minutes;
    // `auto` chooses its graph once it renders (None here).
    let graphs = options
        .graphs
        .iter()
        .map(|path| match auto::is_auto(path) {
            true => Ok(None),
            false => options.registry.load_graph(path).map(Some),
        })
        .collect::<Result<Vec<_>, _>>()?;
    std::fs::create_dir_all(&options.out).map_err(|source| Error::Io {
        path: options.out.clone(),
        source,
    })?;

    let times = snapshot_times(options.seconds, options.snapshots.max(1));
    let mut runs = Vec::new();
    for ((graph, path), label) in graphs
        .into_iter()
        .zip(&options.graphs)
        .zip(labels(&options.graphs))
    {
        progress(&format!("{label}: preparing {}", path.display()));
        let build = |graph| {
            Renderer::builder(gpu, &scene, graph)
                .registry(options.registry.clone())
                .size(width, height)
                .seed(options.seed)
                .build()
        };
        // An `auto` run's clock starts with its pilots, less its winner's preparation (which
        // the other graphs' clocks leave out too).
        let (mut renderer, mut clock) = match graph {
            Some(graph) => (build(graph)?, 0.0),
            None => {
                let timed = Budget {
                    seconds: Some(options.seconds),
                    ..Budget::default()
                };
                let choice = auto::choose(timed, cancel, |name| {
                    let (file, text) = crate::graph::bundled::bundled_graph(name)?;
                    let graph = options.registry.parse_graph(Path::new(file), text)?;
                    Ok((build(graph)?, ()))
                })?;
                let report = choice.report;
                progress(&format!("{label}: {}", report.summary()));
                let winner = report.pilots.iter().find(|p| p.graph == report.graph);
                let prepared = winner.map_or(0.0, |p| p.prepare_seconds);
                (choice.renderer, report.seconds - prepared)
            }
        };
        if let Some(warning) = renderer.unsampled_light_warning() {
            progress(&format!("{label}: {warning}"));
        }
        if options.profile {
            renderer.enable_profiling()?;
        }
        let mut snapshots = Vec::new();
        let mut last_image = None;
        for (index, &at) in times.iter().enumerate() {
            // At least one iteration per snapshot, so seconds strictly increase.
            let budget = if at > clock {
                Budget {
                    spp: None,
                    seconds: Some(at - clock),
                    photons: None,
                    target_error: None,
                    adaptive: false,
                }
            } else {
                Budget {
                    spp: Some(renderer.samples_per_pixel() + renderer.spp_per_iteration()),
                    seconds: None,
                    photons: None,
                    target_error: None,
                    adaptive: false,
                }
            };
            let summary = renderer.run(budget, cancel, |_, _| {})?;
            clock += summary.seconds;
            let (image, estimate) = renderer.image_and_error_estimate()?;
            let metrics = match &reference {
                Some(r) => Some(image.metrics_where(r, |i| keep.as_ref().is_none_or(|k| k[i]))?),
                None => None,
            };
            // Over the pixels measured, as the error against the reference is.
            let estimated = estimate.map(|e| {
                let (relmse, variance, bias) = e.over(|i| keep.as_ref().is_none_or(|k| k[i]));
                Estimated {
                    relmse,
                    variance,
                    bias,
                }
            });
            progress(&format!(
                "{label}: {clock:.2} s, {} iterations, relMSE {}, estimated {}",
                renderer.iterations(),
                metrics.map_or("-".into(), |m| format!("{:.3e}", m.relmse)),
                estimated.map_or("-".into(), |e| format!("{:.3e}", e.relmse)),
            ));
            snapshots.push(Snapshot {
                index,
                seconds: clock,
                iterations: renderer.iterations(),
                spp: renderer.samples_per_pixel(),
                photons: renderer.photons(),
                metrics,
                estimated,
            });
            snapshot(&label, &image);
            last_image = Some(image);
            if summary.cancelled {
                break;
            }
        }
        // The last snapshot's image is the final one.
        let final_image = match last_image {
            Some(image) => image,
            None => renderer.image()?,
        };
        let provenance = Provenance::default()
            .with("hppm_adapter", gpu.adapter_label())
            .with("hppm_scene", options.scene.display())
            .with("hppm_graph", path.display())
            .with("hppm_spp", renderer.samples_per_pixel())
            .with("hppm_seed", options.seed)
            .with("hppm_seconds", format!("{clock:.3}"));
        final_image.write(&options.out.join(format!("{label}.exr")), &provenance)?;
        runs.push(GraphRun {
            slope: log_log_slope(&measured_points(&snapshots))
                .or_else(|| log_log_slope(&estimated_points(&snapshots))),
            label,
            snapshots,
            node_times: renderer.node_times(),
            profiled_iterations: renderer.iterations(),
        });
        if cancel.load(std::sync::atomic::Ordering::Relaxed) {
            break;
        }
    }

    let errors_csv = options.out.join("errors.csv");
    write_file(&errors_csv, &errors_csv_text(&runs))?;
    let profile_csv = if options.profile {
        let path = options.out.join("profile.csv");
        write_file(&path, &profile_csv_text(&runs))?;
        Some(path)
    } else {
        None
    };
    let plot = write_plot(options, gpu, &runs, &peers)?;
    Ok(CompareReport {
        runs,
        peers,
        errors_csv,
        plot,
        profile_csv,
    })
}

/// errors.png, the error of every run against time (with the `cli` feature, which brings the
/// plotting library).
#[cfg(feature = "cli")]
fn write_plot(
    options: &CompareOptions,
    gpu: &GpuContext,
    runs: &[GraphRun],
    peers: &[PeerPoint],
) -> Result<Option<PathBuf>, Error> {
    let plot_path = options.out.join("errors.png");
    let title = format!("{} on {}", scene_label(&options.scene), gpu.info.name);
    let series = plot_series(runs, peers);
    crate::image::write_atomically(&plot_path, |temp| {
        plot::error_vs_time(temp, &title, &series)
    })?;
    Ok(Some(plot_path))
}

#[cfg(not(feature = "cli"))]
fn write_plot(
    _: &CompareOptions,
    _: &GpuContext,
    _: &[GraphRun],
    _: &[PeerPoint],
) -> Result<Option<PathBuf>, Error> {
    Ok(None)
}

/// `refs/scenes/x/scene.xml` -> `x`; `scenes/furnace.ron` -> `furnace`.
#[cfg(feature = "cli")]
fn scene_label(path: &Path) -> String {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
    match (stem.as_deref(), path.parent().and_then(|p| p.file_name())) {
        (Some("scene"), Some(dir)) => dir.to_string_lossy().into_owned(),
        (Some(stem), _) => stem.to_string(),
        (None, _) => "scene".into(),
    }
}

fn write_file(path: &Path, text: &str) -> Result<(), Error> {
    crate::image::write_file_atomically(path, text.as_bytes())
}

/// (seconds, relMSE against the reference) of the snapshots that have one.
pub fn measured_points(snapshots: &[Snapshot]) -> Vec<(f64, f64)> {
    snapshots
        .iter()
        .filter_map(|s| s.metrics.map(|m| (s.seconds, m.relmse)))
        .collect()
}

/// (seconds, estimated relMSE) of the snapshots that have an estimate.
pub fn estimated_points(snapshots: &[Snapshot]) -> Vec<(f64, f64)> {
    snapshots
        .iter()
        .filter_map(|s| s.estimated.map(|e| (s.seconds, e.relmse)))
        .collect()
}

/// One row per snapshot; the measured columns are empty without a reference, the estimated
/// ones before two iterations.
pub fn errors_csv_text(runs: &[GraphRun]) -> String {
    let mut out = String::from(
        "graph,snapshot,seconds,iterations,spp,photons,relmse,rmse,mae,\
         estimated_relmse,estimated_variance,estimated_bias\n",
    );
    let e6 = |v: f64| format!("{v:.6e}");
    for run in runs {
        for s in &run.snapshots {
            let measured = s
                .metrics
                .map_or([String::new(), String::new(), String::new()], |m| {
                    [e6(m.relmse), e6(m.rmse), e6(m.mae)]
                });
            let estimated = s
                .estimated
                .map_or([String::new(), String::new(), String::new()], |e| {
                    [e6(e.relmse), e6(e.variance), e6(e.bias)]
                });
            let _ = writeln!(
                out,
                "{},{},{:.6},{},{},{},{},{}",
                run.label,
                s.index,
                s.seconds,
                s.iterations,
                s.spp,
                s.photons,
                measured.join(","),
                estimated.join(",")
            );
        }
    }
    out
}

/// One row per (graph, node): milliseconds per iteration on the GPU clock (empty where the
/// adapter has no encoder timestamps) and on the CPU wall clock.
pub fn profile_csv_text(runs: &[GraphRun]) -> String {
    let mut out =
        String::from("graph,node,pass,iterations,gpu_ms_per_iteration,wall_ms_per_iteration\n");
    for run in runs {
        let per = |s: f64| s / run.profiled_iterations.max(1) as f64 * 1e3;
        for t in &run.node_times {
            let gpu = t
                .gpu_seconds
                .map(|s| format!("{:.4}", per(s)))
                .unwrap_or_default();
            let _ = writeln!(
                out,
                "{},{},{},{},{gpu},{:.4}",
                run.label,
                t.name,
                t.kind,
                run.profiled_iterations,
                per(t.wall_seconds)
            );
        }
    }
    out
}

/// Per graph its measured error (when there is a reference) and its estimate, dashed in the
/// same colour; then the peers.
#[cfg(feature = "cli")]
fn plot_series(runs: &[GraphRun], peers: &[PeerPoint]) -> Vec<Series> {
    let mut series = Vec::new();
    for (index, run) in runs.iter().enumerate() {
        let slope = run
            .slope
            .map_or(String::new(), |slope| format!(" (slope {slope:.2})"));
        let measured = measured_points(&run.snapshots);
        let estimated = estimated_points(&run.snapshots);
        if !measured.is_empty() {
            series.push(Series {
                label: format!("{}{slope}", run.label),
                points: measured,
                style: SeriesStyle::Measured,
                colour: index,
            });
        }
        if !estimated.is_empty() {
            series.push(Series {
                label: format!("{} estimated", run.label),
                points: estimated,
                style: SeriesStyle::Estimated,
                colour: index,
            });
        }
    }
    for (index, (label, points)) in peer_groups(peers).into_iter().enumerate() {
        series.push(Series {
            label: format!("{label} (peer)"),
            points,
            style: SeriesStyle::Peer,
            colour: index,
        });
    }
    series
}

/// Peer points grouped by label, in first-seen order.
pub fn peer_groups(peers: &[PeerPoint]) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut groups: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for p in peers {
        match groups.iter_mut().find(|g| g.0 == p.label) {
            Some(g) => g.1.push((p.seconds, p.relmse)),
            None => groups.push((p.label.clone(), vec![(p.seconds, p.relmse)])),
        }
    }
    groups
}

/// The per-node table `--profile` prints.
pub fn profile_table(times: &[NodeTime], iterations: u64, adapter: &str) -> String {
    let gpu_timed = times.iter().any(|t| t.gpu_seconds.is_some());
    let mut out = if gpu_timed {
        format!(
            "per-node time per iteration over {iterations} iterations on {adapter} \
             (GPU: timestamp queries; wall: CPU clock, each node waited for on its own)\n"
        )
    } else {
        format!(
            "per-node time per iteration over {iterations} iterations on {adapter} \
             (CPU wall clock only: this adapter cannot write timestamps inside encoders)\n"
        )
    };
    let _ = writeln!(
        out,
        "  {:<16} {:<20} {:>10} {:>10}",
        "node", "pass", "GPU ms", "wall ms"
    );
    let per = |s: f64| s / iterations.max(1) as f64 * 1e3;
    for t in times {
        let gpu = t
            .gpu_seconds
            .map(|s| format!("{:.3}", per(s)))
            .unwrap_or_else(|| "-".into());
        let _ = writeln!(
            out,
            "  {:<16} {:<20} {:>10} {:>10.3}",
            t.name,
            t.kind,
            gpu,
            per(t.wall_seconds)
        );
    }
    out
}
