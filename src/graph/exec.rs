//! Running a validated graph: allocate every output from its slot's size rule, prepare the nodes
//! in schedule order (each input wired to the resource its producer's slot holds), then record
//! iterations. Persistent outputs are zeroed once; the others before every iteration.

use std::collections::{HashMap, HashSet};
use std::time::Instant;

use super::ValidGraph;
use super::pass::{
    Counters, ExecCtx, Pass, PassKind, PrepareCtx, Recorder, Resource, Schedule, Shared, Size,
    SlotDir,
};
use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::shaders::ShaderLibrary;
use crate::gpu::timer::NodeTimer;

/// Per-node time summed over the profiled iterations.
#[derive(Debug, Clone)]
pub struct NodeTime {
    pub name: String,
    pub kind: &'static str,
    /// CPU wall clock from the node's start until the GPU finished its work.
    pub wall_seconds: f64,
    /// GPU clock between timestamps before and after the node's commands, where the adapter
    /// writes timestamps inside encoders. A node that waits on the CPU (the SAH builder) counts
    /// that wait too.
    pub gpu_seconds: Option<f64>,
}

struct Profile {
    timer: Option<NodeTimer>,
    wall_seconds: Vec<f64>,
    gpu_seconds: Vec<f64>,
}

/// A graph whose resources are allocated and whose nodes are prepared on one device.
pub struct PreparedGraph {
    graph: ValidGraph,
    /// Every output slot's resource, by (node, slot).
    resources: HashMap<(usize, &'static str), Resource>,
    /// Outputs the graph zeroes before each iteration (those not declared persistent).
    cleared: Vec<Resource>,
    profile: Option<Profile>,
    /// Nodes another graph runs for this one (a band's [`band_shared_nodes`], run by the first
    /// band): never prepared or run here, their outputs that graph's resources.
    borrowed: HashSet<usize>,
}

/// The part of the image a graph renders: its pixel grid, the whole image's pixel count, and
/// for a band after the first, the first band's graph, whose nodes that do not follow the pixels
/// it borrows ([`band_shared_nodes`]).
#[derive(Clone, Copy)]
pub struct Band<'a> {
    pub size: (u32, u32),
    pub film_pixels: u64,
    pub lender: Option<&'a PreparedGraph>,
}

/// Nodes whose outputs are the same for every band of an image: passes that do not follow the
/// pixel grid ([`Pass::follows_pixels`]), with no pixel-sized output and inputs only from such
/// nodes. An image rendered in bands runs them once, in the first band.
pub fn band_shared_nodes(graph: &ValidGraph) -> HashSet<usize> {
    let mut shared = HashSet::new();
    for &n in &graph.order {
        let node = &graph.nodes[n];
        let pixel_sized = node
            .kind
            .slots
            .iter()
            .any(|s| s.dir == SlotDir::Out && s.size == Size::Pixels);
        let inputs_shared = graph.inputs_of(n).all(|e| shared.contains(&e.from_node));
        if !node.pass.follows_pixels() && !pixel_sized && inputs_shared {
            shared.insert(n);
        }
    }
    shared
}

/// Outputs of `node` that some consumer keeps ([`super::pass::SlotDecl::kept`]).
fn kept_outputs(graph: &ValidGraph, node: usize) -> HashSet<&'static str> {
    graph
        .edges
        .iter()
        .filter(|e| e.from_node == node)
        .filter(|e| {
            graph.nodes[e.to_node]
                .kind
                .slot(e.to_slot)
                .is_some_and(|s| s.kept)
        })
        .map(|e| e.from_slot)
        .collect()
}

