//! Drives a validated graph over a scene: uploads the scene, prepares every node in schedule
//! order (wiring each input to the resource its producer made), then runs iterations until a
//! budget is met.

use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::timer::NodeTimer;
use crate::graph::ValidGraph;
use crate::graph::pass::{ExecCtx, PassStats, PrepareCtx, Recorder, Resource, ResourceKind};
use crate::image::Image;
use crate::scene::Scene;
use crate::scene::gpu_layout::{GpuScene, GpuSceneUniform};
use crate::shaders::ShaderLibrary;

/// The scene on the GPU: bind group 0 of every pass.
pub struct SceneResources {
    pub layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
    pub uniform: GpuSceneUniform,
    _buffers: Vec<wgpu::Buffer>,
}

impl SceneResources {
    pub fn upload(gpu: &GpuContext, scene: &GpuScene) -> Result<Self, Error> {
        use bytemuck::{bytes_of, cast_slice};
        let storage = wgpu::BufferUsages::STORAGE;
        let buffers = vec![
            gpu.create_buffer_init(
                "scene uniform",
                bytes_of(&scene.uniform),
                wgpu::BufferUsages::UNIFORM,
            )?,
            gpu.create_buffer_init("scene bvh nodes", cast_slice(&scene.bvh_nodes), storage)?,
            gpu.create_buffer_init(
                "scene prim indices",
                cast_slice(&scene.prim_indices),
                storage,
            )?,
            gpu.create_buffer_init("scene triangles", cast_slice(&scene.triangles), storage)?,
            gpu.create_buffer_init("scene spheres", cast_slice(&scene.spheres), storage)?,
            gpu.create_buffer_init("scene materials", cast_slice(&scene.materials), storage)?,
            gpu.create_buffer_init("scene lights", cast_slice(&scene.lights), storage)?,
            gpu.create_buffer_init("scene light cdf", cast_slice(&scene.light_cdf), storage)?,
        ];
        let entries: Vec<_> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| {
                (
                    if i == 0 {
                        Access::Uniform
                    } else {
                        Access::Read
                    },
                    b,
                )
            })
            .collect();
        let (layout, bind_group) = bind_buffers(&gpu.device, "scene", &entries);
        Ok(Self {
            layout,
            bind_group,
            uniform: scene.uniform,
            _buffers: buffers,
        })
    }
}

/// When to stop rendering. With several set, whichever comes first.
#[derive(Debug, Clone, Copy, Default)]
pub struct Budget {
    pub spp: Option<u64>,
    pub seconds: Option<f64>,
    /// Photons emitted in total.
    pub photons: Option<u64>,
}

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

/// A graph prepared on a device for one scene, ready to iterate.
pub struct Renderer<'a> {
    gpu: &'a GpuContext,
    scene: SceneResources,
    graph: ValidGraph,
    output: Resource,
    /// Every `Radiance` output of the output node (its AOVs), by slot name.
    aovs: Vec<(&'static str, Resource)>,
    width: u32,
    height: u32,
    seed: u64,
    iteration: u64,
    spp_per_iteration: u64,
    photons_per_iteration: u64,
    /// Per-node timers when profiling; `None` otherwise.
    profile: Option<Profile>,
    /// Nodes the scene had no use for, removed before preparing.
    pruned: Vec<crate::graph::Pruned>,
}

