//! The `hppm` command line: render, info, graph, bench.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::app::bench;
use crate::app::job::{JobWatcher, RenderJob};
use crate::app::tev::TevView;
use crate::gpu::{GpuContext, GpuError};
use crate::image::{OutputFormat, Provenance};
use crate::passes::Registry;
use crate::render::state::StateFile;
use crate::render::{Budget, BudgetField, Renderer};
use crate::{Error, scene};
use clap::{Args, Parser, Subcommand};

/// hppm: path tracing + progressive photon mapping on the GPU, as a render graph.
#[derive(Parser)]
#[command(name = "hppm", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene through a graph.
    Render(RenderArgs),
    /// List GPU adapters and the features hppm uses, and the pass kinds.
    Info {
        /// Print the pass kinds' reference (slots, params) in Markdown instead.
        #[arg(long)]
        markdown: bool,
    },
    /// Print the Mitsuba 3 plugins and properties the scene loader reads, with Mitsuba's
    /// defaults and what hppm does with each (docs/scenes.md's table, in Markdown).
    Plugins,
    /// Check a scene file: every problem in it at once, each with file:line:col, as errors
    /// (it cannot render) and warnings (it renders without that); exits 0 when it renders.
    Check {
        scene: PathBuf,
        /// Set a scene parameter (see `render -D`).
        #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = parse_define)]
        defines: Vec<(String, String)>,
        /// Also say which rules each file was read with (Mitsuba 3's, or 0.6's for a file
        /// older than version 2.0) and list every upgrade applied to a 0.6 file.
        #[arg(short, long)]
        verbose: bool,
    },
    /// Validate a graph file and print its schedule.
    Graph {
        file: PathBuf,
        /// Print Graphviz instead of the schedule.
        #[arg(long)]
        dot: bool,
        /// Prune the graph for this scene first (drop what the scene has no use for).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Set a parameter of the --scene (see `render -D`).
        #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = parse_define)]
        defines: Vec<(String, String)>,
    },
    /// Render several graphs for the same time and plot their error against time.
    Compare(CompareArgs),
    /// Sum the shards of one render (`hppm render --shard k/n`) into its image.
    Merge(MergeArgs),
    /// Measure rays/s and samples/s of path_trace on the bundled Cornell scenes; with
    /// --hybrid, the hybrid's figures (node times, BVH build, report workload, equal-time error);
    /// with --gather, the hit-point structures (CPU SAH BVH, GPU LBVH, hash grid: build + gather).
    Bench(BenchArgs),
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (.xml Mitsuba 3, .ron, .obj); default: the bundled Cornell box.
    scene: Option<PathBuf>,
    /// Set a scene parameter, as `mitsuba -D name=value`: replaces the Mitsuba scene's
    /// `<default name="name">` and fills every `$name` (repeat for each).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = parse_define)]
    defines: Vec<(String, String)>,
    /// Render graph: a RON file, a bundled graph's name (hybrid, pt, hybrid_pppm, ...; the
    /// files of graphs/), or `auto` (the default): short pilots of pt, hybrid and hybrid_pppm
    /// on the scene, the one whose estimated error at the end of the budget is least renders
    /// on (docs/auto.md). With --shard the default is the hybrid; with --resume, the graph the
    /// checkpoint was rendered with.
    #[arg(long)]
    graph: Option<PathBuf>,
    /// Samples per pixel to render.
    #[arg(long, conflicts_with = "time")]
    spp: Option<u64>,
    /// Seconds to render for.
    #[arg(long)]
    time: Option<f64>,
    /// Photons to emit in total (graphs with a photon pass); stops at whichever budget comes
    /// first.
    #[arg(long)]
    photons: Option<u64>,
    /// Stop once the estimated relMSE (printed as the render runs) falls below this; --time,
    /// --spp or --photons caps the render.
    #[arg(long, value_name = "RELMSE")]
    target_error: Option<f64>,
    /// With --target-error: pixels whose estimated error is below the target stop receiving
    /// samples (path tracing graphs such as graphs/pt.ron; --spp then caps each pixel).
    #[arg(long)]
    adaptive: bool,
    /// Also write every image output of the graph's output node (e.g. `pt`, `caustic`,
    /// `radius` of `resolve`) next to `--out`, as OUT.SLOT.EXT, and the per-pixel error
    /// estimate as OUT.error.exr.
    #[arg(long)]
    aovs: bool,
    /// Show the render live in tev listening at [HOST:]PORT (host 127.0.0.1 by default; tev
    /// listens on 14158): the tiles that changed every 250 ms (less often for large images) and
    /// when done, with `--aovs` the output node's other images as layers. No viewer there
    /// changes nothing.
    #[arg(long, value_name = "[HOST:]PORT")]
    tev: Option<String>,
    /// Image size WxH (default: the scene's film).
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Seed of every random stream (default 0; a resumed render takes the checkpoint's).
    #[arg(long)]
    seed: Option<u64>,
    /// Output image: .exr (linear float) or .png (sRGB); with --shard, the shard's
    /// accumulators (a state file for `hppm merge`, any name).
    #[arg(long, default_value = "render.exr")]
    out: PathBuf,
    /// Render only iterations K, K+N, K+2N, ... of the budget (0 <= K < N), and write raw
    /// accumulators to --out for `hppm merge`. Needs a budget in --spp or --photons.
    #[arg(long, value_parser = parse_shard)]
    shard: Option<(u64, u64)>,
    /// Write the render's full state to FILE (atomically) every --checkpoint-every seconds,
    /// at the end and on Ctrl-C.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints.
    #[arg(long, default_value_t = 300.0)]
    checkpoint_every: f64,
    /// Continue the render saved in this checkpoint (same scene, graph and shard) to the
    /// budget given now; the image is the one the uninterrupted render would have made.
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Adapter index (see `hppm info`) or part of its name.
    #[arg(long)]
    adapter: Option<String>,
    /// Time every node (GPU timestamps where the adapter has them, CPU wall clock always) and
    /// print a table; nodes then run one at a time, so the render is slower.
    #[arg(long)]
    profile: bool,
}

