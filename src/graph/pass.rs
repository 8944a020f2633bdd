//! The contract between the render graph and a pass kind. A pass kind declares its slots and
//! params in one place (a [`PassKind`] entry); the graph validates wiring against those
//! declarations before any GPU work, then asks each node to `prepare` (create pipelines and its
//! output resources) and, per iteration, to `execute` (record its GPU work).

use std::any::{Any, TypeId};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

use super::transport::{Transport, TransportCtx};
use crate::gpu::GpuContext;
use crate::gpu::layout::StructLayout;
use crate::gpu::shaders::{ShaderFile, ShaderLibrary};

/// What flows along an edge. Kinds are declared by the passes that produce and consume them
/// (the graph defines only [`IMAGE`], because its output is one); edges must connect slots of
/// the same kind, compared by name. The byte sizes let the graph allocate outputs.
#[derive(Debug, Clone, Copy)]
pub struct ResourceKind {
    pub name: &'static str,
    /// Bytes before the first element (a header its producer writes).
    pub header_bytes: u64,
    /// Bytes of one element.
    pub element_bytes: u64,
}

impl ResourceKind {
    pub const fn new(name: &'static str, header_bytes: u64, element_bytes: u64) -> Self {
        Self {
            name,
            header_bytes,
            element_bytes,
        }
    }

    pub fn name(self) -> &'static str {
        self.name
    }
}

impl PartialEq for ResourceKind {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl Eq for ResourceKind {}

impl std::hash::Hash for ResourceKind {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name.hash(state);
    }
}

/// Per-pixel `vec4<f32>`: RGB radiance sum in xyz, sample count in w. Sums and counts, never
/// averages, so that images from several runs merge exactly. The graph's output has this kind.
pub const IMAGE: ResourceKind = ResourceKind::new("radiance", 0, 16);

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SlotDir {
    In,
    Out,
}

/// How many elements the graph allocates for an output slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Size {
    /// One per image pixel.
    Pixels,
    /// As many as the resource connected to the named input of the same node.
    LikeInput(&'static str),
    /// As many as the pass computes from its params and inputs ([`Pass::output_len`]).
    Computed,
}

/// One named input or output of a pass kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotDecl {
    pub name: &'static str,
    pub kind: ResourceKind,
    pub dir: SlotDir,
    /// Outputs: how many elements the graph allocates.
    pub size: Size,
    /// Outputs: the contents survive from one iteration to the next (accumulators, per-pixel
    /// statistics); allocated zeroed once. Other outputs are zeroed before every iteration.
    pub persistent: bool,
    /// Inputs: may stay unconnected; the pass then does without it.
    pub optional: bool,
    /// Inputs: reads what its producer wrote in the previous iteration (zeros before the
    /// first), so the edge does not order the two nodes; the producer's slot must persist.
    /// This is how state flows back (an estimator's radii to the camera pass).
    pub previous_iteration: bool,
    /// Inputs: this consumer needs the resource written once, in the first iteration, and kept
    /// (`ppm` keeps one camera pass's hit points). Its producer is told through
    /// [`PrepareCtx::kept`]; values may still be updated in place, the layout may not.
    pub kept: bool,
    /// Inputs: only looks at the resource (an AOV), so it does not count as a consumer: the
    /// producer does no work for it and changes nothing because of it.
    pub observe_only: bool,
    /// Inputs: at most one consumer of any output may read it through such a slot (an
    /// estimator shrinks the radii of the hit points it reads; two would shrink one set twice).
    pub exclusive: bool,
    /// Outputs: must feed a node (state a consumer needs back, like an estimator's radii).
    pub required: bool,
}

