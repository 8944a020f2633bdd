//! `path_trace`: the camera pass. Traces `samples_per_iteration` paths per pixel with next-event
//! estimation and adds them to the persistent `radiance` accumulator (sum and count per pixel).
//!
//! When its `hit_points` output feeds another node, the first `merge_depth` diffuse vertices of
//! each pixel's first sample become hit points for photon mapping, and the emission that photon
//! mapping will add there (reached through specular vertices: delta lobes, and microfacet lobes
//! smoother than `glossy_threshold`, of which rough plastic's coating only) is left out of
//! `radiance`. Each hit point's radius comes from the estimator's `radii` (last iteration's), or
//! from its radius rule while the estimator has none for that slot. When a consumer keeps the
//! hit points (`ppm`), they are recorded in the first iteration only; later iterations only
//! refresh their radii.

use serde::Deserialize;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::sample_mask::SampleMask;
use crate::gpu_scene::SceneResources;
use crate::gpu_scene::layout::GpuSceneUniform;
use crate::graph::pass::{
    Counters, ExecCtx, IMAGE, Pass, PassKind, PrepareCtx, Recorder, Size, SlotDecl, params_error,
    parse_params,
};
use crate::graph::transport::{Transport, TransportCtx};
use crate::passes::hit_points::{
    DEFAULT_RADIUS_PIXELS, HIT_POINT_RADII, HIT_POINTS, HitPointsHeader, PHOTON_HITS, RadiusRule,
};
use crate::passes::lanes::items_per_invocation;
use crate::passes::photon_grid::PHOTON_GRID;
use crate::passes::{check_glossy_threshold, depth_rule, glossy_defs, resolve_depths};
use crate::scene::filter::{FILTER_BOX, PixelFilter};
use crate::shader_file;

const SHADER: crate::gpu::shaders::ShaderFile = shader_file!("shaders/passes/path_trace.wgsl");
/// The splat entry point's workgroup side (8x8 pixels).
const WORKGROUP: u32 = 8;
/// Invocations per workgroup of the camera entry point (one-dimensional).
const LANES: u32 = 64;

static SLOTS: &[SlotDecl] = &[
    SlotDecl::output("radiance", IMAGE, Size::Pixels).persistent(),
    SlotDecl::output("hit_points", HIT_POINTS, Size::Computed).persistent(),
    SlotDecl::input("radii", HIT_POINT_RADII)
        .optional()
        .previous_iteration(),
    // Both or neither: this iteration's caustic photons and a `photon_grid` over them, looked up
    // at diffuse vertices past the hit points in place of path tracing their caustics.
    SlotDecl::input("photon_hits", PHOTON_HITS).optional(),
    SlotDecl::input("photon_grid", PHOTON_GRID).optional(),
];

/// `PathTraceUniform` against its namesake in the shader.
const PARAMS_LAYOUT: crate::gpu::layout::StructLayout = crate::struct_layout!(PathTraceUniform => "PathTraceUniform" in SHADER, {
    sample_base, samples_per_iteration, seed, max_depth, rr_depth, merge_depth, record, trace_beyond, lookups,
    glossy_threshold
});

pub const KIND: PassKind = PassKind {
    name: "path_trace",
    description: "camera paths with next-event estimation (MIS for area lights)",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: &[PARAMS_LAYOUT],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let params: PathTraceParams = parse_params(params)?;
    let spp = params.samples_per_iteration;
    if !(1..=MAX_SAMPLES_PER_ITERATION).contains(&spp) {
        return Err(params_error(format!(
            "samples_per_iteration must lie in 1..={MAX_SAMPLES_PER_ITERATION}, got {spp} \
             (an iteration is one dispatch, which Ctrl-C cannot interrupt; more iterations cost \
             nothing extra)"
        )));
    }
    if params.max_depth == Some(0) {
        return Err(params_error(
            "max_depth must be at least 1 (1: emitters seen directly)".into(),
        ));
    }
    check_glossy_threshold(params.glossy_threshold)?;
    Ok(Box::new(PathTrace::new(params)))
}