#[derive(Args)]
struct MergeArgs {
    /// Shard files written by `hppm render --shard k/n`.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// Output image: .exr (linear float) or .png (sRGB).
    #[arg(long)]
    out: PathBuf,
    /// Merge the shards present even when some of the n are missing (an image of fewer
    /// samples, still unbiased for pt and pppm).
    #[arg(long)]
    partial: bool,
}

#[derive(Args)]
struct CompareArgs {
    /// Scene file (.xml Mitsuba 3, .ron, .obj).
    scene: PathBuf,
    /// Set a scene parameter, as `mitsuba -D name=value`: replaces the Mitsuba scene's
    /// `<default name="name">` and fills every `$name` (repeat for each).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = parse_define)]
    defines: Vec<(String, String)>,
    /// Reference image (EXR) the same size as the renders; without one, the error is only
    /// estimated (from the render itself).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// A graph to render, a RON file, a bundled graph's name or `auto` (the graph `hppm
    /// render` chooses, its pilots counted in its time) (repeat for each).
    #[arg(long = "graph", required = true)]
    graphs: Vec<PathBuf>,
    /// Seconds of rendering per graph (readback for the snapshots is not counted).
    #[arg(long)]
    time: f64,
    /// Snapshots per graph, log-spaced from 1% of --time to --time.
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u64).range(1..=1000))]
    snapshots: u64,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// CSV of another renderer's measurements (columns seconds,relmse,label) to plot too.
    #[arg(long)]
    peer: Option<PathBuf>,
    /// Measure only the pixels where this EXR image is zero.
    #[arg(long)]
    mask: Option<PathBuf>,
    /// Output folder: errors.csv, errors.png, one EXR per graph (and profile.csv).
    #[arg(long)]
    out: PathBuf,
    /// Time every node (see `render --profile`); store the table in DIR/profile.csv.
    #[arg(long)]
    profile: bool,
    /// Image size WxH (default: the scene's film).
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Adapter index (see `hppm info`) or part of its name.
    #[arg(long)]
    adapter: Option<String>,
    /// Show each graph's image live in tev at [HOST:]PORT, an image per graph named by its
    /// label, updated at every snapshot (off the clock), and the reference beside them.
    #[arg(long, value_name = "[HOST:]PORT")]
    tev: Option<String>,
}

