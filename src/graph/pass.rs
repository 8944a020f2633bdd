//! The contract between the render graph and a pass kind. A pass kind declares its slots and
//! params in one place (a [`PassKind`] entry); the graph validates wiring against those
//! declarations before any GPU work, then asks each node to `prepare` (create pipelines and its
//! output resources) and, per iteration, to `execute` (record its GPU work).

use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::gpu::GpuContext;

/// What flows along an edge. Edges must connect slots of the same kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ResourceKind {
    /// Per-pixel `vec4<f32>`: RGB radiance sum in xyz, sample count in w. Sums and counts, never
    /// averages, so that images from several runs merge exactly.
    Radiance,
    /// Hit points recorded by the camera pass at photon-mapped vertices.
    HitPoints,
    /// A BVH over hit points, in the layout the photon pass traverses.
    HitPointTree,
    /// Per-hit-point photon count and flux gathered in one iteration.
    Deposits,
}

impl ResourceKind {
    pub fn name(self) -> &'static str {
        match self {
            ResourceKind::Radiance => "radiance",
            ResourceKind::HitPoints => "hit_points",
            ResourceKind::HitPointTree => "hit_point_tree",
            ResourceKind::Deposits => "deposits",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SlotDir {
    In,
    Out,
}

/// One named input or output of a pass kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotDecl {
    pub name: &'static str,
    pub kind: ResourceKind,
    pub dir: SlotDir,
    /// The contents survive from one iteration to the next (accumulators, per-pixel statistics).
    pub persistent: bool,
    /// An input that may stay unconnected; the pass then does without it.
    pub optional: bool,
}

impl SlotDecl {
    pub const fn input(name: &'static str, kind: ResourceKind) -> Self {
        Self {
            name,
            kind,
            dir: SlotDir::In,
            persistent: false,
            optional: false,
        }
    }
    pub const fn output(name: &'static str, kind: ResourceKind) -> Self {
        Self {
            name,
            kind,
            dir: SlotDir::Out,
            persistent: false,
            optional: false,
        }
    }
    pub const fn persistent(mut self) -> Self {
        self.persistent = true;
        self
    }
    pub const fn optional(mut self) -> Self {
        self.optional = true;
        self
    }
}

/// A GPU resource bound to a slot.
#[derive(Debug, Clone)]
pub struct Resource {
    pub kind: ResourceKind,
    pub buffer: Arc<wgpu::Buffer>,
    /// Number of elements (pixels for `Radiance`, hit-point slots for `HitPoints`).
    pub len: u64,
    /// Raised by a consumer that wants the producer to stop rewriting the contents after the
    /// first iteration (`ppm` keeps the hit points of one camera pass). Shared by every clone.
    pub frozen: Arc<AtomicBool>,
}

impl Resource {
    pub fn new(kind: ResourceKind, buffer: wgpu::Buffer, len: u64) -> Self {
        Self {
            kind,
            buffer: Arc::new(buffer),
            len,
            frozen: Arc::new(AtomicBool::new(false)),
        }
    }
}

/// What a pass sees when it is prepared: the device, the scene's shared resources, the resources
/// its inputs are connected to, and the render's size and seed.
pub struct PrepareCtx<'a> {
    pub gpu: &'a GpuContext,
    pub scene: &'a crate::render::SceneResources,
    pub shaders: &'a crate::shaders::ShaderLibrary,
    pub inputs: HashMap<&'static str, Resource>,
    /// Output slots that feed another node or are the graph's output. A pass may skip work for
    /// the others (`path_trace` records no hit points, and drops nothing, when none are used).
    pub consumed: HashSet<&'static str>,
    pub width: u32,
    pub height: u32,
}

impl PrepareCtx<'_> {
    /// The resource connected to input `slot`: present for every required input of a validated
    /// graph, so a miss is a wiring bug worth a clear error rather than a panic.
    pub fn input(&self, slot: &str) -> Result<&Resource, crate::Error> {
        self.inputs
            .get(slot)
            .ok_or_else(|| crate::Error::Other(format!("input slot \"{slot}\" is not connected")))
    }
}

/// Records the GPU work of one iteration. A pass that needs results on the CPU mid-iteration
/// (the CPU BVH builder) calls `flush` to submit what was recorded so far and wait for it.
pub struct Recorder<'a> {
    gpu: &'a GpuContext,
    encoder: Option<wgpu::CommandEncoder>,
}