impl SlotDecl {
    pub const fn input(name: &'static str, kind: ResourceKind) -> Self {
        Self {
            name,
            kind,
            dir: SlotDir::In,
            size: Size::Computed,
            persistent: false,
            optional: false,
            previous_iteration: false,
            kept: false,
            observe_only: false,
            exclusive: false,
            required: false,
        }
    }
    pub const fn output(name: &'static str, kind: ResourceKind, size: Size) -> Self {
        Self {
            name,
            kind,
            dir: SlotDir::Out,
            size,
            persistent: false,
            optional: false,
            previous_iteration: false,
            kept: false,
            observe_only: false,
            exclusive: false,
            required: false,
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
    pub const fn previous_iteration(mut self) -> Self {
        self.previous_iteration = true;
        self
    }
    pub const fn kept(mut self) -> Self {
        self.kept = true;
        self
    }
    pub const fn observe_only(mut self) -> Self {
        self.observe_only = true;
        self
    }
    pub const fn exclusive(mut self) -> Self {
        self.exclusive = true;
        self
    }
    pub const fn required(mut self) -> Self {
        self.required = true;
        self
    }
}

/// A GPU resource bound to a slot.
#[derive(Debug, Clone)]
pub struct Resource {
    pub kind: ResourceKind,
    pub buffer: Arc<wgpu::Buffer>,
    /// Number of elements (pixels for images, hit-point slots for hit points).
    pub len: u64,
}

impl Resource {
    pub fn new(kind: ResourceKind, buffer: wgpu::Buffer, len: u64) -> Self {
        Self {
            kind,
            buffer: Arc::new(buffer),
            len,
        }
    }

    /// Bytes a resource of `len` elements of `kind` takes (at least one element, so that an
    /// empty resource can still be bound); `None` on overflow.
    pub fn bytes(kind: ResourceKind, len: u64) -> Option<u64> {
        len.max(1)
            .checked_mul(kind.element_bytes)?
            .checked_add(kind.header_bytes)
    }

    /// A zeroed resource of `len` elements, usable as storage and as copy source and target.
    pub fn allocate(
        gpu: &GpuContext,
        label: &str,
        kind: ResourceKind,
        len: u64,
    ) -> Result<Self, crate::Error> {
        let bytes = Self::bytes(kind, len).ok_or_else(|| {
            crate::Error::Other(format!(
                "{label}: {len} elements of {} overflow a buffer size",
                kind.name
            ))
        })?;
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let buffer = gpu.create_buffer(label, bytes, usage)?;
        Ok(Self::new(kind, buffer, len))
    }
}

impl Resource {
    /// Its `len` elements read back as `T` (past the header), for passes that need them on
    /// the CPU and for tests. `T` must be the kind's element.
    pub fn read<T: bytemuck::Pod>(&self, gpu: &GpuContext) -> Result<Vec<T>, crate::Error> {
        let bytes = self.len * self.kind.element_bytes;
        if std::mem::size_of::<T>() as u64 != self.kind.element_bytes {
            return Err(crate::Error::Other(format!(
                "{} holds {}-byte elements, not {}",
                self.kind.name,
                self.kind.element_bytes,
                std::any::type_name::<T>()
            )));
        }
        let read = gpu.read_buffer(&self.buffer, self.kind.header_bytes, bytes)?;
        Ok(bytemuck::pod_collect_to_vec(&read[..bytes as usize]))
    }

    /// Its header read back as `T`, which must be the kind's header.
    pub fn read_header<T: bytemuck::Pod>(&self, gpu: &GpuContext) -> Result<T, crate::Error> {
        let bytes = self.kind.header_bytes;
        if std::mem::size_of::<T>() as u64 != bytes {
            return Err(crate::Error::Other(format!(
                "{} has a {bytes}-byte header, not {}",
                self.kind.name,
                std::any::type_name::<T>()
            )));
        }
        let read = gpu.read_buffer(&self.buffer, 0, bytes)?;
        Ok(bytemuck::pod_read_unaligned(&read[..bytes as usize]))
    }
}

/// What the render shares with every pass (the scene on the GPU, say), keyed by type, so that
/// the graph carries it without naming it.
#[derive(Default)]
pub struct Shared {
    items: HashMap<TypeId, Box<dyn Any + Send>>,
}

impl Shared {
    pub fn insert<T: Any + Send>(&mut self, item: T) {
        self.items.insert(TypeId::of::<T>(), Box::new(item));
    }

    pub fn get<T: Any>(&self) -> Result<&T, crate::Error> {
        self.items
            .get(&TypeId::of::<T>())
            .and_then(|item| item.downcast_ref())
            .ok_or_else(|| {
                crate::Error::Other(format!(
                    "the render shares no {} with its passes",
                    std::any::type_name::<T>()
                ))
            })
    }
}

/// What a pass sees when it is prepared: the device, the shader library, what the render
/// shares, its connected inputs and the outputs the graph allocated for it.
pub struct PrepareCtx<'a> {
    pub gpu: &'a GpuContext,
    pub shaders: &'a ShaderLibrary,
    pub shared: &'a Shared,
    pub inputs: HashMap<&'static str, Resource>,
    /// Empty while the graph asks [`Pass::output_len`]; every output slot when preparing.
    pub outputs: HashMap<&'static str, Resource>,
    /// Output slots that feed another node (not merely one that observes them) or are the
    /// graph's output. A pass may skip work for the others (`path_trace` records no hit points,
    /// and drops nothing, when none are used).
    pub consumed: HashSet<&'static str>,
    /// Output slots some consumer keeps ([`SlotDecl::kept`]): write them in the first
    /// iteration only.
    pub kept: HashSet<&'static str>,
    /// Input slots whose producer keeps them: their layout never changes after the first
    /// iteration (a builder may then only refit).
    pub kept_inputs: HashSet<&'static str>,
    /// The pixel grid this graph renders: the whole image, or one tile of it.
    pub width: u32,
    pub height: u32,
    /// Pixels of the whole image (more than `width` x `height` when the graph renders a tile):
    /// what per-image budgets, such as photons per iteration, follow.
    pub film_pixels: u64,
    /// Global index of the first iteration the render will run (0, or where a shard or a
    /// resumed render starts): passes with a schedule set their first state from it.
    pub first_iteration: u64,
}

impl PrepareCtx<'_> {
    /// The resource connected to input `slot`: present for every required input of a validated
    /// graph, so a miss is a wiring bug worth a clear error rather than a panic.
    pub fn input(&self, slot: &str) -> Result<&Resource, crate::Error> {
        self.inputs
            .get(slot)
            .ok_or_else(|| crate::Error::Other(format!("input slot \"{slot}\" is not connected")))
    }