#[derive(Args)]
struct BenchArgs {
    /// Adapter index (see `hppm info`) or part of its name.
    #[arg(long)]
    adapter: Option<String>,
    /// Samples per pixel for each measurement.
    #[arg(long, default_value_t = 64)]
    spp: u64,
    /// Append the results to this Markdown file (e.g. BENCHMARKS.md).
    #[arg(long)]
    write: Option<PathBuf>,
    /// Benchmark the hybrid instead (needs tests/refs from the source tree).
    #[arg(long)]
    hybrid: bool,
    /// Benchmark the hit-point structures instead (CPU SAH BVH, GPU LBVH, hash grid; build +
    /// gather at 16K, 262K and 1M hit points).
    #[arg(long, alias = "lbvh", conflicts_with = "hybrid")]
    gather: bool,
    /// Wall-clock budgets for the equal-time error table, comma-separated (with --hybrid).
    #[arg(long, value_delimiter = ',', default_value = "10,60")]
    seconds: Vec<f64>,
    /// Iterations of the 512x512 report workload to run (with --hybrid).
    #[arg(long, default_value_t = 4)]
    workload_iterations: u64,
    /// Render the seed report's Cornell workload whole (512x512, 512 spp, 2M photons) with pt,
    /// ppm_only and hybrid: whole-run seconds, per-node times, rays/s.
    #[arg(long, conflicts_with_all = ["hybrid", "gather"])]
    seed_workload: bool,
    /// Fraction of the seed workload's samples and photons to render (with --seed-workload).
    #[arg(long, default_value_t = 1.0, requires = "seed_workload")]
    scale: f64,
}

/// `NAME=VALUE` of `-D`: a name as Mitsuba's `$name` references spell it (letters, digits,
/// `_`), any value.
fn parse_define(text: &str) -> Result<(String, String), String> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, e.g. -D spp=16, got {text:?}"))?;
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!(
            "parameter name {name:?} must be letters, digits and _ (as in $name)"
        ));
    }
    Ok((name.to_string(), value.to_string()))
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, e.g. 512x512, got {text:?}"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (1..=scene::MAX_FILM_SIDE).contains(&v))
            .ok_or_else(|| {
                format!(
                    "size {s:?} is not a whole number from 1 to {}",
                    scene::MAX_FILM_SIDE
                )
            })
    };
    Ok((parse(w)?, parse(h)?))
}

/// `k/n` with 0 <= k < n.
fn parse_shard(text: &str) -> Result<(u64, u64), String> {
    let (k, n) = text
        .split_once('/')
        .ok_or_else(|| format!("expected K/N, e.g. 0/4, got {text:?}"))?;
    let k: u64 = k
        .trim()
        .parse()
        .map_err(|_| format!("shard index {k:?} is not a whole number"))?;
    let n: u64 = n
        .trim()
        .parse()
        .map_err(|_| format!("shard count {n:?} is not a whole number"))?;
    if n == 0 || k >= n {
        return Err(format!("shard {k}/{n}: need 0 <= K < N"));
    }
    Ok((k, n))
}

/// A file shipped with hppm, found relative to the working directory or, failing that, to the
/// source tree the binary was built from; where neither has it (an installed binary), its
/// repository path, which the scene and graph loaders resolve to their built-in copies.
fn bundled(relative: &str) -> PathBuf {
    let local = PathBuf::from(relative);
    let source_tree = Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
    if local.exists() || !source_tree.exists() {
        return local;
    }
    source_tree
}

/// The `render` flag that sets a budget field, for messages.
fn flag_of(field: BudgetField) -> &'static str {
    match field {
        BudgetField::Spp => "--spp",
        BudgetField::Photons => "--photons",
        BudgetField::Seconds => "--time",
        BudgetField::TargetError => "--target-error",
        BudgetField::Adaptive => "--adaptive",
        BudgetField::Shard => "--shard",
        BudgetField::CheckpointEvery => "--checkpoint-every",
    }
}

fn cancel_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let handler_flag = flag.clone();
    // A second handler cannot be installed (e.g. in an embedding program): rendering still works,
    // only Ctrl-C then ends the process without writing.
    let _ = ctrlc::set_handler(move || handler_flag.store(true, Ordering::Relaxed));
    flag
}

