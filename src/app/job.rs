//! A render job from files to files, as `hppm render` runs it: plan (the scene, the graph, the
//! budget and size, a shard's or a resumed render's iterations), run (the renderer, with
//! checkpoints) and write (the image or the shard's accumulators, AOVs, provenance). The command
//! line maps its arguments to a [`RenderJob`] and watches it through a [`JobWatcher`] (a
//! progress bar, Ctrl-C, its messages on stderr); a program may run one the same way.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::Error;
use crate::gpu::GpuContext;
use crate::graph::ValidGraph;
use crate::graph::pass::Schedule;
use crate::image::{Image, OutputFormat, Provenance};
use crate::passes::Registry;
use crate::render::auto;
use crate::render::error_estimate::ErrorEstimate;
use crate::render::fingerprint::graph_fingerprint;
use crate::render::state::{Origin, StateFile, checkpoint_file, shard_file};
use crate::render::{Budget, BudgetField, Renderer, RunSummary, Stop};
use crate::scene::Scene;

/// What to render and where to write it.
#[derive(Debug, Clone)]
pub struct RenderJob {
    /// Mitsuba 3 XML, hppm RON or OBJ.
    pub scene: PathBuf,
    /// Mitsuba `-D name=value` scene parameters.
    pub defines: Vec<(String, String)>,
    pub graph: PathBuf,
    /// The image (.exr or .png), or with `shard` the shard's accumulators.
    pub out: PathBuf,
    /// Default: the scene's film (or the resumed render's size).
    pub size: Option<(u32, u32)>,
    /// Default: 0 (or the resumed render's).
    pub seed: Option<u64>,
    /// Shard k of n: iterations k, k + n, ...
    pub shard: Option<(u64, u64)>,
    /// Budgets: samples per pixel (default: the scene's sample count, else 64, when no other
    /// budget is given), seconds, photons, a target error (with `adaptive`, per pixel).
    pub spp: Option<u64>,
    pub seconds: Option<f64>,
    pub photons: Option<u64>,
    pub target_error: Option<f64>,
    pub adaptive: bool,
    /// Write the render's whole state here every `checkpoint_every` seconds and at the end.
    pub checkpoint: Option<PathBuf>,
    pub checkpoint_every: f64,
    /// Continue the render saved in this checkpoint.
    pub resume: Option<PathBuf>,
    /// Also write the output node's other images and the per-pixel error estimate.
    pub aovs: bool,
    /// Time each node and report the table.
    pub profile: bool,
    /// An adapter index or part of its name; default: the best.
    pub adapter: Option<String>,
}

/// How a job reports as it runs. Every method has a quiet default.
pub trait JobWatcher {
    /// How messages name the budget's and the job's fields (a program: the field names; the
    /// command line: its flags).
    fn names(&self) -> fn(BudgetField) -> &'static str {
        BudgetField::field_name
    }
    /// A line about the job: what was loaded, pruned, how it stopped, warnings.
    fn note(&mut self, _line: &str) {}
    /// A result: a file written, the profile, the closing summary.
    fn written(&mut self, _line: &str) {}
    /// The flag that stops the render (and writes what it has) once set; asked for just before
    /// the render starts.
    fn cancel_flag(&mut self) -> Arc<AtomicBool> {
        Arc::new(AtomicBool::new(false))
    }
    /// The render starts with this budget.
    fn start(&mut self, _budget: Budget) {}
    /// After each iteration, `seconds` into the render.
    fn progress(&mut self, _renderer: &Renderer, _seconds: f64) {}
    /// The render loop ended.
    fn finish(&mut self) {}
    /// The finished image, just before it is written (a shard writes accumulators instead);
    /// the renderer is there for what else the watcher shows (its AOVs).
    fn image(&mut self, _renderer: &Renderer, _image: &Image) {}
}

