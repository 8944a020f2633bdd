//! Renders a validated graph over a scene: prunes what the scene does not need, uploads the
//! scene and shares it with the passes, prepares the graph, then runs iterations until a budget
//! is met.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use super::budget::Budget;
use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::odd_iterations::OddIterations;
use crate::gpu::sample_mask::{SAMPLED, SampleMask};
use crate::gpu_scene::layout::GpuScene;
use crate::gpu_scene::{SceneResources, TablePlacement};
use crate::graph::ValidGraph;
use crate::graph::exec::PreparedGraph;
use crate::graph::pass::{Counters, IMAGE, Resource, Schedule, Shared};
use crate::image::Image;
use crate::passes::hit_points::KERNEL_BIAS;
use crate::passes::{Registry, paths};
use crate::render::error_estimate::{self, ErrorEstimate, Halves};
use crate::scene::Scene;

pub use crate::graph::exec::NodeTime;

/// Per-pixel sums and counts (RGB sum, count) of one accumulator, by its `node.slot` name.
pub type Term = (String, Vec<[f32; 4]>);

/// One band of the image: a graph prepared for the film rows `grid_y..grid_y + grid_rows`, of
/// which it contributes `keep_y..keep_y + keep_rows` (the rest is the halo that splatting pixel
/// filters read across the band's edge).
struct Tile {
    graph: PreparedGraph,
    output: Resource,
    /// Every image output of the output node and every image it reads (its AOVs), by slot.
    aovs: Vec<(&'static str, Resource)>,
    /// The output and every estimator's kernel bias, with their odd-iteration sums.
    halves: OddIterations,
    /// What `halves` tracks, in its order: the output first.
    tracked: Vec<Resource>,
    /// Adaptive sampling's flags for this band's pixels (disabled unless the render is adaptive).
    mask: SampleMask,
    grid_y: u32,
    grid_rows: u32,
    keep_y: u32,
    keep_rows: u32,
}

/// A graph prepared on a device for one scene, ready to iterate. An image whose buffers would
/// not fit the adapter's bindings is rendered in bands, each its own prepared graph: rays and
/// random streams follow film pixels, and the first band traces the photons the whole image
/// would and the others read them (the nodes that do not follow the pixels run once), so the
/// bands together are the image the untiled render would make.
pub struct Renderer<'a> {
    gpu: &'a GpuContext,
    tiles: Vec<Tile>,
    width: u32,
    height: u32,
    seed: u64,
    /// Which global iterations this render runs (all of them, or a shard's share).
    schedule: Schedule,
    /// Iterations run so far by this render (its local count; `schedule` maps it to global).
    iteration: u64,
    spp_per_iteration: u64,
    photons_per_iteration: u64,
    /// Nodes the scene had no use for, removed before preparing.
    pruned: Vec<crate::graph::Pruned>,
    /// Fingerprint of the scene as uploaded (geometry, materials, lights, camera at this size).
    scene_hash: u64,
    /// Which scene tables are bound as uniform buffers.
    placement: TablePlacement,
    profiling: Profiling,
    /// Whether `run` estimates the error as it renders (always with a target error).
    watch_error: bool,
    /// The latest estimate `run` made.
    latest_error: Option<ErrorReport>,
    /// The pixel filter's reach in pixels, past which a sample does not change a pixel.
    filter_reach: u32,
    /// Share of the pixels the camera samples now (1 unless adaptive sampling stopped some).
    sampled_share: f64,
    /// Camera samples per pixel so far, averaged over the image.
    mean_spp: f64,
    /// The scene has lights at a point or from one direction and delta surfaces: their
    /// caustics exist only where a graph traces photons.
    delta_caustics: bool,
}

/// Puts one item a program shares with its passes into a band's [`Shared`].
type ShareItem = Box<dyn Fn(&mut Shared)>;

/// Builds a [`Renderer`] ([`Renderer::builder`]).
pub struct RendererBuilder<'a, 's> {
    gpu: &'a GpuContext,
    scene: &'s Scene,
    graph: ValidGraph,
    size: (u32, u32),
    seed: u64,
    schedule: Schedule,
    bands: Option<u32>,
    registry: Registry,
    /// Each puts one item the program shares with its passes into a band's [`Shared`].
    shared: Vec<ShareItem>,
}