fn progress_bar(budget: Budget) -> indicatif::ProgressBar {
    let (length, template) = match (budget.spp, budget.seconds) {
        (Some(spp), _) => (spp, "{bar:40} {pos}/{len} spp  {msg}  eta {eta}"),
        (None, Some(s)) => ((s * 1000.0) as u64, "{bar:40} {msg}  eta {eta}"),
        (None, None) => (0, "{msg}"),
    };
    let bar = indicatif::ProgressBar::new(length);
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}

fn render(args: RenderArgs, registry: &Registry) -> Result<(), Error> {
    let args_tev = args.tev.clone();
    let job = RenderJob {
        scene: args
            .scene
            .unwrap_or_else(|| bundled("scenes/cornell_box.ron")),
        defines: args.defines,
        graph: args.graph.unwrap_or_else(|| match args.shard {
            // Every shard must render the same graph; auto's choice depends on timing.
            Some(_) => bundled("graphs/hybrid.ron"),
            None => PathBuf::from(crate::render::auto::AUTO),
        }),
        out: args.out,
        size: args.size,
        seed: args.seed,
        shard: args.shard,
        spp: args.spp,
        seconds: args.time,
        photons: args.photons,
        target_error: args.target_error,
        adaptive: args.adaptive,
        checkpoint: args.checkpoint,
        checkpoint_every: args.checkpoint_every,
        resume: args.resume,
        aovs: args.aovs,
        profile: args.profile,
        adapter: args.adapter,
    };
    let tev = match &args_tev {
        Some(address) => {
            let name = job
                .out
                .file_name()
                .map_or("hppm".into(), |n| n.to_string_lossy());
            Some(TevView::new(address, &name)?)
        }
        None => None,
    };
    let mut terminal = Terminal {
        bar: None,
        tev,
        tev_aovs: job.aovs,
        tev_cost: std::time::Duration::ZERO,
    };
    crate::app::job::run(&job, registry, &mut terminal)
}

/// The job's watcher on a terminal: notes on stderr, results on stdout, a progress bar, Ctrl-C,
/// and a live view in tev when asked for.
struct Terminal {
    bar: Option<(indicatif::ProgressBar, Budget)>,
    tev: Option<TevView>,
    /// The live view shows the output node's other images too (`--aovs`).
    tev_aovs: bool,
    /// What the last live update took (readback and sending), which spaces the next.
    tev_cost: std::time::Duration,
}

impl Terminal {
    /// Sends the image, and with `--aovs` the output node's other images as its layers.
    fn show(&mut self, r: &Renderer, image: &crate::image::Image) {
        let Some(tev) = &mut self.tev else {
            return;
        };
        let aovs = match self.tev_aovs {
            true => r.aovs().unwrap_or_default(),
            false => Vec::new(),
        };
        let layers: Vec<(&str, &crate::image::Image)> = std::iter::once(("", image))
            .chain(aovs.iter().map(|(slot, aov)| (*slot, aov)))
            .collect();
        tev.show_layers(&layers);
    }
}

/// How often the live view is sent the image: every 250 ms, or where an update costs more than
/// a tenth of that (a large image read back and sent), every ten updates' cost, so the view
/// never takes more than about a tenth of the render's time.
const TEV_INTERVAL: std::time::Duration = std::time::Duration::from_millis(250);
const TEV_SHARE: u32 = 10;

impl JobWatcher for Terminal {
    fn names(&self) -> fn(BudgetField) -> &'static str {
        flag_of
    }

    fn note(&mut self, line: &str) {
        eprintln!("{line}");
    }

    fn written(&mut self, line: &str) {
        println!("{line}");
    }

    fn cancel_flag(&mut self) -> Arc<AtomicBool> {
        cancel_flag()
    }

    fn start(&mut self, budget: Budget) {
        self.bar = Some((progress_bar(budget), budget));
    }

    fn progress(&mut self, r: &Renderer, seconds: f64) {
        let interval = TEV_INTERVAL.max(self.tev_cost * TEV_SHARE);
        if self.tev.as_ref().is_some_and(|t| t.due(interval)) {
            let started = std::time::Instant::now();
            if let Ok(image) = r.image() {
                self.show(r, &image);
            }
            self.tev_cost = started.elapsed();
        }
        let Some((bar, budget)) = &self.bar else {
            return;
        };
        let spp = r.samples_per_pixel();
        match budget.spp {
            Some(_) => bar.set_position(spp),
            None => bar.set_position((seconds * 1000.0) as u64),
        }
        let rate = spp as f64 / seconds.max(1e-9);
        let sampling = match budget.adaptive {
            true => format!("  sampling {:.0}% of pixels", 100.0 * r.sampled_share()),
            false => String::new(),
        };
        bar.set_message(match r.latest_error() {
            Some(e) => format!(
                "{rate:.1} spp/s  estimated relMSE {:.3e}{sampling}",
                e.relmse
            ),
            None => format!("{rate:.1} spp/s{sampling}"),
        });
    }

    fn finish(&mut self) {
        if let Some((bar, _)) = self.bar.take() {
            bar.finish_and_clear();
        }
    }

    fn image(&mut self, r: &Renderer, image: &crate::image::Image) {
        self.show(r, image);
    }
}