/// Most camera samples per pixel in one iteration.
pub const MAX_SAMPLES_PER_ITERATION: u32 = 64;

#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PathTraceParams {
    /// Longest path in segments (Mitsuba's rule); `None` takes the scene's.
    pub max_depth: Option<u32>,
    /// Camera samples per pixel in one iteration.
    pub samples_per_iteration: u32,
    /// Depth from which Russian roulette terminates paths; `None` takes the scene's (off unless
    /// the scene asks for it, or its depth is unbounded).
    pub rr_depth: Option<u32>,
    /// Photon-mapped diffuse vertices per path: `1` (SPPM) up to `max` (every diffuse vertex,
    /// as in the original hybrid report). Used only when `hit_points` is connected.
    pub merge_depth: MergeDepth,
    /// Continue paths past photon-mapped vertices (hybrid). `false` stops them there, so path
    /// tracing adds only emission seen directly or through specular surfaces (photon mapping
    /// alone).
    pub trace_beyond: bool,
    /// Microfacet lobes whose roughness (the larger of alpha_u and alpha_v, at the surface
    /// point) is below this are specular vertices of the partition (docs/design.md section 1): after
    /// a photon-mapped vertex the light through them is left to photon mapping. Must equal the
    /// photon pass's; 0 (the default): only delta lobes are specular.
    pub glossy_threshold: f32,
}

impl Default for PathTraceParams {
    fn default() -> Self {
        Self {
            max_depth: None,
            samples_per_iteration: 1,
            rr_depth: None,
            merge_depth: MergeDepth::Depth(1),
            trace_beyond: true,
            glossy_threshold: 0.0,
        }
    }
}

/// `merge_depth: 2` or `merge_depth: max`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MergeDepth {
    Depth(u32),
    Max,
}

/// Most hit-point slots per pixel. Photon-mapping fewer vertices than a path has keeps the
/// partition exact (the camera drops light only at the vertices it records), so deeper
/// vertices are simply path traced; the cap keeps `pixels x slots` buffers bounded.
pub const MAX_MERGE_SLOTS: u32 = 16;

impl MergeDepth {
    /// Hit-point slots per pixel: a diffuse vertex needs at least one segment before it and one
    /// after it, so a path of `max_depth` segments has at most `max_depth - 1`; and at most
    /// `MAX_MERGE_SLOTS`.
    pub fn slots(self, max_depth: u32) -> u32 {
        let possible = max_depth.saturating_sub(1).min(MAX_MERGE_SLOTS);
        match self {
            MergeDepth::Depth(d) => d.min(possible),
            MergeDepth::Max => possible,
        }
    }
}