impl<'a> RendererBuilder<'a, '_> {
    /// The pass kinds, WGSL modules and scene-need tests the graph was validated against
    /// (default: [`Registry::builtin`]).
    pub fn registry(mut self, registry: Registry) -> Self {
        self.registry = registry;
        self
    }

    /// The image size (default: the scene's film).
    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.size = (width, height);
        self
    }

    /// The seed of every random stream (default 0).
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Which global iterations to run (default: all, from 0).
    pub fn schedule(mut self, schedule: Schedule) -> Self {
        self.schedule = schedule;
        self
    }

    /// Render in this many bands of rows (default: the fewest whose buffers fit the adapter).
    pub fn bands(mut self, bands: u32) -> Self {
        self.bands = Some(bands);
        self
    }

    /// Shares `item` with every pass ([`Shared::get`] in `prepare`), as the render shares the
    /// scene's GPU tables; each band of the image gets a clone.
    pub fn share<T: std::any::Any + Clone + Send>(mut self, item: T) -> Self {
        self.shared.push(Box::new(move |shared: &mut Shared| {
            shared.insert(item.clone())
        }));
        self
    }

    pub fn build(self) -> Result<Renderer<'a>, Error> {
        Renderer::build(self)
    }
}

/// An error estimate made during a render, without its per-pixel image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorReport {
    pub seconds: f64,
    pub iterations: u64,
    pub relmse: f64,
    pub variance: f64,
    pub bias: f64,
}

/// Least iterations before a target error may end a render: two halves of 4 each, so that one
/// lucky pair of iterations does not stop it.
const MIN_ITERATIONS_FOR_TARGET: u64 = 8;

/// What ended a render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// The samples or photons asked for were rendered.
    Count,
    Time,
    /// The estimated error fell below the target.
    TargetError,
    Cancelled,
}

/// When the nodes are timed ([`Renderer::profile_from`]).
#[derive(Clone, Copy, PartialEq)]
enum Profiling {
    Off,
    /// From this local iteration on, which has not started yet.
    From(u64),
    /// Since this local iteration.
    Since(u64),
}

/// Rows above and below a band that its pixels' splatted samples come from: the pixel filter's
/// reach as path_trace.wgsl's `splat` computes it (none for the box filter, which never splats;
/// for a filter with negative lobes that of the samples drawn from it, which land up to the
/// radius from their pixel's centre).
fn halo_rows(scene: &Scene) -> u32 {
    match scene.camera.filter {
        crate::scene::filter::PixelFilter::Box => 0,
        filter if filter.is_signed() => ((2.0 * filter.radius()).ceil() - 1.0).max(0.0) as u32,
        filter => (filter.radius() - 0.5).ceil().max(0.0) as u32,
    }
}

impl<'a> Renderer<'a> {
    pub fn new(
        gpu: &'a GpuContext,
        scene: &Scene,
        graph: ValidGraph,
        width: u32,
        height: u32,
        seed: u64,
    ) -> Result<Self, Error> {
        Self::with_schedule(gpu, scene, graph, width, height, seed, Schedule::default())
    }

    /// A renderer that runs the global iterations of `schedule` (a shard's, or the rest of a
    /// resumed render), each drawing the random numbers it would in one full render.
    pub fn with_schedule(
        gpu: &'a GpuContext,
        scene: &Scene,
        graph: ValidGraph,
        width: u32,
        height: u32,
        seed: u64,
        schedule: Schedule,
    ) -> Result<Self, Error> {
        Self::with_bands(gpu, scene, graph, (width, height), seed, schedule, None)
    }

    /// As [`Renderer::with_schedule`], in `bands` bands of rows (`None`: the fewest whose
    /// buffers fit the adapter, trying 1, 2, 4, ...).
    pub fn with_bands(
        gpu: &'a GpuContext,
        scene: &Scene,
        graph: ValidGraph,
        (width, height): (u32, u32),
        seed: u64,
        schedule: Schedule,
        bands: Option<u32>,
    ) -> Result<Self, Error> {
        let mut builder = Self::builder(gpu, scene, graph)
            .size(width, height)
            .seed(seed)
            .schedule(schedule);
        builder.bands = bands;
        builder.build()
    }