/// Every output of a pass, allocated by its slot's size rule; the non-persistent ones are also
/// added to `cleared`, which the graph zeroes before every iteration.
fn allocate_outputs(
    ctx: &PrepareCtx<'_>,
    kind: &PassKind,
    label: &str,
    pass: &dyn Pass,
    cleared: &mut Vec<Resource>,
) -> Result<HashMap<&'static str, Resource>, Error> {
    let mut outputs = HashMap::new();
    for slot in kind.slots.iter().filter(|s| s.dir == SlotDir::Out) {
        let len = match slot.size {
            Size::Pixels => ctx.pixels(),
            Size::LikeInput(input) => ctx.input(input)?.len,
            Size::Computed => pass.output_len(slot.name, ctx)?,
        };
        let label = format!("{label}.{}", slot.name);
        let resource = Resource::allocate(ctx.gpu, &label, slot.kind, len)?;
        if !slot.persistent {
            cleared.push(resource.clone());
        }
        outputs.insert(slot.name, resource);
    }
    Ok(outputs)
}

/// A recorder for one iteration that starts by zeroing the non-persistent outputs.
fn begin_iteration<'a>(gpu: &'a GpuContext, cleared: &[Resource]) -> Recorder<'a> {
    let mut recorder = Recorder::new(gpu);
    for resource in cleared {
        recorder.encoder().clear_buffer(&resource.buffer, 0, None);
    }
    recorder
}

/// A node's error, placed at the node in its graph file.
fn in_node(node: &super::ValidNode, error: Error) -> Error {
    Error::InNode {
        place: format!(
            "{}: node \"{}\" ({})",
            node.location, node.name, node.kind.name
        ),
        source: Box::new(error),
    }
}

impl PreparedGraph {
    pub fn new(
        gpu: &GpuContext,
        shaders: &ShaderLibrary,
        shared: &Shared,
        mut graph: ValidGraph,
        band: Band<'_>,
        first_iteration: u64,
    ) -> Result<Self, Error> {
        let Band {
            size: (width, height),
            film_pixels,
            lender,
        } = band;
        let order = graph.order.clone();
        // A later band borrows the first band's photon nodes and their outputs.
        let borrowed = match lender {
            Some(_) => band_shared_nodes(&graph),
            None => HashSet::new(),
        };
        let context = |graph: &ValidGraph,
                       node: usize,
                       resources: &HashMap<(usize, &'static str), Resource>| {
            let inputs: HashMap<&'static str, Resource> = graph
                .inputs_of(node)
                .filter_map(|e| {
                    resources
                        .get(&(e.from_node, e.from_slot))
                        .map(|r| (e.to_slot, r.clone()))
                })
                .collect();
            let consumed = graph.consumed(node);
            let kept_inputs = graph
                .inputs_of(node)
                .filter(|e| kept_outputs(graph, e.from_node).contains(e.from_slot))
                .map(|e| e.to_slot)
                .collect();
            PrepareCtx {
                gpu,
                shaders,
                shared,
                inputs,
                outputs: HashMap::new(),
                consumed,
                kept: kept_outputs(graph, node),
                kept_inputs,
                width,
                height,
                film_pixels,
                first_iteration,
            }
        };
        // Outputs first, all of them: an input that reads the previous iteration is wired to
        // a node scheduled after its consumer.
        let mut resources = HashMap::new();
        let mut cleared = Vec::new();
        for &node in &order {
            if let Some(lender) = lender.filter(|_| borrowed.contains(&node)) {
                for ((n, slot), resource) in &lender.resources {
                    if *n == node {
                        resources.insert((node, *slot), resource.clone());
                    }
                }
                continue;
            }
            let ctx = context(&graph, node, &resources);
            let valid = &graph.nodes[node];
            let outputs =
                allocate_outputs(&ctx, valid.kind, &valid.name, &*valid.pass, &mut cleared)
                    .map_err(|e| in_node(valid, e))?;
            for (slot, resource) in outputs {
                resources.insert((node, slot), resource);
            }
        }
        for &node in order.iter().filter(|n| !borrowed.contains(n)) {
            let mut ctx = context(&graph, node, &resources);
            ctx.outputs = resources
                .iter()
                .filter(|((n, _), _)| *n == node)
                .map(|((_, slot), r)| (*slot, r.clone()))
                .collect();
            let valid = &mut graph.nodes[node];
            let prepared = valid.pass.prepare(ctx);
            prepared.map_err(|e| in_node(valid, e))?;
        }
        gpu.check_errors()?;
        Ok(Self {
            graph,
            resources,
            cleared,
            profile: None,
            borrowed,
        })
    }