/// Runs `job` with the pass kinds of `registry`: plan, prepare, render, write. A job whose
/// graph is `auto` prepares and pilots each candidate graph first ([`crate::render::auto`]) and
/// goes on with the one chosen.
pub fn run(job: &RenderJob, registry: &Registry, watch: &mut dyn JobWatcher) -> Result<(), Error> {
    let job = &with_graph_named(job)?;
    if auto::is_auto(&job.graph) {
        return run_auto(job, registry, watch);
    }
    let (plan, graph, graph_text) = plan(job, registry, watch)?;
    let (mut renderer, origin) = prepare_graph(job, registry, &plan, &graph_text, graph, watch)?;
    let cancel = watch.cancel_flag();
    let rendered = render(
        job,
        &plan,
        plan.budget,
        &mut renderer,
        &origin,
        &cancel,
        watch,
    )?;
    write(job, &plan, &renderer, &origin, rendered, watch)
}

/// `job`, where its graph is `auto` and it resumes a checkpoint, with the checkpoint's graph
/// (the one the render began with); `auto` for a shard is refused, since every shard must
/// render the same graph and the choice depends on each machine's timing.
fn with_graph_named(job: &RenderJob) -> Result<RenderJob, Error> {
    if !auto::is_auto(&job.graph) {
        return Ok(job.clone());
    }
    if let Some(path) = &job.resume {
        let saved = StateFile::read(path)?;
        return Ok(RenderJob {
            graph: PathBuf::from(saved.header.graph),
            ..job.clone()
        });
    }
    if job.shard.is_some() {
        return Err(Error::Other(
            "a shard needs a named graph (--graph hybrid, pt, ...), not auto: every shard must              render the same graph, and auto's choice depends on each machine's timing"
                .into(),
        ));
    }
    Ok(job.clone())
}

/// Runs an `auto` job: plans it once, pilots the candidate graphs on its scene, renders the
/// rest of the budget with the chosen one, from where its pilot ended.
fn run_auto(job: &RenderJob, registry: &Registry, watch: &mut dyn JobWatcher) -> Result<(), Error> {
    let plan = plan_scene(job, registry, watch)?;
    let cancel = watch.cancel_flag();
    if auto::pilots_for(plan.budget) {
        watch.note(&format!(
            "auto: piloting {} on this scene (at most {:.0}% of a time budget) to choose the graph",
            auto::CANDIDATES.join(", "),
            auto::PILOT_SHARE * 100.0
        ));
    }
    let choice = auto::choose(plan.budget, &cancel, |name| {
        let (file, text) = crate::graph::bundled::bundled_graph(name)?;
        let chosen = RenderJob {
            graph: PathBuf::from(file),
            ..job.clone()
        };
        let graph = registry.parse_graph(&chosen.graph, text)?;
        let mut notes = Notes::default();
        let (renderer, origin) = prepare_graph(&chosen, registry, &plan, text, graph, &mut notes)?;
        Ok((renderer, (chosen, origin, notes)))
    })?;
    let auto::Choice {
        mut renderer,
        prepared: (chosen, origin, notes),
        report,
    } = choice;
    for line in &notes.0 {
        watch.note(line);
    }
    watch.note(&report.summary());
    // The render goes on from the winner's pilot with what the budget has left.
    let left = Budget {
        seconds: plan
            .budget
            .seconds
            .map(|s| (s - report.seconds).max(f64::MIN_POSITIVE)),
        ..plan.budget
    };
    let mut rendered = render(&chosen, &plan, left, &mut renderer, &origin, &cancel, watch)?;
    rendered.summary.seconds += report.seconds;
    rendered.auto = Some(report);
    write(&chosen, &plan, &renderer, &origin, rendered, watch)
}

/// A watcher that keeps the notes of a candidate's preparation, to say only the winner's.
#[derive(Default)]
struct Notes(Vec<String>);

impl JobWatcher for Notes {
    fn note(&mut self, line: &str) {
        self.0.push(line.to_string());
    }
}

/// What a job renders, settled before any GPU work: the scene, the device, the graph file's
/// text (for checkpoints), the size, seed, iterations and budget, the render it resumes.
struct Plan {
    scene: Scene,
    gpu: GpuContext,
    width: u32,
    height: u32,
    seed: u64,
    schedule: Schedule,
    budget: Budget,
    resume: Option<(PathBuf, StateFile)>,
}