impl<'de> Deserialize<'de> for MergeDepth {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        // RON hands a bare identifier such as `max` to generic visitors as a unit value without
        // its name, so read the raw text of the value and look at it.
        use serde::de::Error as _;
        let raw = Box::<ron::value::RawValue>::deserialize(deserializer)?;
        let text = raw.get_ron().trim();
        if text == "max" {
            return Ok(MergeDepth::Max);
        }
        raw.into_rust::<u32>().map(MergeDepth::Depth).map_err(|_| {
            D::Error::custom(format!(
                "merge_depth is a whole number (1, 2, ...) or `max`, got `{text}`"
            ))
        })
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PathTraceUniform {
    sample_base: u32,
    samples_per_iteration: u32,
    seed: u32,
    max_depth: u32,
    rr_depth: u32,
    merge_depth: u32,
    record: u32,
    trace_beyond: u32,
    lookups: u32,
    splat: u32,
    fis_weight: f32,
    glossy_threshold: f32,
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    /// The `splat` entry point, when the pixel filter is splatted.
    splat: Option<wgpu::ComputePipeline>,
    /// The shader's `splat` parameter ([`splat_mode`]).
    splat_mode: u32,
    /// What a filter-distributed sample counts while splatting.
    fis_weight: f32,
    scene: wgpu::BindGroup,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    counters: wgpu::Buffer,
    /// Workgroups of the camera entry point, each lane taking several pixels in turn on CPU
    /// adapters (`lanes`).
    workgroups: u32,
    width: u32,
    height: u32,
    max_depth: u32,
    rr_depth: u32,
    merge_slots: u32,
    /// A consumer keeps the hit points: record them in the first iteration only.
    keep_hit_points: bool,
    /// A photon grid is connected: look caustics up past the hit points.
    lookups: bool,
}

pub struct PathTrace {
    params: PathTraceParams,
    prepared: Option<Prepared>,
}

impl PathTrace {
    pub fn new(params: PathTraceParams) -> Self {
        Self {
            params,
            prepared: None,
        }
    }
}

impl PathTrace {
    /// (max_depth, rr_depth, hit-point slots per pixel) for this scene and wiring.
    fn depths(&self, ctx: &PrepareCtx<'_>) -> Result<(u32, u32, u32), Error> {
        let scene = ctx.shared.get::<SceneResources>()?;
        let (max_depth, rr_depth) =
            resolve_depths(self.params.max_depth, self.params.rr_depth, &scene.uniform);
        // No consumer, no hit points: the pass is then a plain path tracer that drops nothing.
        let merge_slots = if ctx.consumed.contains("hit_points") {
            self.params.merge_depth.slots(max_depth)
        } else {
            0
        };
        Ok((max_depth, rr_depth, merge_slots))
    }
}

/// Whether samples are splatted through the pixel filter as Mitsuba's film does: for every
/// filter but the box with samples kept on the film. (With `sample_border` samples also land
/// beyond the film, which no pixel's invocation traces: those filters keep their distributed
/// sample positions.)
fn splats(scene: &GpuSceneUniform) -> bool {
    scene.filter_kind != FILTER_BOX && scene.sample_border == 0
}

/// The shader's `splat` mode: 0 none, 1 the samples that record no hit points, 2 all of them
/// (a filter with negative lobes, whose drawn samples would count signed weights otherwise).
fn splat_mode(scene: &GpuSceneUniform) -> u32 {
    let filter = PixelFilter::from_gpu_code(
        scene.filter_kind,
        [scene.filter_param, scene.filter_param_b],
    );
    match (splats(scene), filter.is_signed()) {
        (false, _) => 0,
        (true, false) => 1,
        (true, true) => 2,
    }
}

/// The weight a splatted sample brings an interior pixel on average: the filter's integral over
/// the plane (in pixels, separable), what a filter-distributed sample then counts.
fn filter_weight_per_sample(scene: &GpuSceneUniform) -> f32 {
    PixelFilter::from_gpu_code(
        scene.filter_kind,
        [scene.filter_param, scene.filter_param_b],
    )
    .plane_integral() as f32
}

impl Pass for PathTrace {
    fn output_len(&self, _slot: &str, ctx: &PrepareCtx<'_>) -> Result<u64, Error> {
        let (_, _, merge_slots) = self.depths(ctx)?;
        ctx.pixels().checked_mul(merge_slots as u64).ok_or_else(|| {
            Error::Other(format!(
                "path_trace: {} pixels x {merge_slots} hit points overflow",
                ctx.pixels()
            ))
        })
    }

    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        let radiance = ctx.output("radiance")?;
        let hit_points = ctx.output("hit_points")?;
        let params = gpu.create_buffer(
            "path_trace params",
            std::mem::size_of::<PathTraceUniform>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let splat = splats(&scene.uniform);
        // The counters, then room for one iteration's splatted samples (16 bytes each), and with
        // a signed filter one drawn sample's offset per pixel.
        let drawn_offsets = (splat_mode(&scene.uniform) == 2) as u64;
        let film_bytes = if splat {
            ctx.pixels()
                .checked_mul((self.params.samples_per_iteration as u64 + drawn_offsets) * 16)
                .and_then(|b| b.checked_add(16))
                .ok_or_else(|| Error::Other("path_trace: the splat buffer overflows".into()))?
        } else {
            32
        };
        let counters = gpu.create_buffer(
            "path_trace counters and film samples",
            film_bytes,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let (max_depth, rr_depth, merge_slots) = self.depths(&ctx)?;
        let header = HitPointsHeader {
            slots_per_pixel: merge_slots,
            _pad: [0; 3],
        };
        gpu.queue
            .write_buffer(&hit_points.buffer, 0, bytemuck::bytes_of(&header));
        // Without an estimator's radii every hit point takes the default rule's first radius.
        let own_radii;
        let radii = match ctx.inputs.get("radii") {
            Some(radii) => &*radii.buffer,
            None => {
                let rule = RadiusRule::new(0.0, DEFAULT_RADIUS_PIXELS, scene.uniform.scene_radius);
                let mut bytes = bytemuck::bytes_of(&rule).to_vec();
                bytes.resize(bytes.len() + 4 * hit_points.len.max(1) as usize, 0);
                own_radii = gpu.create_buffer_init(
                    "path_trace default radii",
                    &bytes,
                    wgpu::BufferUsages::STORAGE,
                )?;
                &own_radii
            }
        };
        let lookups = match (ctx.inputs.get("photon_hits"), ctx.inputs.get("photon_grid")) {
            (Some(hits), Some(grid)) => Some((hits.buffer.clone(), grid.buffer.clone())),
            (None, None) => None,
            _ => {
                return Err(Error::Other(
                    "path_trace: connect both photon_hits and photon_grid (the grid lists the \
                     hits it is built from), or neither"
                        .into(),
                ));
            }
        };
        let no_lookups;
        let (photon_hits, photon_grid) = match &lookups {
            Some((hits, grid)) => (&**hits, &**grid),
            None => {
                // Unread stand-ins of the least size the bindings take.
                let bytes = (PHOTON_HITS.header_bytes + PHOTON_HITS.element_bytes) as usize;
                no_lookups = (
                    gpu.create_buffer_init(
                        "path_trace no photons",
                        &vec![0; bytes],
                        wgpu::BufferUsages::STORAGE,
                    )?,
                    gpu.create_buffer_init(
                        "path_trace no photon grid",
                        &vec![0; (PHOTON_GRID.header_bytes + 16) as usize],
                        wgpu::BufferUsages::STORAGE,
                    )?,
                );
                (&no_lookups.0, &no_lookups.1)
            }
        };
        // Without a renderer's mask (a pass run alone), a disabled one.
        let own_mask;
        let mask = match ctx.shared.get::<SampleMask>() {
            Ok(mask) => mask,
            Err(_) => {
                own_mask = SampleMask::new(gpu, 1)?;
                &own_mask
            }
        };
        let (layout, bind_group) = bind_buffers(
            gpu,
            "path_trace",
            &[
                (Access::Uniform, &params),
                (Access::ReadWrite, &radiance.buffer),
                (Access::ReadWrite, &counters),
                (Access::ReadWrite, &hit_points.buffer),
                (Access::Read, radii),
                (Access::Read, photon_hits),
                (Access::Read, photon_grid),
                (Access::Read, &mask.buffer),
            ],
        );
        let defs = glossy_defs(self.params.glossy_threshold, scene);
        let pipeline = ctx.shaders.compute_pipeline_with(
            gpu,
            &SHADER,
            "main",
            &[&scene.layout, &layout],
            defs,
        )?;
        let splat_pipeline = splat
            .then(|| {
                ctx.shaders.compute_pipeline_with(
                    gpu,
                    &SHADER,
                    "splat",
                    &[&scene.layout, &layout],
                    defs,
                )
            })
            .transpose()?;
        // The film's sides are at most MAX_FILM_SIDE, so its pixels fit a u32.
        let pixels = ctx.width * ctx.height;
        let per_invocation = items_per_invocation(
            gpu.info.device_type,
            pixels,
            self.params.samples_per_iteration,
            gpu.limits
                .max_compute_workgroups_per_dimension
                .saturating_mul(LANES),
        );
        let workgroups = pixels.div_ceil(per_invocation).div_ceil(LANES);
        self.prepared = Some(Prepared {
            pipeline,
            splat: splat_pipeline,
            splat_mode: splat_mode(&scene.uniform),
            fis_weight: if splat {
                filter_weight_per_sample(&scene.uniform)
            } else {
                1.0
            },
            scene: scene.bind_group.clone(),
            bind_group,
            params,
            counters,
            workgroups,
            width: ctx.width,
            height: ctx.height,
            max_depth,
            rr_depth,
            merge_slots,
            keep_hit_points: ctx.kept.contains("hit_points"),
            lookups: lookups.is_some(),
        });
        Ok(())
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        let record = ctx.first || !p.keep_hit_points;
        let spp = self.params.samples_per_iteration;
        let gpu_params = PathTraceUniform {
            sample_base: (ctx.iteration as u32).wrapping_mul(spp),
            samples_per_iteration: spp,
            seed: crate::passes::rng::camera_seed(ctx.seed),
            max_depth: p.max_depth,
            rr_depth: p.rr_depth,
            merge_depth: p.merge_slots,
            record: record as u32,
            trace_beyond: self.params.trace_beyond as u32,
            lookups: p.lookups as u32,
            splat: p.splat_mode,
            fis_weight: p.fis_weight,
            glossy_threshold: self.params.glossy_threshold,
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&gpu_params));
        recorder.dispatch(
            "path_trace",
            &p.pipeline,
            &[&p.scene, &p.bind_group],
            [p.workgroups, 1, 1],
        );
        if let Some(splat) = &p.splat {
            recorder.dispatch(
                "path_trace splat",
                splat,
                &[&p.scene, &p.bind_group],
                [p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1],
            );
        }
        Ok(())
    }