    pub fn graph(&self) -> &ValidGraph {
        &self.graph
    }

    /// Bytes of the output buffers the graph allocated (pass-internal buffers not counted), as
    /// (those a later band would allocate again, those it would borrow from this one).
    pub fn allocated_bytes(&self) -> (u64, u64) {
        let shared = band_shared_nodes(&self.graph);
        let mut bytes = (0, 0);
        for ((node, _), r) in &self.resources {
            if self.borrowed.contains(node) {
                continue;
            }
            match shared.contains(node) {
                true => bytes.1 += r.buffer.size(),
                false => bytes.0 += r.buffer.size(),
            }
        }
        bytes
    }

    /// The resource of output `slot` of `node`.
    pub fn resource(&self, node: usize, slot: &'static str) -> Option<&Resource> {
        self.resources.get(&(node, slot))
    }

    /// The resource the graph's output slot holds.
    pub fn output(&self) -> Result<&Resource, Error> {
        let (node, slot) = self.graph.output;
        self.resource(node, slot).ok_or_else(|| {
            Error::Other(format!(
                "node \"{}\" has no output slot \"{slot}\"",
                self.graph.nodes[node].name
            ))
        })
    }

    /// The resource connected to input `slot` of `node`, if any.
    pub fn input(&self, node: usize, slot: &str) -> Option<&Resource> {
        self.graph
            .inputs_of(node)
            .find(|e| e.to_slot == slot)
            .and_then(|e| self.resource(e.from_node, e.from_slot))
    }

    /// Records and submits the `local`-th iteration (0-based) of `schedule`, every node in
    /// schedule order.
    pub fn iterate(
        &mut self,
        gpu: &GpuContext,
        schedule: Schedule,
        local: u64,
        seed: u64,
    ) -> Result<(), Error> {
        let mut recorder = begin_iteration(gpu, &self.cleared);
        let ctx = ExecCtx {
            gpu,
            iteration: schedule.global(local),
            next_iteration: schedule.global(local + 1),
            first: local == 0,
            seed,
        };
        for &node in &self.graph.order {
            if self.borrowed.contains(&node) {
                continue;
            }
            let start = Instant::now();
            let timer = self.profile.as_ref().and_then(|p| p.timer.as_ref());
            if let Some(timer) = timer {
                timer.begin(recorder.encoder(), node);
            }
            self.graph.nodes[node].pass.execute(&ctx, &mut recorder)?;
            if let Some(timer) = timer {
                timer.end(recorder.encoder(), node);
            }
            if let Some(profile) = &mut self.profile {
                // Each node's work is submitted and waited for on its own: wall time per node,
                // at the cost of the overlap a real render has.
                recorder.flush()?;
                profile.wall_seconds[node] += start.elapsed().as_secs_f64();
            }
        }
        if let Some(profile) = &mut self.profile
            && let Some(timer) = &profile.timer
        {
            timer.resolve(recorder.encoder());
            recorder.flush()?;
            let seconds = timer.read(gpu)?;
            for &node in &self.graph.order {
                profile.gpu_seconds[node] += seconds[node];
            }
        }
        recorder.submit();
        Ok(())
    }

    /// Times every node from now on: GPU time from timestamp queries where the adapter can
    /// write them inside encoders, and CPU wall time (each node waited for on its own) always.
    /// Profiling serialises the nodes, so an iteration is slower than without it.
    pub fn enable_profiling(&mut self, gpu: &GpuContext) -> Result<(), Error> {
        let nodes = self.graph.nodes.len();
        self.profile = Some(Profile {
            timer: NodeTimer::new(gpu, nodes)?,
            wall_seconds: vec![0.0; nodes],
            gpu_seconds: vec![0.0; nodes],
        });
        Ok(())
    }