    /// The resource the graph allocated for output `slot`.
    pub fn output(&self, slot: &str) -> Result<&Resource, crate::Error> {
        self.outputs
            .get(slot)
            .ok_or_else(|| crate::Error::Other(format!("output slot \"{slot}\" was not allocated")))
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
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

    /// Records one dispatch of `pipeline` with `groups` bound in order (the pass kernels take
    /// the scene as group 0 and their own resources as group 1).
    pub fn dispatch(
        &mut self,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        groups: &[&wgpu::BindGroup],
        workgroups: [u32; 3],
    ) {
        let mut pass = self
            .encoder()
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: None,
            });
        pass.set_pipeline(pipeline);
        for (index, group) in (0u32..).zip(groups) {
            pass.set_bind_group(index, *group, &[]);
        }
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
    /// 0-based global iteration index: with the seed it keys every random stream, and schedules
    /// (pppm's radius) follow it. A shard k of n runs k, k + n, ...; a resumed render goes on
    /// where it stopped; so each iteration draws what it would in one uninterrupted render.
    pub iteration: u64,
    /// Global index of the iteration after this one in this render (`iteration` + 1, or + n
    /// for a shard): state a pass leaves for the next iteration is for that one.
    pub next_iteration: u64,
    /// This render's first iteration (a kept resource is written then).
    pub first: bool,
    pub seed: u64,
}

/// Which global iterations a render runs: `first`, `first + stride`, `first + 2 stride`, ...
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Schedule {
    pub first: u64,
    pub stride: u64,
}

impl Default for Schedule {
    fn default() -> Self {
        Self {
            first: 0,
            stride: 1,
        }
    }
}

impl Schedule {
    /// Global index of this render's `local`-th iteration (0-based).
    pub fn global(&self, local: u64) -> u64 {
        self.first + local * self.stride
    }