    fn samples_per_iteration(&self) -> u32 {
        self.params.samples_per_iteration
    }

    fn adaptive_refusal(&self) -> Option<&'static str> {
        match &self.prepared {
            Some(p) if p.merge_slots == 0 => None,
            _ => Some(
                "it records hit points, and the photon-mapping estimators count every pixel's \
                 photons in every iteration",
            ),
        }
    }

    fn transport(&self, slot: &str, ctx: &TransportCtx<'_>) -> Option<Transport> {
        use crate::passes::paths::{ALL, CAUSTIC, DEEP_CAUSTIC, UNMERGED};
        if slot != "radiance" {
            return Some(Transport::none());
        }
        let merges =
            ctx.consumed.contains("hit_points") && self.params.merge_depth != MergeDepth::Depth(0);
        let paths = match (merges, self.params.trace_beyond) {
            (false, _) => ALL,
            // What photon mapping adds at the photon-mapped vertices is dropped here.
            (true, true) => ALL & !CAUSTIC,
            // Paths stop at their first photon-mapped vertex.
            (true, false) => UNMERGED,
        };
        let depth = depth_rule(self.params.max_depth);
        // Which lobes are specular decides what the camera leaves to photons when it merges.
        let source = |paths: u32| match merges && self.params.trace_beyond {
            true => ctx.source_specular_below(paths, depth, self.params.glossy_threshold),
            false => ctx.source(paths, depth),
        };
        match ctx.inputs.get("photon_grid") {
            // The grid's photons add the deeper caustics the camera then drops.
            Some(grid) => Some(source(paths & !DEEP_CAUSTIC).and(grid)),
            None => Some(source(paths)),
        }
    }

    fn state(&self) -> Vec<(&'static str, &wgpu::Buffer)> {
        self.prepared
            .iter()
            .map(|p| ("counters", &p.counters))
            .collect()
    }

    fn counters(&self, gpu: &GpuContext) -> Result<Counters, Error> {
        let Some(p) = &self.prepared else {
            return Ok(Counters::default());
        };
        let c: Vec<u32> = gpu.read_pod(&p.counters, 4)?;
        let wide = |lo: u32, hi: u32| (hi as u64) << 32 | lo as u64;
        Ok(Counters::of(&[
            ("rays", wide(c[0], c[1])),
            ("discarded_samples", wide(c[2], c[3])),
        ]))
    }
}