fn merge(args: MergeArgs) -> Result<(), Error> {
    OutputFormat::of(&args.out)?;
    crate::image::check_writable(&args.out)?;
    let shards = args
        .shards
        .iter()
        .map(|path| Ok((path.clone(), StateFile::read(path)?)))
        .collect::<Result<Vec<_>, Error>>()?;
    let merged = crate::render::state::merge(&shards, args.partial)?;
    let h = &merged.header;
    let provenance = Provenance::default()
        .with("hppm_scene", &h.scene)
        .with("hppm_graph", &h.graph)
        .with("hppm_spp", merged.samples_per_pixel)
        .with("hppm_seed", h.seed)
        .with(
            "hppm_shards",
            format!("{:?} of {}", merged.shards, merged.of),
        );
    merged.image.write(&args.out, &provenance)?;
    println!(
        "{}: {} of {} shards, {}x{}, {} spp and {} photons",
        args.out.display(),
        merged.shards.len(),
        merged.of,
        h.width,
        h.height,
        merged.samples_per_pixel,
        merged.photons
    );
    Ok(())
}

fn info(registry: &Registry) -> Result<(), Error> {
    let adapters = crate::gpu::list_adapters();
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter.into());
    }
    for (i, (info, features, limits)) in adapters.iter().enumerate() {
        println!("{i}: {}", crate::gpu::adapter_label(info));
        println!("   driver: {} {}", info.driver, info.driver_info);
        if let Some(warning) = crate::gpu::old_lavapipe_warning(info) {
            println!("   {warning}");
        }
        let has = |f: wgpu::Features| if features.contains(f) { "yes" } else { "no" };
        println!(
            "   float32 atomics: {}   timestamp queries: {}   subgroups: {}",
            has(wgpu::Features::SHADER_FLOAT32_ATOMIC),
            has(wgpu::Features::TIMESTAMP_QUERY),
            has(wgpu::Features::SUBGROUP)
        );
        println!(
            "   max storage binding: {} MiB   max uniform binding: {} KiB   max buffer: {} MiB",
            limits.max_storage_buffer_binding_size >> 20,
            limits.max_uniform_buffer_binding_size >> 10,
            limits.max_buffer_size >> 20
        );
    }
    println!("pass kinds:");
    for kind in registry.kinds() {
        println!("   {:<20} {}", kind.name, kind.description);
    }
    Ok(())
}

fn check_scene(
    registry: &Registry,
    path: &Path,
    defines: &[(String, String)],
    verbose: bool,
) -> Result<(), Error> {
    let report = crate::loaders::check_in(path, defines, registry.bsdfs());
    for rules in &report.rule_sets {
        if rules.legacy || verbose {
            println!("rules: {rules}");
        }
    }
    if verbose {
        for upgrade in &report.upgrades {
            println!("upgrade: {upgrade}");
        }
    } else if !report.upgrades.is_empty() {
        println!(
            "rules: {} upgrades applied to read Mitsuba 0.6 files (--verbose lists them)",
            report.upgrades.len()
        );
    }
    for warning in &report.warnings {
        println!("warning: {warning}");
    }
    for error in report.errors.iter().flat_map(|e| e.problems()) {
        println!("error: {error}");
    }
    let (errors, warnings) = (
        report
            .errors
            .iter()
            .map(|e| e.problems().len())
            .sum::<usize>(),
        report.warnings.len(),
    );
    match report.scene {
        Some(scene) if errors == 0 => {
            println!(
                "{}: renders ({}; {warnings} warnings)",
                path.display(),
                scene.features()
            );
            Ok(())
        }
        _ => Err(Error::Other(format!(
            "{}: does not render ({errors} errors, {warnings} warnings)",
            path.display()
        ))),
    }
}