/// Reads the job's graph file (before the scene, so that a mistake in it is found at once), then
/// plans the rest ([`plan_scene`]); returns the graph and its text too.
fn plan(
    job: &RenderJob,
    registry: &Registry,
    watch: &mut dyn JobWatcher,
) -> Result<(Plan, ValidGraph, String), Error> {
    // A bundled graph's name, or its repository path where the repository is not at hand,
    // stands for its compiled-in text.
    let (graph_file, graph_text) = crate::graph::bundled::read_graph(&job.graph)?;
    let plan = plan_scene(job, registry, watch)?;
    let graph = registry.parse_graph(&graph_file, &graph_text)?;
    for warning in &graph.warnings {
        watch.note(&format!("warning: {warning}"));
    }
    Ok((plan, graph, graph_text))
}

/// Checks the job, loads the scene, opens the device, settles size, seed, iterations and
/// budget.
fn plan_scene(
    job: &RenderJob,
    registry: &Registry,
    watch: &mut dyn JobWatcher,
) -> Result<Plan, Error> {
    use BudgetField::*;
    let name = watch.names();
    let scene_path = &job.scene;
    if job.shard.is_none() {
        OutputFormat::of(&job.out)?;
    }
    // A missing or read-only folder is found now, not after the render.
    crate::image::check_writable(&job.out)?;
    if let Some(checkpoint) = &job.checkpoint {
        crate::image::check_writable(checkpoint)?;
        if !(job.checkpoint_every.is_finite() && job.checkpoint_every > 0.0) {
            return Err(Error::Other(format!(
                "{} must be a positive number of seconds, got {}",
                name(CheckpointEvery),
                job.checkpoint_every
            )));
        }
    }
    let resume = match &job.resume {
        Some(path) => Some((path.clone(), StateFile::read(path)?)),
        None => None,
    };
    let loading = std::time::Instant::now();
    let scene = crate::loaders::load_reporting(scene_path, &job.defines, registry.bsdfs(), |w| {
        watch.note(&format!("warning: {w}"))
    })?;
    let features = scene.features();
    watch.note(&format!(
        "scene: {features} ({} triangles, loaded in {:.2} s)",
        scene.triangles.len(),
        loading.elapsed().as_secs_f64()
    ));
    if let Some(warning) = scene.no_light_warning() {
        watch.note(&format!("warning: {warning}"));
    }
    let gpu = GpuContext::new(job.adapter.as_deref())?;
    watch.note(&format!("adapter: {}", gpu.adapter_label()));
    let saved = resume.as_ref().map(|(_, f)| &f.header);
    let (width, height) = job.size.unwrap_or(match saved {
        Some(h) => (h.width, h.height),
        None => (scene.camera.width, scene.camera.height),
    });
    let seed = job.seed.or(saved.map(|h| h.seed)).unwrap_or(0);
    let (shard, shards) = job
        .shard
        .or(saved.map(|h| (h.shard, h.shards)))
        .unwrap_or((0, 1));
    let budget = Budget {
        spp: job.spp,
        seconds: job.seconds,
        photons: job.photons,
        target_error: job.target_error,
        adaptive: job.adaptive,
    }
    .or_scene_spp(scene.spp_hint);
    budget.check_named(name)?;
    if job.shard.is_some() && job.target_error.is_some() {
        return Err(Error::Other(format!(
            "{} and {}: a shard renders a fixed share of the iterations, so it cannot stop at an \
             error",
            name(Shard),
            name(TargetError)
        )));
    }
    if job.shard.is_some() && budget.spp.is_none() && budget.photons.is_none() {
        return Err(Error::Other(format!(
            "{} needs a budget in {} or {}: a time budget ends at a different iteration on every \
             machine, so the shards would not add up to one render",
            name(Shard),
            name(Spp),
            name(Photons)
        )));
    }
    let schedule = Schedule {
        first: shard,
        stride: shards,
    };
    let plan = Plan {
        scene,
        gpu,
        width,
        height,
        seed,
        schedule,
        budget,
        resume,
    };
    Ok(plan)
}