    /// Iterations this render runs out of a budget of `total` global iterations (0..total).
    pub fn local_count(&self, total: u64) -> u64 {
        if total <= self.first {
            0
        } else {
            (total - self.first).div_ceil(self.stride)
        }
    }
}

/// Counters a pass reports after the render (read back from the GPU once, not per iteration),
/// by name: `rays`, `discarded_samples`, `photon_segments`, or whatever a pass counts.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Counters(pub BTreeMap<&'static str, u64>);

impl Counters {
    pub fn of(entries: &[(&'static str, u64)]) -> Self {
        Self(entries.iter().copied().collect())
    }

    /// A counter's value; 0 when no pass counts it.
    pub fn get(&self, name: &str) -> u64 {
        self.0.get(name).copied().unwrap_or(0)
    }

    pub fn add(&mut self, other: &Counters) {
        for (name, value) in &other.0 {
            *self.0.entry(name).or_default() += value;
        }
    }
}

/// `Send`: a renderer may be made on one thread and run on another (a host program's worker,
/// a Python thread with the GIL released).
pub trait Pass: Send {
    /// Elements of output `slot` when its size is [`Size::Computed`]; `ctx.outputs` is empty.
    fn output_len(&self, slot: &str, _ctx: &PrepareCtx<'_>) -> Result<u64, crate::Error> {
        Err(crate::Error::Other(format!(
            "output slot \"{slot}\" declares a computed size the pass does not compute"
        )))
    }

    /// Create pipelines and bind the inputs and the allocated outputs.
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), crate::Error>;

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
    fn needs(&self) -> Vec<SceneNeed> {
        Vec::new()
    }

    /// Why renders of disjoint iterations through this pass cannot be summed into one image
    /// (an estimator whose state depends on every earlier iteration); `None`: they can.
    fn shard_refusal(&self) -> Option<&'static str> {
        None
    }

    /// Why this pass cannot follow an adaptive sample mask (src/gpu/sample_mask.rs), which
    /// leaves converged pixels unsampled for some iterations; `None`: it skips them and its
    /// per-pixel images stay the mean of each pixel's own samples. Every pass refuses unless
    /// it says otherwise.
    fn adaptive_refusal(&self) -> Option<&'static str> {
        Some("its per-pixel statistics assume every pixel is updated every iteration")
    }

    /// Photons this pass emits each iteration (known after `prepare`).
    fn photons_per_iteration(&self) -> u64 {
        0
    }

    /// Whether its work follows the pixel grid it renders (the default). A pass whose outputs
    /// are the same whichever part of the image is rendered (photons, which follow the whole
    /// image) answers false: an image rendered in bands then runs it once, in the first band,
    /// and the other bands read its outputs ([`super::exec::PreparedGraph::new`]).
    fn follows_pixels(&self) -> bool {
        true
    }

    /// Which light paths output `slot` carries (see graph/transport.rs), given what the inputs
    /// carry; `None`: the union of the inputs. Sources of light (camera and photon passes)
    /// answer; pass-throughs need not.
    fn transport(&self, _slot: &str, _ctx: &TransportCtx<'_>) -> Option<Transport> {
        None
    }

    /// Buffers of its own (not graph resources) whose contents carry from one iteration to the
    /// next (sppm's per-slot statistics, counters), by name: a checkpoint saves them with the
    /// persistent resources and a resumed render restores them. They need COPY_SRC and COPY_DST.
    fn state(&self) -> Vec<(&'static str, &wgpu::Buffer)> {
        Vec::new()
    }

    /// For an output slot that is computed from image inputs (resolve's `combined`), the input
    /// slots whose per-pixel means add up to it; `None`: the slot is an accumulator itself.
    /// Shards are merged through these terms.
    fn output_terms(&self, _slot: &str) -> Option<&'static [&'static str]> {
        None
    }

    /// Counters gathered on the GPU so far (may read back; called rarely).
    fn counters(&self, _gpu: &GpuContext) -> Result<Counters, crate::Error> {
        Ok(Counters::default())
    }
}

