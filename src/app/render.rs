//! Renders a validated graph over a scene: prunes what the scene does not need, uploads the
//! scene and shares it with the passes, prepares the graph, then runs iterations until a budget
//! is met.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::Error;
use crate::gpu::GpuContext;
use crate::graph::ValidGraph;
use crate::graph::exec::PreparedGraph;
use crate::graph::pass::{Counters, IMAGE, Resource, Schedule, Shared};
use crate::image::Image;
use crate::passes::{SceneResources, TablePlacement, paths, scene_meets, shader_library};
use crate::scene::Scene;
use crate::scene::gpu_layout::GpuScene;

pub use crate::graph::exec::NodeTime;

/// When to stop rendering. With several set, whichever comes first.
#[derive(Debug, Clone, Copy, Default)]
pub struct Budget {
    pub spp: Option<u64>,
    pub seconds: Option<f64>,
    /// Photons emitted in total.
    pub photons: Option<u64>,
}

impl Budget {
    /// Refuses a budget that would render nothing or never end, before any work.
    pub fn check(&self) -> Result<(), Error> {
        let refuse = |m: String| Err(Error::Other(m));
        if self.spp == Some(0) {
            return refuse("--spp must be at least 1".into());
        }
        if self.photons == Some(0) {
            return refuse("--photons must be at least 1".into());
        }
        if let Some(s) = self.seconds
            && !(s.is_finite() && s > 0.0)
        {
            return refuse(format!(
                "--time must be a positive, finite number of seconds, got {s}"
            ));
        }
        if self.spp.is_none() && self.seconds.is_none() && self.photons.is_none() {
            return refuse("no budget: give --spp, --time or --photons".into());
        }
        Ok(())
    }
}

/// A graph prepared on a device for one scene, ready to iterate.
pub struct Renderer<'a> {
    gpu: &'a GpuContext,
    graph: PreparedGraph,
    output: Resource,
    /// Every image output of the output node and every image it reads (its AOVs), by slot.
    aovs: Vec<(&'static str, Resource)>,
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
        mut graph: ValidGraph,
        width: u32,
        height: u32,
        seed: u64,
        schedule: Schedule,
    ) -> Result<Self, Error> {
        if schedule.stride == 0 {
            return Err(Error::Other(
                "a schedule's stride must be at least 1".into(),
            ));
        }
        // The loaders refuse these already; a scene made or scaled in code must not render black
        // without a word either.
        scene.check_extent()?;
        let features = scene.features();
        let pruned = graph.prune(|need| scene_meets(&features, need))?;
        graph.check_transport(&paths::CLASSES)?;
        let gpu_scene = GpuScene::new(scene, width, height);
        let resources = SceneResources::for_adapter(gpu, &gpu_scene)?;
        let placement = resources.placement.clone();
        let shaders = shader_library(gpu.has_float_atomics(), scene, &placement)?;
        let mut shared = Shared::default();
        let scene_hash = scene_fingerprint(&gpu_scene);
        shared.insert(resources);
        let graph =
            PreparedGraph::new(gpu, &shaders, &shared, graph, width, height, schedule.first)?;
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
        let output = graph.output()?.clone();
        let spp_per_iteration = graph.spp_per_iteration();
        let photons_per_iteration = graph.photons_per_iteration();
        Ok(Self {
            gpu,
            graph,
            output,
            aovs,
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
        })
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
    pub fn read_terms(&self) -> Result<Vec<crate::app::state::Term>, Error> {
        self.graph
            .output_terms()?
            .into_iter()
            .map(|(name, r)| Ok((name, self.gpu.read_pod(&r.buffer, r.len as usize)?)))
            .collect()
    }

    /// Every buffer whose contents carry between iterations, read back whole, by name (what a
    /// checkpoint holds, besides the iteration count).
    pub fn read_state(&self) -> Result<Vec<(String, Vec<u8>)>, Error> {
        self.gpu.wait()?;
        self.graph
            .state_buffers()
            .into_iter()
            .map(|(name, buffer)| Ok((name, self.gpu.read_buffer(buffer, 0, buffer.size())?)))
            .collect()
    }

    /// Puts back what `read_state` read after `iterations` iterations of a render of the same
    /// graph, scene and schedule, so that the next iteration is the one that render would run.
    pub fn restore_state(
        &mut self,
        iterations: u64,
        sections: &[(String, Vec<u8>)],
    ) -> Result<(), Error> {
        let buffers = self.graph.state_buffers();
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
        Ok(())
    }

    /// Records and submits one iteration of every node, in schedule order.
    pub fn iterate(&mut self) -> Result<(), Error> {
        self.graph
            .iterate(self.gpu, self.schedule, self.iteration, self.seed)?;
        self.iteration += 1;
        Ok(())
    }

    /// Nodes removed because the scene had no use for them, with the reason.
    /// Which scene tables are bound as uniform buffers on this adapter.
    pub fn placement(&self) -> &TablePlacement {
        &self.placement
    }

    pub fn pruned(&self) -> &[crate::graph::Pruned] {
        &self.pruned
    }

    /// Times every node from now on (see `PreparedGraph::enable_profiling`).
    pub fn enable_profiling(&mut self) -> Result<(), Error> {
        self.graph.enable_profiling(self.gpu)
    }

    /// Per-node times summed since profiling began, in schedule order.
    pub fn node_times(&self) -> Vec<NodeTime> {
        self.graph.node_times()
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
        self.graph.shard_refusal()
    }

    pub fn samples_per_pixel(&self) -> u64 {
        self.iteration * self.spp_per_iteration
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
        self.read_radiance(&self.output)
    }

    /// Every image slot of the output node, written or read (e.g. `combined`, `pt`,
    /// `caustic`, `radius` of `resolve`), by slot name.
    pub fn aovs(&self) -> Result<Vec<(&'static str, Image)>, Error> {
        self.aovs
            .iter()
            .map(|(slot, r)| Ok((*slot, self.read_radiance(r)?)))
            .collect()
    }

    fn read_radiance(&self, resource: &Resource) -> Result<Image, Error> {
        let sums: Vec<[f32; 4]> = self.gpu.read_pod(&resource.buffer, resource.len as usize)?;
        Ok(Image::from_sums(self.width, self.height, &sums))
    }

    /// Counters summed over every node.
    pub fn counters(&self) -> Result<Counters, Error> {
        self.graph.counters(self.gpu)
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
                "--photons: this graph emits no photons (for this scene, after pruning), so a \
                 photon budget would never be met; give --spp or --time"
                    .into(),
            ));
        }
        let start = Instant::now();
        // Budgets count the iterations of the whole render; this one runs its share of them.
        let target_iterations = self
            .total_iterations(budget)
            .map(|total| self.schedule.local_count(total));
        loop {
            let elapsed = start.elapsed().as_secs_f64();
            let spp_done = target_iterations.is_some_and(|t| self.iteration >= t);
            let time_done = budget.seconds.is_some_and(|s| elapsed >= s);
            if spp_done || time_done || cancel.load(Ordering::Relaxed) {
                break;
            }
            self.iterate()?;
            // Waiting each iteration keeps the queue short, so the time budget and Ctrl-C are
            // honoured within one iteration.
            self.gpu.wait()?;
            progress(self, start.elapsed().as_secs_f64());
        }
        Ok(RunSummary {
            seconds: start.elapsed().as_secs_f64(),
            iterations: self.iteration,
            samples_per_pixel: self.samples_per_pixel(),
            photons: self.photons(),
            cancelled: cancel.load(Ordering::Relaxed),
        })
    }
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
    let mut hash = crate::app::state::Fnv::default();
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
}