/// Builds the renderer (pruned graph, pipelines, buffers) and says what it did; refuses a shard
/// of a graph that cannot be summed; resumes a saved render; starts profiling.
fn prepare_graph<'p>(
    job: &RenderJob,
    registry: &Registry,
    plan: &'p Plan,
    graph_text: &str,
    graph: ValidGraph,
    watch: &mut dyn JobWatcher,
) -> Result<(Renderer<'p>, Origin), Error> {
    use BudgetField::*;
    let name = watch.names();
    let (scene_path, graph_path) = (&job.scene, &job.graph);
    let (gpu, scene, resume) = (&plan.gpu, &plan.scene, &plan.resume);
    let &Plan {
        width,
        height,
        seed,
        schedule,
        budget,
        ..
    } = plan;
    let preparing = std::time::Instant::now();
    let mut renderer = Renderer::builder(gpu, scene, graph)
        .registry(registry.clone())
        .size(width, height)
        .seed(seed)
        .schedule(schedule)
        .build()?;
    watch.note(&format!(
        "prepared in {:.2} s (scene BVH built and uploaded, graph's buffers and pipelines)",
        preparing.elapsed().as_secs_f64()
    ));
    let uniform_tables = renderer.placement().uniform_defs();
    if !uniform_tables.is_empty() {
        watch.note(&format!(
            "scene tables in uniform buffers: {}",
            uniform_tables.join(" ")
        ));
    }
    let chunked = renderer.placement().chunked_report();
    if !chunked.is_empty() {
        watch.note(&format!(
            "scene tables larger than one binding, in chunks: {}",
            chunked.join(", ")
        ));
    }
    if let Some(budget) = renderer.placement().node_budget() {
        watch.note(&format!(
            "scene BVH collapsed to at most {budget} nodes (a few larger leaves) to fit a uniform binding"
        ));
    }
    if let Some((triangles, spheres)) = renderer.placement().every_prim() {
        watch.note(&format!(
            "rays test every primitive instead of the BVH ({triangles} triangles, {spheres} spheres)"
        ));
    }
    for pruned in renderer.pruned() {
        watch.note(&pruned.to_string());
    }
    if job.shard.is_some() {
        if let Some((node, why)) = renderer.shard_refusal() {
            return Err(Error::Other(format!(
                "{}: {} cannot be rendered in shards: {node}: {why}",
                name(Shard),
                graph_path.display()
            )));
        }
        renderer.read_terms().map_err(|e| {
            Error::Other(format!(
                "{}: {}'s output cannot be summed over shards: {e}",
                name(Shard),
                graph_path.display()
            ))
        })?;
    }
    let origin = Origin {
        scene: scene_path.display().to_string(),
        graph: graph_path.display().to_string(),
        graph_hash: graph_fingerprint(graph_text),
        total_iterations: renderer.total_iterations(budget),
    };
    if let Some((path, file)) = &resume {
        crate::render::state::resume(&mut renderer, &origin, path, file)?;
        watch.note(&format!(
            "resumed {}: {} iterations done ({} spp)",
            path.display(),
            renderer.iterations(),
            renderer.samples_per_pixel()
        ));
    }
    if job.profile {
        // The first iteration compiles the pipelines: time the ones after it, when there are.
        let total = renderer
            .total_iterations(budget)
            .map(|t| renderer.schedule().local_count(t));
        let warm_up = total.is_none_or(|t| t > renderer.iterations() + 1);
        renderer.profile_from(renderer.iterations() + u64::from(warm_up))?;
    }
    if renderer.bands() > 1 {
        watch.note(&format!(
            "{width}x{height} does not fit the adapter's bindings whole: rendering it in {} bands \
             of rows (the photons traced once, for the whole image, and read by every band)",
            renderer.bands()
        ));
    }
    if let Some(warning) = renderer.unsampled_light_warning() {
        watch.note(&warning);
    }
    Ok((renderer, origin))
}

/// What the render loop leaves for writing.
struct Rendered {
    summary: RunSummary,
    /// None for a shard, which writes its accumulators.
    image: Option<Image>,
    estimate: Option<ErrorEstimate>,
    /// How `auto` chose the graph, where it did.
    auto: Option<auto::ChoiceReport>,
}