    /// Per-node times summed since profiling began, in schedule order.
    pub fn node_times(&self) -> Vec<NodeTime> {
        let Some(profile) = &self.profile else {
            return Vec::new();
        };
        self.graph
            .order
            .iter()
            .map(|&n| {
                let node = &self.graph.nodes[n];
                NodeTime {
                    name: node.name.clone(),
                    kind: node.kind.name,
                    wall_seconds: profile.wall_seconds[n],
                    gpu_seconds: profile.timer.as_ref().map(|_| profile.gpu_seconds[n]),
                }
            })
            .collect()
    }

    /// Camera samples per pixel one iteration adds (the most any node adds).
    pub fn spp_per_iteration(&self) -> u64 {
        self.graph
            .nodes
            .iter()
            .map(|n| n.pass.samples_per_iteration() as u64)
            .max()
            .unwrap_or(0)
    }

    /// Photons one iteration emits, over every node.
    pub fn photons_per_iteration(&self) -> u64 {
        self.graph
            .nodes
            .iter()
            .map(|n| n.pass.photons_per_iteration())
            .sum()
    }

    /// What a checkpoint saves, in schedule order: every persistent output (named
    /// `node.slot`) and every pass's own state (`node#name`).
    pub fn state_buffers(&self) -> Vec<(String, &wgpu::Buffer)> {
        let mut out = Vec::new();
        for &n in self
            .graph
            .order
            .iter()
            .filter(|n| !self.borrowed.contains(n))
        {
            let node = &self.graph.nodes[n];
            let persistent = node
                .kind
                .slots
                .iter()
                .filter(|s| s.dir == SlotDir::Out && s.persistent);
            for slot in persistent {
                if let Some(r) = self.resources.get(&(n, slot.name)) {
                    out.push((format!("{}.{}", node.name, slot.name), &*r.buffer));
                }
            }
            for (name, buffer) in node.pass.state() {
                out.push((format!("{}#{name}", node.name), buffer));
            }
        }
        out
    }