impl<'a> Renderer<'a> {
    pub fn new(
        gpu: &'a GpuContext,
        scene: &Scene,
        mut graph: ValidGraph,
        width: u32,
        height: u32,
        seed: u64,
    ) -> Result<Self, Error> {
        let shaders =
            ShaderLibrary::new(gpu.has_float_atomics(), crate::shaders::scene_defs(scene));
        let features = scene.features();
        let pruned = graph.prune(|need| features.meets(need))?;
        let scene_resources = SceneResources::upload(gpu, &GpuScene::new(scene, width, height))?;
        let mut produced: HashMap<(usize, &'static str), Resource> = HashMap::new();
        let order = graph.order.clone();
        for &node in &order {
            let inputs = graph
                .inputs_of(node)
                .filter_map(|e| {
                    produced
                        .get(&(e.from_node, e.from_slot))
                        .map(|r| (e.to_slot, r.clone()))
                })
                .collect();
            let consumed: HashSet<&'static str> = graph
                .edges
                .iter()
                .filter(|e| e.from_node == node)
                .map(|e| e.from_slot)
                .chain((graph.output.0 == node).then_some(graph.output.1))
                .collect();
            let ctx = PrepareCtx {
                gpu,
                scene: &scene_resources,
                shaders: &shaders,
                inputs,
                consumed,
                width,
                height,
            };
            let outputs = graph.nodes[node].pass.prepare(ctx)?;
            for (slot, resource) in outputs {
                produced.insert((node, slot), resource);
            }
        }
        // The output node's image inputs and outputs, named by its slots.
        let out_node = graph.output.0;
        let mut aovs: Vec<(&'static str, Resource)> = produced
            .iter()
            .filter(|((node, _), r)| *node == out_node && r.kind == ResourceKind::Radiance)
            .map(|((_, slot), r)| (*slot, r.clone()))
            .chain(graph.inputs_of(out_node).filter_map(|e| {
                produced
                    .get(&(e.from_node, e.from_slot))
                    .filter(|r| r.kind == ResourceKind::Radiance)
                    .map(|r| (e.to_slot, r.clone()))
            }))
            .collect();
        aovs.sort_by_key(|(slot, _)| *slot);
        let output = produced.remove(&graph.output).ok_or_else(|| {
            Error::Other(format!(
                "node \"{}\" did not produce its output slot \"{}\"",
                graph.nodes[graph.output.0].name, graph.output.1
            ))
        })?;
        let spp_per_iteration = graph
            .nodes
            .iter()
            .map(|n| n.pass.samples_per_iteration() as u64)
            .max()
            .unwrap_or(0);
        let photons_per_iteration = graph
            .nodes
            .iter()
            .map(|n| n.pass.photons_per_iteration())
            .sum();
        gpu.check_errors()?;
        Ok(Self {
            gpu,
            scene: scene_resources,
            graph,
            output,
            aovs,
            width,
            height,
            seed,
            iteration: 0,
            spp_per_iteration,
            photons_per_iteration,
            profile: None,
            pruned,
        })
    }

    /// Records and submits one iteration of every node, in schedule order.
    pub fn iterate(&mut self) -> Result<(), Error> {
        let mut recorder = Recorder::new(self.gpu);
        let ctx = ExecCtx {
            gpu: self.gpu,
            scene: &self.scene,
            iteration: self.iteration,
            seed: self.seed,
        };
        for &node in &self.graph.order {
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
            let seconds = timer.read(self.gpu)?;
            for &node in &self.graph.order {
                profile.gpu_seconds[node] += seconds[node];
            }
        }
        recorder.submit();
        self.iteration += 1;
        Ok(())
    }

    /// Nodes removed because the scene had no use for them, with the reason.
    pub fn pruned(&self) -> &[crate::graph::Pruned] {
        &self.pruned
    }

    /// Times every node from now on: GPU time from timestamp queries where the adapter can
    /// write them inside encoders, and CPU wall time (each node waited for on its own) always.
    /// Profiling serialises the nodes, so an iteration is slower than without it.
    pub fn enable_profiling(&mut self) -> Result<(), Error> {
        let nodes = self.graph.nodes.len();
        self.profile = Some(Profile {
            timer: NodeTimer::new(self.gpu, nodes)?,
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

    pub fn iterations(&self) -> u64 {
        self.iteration
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

    /// Every `Radiance` output of the output node (e.g. `combined`, `pt`, `caustic`, `radius`
    /// of `resolve`), by slot name.
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
    pub fn stats(&self) -> Result<PassStats, Error> {
        let mut total = PassStats::default();
        for node in &self.graph.nodes {
            total.add(&node.pass.stats(self.gpu)?);
        }
        Ok(total)
    }

    /// Iterates until `budget` is met or `cancel` is raised, calling `progress` after each
    /// iteration with the seconds elapsed.
    pub fn run(
        &mut self,
        budget: Budget,
        cancel: &AtomicBool,
        mut progress: impl FnMut(&Self, f64),
    ) -> Result<RunSummary, Error> {
        let start = Instant::now();
        let spp_iterations = budget
            .spp
            .map(|spp| spp.div_ceil(self.spp_per_iteration.max(1)));
        let photon_iterations = budget
            .photons
            .filter(|_| self.photons_per_iteration > 0)
            .map(|n| n.div_ceil(self.photons_per_iteration.max(1)));
        let target_iterations = match (spp_iterations, photon_iterations) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
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

#[derive(Debug, Clone, Copy)]
pub struct RunSummary {
    pub seconds: f64,
    pub iterations: u64,
    pub samples_per_pixel: u64,
    pub photons: u64,
    pub cancelled: bool,
}