/// The scene at `path`, its warnings printed.
fn load_scene(
    registry: &Registry,
    path: &Path,
    defines: &[(String, String)],
) -> Result<scene::Scene, Error> {
    let scene = crate::loaders::load_reporting(path, defines, registry.bsdfs(), |w| {
        eprintln!("warning: {w}")
    })?;
    Ok(scene)
}

fn show_graph(
    registry: &Registry,
    file: &Path,
    dot: bool,
    scene_path: Option<&Path>,
    defines: &[(String, String)],
) -> Result<(), Error> {
    let mut graph = registry.load_graph(file)?;
    for warning in &graph.warnings {
        eprintln!("warning: {warning}");
    }
    if let Some(scene_path) = scene_path {
        let scene = load_scene(registry, scene_path, defines)?;
        let features = scene.features();
        println!("scene: {features}");
        for pruned in graph.prune(|need| registry.scene_meets(&scene, &features, need))? {
            println!("{pruned}");
        }
    }
    graph.check_transport(&crate::passes::paths::CLASSES)?;
    if dot {
        print!("{}", graph.to_dot());
    } else {
        print!("{}", graph.schedule_text());
    }
    Ok(())
}

fn compare(args: CompareArgs, registry: &Registry) -> Result<(), Error> {
    let gpu = GpuContext::new(args.adapter.as_deref())?;
    eprintln!("adapter: {}", gpu.adapter_label());
    let options = crate::app::compare::CompareOptions {
        registry: registry.clone(),
        scene: args.scene,
        defines: args.defines,
        reference: args.reference,
        graphs: args.graphs,
        seconds: args.time,
        snapshots: args.snapshots as usize,
        seed: args.seed,
        peer: args.peer,
        mask: args.mask,
        out: args.out,
        profile: args.profile,
        size: args.size,
    };
    // The address is checked before any render; the reference goes to the viewer first. The
    // graphs render one after another, so one view at a time (tev keeps a closed view's image).
    let mut view = match &args.tev {
        Some(address) => Some(TevView::new(address, "reference")?),
        None => None,
    };
    if let (Some(view), Some(reference)) = (&mut view, &options.reference) {
        view.show(&crate::image::Image::read_exr(reference)?);
    }
    let mut show = |label: &str, image: &crate::image::Image| {
        let Some(address) = &args.tev else {
            return;
        };
        if view.as_ref().is_none_or(|v| v.name() != label) {
            view = TevView::new(address, label)
                .inspect_err(|e| eprintln!("warning: {e}"))
                .ok();
        }
        if let Some(view) = &mut view {
            view.show(image);
        }
    };
    let cancel = cancel_flag();
    let report = crate::app::compare::compare(
        &gpu,
        &options,
        &cancel,
        |line| eprintln!("{line}"),
        &mut show,
    )?;
    for run in &report.runs {
        let last = run.snapshots.last();
        println!(
            "{:<20} relMSE {} (estimated {}) after {:.1} s ({} spp); slope {}",
            run.label,
            last.and_then(|s| s.metrics)
                .map_or("-".into(), |m| format!("{:.3e}", m.relmse)),
            last.and_then(|s| s.estimated)
                .map_or("-".into(), |e| format!("{:.3e}", e.relmse)),
            last.map_or(0.0, |s| s.seconds),
            last.map_or(0, |s| s.spp),
            run.slope
                .map_or("n/a (fewer than 2 snapshots)".into(), |s| format!("{s:.2}"))
        );
        if options.profile {
            print!(
                "{}",
                crate::app::compare::profile_table(
                    &run.node_times,
                    run.profiled_iterations,
                    &gpu.adapter_label()
                )
            );
        }
    }
    for (label, points) in crate::app::compare::peer_groups(&report.peers) {
        let slope =
            crate::app::compare::log_log_slope(&points).map_or("n/a".into(), |s| format!("{s:.2}"));
        println!("{label:<20} (peer) slope {slope}");
    }
    println!("{}", report.errors_csv.display());
    if let Some(plot) = &report.plot {
        println!("{}", plot.display());
    }
    if let Some(profile) = &report.profile_csv {
        println!("{}", profile.display());
    }
    Ok(())
}