/// A scene feature a pass may need, named by the passes; the render answers whether the scene
/// has it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneNeed {
    pub name: &'static str,
    /// For messages: "the scene has no {description}".
    pub description: &'static str,
    /// For a need of glossy surfaces: microfacet lobes count below this roughness.
    pub glossy_below: f32,
}

/// A pass kind as the registry knows it: its name, slots, shaders and constructor.
/// `construct` receives the node's `params` exactly as written in the graph file (RON text, e.g.
/// `(max_depth: 12)`, or `()` when absent) and parses it with `#[serde(deny_unknown_fields)]`, so
/// a parse error's position is relative to that text.
pub struct PassKind {
    pub name: &'static str,
    pub description: &'static str,
    pub slots: &'static [SlotDecl],
    /// The WGSL entry files its kernels come from.
    pub shaders: &'static [ShaderFile],
    /// The Rust structs it uploads to WGSL structs (its params), checked against the shaders.
    pub layouts: &'static [StructLayout],
    pub construct: fn(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError>,
}

impl PassKind {
    pub fn slot(&self, name: &str) -> Option<&'static SlotDecl> {
        self.slots.iter().find(|s| s.name == name)
    }

    /// The params its constructor knows, as its params struct names them (read from the error
    /// an unknown param gives, so never out of date); `None` when it accepts unknown ones.
    pub fn param_names(&self) -> Option<&'static [&'static str]> {
        match (self.construct)("(no_such_param_: 0)") {
            Err(e) => match e.code {
                ron::Error::NoSuchStructField { expected, .. } => Some(expected),
                _ => None,
            },
            Ok(_) => None,
        }
    }

    /// Its reference in Markdown: description, slots (kind, size, flags) and params.
    pub fn markdown(&self) -> String {
        let mut out = format!("### `{}`\n\n{}.\n\n", self.name, self.description);
        out.push_str("| slot | direction | resource | size | flags |\n|---|---|---|---|---|\n");
        for slot in self.slots {
            let (dir, size) = match slot.dir {
                SlotDir::In => ("in", String::new()),
                SlotDir::Out => (
                    "out",
                    match slot.size {
                        Size::Pixels => "one per pixel".to_string(),
                        Size::LikeInput(input) => format!("as input `{input}`"),
                        Size::Computed => "computed by the pass".to_string(),
                    },
                ),
            };
            let flags: Vec<&str> = [
                (slot.persistent, "persistent"),
                (slot.optional, "optional"),
                (slot.previous_iteration, "previous iteration"),
                (slot.kept, "kept"),
                (slot.observe_only, "observe only"),
                (slot.exclusive, "exclusive"),
                (slot.required, "required"),
            ]
            .iter()
            .filter(|f| f.0)
            .map(|f| f.1)
            .collect();
            out.push_str(&format!(
                "| `{}` | {dir} | {} | {size} | {} |\n",
                slot.name,
                slot.kind.name,
                flags.join(", ")
            ));
        }
        let params = match self.param_names() {
            Some([]) => "none".to_string(),
            Some(names) => names
                .iter()
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", "),
            None => "any (not checked)".to_string(),
        };
        out.push_str(&format!("\nParams: {params}.\n"));
        out
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

/// A params error at the start of the params text, for range checks serde cannot express.
pub fn params_error(message: String) -> ron::error::SpannedError {
    let start = ron::error::Position { line: 1, col: 1 };
    ron::error::SpannedError {
        code: ron::Error::Message(message),
        span: ron::error::Span { start, end: start },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sizes that do not fit a u64 are an error, never a wrapped small buffer.
    #[test]
    fn resource_bytes_overflow_is_refused() {
        let kind = ResourceKind::new("big", 16, 64);
        assert_eq!(Resource::bytes(kind, 0), Some(80));
        assert_eq!(Resource::bytes(kind, 1 << 40), Some((1 << 46) + 16));
        assert_eq!(Resource::bytes(kind, u64::MAX / 32), None);
        assert_eq!(
            Resource::bytes(ResourceKind::new("h", u64::MAX, 1), 1),
            None
        );
    }
}