impl<'a> Recorder<'a> {
    pub fn new(gpu: &'a GpuContext) -> Self {
        Self { gpu, encoder: None }
    }

    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        let device = &self.gpu.device;
        self.encoder.get_or_insert_with(|| {
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("iteration"),
            })
        })
    }

    /// Records one dispatch of `pipeline` with the scene as bind group 0 and the pass's own
    /// resources as group 1 (the layout every pass kernel follows).
    pub fn dispatch(
        &mut self,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        scene: &wgpu::BindGroup,
        pass_group: &wgpu::BindGroup,
        workgroups: [u32; 3],
    ) {
        let mut pass = self
            .encoder()
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: None,
            });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, scene, &[]);
        pass.set_bind_group(1, pass_group, &[]);
        let [x, y, z] = workgroups;
        pass.dispatch_workgroups(x, y, z);
    }

    /// Submits what was recorded (if anything) without waiting.
    pub fn submit(&mut self) {
        if let Some(encoder) = self.encoder.take() {
            self.gpu.queue.submit([encoder.finish()]);
        }
    }

    /// Submits what was recorded and waits until the GPU has finished it.
    pub fn flush(&mut self) -> Result<(), crate::Error> {
        self.submit();
        self.gpu.wait()?;
        Ok(())
    }
}

/// Per-iteration information handed to `execute`.
pub struct ExecCtx<'a> {
    pub gpu: &'a GpuContext,
    pub scene: &'a crate::render::SceneResources,
    /// 0-based iteration index; with the seed it decorrelates random streams between iterations.
    pub iteration: u64,
    pub seed: u64,
}

/// Statistics a pass reports after the render (read back from the GPU once, not per iteration).
#[derive(Debug, Clone, Default)]
pub struct PassStats {
    pub rays: u64,
    pub discarded_samples: u64,
    /// Segments photons were traced along (photons emitted: `Renderer::photons`, exact on the
    /// CPU).
    pub photon_segments: u64,
}

impl PassStats {
    pub fn add(&mut self, other: &PassStats) {
        self.rays += other.rays;
        self.discarded_samples += other.discarded_samples;
        self.photon_segments += other.photon_segments;
    }
}

pub trait Pass {
    /// Create pipelines and output resources. Returns the resource for every output slot.
    fn prepare(
        &mut self,
        ctx: PrepareCtx<'_>,
    ) -> Result<HashMap<&'static str, Resource>, crate::Error>;

    /// Record this iteration's GPU work.
    fn execute(
        &mut self,
        ctx: &ExecCtx<'_>,
        recorder: &mut Recorder<'_>,
    ) -> Result<(), crate::Error>;

    /// Camera samples per pixel this pass adds each iteration (0 for passes that add none).
    fn samples_per_iteration(&self) -> u32 {
        0
    }

    /// What the scene must have for this node to do anything; after validation the graph drops
    /// nodes whose needs the scene lacks (src/graph/prune.rs).
    fn needs(&self) -> &'static [SceneNeed] {
        &[]
    }

    /// Photons this pass emits each iteration (known after `prepare`).
    fn photons_per_iteration(&self) -> u64 {
        0
    }

    /// Counters gathered on the GPU so far (may read back; called rarely).
    fn stats(&self, _gpu: &GpuContext) -> Result<PassStats, crate::Error> {
        Ok(PassStats::default())
    }
}

/// A scene feature a pass may need.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneNeed {
    /// A mirror or dielectric surface (caustic photons need one to become caustic photons).
    SpecularSurface,
}

impl SceneNeed {
    pub fn describe(self) -> &'static str {
        match self {
            SceneNeed::SpecularSurface => "specular (mirror or dielectric) surface",
        }
    }
}

/// A pass kind as the registry knows it: its name, slots, parameter names and constructor.
/// `construct` receives the node's `params` exactly as written in the graph file (RON text, e.g.
/// `(max_depth: 12)`, or `()` when absent) and parses it with `#[serde(deny_unknown_fields)]`, so
/// a parse error's position is relative to that text.
pub struct PassKind {
    pub name: &'static str,
    pub description: &'static str,
    pub slots: &'static [SlotDecl],
    pub construct: fn(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError>,
}

impl PassKind {
    pub fn slot(&self, name: &str) -> Option<&'static SlotDecl> {
        self.slots.iter().find(|s| s.name == name)
    }
}

/// Parses a pass's params from the text of its `params` field.
pub fn parse_params<P: serde::de::DeserializeOwned>(
    params: &str,
) -> Result<P, ron::error::SpannedError> {
    // `max_depth: 5` and `max_depth: Some(5)` both set an optional param.
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(params)
}