    /// A renderer with every choice spelled out: the pass registry (the built-in one unless
    /// given), what the render shares with its passes, size, seed, schedule and bands.
    ///
    /// ```no_run
    /// # fn main() -> Result<(), hppm::Error> {
    /// let gpu = hppm::gpu::GpuContext::new(None)?;
    /// let scene = hppm::loaders::load(std::path::Path::new("scene.xml"))?;
    /// let registry = hppm::passes::Registry::builtin();
    /// let graph = registry.bundled_graph("hybrid")?;
    /// let mut renderer = hppm::render::Renderer::builder(&gpu, &scene, graph)
    ///     .registry(registry)
    ///     .size(256, 256)
    ///     .build()?;
    /// renderer.iterate()?;
    /// let image = renderer.image()?;
    /// # let _ = image;
    /// # Ok(())
    /// # }
    /// ```
    pub fn builder<'s>(
        gpu: &'a GpuContext,
        scene: &'s Scene,
        graph: ValidGraph,
    ) -> RendererBuilder<'a, 's> {
        RendererBuilder {
            gpu,
            scene,
            graph,
            size: (scene.camera.width, scene.camera.height),
            seed: 0,
            schedule: Schedule::default(),
            bands: None,
            registry: Registry::builtin(),
            shared: Vec::new(),
        }
    }

    fn build(builder: RendererBuilder<'a, '_>) -> Result<Self, Error> {
        let RendererBuilder {
            gpu,
            scene,
            mut graph,
            size: (width, height),
            seed,
            schedule,
            bands,
            registry,
            shared: shared_items,
        } = builder;
        if schedule.stride == 0 {
            return Err(Error::Other(
                "a schedule's stride must be at least 1".into(),
            ));
        }
        let side = 1..=crate::scene::MAX_FILM_SIDE;
        if !(side.contains(&width) && side.contains(&height)) {
            return Err(Error::Other(format!(
                "image size {width}x{height}: each side must be a whole number from 1 to {}",
                crate::scene::MAX_FILM_SIDE
            )));
        }
        // The loaders refuse these already; a scene made or scaled in code must not render black
        // without a word either.
        scene.check_extent()?;
        let features = scene.features();
        let pruned = graph.prune(|need| registry.scene_meets(scene, &features, need))?;
        graph.check_transport(&paths::CLASSES)?;
        let mut gpu_scene = GpuScene::with_bsdfs(scene, width, height, registry.bsdfs())?;
        let scene_hash = scene_fingerprint(&gpu_scene);
        let placement = TablePlacement::for_adapter(gpu, &gpu_scene)?;
        let shaders = registry.shader_library(gpu.has_float_atomics(), scene, &placement)?;
        let halo = halo_rows(scene);
        let table_bytes = gpu_scene.table_bytes();
        // The tables once; every band binds them with its own uniform.
        let tables = SceneResources::upload(gpu, &gpu_scene, &placement)?;
        // Band `index` of `bands` bands of rows.
        let mut prepare_band =
            |bands: u32, index: u32, lender: Option<&PreparedGraph>| -> Result<Tile, Error> {
                let rows = height.div_ceil(bands.max(1)).max(1);
                let keep_y = index * rows;
                let keep_rows = rows.min(height - keep_y);
                let grid_y = keep_y.saturating_sub(halo);
                let grid_rows = (keep_y + keep_rows + halo).min(height) - grid_y;
                gpu_scene.set_tile(0, grid_y, width, grid_rows);
                let band = crate::graph::exec::Band {
                    size: (width, grid_rows),
                    film_pixels: width as u64 * height as u64,
                    lender,
                };
                let mask = SampleMask::new(gpu, width * grid_rows)?;
                let mut shared = Shared::default();
                shared.insert(tables.with_uniform(gpu, &gpu_scene.uniform)?);
                shared.insert(mask.clone());
                for share in &shared_items {
                    share(&mut shared);
                }
                let graph = PreparedGraph::new(
                    gpu,
                    &shaders,
                    &shared,
                    graph.instance()?,
                    band,
                    schedule.first,
                )?;
                let tracked = tracked_images(&graph)?;
                let named: Vec<_> = tracked
                    .iter()
                    .map(|(name, r)| (name.clone(), r.buffer.clone(), r.len as u32))
                    .collect();
                let halves = OddIterations::new(gpu, &shaders, &named, &mask)?;
                Ok(Tile {
                    output: graph.output()?.clone(),
                    aovs: image_aovs(&graph),
                    halves,
                    tracked: tracked.into_iter().map(|(_, r)| r).collect(),
                    mask,
                    graph,
                    grid_y,
                    grid_rows,
                    keep_y,
                    keep_rows,
                })
            };
        // The first band decides: the fewest bands whose buffers fit the adapter's bindings.
        let (bands, first) = match bands {
            Some(bands) => {
                let bands = bands.clamp(1, height.max(1));
                (bands, prepare_band(bands, 0, None)?)
            }
            None => {
                let mut bands = 1;
                loop {
                    match prepare_band(bands, 0, None) {
                        Ok(first) => break (bands, first),
                        Err(e) if e.is_too_large() && bands < height => {
                            bands = (bands * 2).min(height)
                        }
                        Err(e) if bands > 1 => {
                            return Err(Error::Other(format!(
                                "{e}\n(the image was split into bands of as few as {} rows, and \
                                 a band still does not fit: buffers that grow with the photons \
                                 or per pixel do not shrink with the bands)",
                                height.div_ceil(bands)
                            )));
                        }
                        Err(e) => return Err(e),
                    }
                }
            }
        };
        let rows = height.div_ceil(bands);
        let count = height.div_ceil(rows);
        check_memory(gpu, &first, table_bytes, count, (width, height))?;
        let spp_per_iteration = first.graph.spp_per_iteration();
        // The first band traces the photons for every band: the image counts them once.
        let photons_per_iteration = first.graph.photons_per_iteration();
        let mut rest = Vec::new();
        for index in 1..count {
            rest.push(prepare_band(bands, index, Some(&first.graph))?);
        }
        let tiles: Vec<Tile> = std::iter::once(first).chain(rest).collect();
        Ok(Self {
            gpu,
            tiles,
            width,
            height,
            seed,
            schedule,
            iteration: 0,
            spp_per_iteration,
            photons_per_iteration,
            pruned,
            placement,
            scene_hash,
            profiling: Profiling::Off,
            watch_error: false,
            latest_error: None,
            filter_reach: halo,
            sampled_share: 1.0,
            mean_spp: 0.0,
            delta_caustics: features.delta
                && (features.point_lights || features.spot_lights || features.directional_lights),
        })
    }

    /// Bands of rows the image is rendered in (1 when its buffers fit the adapter whole).
    pub fn bands(&self) -> usize {
        self.tiles.len()
    }

    /// Fingerprint of the scene as the GPU sees it: two renders with equal fingerprints render
    /// the same scene at the same size.
    pub fn scene_hash(&self) -> u64 {
        self.scene_hash
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The accumulators whose means add up to the image, read back as per-pixel sums and
    /// counts, by `node.slot` (what a shard writes and `hppm merge` sums).
    pub fn read_terms(&self) -> Result<Vec<Term>, Error> {
        let mut terms: Vec<Term> = Vec::new();
        for (t, tile) in self.tiles.iter().enumerate() {
            for (i, (name, r)) in tile.graph.output_terms()?.into_iter().enumerate() {
                if t == 0 {
                    terms.push((name.clone(), self.blank()));
                }
                let (_, sums) = terms.get_mut(i).ok_or_else(|| {
                    Error::Other(format!("band {t} has a term {name} the first band lacks"))
                })?;
                self.place(tile, &r, sums)?;
            }
        }
        Ok(terms)
    }

    /// Zeroed per-pixel sums of the whole image.
    fn blank(&self) -> Vec<[f32; 4]> {
        vec![[0.0; 4]; self.width as usize * self.height as usize]
    }

    /// Copies the rows `tile` keeps of its image resource `r` into the whole image's `sums`.
    fn place(&self, tile: &Tile, r: &Resource, sums: &mut [[f32; 4]]) -> Result<(), Error> {
        let width = self.width as usize;
        if r.len != width as u64 * tile.grid_rows as u64 {
            return Err(Error::Other(format!(
                "an image of {} pixels in a band of {width}x{}",
                r.len, tile.grid_rows
            )));
        }
        let grid: Vec<[f32; 4]> = self.gpu.read_pod(&r.buffer, r.len as usize)?;
        self.place_rows(tile, &grid, sums);
        Ok(())
    }

    /// Copies the rows `tile` keeps of `grid`, one value per pixel of its rows, into `sums`.
    fn place_rows(&self, tile: &Tile, grid: &[[f32; 4]], sums: &mut [[f32; 4]]) {
        let width = self.width as usize;
        let skip = (tile.keep_y - tile.grid_y) as usize * width;
        let kept = tile.keep_rows as usize * width;
        let at = tile.keep_y as usize * width;
        sums[at..at + kept].copy_from_slice(&grid[skip..skip + kept]);
    }

    /// Every buffer whose contents carry between iterations, read back whole, by name (what a
    /// checkpoint holds, besides the iteration count).
    pub fn read_state(&self) -> Result<Vec<(String, Vec<u8>)>, Error> {
        self.gpu.wait()?;
        self.state_buffers()
            .into_iter()
            .map(|(name, buffer)| Ok((name, self.gpu.read_buffer(buffer, 0, buffer.size())?)))
            .collect()
    }

    /// Every band's state buffers, named as one graph's are, prefixed `bandK/` when there are
    /// several bands.
    fn state_buffers(&self) -> Vec<(String, &wgpu::Buffer)> {
        let several = self.tiles.len() > 1;
        self.tiles
            .iter()
            .enumerate()
            .flat_map(|(k, tile)| {
                tile.graph
                    .state_buffers()
                    .into_iter()
                    .chain(tile.halves.state_buffers())
                    .map(move |(name, b)| {
                        let name = if several {
                            format!("band{k}/{name}")
                        } else {
                            name
                        };
                        (name, b)
                    })
            })
            .collect()
    }

    /// Puts back what `read_state` read after `iterations` iterations of a render of the same
    /// graph, scene and schedule, so that the next iteration is the one that render would run.
    pub fn restore_state(
        &mut self,
        iterations: u64,
        sections: &[(String, Vec<u8>)],
    ) -> Result<(), Error> {
        let buffers = self.state_buffers();
        let ours: Vec<String> = buffers.iter().map(|(n, _)| n.clone()).collect();
        let theirs: Vec<String> = sections.iter().map(|(n, _)| n.clone()).collect();
        if ours != theirs {
            return Err(Error::Other(format!(
                "the checkpoint holds state [{}] but this graph has [{}]",
                theirs.join(", "),
                ours.join(", ")
            )));
        }
        for ((name, buffer), (_, bytes)) in buffers.iter().zip(sections) {
            if bytes.len() as u64 != buffer.size() {
                return Err(Error::Other(format!(
                    "checkpoint state {name} has {} bytes, this render's {}",
                    bytes.len(),
                    buffer.size()
                )));
            }
            self.gpu.queue.write_buffer(buffer, 0, bytes);
        }
        self.gpu.wait()?;
        self.iteration = iterations;
        // A checkpoint keeps no sample mask: the resumed render samples every pixel until its
        // first estimate, and counts the earlier iterations as if it had.
        self.mean_spp = iterations as f64 * self.spp_per_iteration as f64;
        Ok(())
    }

    /// Records and submits one iteration of every node, in schedule order.
    pub fn iterate(&mut self) -> Result<(), Error> {
        if self.profiling == Profiling::From(self.iteration) {
            self.enable_profiling()?;
        }
        for tile in &mut self.tiles {
            tile.graph
                .iterate(self.gpu, self.schedule, self.iteration, self.seed)?;
            tile.halves.update(self.gpu);
        }
        self.iteration += 1;
        self.mean_spp += self.sampled_share * self.spp_per_iteration as f64;
        Ok(())
    }

    /// Makes `run` estimate the error as it renders (see [`Renderer::latest_error`]).
    pub fn watch_error(&mut self) {
        self.watch_error = true;
    }

    /// The latest error estimate `run` made, when it watched the error.
    pub fn latest_error(&self) -> Option<ErrorReport> {
        self.latest_error
    }

    /// Which scene tables are bound as uniform buffers on this adapter.
    pub fn placement(&self) -> &TablePlacement {
        &self.placement
    }

    /// Nodes removed because the scene had no use for them, with the reason.
    pub fn pruned(&self) -> &[crate::graph::Pruned] {
        &self.pruned
    }

    /// Times every node from now on (see `PreparedGraph::enable_profiling`).
    pub fn enable_profiling(&mut self) -> Result<(), Error> {
        for tile in &mut self.tiles {
            tile.graph.enable_profiling(self.gpu)?;
        }
        self.profiling = Profiling::Since(self.iteration);
        Ok(())
    }

    /// Times every node from local iteration `iteration` on (now, if it has passed): a render
    /// that skips its first iteration, which compiles the pipelines, times what an iteration
    /// costs from then on.
    pub fn profile_from(&mut self, iteration: u64) -> Result<(), Error> {
        if iteration <= self.iteration {
            return self.enable_profiling();
        }
        self.profiling = Profiling::From(iteration);
        Ok(())
    }

    /// Iterations timed so far.
    pub fn profiled_iterations(&self) -> u64 {
        match self.profiling {
            Profiling::Since(start) => self.iteration - start,
            Profiling::Off | Profiling::From(_) => 0,
        }
    }

    /// Per-node times summed since profiling began (over every band), in schedule order.
    pub fn node_times(&self) -> Vec<NodeTime> {
        let mut times: Vec<NodeTime> = Vec::new();
        for tile in &self.tiles {
            let band = tile.graph.node_times();
            if times.is_empty() {
                times = band;
                continue;
            }
            for (total, t) in times.iter_mut().zip(band) {
                total.wall_seconds += t.wall_seconds;
                total.gpu_seconds = total.gpu_seconds.zip(t.gpu_seconds).map(|(a, b)| a + b);
            }
        }
        times
    }

    /// Iterations this render has run.
    pub fn iterations(&self) -> u64 {
        self.iteration
    }

    pub fn schedule(&self) -> Schedule {
        self.schedule
    }

    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Why this graph's renders of disjoint iterations cannot be summed into one image, naming
    /// the node; `None` when they can.
    pub fn shard_refusal(&self) -> Option<(String, &'static str)> {
        self.tiles.first().and_then(|t| t.graph.shard_refusal())
    }

    /// Camera samples per pixel so far: every pixel's, or with adaptive sampling the most
    /// any pixel has.
    pub fn samples_per_pixel(&self) -> u64 {
        self.iteration * self.spp_per_iteration
    }

    /// Light this render cannot reach, said before it starts: a path tracer never samples a
    /// point, spot or directional light through a delta surface (glass, mirror) onto a diffuse
    /// one, so without photons those caustics are black, and the error estimate, built from
    /// the render alone, cannot see them.
    pub fn unsampled_light_warning(&self) -> Option<String> {
        (self.delta_caustics && self.photons_per_iteration == 0).then(|| {
            "warning: the scene has point, spot or directional lights and specular (delta) \
             surfaces, and this graph traces no photons: light from those lights through or off \
             the specular surfaces onto diffuse ones (their caustics) cannot be path traced and \
             is missing from the image, and from its error estimate; a graph with photons \
             (graphs/hybrid.ron) renders it"
                .to_string()
        })
    }

    /// Camera samples per pixel so far, averaged over the image (less than
    /// [`Renderer::samples_per_pixel`] once adaptive sampling stops pixels).
    pub fn mean_samples_per_pixel(&self) -> f64 {
        self.mean_spp
    }

    /// Share of the pixels the camera samples in the next iteration.
    pub fn sampled_share(&self) -> f64 {
        self.sampled_share
    }

    /// Why this render cannot sample adaptively (a node that needs every pixel every
    /// iteration), naming the node.
    pub fn adaptive_refusal(&self) -> Option<String> {
        let first = self.tiles.first()?;
        first.graph.adaptive_refusal().map(|(node, why)| {
            format!(
                "adaptive sampling: {node} cannot skip converged pixels: {why}; it works with \
                 path tracing alone (graphs/pt.ron)"
            )
        })
    }

    /// Stops sampling the pixels whose estimated error (`per_pixel`, the whole image's) is
    /// below `target`, or samples every pixel again (`None`).
    pub fn set_sample_mask(&mut self, per_pixel: Option<(&Image, f64)>) {
        let Some((per_pixel, target)) = per_pixel else {
            for tile in &self.tiles {
                tile.mask.write(self.gpu, None);
            }
            self.sampled_share = 1.0;
            return;
        };
        let flags = crate::render::adaptive::sample_flags(per_pixel, target, self.filter_reach);
        let sampled = flags.iter().filter(|&&f| f & SAMPLED != 0).count();
        if sampled == 0 {
            // Every window below the target while the mean is not (the windows weigh edge
            // pixels differently): sample them all rather than stall.
            return self.set_sample_mask(None);
        }
        let width = self.width as usize;
        for tile in &self.tiles {
            let rows = tile.grid_y as usize..(tile.grid_y + tile.grid_rows) as usize;
            tile.mask
                .write(self.gpu, Some(&flags[rows.start * width..rows.end * width]));
        }
        self.sampled_share = sampled as f64 / flags.len().max(1) as f64;
    }

    pub fn spp_per_iteration(&self) -> u64 {
        self.spp_per_iteration
    }

    /// Photons emitted so far (exact: a u64 on the CPU).
    pub fn photons(&self) -> u64 {
        self.iteration * self.photons_per_iteration
    }

    pub fn photons_per_iteration(&self) -> u64 {
        self.photons_per_iteration
    }

    /// Reads the output slot back and averages it.
    pub fn image(&self) -> Result<Image, Error> {
        let mut sums = self.blank();
        for tile in &self.tiles {
            self.place(tile, &tile.output, &mut sums)?;
        }
        Ok(Image::from_sums(self.width, self.height, &sums))
    }

    /// The estimated error of the image so far (docs/error-estimate.md); `None` before two
    /// iterations.
    pub fn error_estimate(&self) -> Result<Option<ErrorEstimate>, Error> {
        if self.iteration < 2 {
            return Ok(None);
        }
        Ok(self.image_and_error_estimate()?.1)
    }

    /// The image and its estimated error, reading the image back once (the estimate needs it
    /// too).
    pub fn image_and_error_estimate(&self) -> Result<(Image, Option<ErrorEstimate>), Error> {
        let Some(first) = self.tiles.first().filter(|_| self.iteration >= 2) else {
            return Ok((self.image()?, None));
        };
        // Per band, per tracked image: the odd-iteration sums of its rows.
        let band_sums = self
            .tiles
            .iter()
            .map(|tile| tile.halves.odd_sums(self.gpu))
            .collect::<Result<Vec<_>, _>>()?;
        // Per tracked image: the whole image's mean and odd-iteration sums.
        let mut means = Vec::new();
        let mut odd_sums = Vec::new();
        for i in 0..first.tracked.len() {
            let (mut sums, mut odd) = (self.blank(), self.blank());
            for tile in &self.tiles {
                let r = tile.tracked.get(i).ok_or_else(|| {
                    Error::Other("bands track different images for the error estimate".into())
                })?;
                self.place(tile, r, &mut sums)?;
            }
            for (tile, sums) in self.tiles.iter().zip(&band_sums) {
                let grid = sums.get(i).ok_or_else(|| {
                    Error::Other("bands track different images for the error estimate".into())
                })?;
                self.place_rows(tile, grid, &mut odd);
            }
            means.push(Image::from_sums(self.width, self.height, &sums));
            odd_sums.push(odd);
        }
        let halves: Vec<Halves<'_>> = means
            .iter()
            .zip(&odd_sums)
            .map(|(mean, odd_sums)| Halves { mean, odd_sums })
            .collect();
        let estimate = match halves.split_first() {
            Some((image, biases)) => error_estimate::estimate(self.iteration, image, biases),
            None => None,
        };
        drop(halves);
        // The output is tracked first.
        let image = match means.into_iter().next() {
            Some(image) => image,
            None => self.image()?,
        };
        Ok((image, estimate))
    }

    /// Every image slot of the output node, written or read (e.g. `combined`, `pt`,
    /// `caustic`, `radius` of `resolve`), by slot name.
    pub fn aovs(&self) -> Result<Vec<(&'static str, Image)>, Error> {
        let Some(first) = self.tiles.first() else {
            return Ok(Vec::new());
        };
        let mut out = Vec::new();
        for (i, (slot, _)) in first.aovs.iter().enumerate() {
            let mut sums = self.blank();
            for tile in &self.tiles {
                let (_, r) = &tile.aovs[i];
                self.place(tile, r, &mut sums)?;
            }
            out.push((*slot, Image::from_sums(self.width, self.height, &sums)));
        }
        Ok(out)
    }

    /// Counters summed over every node of every band.
    pub fn counters(&self) -> Result<Counters, Error> {
        let mut total = Counters::default();
        for tile in &self.tiles {
            total.add(&tile.graph.counters(self.gpu)?);
        }
        Ok(total)
    }

    /// Global iterations the whole render of `budget` runs (all shards together), when the
    /// budget counts samples or photons; `None` for a time budget alone.
    pub fn total_iterations(&self, budget: Budget) -> Option<u64> {
        let spp_iterations = budget
            .spp
            .map(|spp| spp.div_ceil(self.spp_per_iteration.max(1)));
        let photon_iterations = budget
            .photons
            .filter(|_| self.photons_per_iteration > 0)
            .map(|n| n.div_ceil(self.photons_per_iteration.max(1)));
        match (spp_iterations, photon_iterations) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Iterates until `budget` is met or `cancel` is raised, calling `progress` after each
    /// iteration with the seconds elapsed.
    pub fn run(
        &mut self,
        budget: Budget,
        cancel: &AtomicBool,
        mut progress: impl FnMut(&Self, f64),
    ) -> Result<RunSummary, Error> {
        budget.check()?;
        if budget.photons.is_some()
            && self.photons_per_iteration == 0
            && budget.spp.is_none()
            && budget.seconds.is_none()
        {
            return Err(Error::Other(
                "a photon budget: this graph emits no photons (for this scene, after pruning), \
                 so it would never be met; give a budget of samples or seconds"
                    .into(),
            ));
        }
        let start = Instant::now();
        // Budgets count the iterations of the whole render; this one runs its share of them.
        let target_iterations = self
            .total_iterations(budget)
            .map(|total| self.schedule.local_count(total));
        if budget.adaptive
            && let Some(why) = self.adaptive_refusal()
        {
            return Err(Error::Other(why));
        }
        let watching = self.watch_error || budget.target_error.is_some();
        let mut next_estimate = 0.0;
        let stop = loop {
            let elapsed = start.elapsed().as_secs_f64();
            if cancel.load(Ordering::Relaxed) {
                break Stop::Cancelled;
            }
            if target_iterations.is_some_and(|t| self.iteration >= t) {
                break Stop::Count;
            }
            if budget.seconds.is_some_and(|s| elapsed >= s) {
                break Stop::Time;
            }
            if let (Some(target), Some(latest)) = (budget.target_error, self.latest_error)
                && latest.iterations >= MIN_ITERATIONS_FOR_TARGET
                && latest.relmse < target
            {
                break Stop::TargetError;
            }
            self.iterate()?;
            // Waiting each iteration keeps the queue short, so the time budget and Ctrl-C are
            // honoured within one iteration.
            self.gpu.wait()?;
            let elapsed = start.elapsed().as_secs_f64();
            if watching && elapsed >= next_estimate {
                // Reading the halves back costs about one small iteration: at most every
                // half second and a tenth of the time so far, so it adds a few percent.
                if let Some(e) = self.error_estimate()? {
                    self.latest_error = Some(ErrorReport {
                        seconds: elapsed,
                        iterations: self.iteration,
                        relmse: e.relmse,
                        variance: e.variance,
                        bias: e.bias,
                    });
                    if let Some(target) = budget.target_error
                        && budget.adaptive
                        && self.iteration >= MIN_ITERATIONS_FOR_TARGET
                    {
                        self.set_sample_mask(Some((&e.per_pixel, target)));
                    }
                }
                let spent = start.elapsed().as_secs_f64();
                next_estimate = spent + (0.1 * spent).max(0.5);
            }
            progress(self, start.elapsed().as_secs_f64());
        };
        Ok(RunSummary {
            seconds: start.elapsed().as_secs_f64(),
            iterations: self.iteration,
            samples_per_pixel: self.samples_per_pixel(),
            photons: self.photons(),
            cancelled: stop == Stop::Cancelled,
            stop,
        })
    }
}

/// Refuses, before the other bands are allocated, an image whose bands together need more
/// memory than the machine has free, where the adapter's memory is the machine's (a CPU
/// adapter: lavapipe), naming what it needs and what would fit. GPUs do not report their
/// memory through wgpu; there an allocation that fails names its buffer.
fn check_memory(
    gpu: &GpuContext,
    first: &Tile,
    table_bytes: u64,
    bands: u32,
    (width, height): (u32, u32),
) -> Result<(), Error> {
    if gpu.info.device_type != wgpu::DeviceType::Cpu {
        return Ok(());
    }
    let Some(available) = available_memory() else {
        return Ok(());
    };
    let (per_band, shared) = first.graph.allocated_bytes();
    let needed = per_band.saturating_mul(bands as u64) + shared + table_bytes;
    if needed <= available {
        return Ok(());
    }
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    // Pixel buffers dominate: scale both sides by the share that fits.
    let share = (available as f64 / needed as f64).sqrt();
    Err(Error::Other(format!(
        "a {width}x{height} image with this graph needs about {:.1} GiB of buffers ({bands} \
         bands of {:.2} GiB), but {:.1} GiB of memory is free on this machine (the adapter, {}, \
         keeps its buffers there); about {}x{} would fit",
        gib(needed),
        gib(per_band),
        gib(available),
        gpu.adapter_label(),
        (width as f64 * share) as u32,
        (height as f64 * share) as u32,
    )))
}

/// `MemAvailable` of /proc/meminfo, in bytes; `None` where there is none.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The images whose halves the error estimate needs, named for checkpoints: the graph's
/// output, then each estimator's kernel bias.
fn tracked_images(graph: &PreparedGraph) -> Result<Vec<(String, Resource)>, Error> {
    let mut tracked = vec![("output".to_string(), graph.output()?.clone())];
    for (index, node) in graph.graph().nodes.iter().enumerate() {
        if let Some(r) = graph.resource(index, KERNEL_BIAS) {
            tracked.push((format!("{}.{KERNEL_BIAS}", node.name), r.clone()));
        }
    }
    Ok(tracked)
}

/// Every image slot of the graph's output node, written or read, by slot name.
fn image_aovs(graph: &PreparedGraph) -> Vec<(&'static str, Resource)> {
    let out_node = graph.graph().output.0;
    let kind = graph.graph().nodes[out_node].kind;
    let mut aovs: Vec<(&'static str, Resource)> = kind
        .slots
        .iter()
        .filter(|slot| slot.kind == IMAGE)
        .filter_map(|slot| {
            graph
                .resource(out_node, slot.name)
                .or_else(|| graph.input(out_node, slot.name))
                .map(|r| (slot.name, r.clone()))
        })
        .collect();
    aovs.sort_by_key(|(slot, _)| *slot);
    aovs
}

/// FNV-1a over the uploaded scene (uniform and tables), so a shard or checkpoint made from
/// another scene, or at another size, is recognised whatever its file is called.
fn scene_fingerprint(scene: &GpuScene) -> u64 {
    use bytemuck::{bytes_of, cast_slice};
    let parts: [&[u8]; 11] = [
        bytes_of(&scene.uniform),
        cast_slice(&scene.bvh_nodes),
        cast_slice(&scene.prim_indices),
        cast_slice(&scene.triangles),
        cast_slice(&scene.triangle_normals),
        cast_slice(&scene.triangle_uvs),
        cast_slice(&scene.spheres),
        cast_slice(&scene.materials),
        cast_slice(&scene.lights),
        cast_slice(&scene.light_cdf),
        cast_slice(&scene.bsdf_tables),
    ];
    let mut hash = crate::render::fingerprint::Fnv::default();
    // Textures only when there are some, so untextured scenes keep their fingerprints.
    let textures: &[u8] = cast_slice(&scene.textures);
    let textured = (!textures.is_empty()).then_some(textures);
    for part in parts.into_iter().chain(textured) {
        hash.write(&(part.len() as u64).to_le_bytes());
        hash.write(part);
    }
    hash.finish()
}

#[derive(Debug, Clone, Copy)]
pub struct RunSummary {
    pub seconds: f64,
    pub iterations: u64,
    pub samples_per_pixel: u64,
    pub photons: u64,
    pub cancelled: bool,
    pub stop: Stop,
}