/// Runs the render to its budget (or Ctrl-C), checkpointing on the way, and takes the image and
/// its error estimate.
fn render(
    job: &RenderJob,
    plan: &Plan,
    budget: Budget,
    renderer: &mut Renderer<'_>,
    origin: &Origin,
    cancel: &AtomicBool,
    watch: &mut dyn JobWatcher,
) -> Result<Rendered, Error> {
    let name = watch.names();
    let graph_path = &job.graph;
    let &Plan { width, height, .. } = plan;
    // From here on Ctrl-C stops the render and writes what it has (tests wait for this line).
    watch.note(&format!(
        "rendering {width}x{height} through {} (Ctrl-C stops and writes the image so far)",
        graph_path.display()
    ));
    watch.start(budget);
    if job.shard.is_none() {
        renderer.watch_error();
    }
    let mut last_checkpoint = 0.0;
    let mut checkpoint_error = None;
    let summary = renderer.run(budget, cancel, |r, seconds| {
        if let Some(path) = &job.checkpoint
            && seconds - last_checkpoint >= job.checkpoint_every
            && checkpoint_error.is_none()
        {
            last_checkpoint = seconds;
            if let Err(e) = checkpoint_file(r, origin).and_then(|f| f.write(path)) {
                checkpoint_error = Some(e);
            }
        }
        watch.progress(r, seconds);
    })?;
    watch.finish();
    // The estimate at the image written, not the last one made on the way.
    let (image, estimate) = match job.shard {
        Some(_) => (None, None),
        None => {
            let (image, estimate) = renderer.image_and_error_estimate()?;
            (Some(image), estimate)
        }
    };
    let unsampled = renderer.unsampled_light_warning().is_some();
    let no_estimate = match job.shard {
        Some(_) => "no error estimate (a shard's accumulators are not an image)",
        None => "no error estimate (fewer than 2 iterations)",
    };
    watch.note(&stop_line(
        &summary,
        budget,
        estimate.as_ref().ok_or(no_estimate),
        unsampled,
        name,
    ));
    if let Some(e) = checkpoint_error {
        return Err(e);
    }
    Ok(Rendered {
        summary,
        image,
        estimate,
        auto: None,
    })
}