fn bench_hybrid(args: &BenchArgs) -> Result<(), Error> {
    let options = crate::app::bench_hybrid::HybridBenchOptions {
        adapter: args.adapter.as_deref(),
        seconds: args.seconds.clone(),
        workload_iterations: args.workload_iterations.max(1),
    };
    let text = crate::app::bench_hybrid::run(&options, bundled)?;
    print!("{text}");
    if let Some(path) = &args.write {
        bench::append_markdown(path, &text)?;
    }
    Ok(())
}

fn bench_seed(args: &BenchArgs) -> Result<(), Error> {
    let options = crate::app::bench_seed::SeedWorkloadOptions {
        adapter: args.adapter.as_deref(),
        scale: args.scale,
    };
    let text = crate::app::bench_seed::run(&options, bundled)?;
    print!("{text}");
    if let Some(path) = &args.write {
        bench::append_markdown(path, &text)?;
    }
    Ok(())
}

fn bench_gather(args: &BenchArgs) -> Result<(), Error> {
    let text = crate::app::bench_gather::run(args.adapter.as_deref(), bundled)?;
    print!("{text}");
    if let Some(path) = &args.write {
        bench::append_markdown(path, &text)?;
    }
    Ok(())
}

/// On a headless machine Mesa's Vulkan and EGL drivers try to reach a Wayland compositor while
/// wgpu opens them, and libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set" when
/// the variable is missing: two lines a user reads as errors of the render. Pointing it at the
/// temporary folder lets the (failing, harmless) connection attempt stay quiet.
fn quiet_headless_wayland_probe() {
    let valid = std::env::var_os("XDG_RUNTIME_DIR")
        .is_some_and(|dir| Path::new(&dir).is_absolute() && Path::new(&dir).is_dir());
    if !valid {
        // SAFETY: `run` is called first thing in `main` (its documented contract), before any
        // other thread exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
}

/// Runs the `hppm` command line (`render`, `compare`, `graph`, `info`, ...) on the process's
/// arguments with the pass kinds, WGSL modules and scene needs of `registry`: a program that
/// registers passes of its own gets the whole CLI with them in it. Call it first thing in
/// `main`, before other threads start (it may set `XDG_RUNTIME_DIR` for wgpu's probe).
pub fn run(registry: Registry) -> ExitCode {
    quiet_headless_wayland_probe();
    run_from(std::env::args_os(), registry)
}

/// [`run`] on the given arguments (the first is the program's name). It leaves the process's
/// environment alone, so any thread may call it (tests, the Python module); on a headless
/// machine without `XDG_RUNTIME_DIR` wgpu's driver probe may then print libwayland's two
/// harmless lines.
pub fn run_from(
    args: impl IntoIterator<Item = impl Into<std::ffi::OsString> + Clone>,
    registry: Registry,
) -> ExitCode {
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    let result = match cli.command {
        Command::Render(args) => render(args, &registry),
        Command::Compare(args) => compare(args, &registry),
        Command::Merge(args) => merge(args),
        Command::Info { markdown: true } => {
            print!("{}", registry.markdown());
            Ok(())
        }
        Command::Info { markdown: false } => info(&registry),
        Command::Check {
            scene,
            defines,
            verbose,
        } => check_scene(&registry, &scene, &defines, verbose),
        Command::Plugins => {
            print!("{}", crate::loaders::plugins::markdown(registry.bsdfs()));
            Ok(())
        }
        Command::Graph {
            file,
            dot,
            scene,
            defines,
        } => show_graph(&registry, &file, dot, scene.as_deref(), &defines),
        Command::Bench(args) if args.hybrid => bench_hybrid(&args),
        Command::Bench(args) if args.gather => bench_gather(&args),
        Command::Bench(args) if args.seed_workload => bench_seed(&args),
        Command::Bench(args) => bench::run(
            args.adapter.as_deref(),
            args.spp,
            args.write.as_deref(),
            bundled,
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            match error {
                Error::Gpu(GpuError::NoAdapter) => ExitCode::from(2),
                _ => ExitCode::FAILURE,
            }
        }
    }
}