    /// The accumulators whose per-pixel means add up to the output image (resolve's `pt` and
    /// `caustic` inputs, or the output itself), named `node.slot` after their producers. An
    /// error when one is not an accumulator (a persistent sum and count): such an output
    /// cannot be summed over renders.
    pub fn output_terms(&self) -> Result<Vec<(String, Resource)>, Error> {
        let (out_node, out_slot) = self.graph.output;
        let producers: Vec<(usize, &'static str)> =
            match self.graph.nodes[out_node].pass.output_terms(out_slot) {
                Some(inputs) => inputs
                    .iter()
                    .filter_map(|input| {
                        self.graph
                            .inputs_of(out_node)
                            .find(|e| e.to_slot == *input)
                            .map(|e| (e.from_node, e.from_slot))
                    })
                    .collect(),
                None => vec![(out_node, out_slot)],
            };
        producers
            .into_iter()
            .map(|(node, slot)| {
                let valid = &self.graph.nodes[node];
                let name = format!("{}.{slot}", valid.name);
                let persistent = valid.kind.slot(slot).is_some_and(|s| s.persistent);
                let resource = self.resource(node, slot).filter(|_| persistent);
                resource.map(|r| (name.clone(), r.clone())).ok_or_else(|| {
                    Error::Other(format!(
                        "{name} ({}) is not an accumulator of sums and counts",
                        valid.kind.name
                    ))
                })
            })
            .collect()
    }

    /// The first reason a node gives why renders of disjoint iterations cannot be summed.
    pub fn shard_refusal(&self) -> Option<(String, &'static str)> {
        self.graph.nodes.iter().find_map(|n| {
            n.pass
                .shard_refusal()
                .map(|why| (format!("node \"{}\" ({})", n.name, n.kind.name), why))
        })
    }

    /// The first reason a node gives why it cannot follow an adaptive sample mask.
    pub fn adaptive_refusal(&self) -> Option<(String, &'static str)> {
        self.graph.nodes.iter().find_map(|n| {
            n.pass
                .adaptive_refusal()
                .map(|why| (format!("node \"{}\" ({})", n.name, n.kind.name), why))
        })
    }

    /// Counters summed over every node.
    pub fn counters(&self, gpu: &GpuContext) -> Result<Counters, Error> {
        let mut total = Counters::default();
        for (n, node) in self.graph.nodes.iter().enumerate() {
            if !self.borrowed.contains(&n) {
                total.add(&node.pass.counters(gpu)?);
            }
        }
        Ok(total)
    }
}

/// How a pass run alone is wired: which of its outputs count as consumed and kept, and which
/// inputs come kept from their producer (what a graph would tell it).
#[derive(Debug, Clone, Default)]
pub struct Wiring {
    pub consumed: Vec<&'static str>,
    pub kept: Vec<&'static str>,
    pub kept_inputs: Vec<&'static str>,
    /// The global iteration the pass will first run (`PrepareCtx::first_iteration`).
    pub first_iteration: u64,
}

/// A pass prepared alone: its outputs, allocated as a graph would.
pub struct Standalone {
    pub outputs: HashMap<&'static str, Resource>,
    cleared: Vec<Resource>,
    first_iteration: u64,
}

impl Standalone {
    /// Allocates the outputs of `pass` (of `kind`) by its slots' rules and prepares it with
    /// `inputs`, as one node of a graph at `width` x `height` would be. For pass tests and
    /// benchmarks.
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(
        gpu: &GpuContext,
        shaders: &ShaderLibrary,
        shared: &Shared,
        size: (u32, u32),
        kind: &PassKind,
        pass: &mut dyn Pass,
        inputs: &[(&'static str, &Resource)],
        wiring: &Wiring,
    ) -> Result<Self, Error> {
        let mut ctx = PrepareCtx {
            gpu,
            shaders,
            shared,
            inputs: inputs.iter().map(|(s, r)| (*s, (*r).clone())).collect(),
            outputs: HashMap::new(),
            consumed: wiring.consumed.iter().copied().collect(),
            kept: wiring.kept.iter().copied().collect(),
            kept_inputs: wiring.kept_inputs.iter().copied().collect(),
            width: size.0,
            height: size.1,
            film_pixels: size.0 as u64 * size.1 as u64,
            first_iteration: wiring.first_iteration,
        };
        let mut cleared = Vec::new();
        let outputs = allocate_outputs(&ctx, kind, kind.name, pass, &mut cleared)?;
        ctx.outputs = outputs.clone();
        pass.prepare(ctx)?;
        gpu.check_errors()?;
        Ok(Self {
            outputs,
            cleared,
            first_iteration: wiring.first_iteration,
        })
    }

    /// The output `slot` (allocated for every output slot of the kind).
    pub fn output(&self, slot: &str) -> Result<&Resource, Error> {
        self.outputs
            .get(slot)
            .ok_or_else(|| Error::Other(format!("no output slot \"{slot}\"")))
    }

    /// Records global iteration `iteration` of `pass` after zeroing its non-persistent
    /// outputs, as a graph with consecutive iterations does, submits it and waits.
    pub fn run(
        &self,
        gpu: &GpuContext,
        pass: &mut dyn Pass,
        iteration: u64,
        seed: u64,
    ) -> Result<(), Error> {
        let mut recorder = begin_iteration(gpu, &self.cleared);
        let ctx = ExecCtx {
            gpu,
            iteration,
            next_iteration: iteration + 1,
            first: iteration == self.first_iteration,
            seed,
        };
        pass.execute(&ctx, &mut recorder)?;
        recorder.flush()
    }
}