/// Writes the last checkpoint, the image (or the shard's accumulators) with its provenance,
/// the AOVs, and the closing lines.
fn write(
    job: &RenderJob,
    plan: &Plan,
    renderer: &Renderer<'_>,
    origin: &Origin,
    rendered: Rendered,
    watch: &mut dyn JobWatcher,
) -> Result<(), Error> {
    use BudgetField::*;
    let name = watch.names();
    let (scene_path, graph_path, gpu) = (&job.scene, &job.graph, &plan.gpu);
    let &Plan {
        width,
        height,
        seed,
        budget,
        ..
    } = plan;
    let Rendered {
        summary,
        image,
        estimate,
        auto,
    } = rendered;
    if let Some(path) = &job.checkpoint {
        checkpoint_file(renderer, origin)?.write(path)?;
        watch.note(&format!(
            "checkpoint {}: {} iterations",
            path.display(),
            renderer.iterations()
        ));
    }
    let counters = renderer.counters()?;
    let mut provenance = Provenance::default()
        .with("hppm_adapter", gpu.adapter_label())
        .with("hppm_scene", scene_path.display())
        .with("hppm_graph", graph_path.display())
        .with("hppm_spp", renderer.samples_per_pixel())
        .with("hppm_seed", seed)
        .with("hppm_seconds", format!("{:.3}", summary.seconds));
    if budget.adaptive {
        provenance = provenance.with(
            "hppm_mean_spp",
            format!("{:.3}", renderer.mean_samples_per_pixel()),
        );
    }
    if let Some(e) = &estimate {
        provenance = provenance
            .with("hppm_estimated_relmse", format!("{:.6e}", e.relmse))
            .with("hppm_estimated_variance", format!("{:.6e}", e.variance))
            .with("hppm_estimated_bias", format!("{:.6e}", e.bias));
    }
    if let Some(report) = &auto {
        provenance = provenance.with("hppm_auto", report.summary());
    }
    if !job.defines.is_empty() {
        let defines: Vec<String> = job
            .defines
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        provenance = provenance.with("hppm_defines", defines.join(" "));
    }
    if let Some(image) = &image {
        watch.image(renderer, image);
    }
    match image {
        Some(image) => image.write(&job.out, &provenance)?,
        None => shard_file(renderer, origin)?.write(&job.out)?,
    }
    if job.aovs {
        for (slot, aov) in renderer.aovs()? {
            let path = aov_path(&job.out, slot);
            aov.write(&path, &provenance.clone().with("hppm_aov", slot))?;
            watch.written(&format!("{}: {slot}", path.display()));
        }
        if let Some(e) = &estimate {
            let path = aov_path(&job.out.with_extension("exr"), "error");
            e.per_pixel
                .write(&path, &provenance.clone().with("hppm_aov", "error"))?;
            watch.written(&format!(
                "{}: error (estimated relative squared error)",
                path.display()
            ));
        }
    }
    let dropped = counters.get("photon_hits_dropped");
    if dropped > 0 {
        watch.note(&format!(
            "warning: {dropped} photon hits did not fit their buffer and were left out (caustics too dark); \
             lower photons_per_iteration"
        ));
    }
    if budget.photons.is_some() && renderer.photons_per_iteration() == 0 {
        watch.note(&format!(
            "warning: {} ignored: the graph emits no photons",
            name(Photons)
        ));
    }
    if summary.cancelled {
        watch.note("interrupted: wrote what was rendered so far");
    }
    if job.profile {
        let table = crate::app::compare::profile_table(
            &renderer.node_times(),
            renderer.profiled_iterations(),
            &gpu.adapter_label(),
        );
        watch.written(table.trim_end());
    }
    let spp = match budget.adaptive {
        true => format!(
            "{:.1} spp on average (at most {})",
            renderer.mean_samples_per_pixel(),
            renderer.samples_per_pixel()
        ),
        false => format!("{} spp", renderer.samples_per_pixel()),
    };
    watch.written(&format!(
        "{}: {}x{}, {spp} and {} photons in {:.2} s ({:.2} Mrays/s, {} samples discarded as NaN/Inf) on {}",
        job.out.display(),
        width,
        height,
        renderer.photons(),
        summary.seconds,
        counters.get("rays") as f64 / summary.seconds.max(1e-9) / 1e6,
        counters.get("discarded_samples"),
        gpu.adapter_label()
    ));
    Ok(())
}

/// Why the render stopped and its estimated error (or why there is none), in one line.
fn stop_line(
    summary: &RunSummary,
    budget: Budget,
    estimate: Result<&ErrorEstimate, &str>,
    unsampled_light: bool,
    name: fn(BudgetField) -> &'static str,
) -> String {
    use BudgetField::*;
    let why = match summary.stop {
        Stop::Count if budget.spp.is_some() => {
            format!("the samples asked for ({}) were rendered", name(Spp))
        }
        Stop::Count => format!("the photons asked for ({}) were emitted", name(Photons)),
        Stop::Time => format!("the time budget ({}) ran out", name(Seconds)),
        Stop::TargetError => format!("the estimated error fell below {}", name(TargetError)),
        Stop::Cancelled => "interrupted".to_string(),
    };
    let lower_bound = match unsampled_light {
        true => ", a lower bound: the caustics this graph cannot sample are missing from it",
        false => "",
    };
    let estimate = estimate.map_or_else(str::to_string, |e| {
        format!(
            "estimated relMSE {:.3e} (noise {:.3e}, kernel bias {:.3e}{lower_bound})",
            e.relmse, e.variance, e.bias
        )
    });
    match budget.target_error {
        Some(target) if summary.stop != Stop::TargetError => format!(
            "stopped before {} {target:e}: {why}; {estimate}",
            name(TargetError)
        ),
        _ => format!("stopped: {why}; {estimate}"),
    }
}

/// `render.exr` + `pt` -> `render.pt.exr`.
fn aov_path(out: &Path, slot: &str) -> PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let name = match out.extension() {
        Some(ext) => format!("{stem}.{slot}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{slot}"),
    };
    out.with_file_name(name)
}
