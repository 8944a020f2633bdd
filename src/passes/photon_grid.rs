//! `photon_grid`: this iteration's caustic photon hits in a hash grid with one global search
//! radius, for the camera pass to look up at diffuse vertices past its hit points (docs/design.md
//! section 1, the photon grid). The radius shrinks with the global iteration number
//! by Knaus & Zwicker's schedule (2011, "Progressive Photon Mapping: A Probabilistic Approach",
//! eq. 20): r_i^2 = r_1^2 * prod_{k<i} (k + alpha) / (k + 1). Each iteration's lookups are an
//! independent density estimate; the camera's running mean averages them, so the looked-up
//! caustic converges as the radius shrinks, with no per-pixel statistics.
//!
//! The first radius follows the photon count: a lookup would find `lookup_photons` photons if
//! this iteration's hits covered the scene's bounding disc evenly, r_1 = R sqrt(lookup_photons /
//! hits). Photons per iteration follow the pixel count, so a radius fixed to the scene would make
//! every lookup walk more photons as the image grows (cost in pixels squared: 113 s per
//! iteration at 1024x1024, BENCHMARKS.md); this way a lookup's expected work is bounded whatever
//! the image, and only the scene's own concentration of caustics (a constant) multiplies it. The
//! rule uses the hit capacity, known before rendering, rather than counting this iteration's
//! hits, so that every shard and resumed render steps the very same radii. `radius` caps r_1 (as
//! a fraction of R), so small images keep a kernel no wider than they had.
//!
//! Why: with sppm at the first diffuse vertex only, a caustic seen after a diffuse bounce
//! (`L S+ D D E`, the ceiling lit by a glass sphere's caustic) is left to path tracing, where a
//! small light makes it fireflies; hit points at every depth cost a slot per vertex per pixel.
//! Here the cost is one list walk per later diffuse vertex.

use serde::Deserialize;

use crate::Error;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::dispatch::workgroup_grid;
use crate::gpu::layout::StructLayout;
use crate::gpu::shaders::ShaderFile;
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{
    ExecCtx, Pass, PassKind, PrepareCtx, Recorder, ResourceKind, Size, SlotDecl, params_error,
    parse_params,
};
use crate::graph::transport::{Transport, TransportCtx};
use crate::passes::hit_points::PHOTON_HITS;
use crate::passes::pppm::RadiusSchedule;
use crate::{shader_file, struct_layout};

const SHADER: ShaderFile = shader_file!("shaders/passes/photon_grid.wgsl");
/// `WORKGROUP_SIZE` in shaders/gpu/dispatch.wgsl.
const WORKGROUP: u64 = 256;
/// Cell edge = 2 * radius * (1 + CELL_MARGIN): the sphere around a lookup point then spans at
/// most 2 cells per axis even after rounding.
const CELL_MARGIN: f32 = 1.0 / 64.0;
/// Smallest radius as a fraction of the scene's bounding radius, as for hit points.
const MIN_RADIUS_FRACTION: f32 = crate::passes::hit_points::MIN_RADIUS_FRACTION;
/// 8: at 128x128 (16,384 caustic photons) the cap `radius` 0.02 still decides, so the radius
/// measured there (BENCHMARKS.md) is kept; from about 141x141 up the photon count does.
pub const DEFAULT_LOOKUP_PHOTONS: f32 = 8.0;
/// Most photon hits the grid lists (links and heads share one u32-indexed buffer).
const MAX_PHOTON_HITS: u64 = 1 << 29;

/// Precedes the words of a grid; mirrors `PhotonGridInfo` in shaders/common/photon_grid.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PhotonGridInfo {
    pub radius: f32,
    pub inv_cell: f32,
    pub bucket_mask: u32,
    pub count: u32,
    pub center: [f32; 3],
    pub _pad: u32,
}

/// `PhotonGridUniform` in the shader, written every iteration.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct PhotonGridUniform {
    radius: f32,
    inv_cell: f32,
    bucket_mask: u32,
    _pad_a: u32,
    center: [f32; 3],
    _pad_b: u32,
}

const LAYOUTS: &[StructLayout] = &[
    struct_layout!(PhotonGridUniform => "PhotonGridUniform" in SHADER, { radius, inv_cell, bucket_mask, center }),
    struct_layout!(PhotonGridInfo => "PhotonGridInfo" in SHADER, {
        radius, inv_cell, bucket_mask, count, center
    }),
];

/// A `PhotonGridInfo`, then u32 words: `bucket_count(hits)` list heads, then one link per photon
/// hit. A head or link is a photon hit's index + 1; 0 ends a list.
pub const PHOTON_GRID: ResourceKind = ResourceKind::new(
    "photon_grid",
    std::mem::size_of::<PhotonGridInfo>() as u64,
    4,
);

/// List heads for `hits` photon hits: a power of two of at least twice the hits.
pub fn bucket_count(hits: u64) -> u64 {
    (2 * hits.max(1)).next_power_of_two()
}

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("photon_hits", PHOTON_HITS),
    // Zeroed by the graph every iteration: empty heads; links are written before a list
    // reaches them.
    SlotDecl::output("grid", PHOTON_GRID, Size::Computed),
];

pub const KIND: PassKind = PassKind {
    name: "photon_grid",
    description: "caustic photon hits in a hash grid with a global shrinking radius, looked up by the camera past its hit points",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: LAYOUTS,
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let params: PhotonGridParams = parse_params(params)?;
    if !(params.alpha > 0.0 && params.alpha < 1.0) {
        return Err(params_error(format!(
            "alpha must lie in (0, 1), got {}",
            params.alpha
        )));
    }
    if !(params.radius > MIN_RADIUS_FRACTION && params.radius <= 1.0) {
        return Err(params_error(format!(
            "radius (the largest first search radius as a fraction of the scene's bounding \
             radius) must lie in ({MIN_RADIUS_FRACTION}, 1], got {}",
            params.radius
        )));
    }
    if !(params.lookup_photons.is_finite() && params.lookup_photons > 0.0) {
        return Err(params_error(format!(
            "lookup_photons (photons a first-iteration lookup expects if the hits covered the \
             scene evenly) must be positive, got {}",
            params.lookup_photons
        )));
    }
    Ok(Box::new(PhotonGrid::new(params)))
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhotonGridParams {
    /// Largest first search radius, as a fraction of the scene's bounding radius R.
    pub radius: f32,
    /// Photons a first-iteration lookup would find if the iteration's photon hits covered a disc
    /// of radius R evenly: sets r_1 = R sqrt(lookup_photons / hits), capped by `radius`.
    pub lookup_photons: f32,
    /// Knaus & Zwicker's alpha in (0, 1): how fast the radius shrinks.
    pub alpha: f32,
}

impl Default for PhotonGridParams {
    fn default() -> Self {
        Self {
            radius: 0.02,
            lookup_photons: DEFAULT_LOOKUP_PHOTONS,
            alpha: 0.7,
        }
    }
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    groups: [u32; 3],
    first_radius: f64,
    min_radius: f32,
    bucket_mask: u32,
    center: [f32; 3],
}

pub struct PhotonGrid {
    params: PhotonGridParams,
    prepared: Option<Prepared>,
    schedule: RadiusSchedule,
}

impl PhotonGrid {
    pub fn new(params: PhotonGridParams) -> Self {
        Self {
            params,
            prepared: None,
            schedule: RadiusSchedule::new(params.alpha as f64),
        }
    }
}

/// r_1 / R for a grid of `hits` photon hits per iteration: the count rule, capped.
pub fn first_radius_fraction(params: PhotonGridParams, hits: u64) -> f64 {
    let by_count = (params.lookup_photons as f64 / hits.max(1) as f64).sqrt();
    by_count.min(params.radius as f64)
}

fn hit_capacity(len: u64) -> Result<u64, Error> {
    if len > MAX_PHOTON_HITS {
        return Err(Error::Other(format!(
            "photon_grid: {len} photon hits are more than the grid lists (at most {MAX_PHOTON_HITS})"
        )));
    }
    Ok(len)
}

impl Pass for PhotonGrid {
    fn output_len(&self, _slot: &str, ctx: &PrepareCtx<'_>) -> Result<u64, Error> {
        let hits = hit_capacity(ctx.input("photon_hits")?.len)?;
        Ok(bucket_count(hits) + hits)
    }

    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        let photon_hits = ctx.input("photon_hits")?;
        let grid = ctx.output("grid")?;
        let hits = hit_capacity(photon_hits.len)?;
        // At most 2^30 by MAX_PHOTON_HITS, so it fits the kernels' u32.
        let bucket_mask = (bucket_count(hits) - 1) as u32;
        let params = gpu.create_buffer(
            "photon_grid params",
            std::mem::size_of::<PhotonGridUniform>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let (layout, bind_group) = bind_buffers(
            gpu,
            "photon_grid",
            &[
                (Access::Read, &photon_hits.buffer),
                (Access::Uniform, &params),
                (Access::ReadWrite, &grid.buffer),
            ],
        );
        let pipeline = ctx
            .shaders
            .compute_pipeline(gpu, &SHADER, "main", &[&layout])?;
        let groups = u32::try_from(hits.div_ceil(WORKGROUP).max(1))
            .map_err(|_| Error::Other("photon_grid: too many photon hits".into()))?;
        let u = &scene.uniform;
        let center = std::array::from_fn(|i| 0.5 * (u.bounds_min[i] + u.bounds_max[i]));
        self.prepared = Some(Prepared {
            pipeline,
            bind_group,
            params,
            groups: workgroup_grid(groups),
            first_radius: first_radius_fraction(self.params, hits) * u.scene_radius as f64,
            min_radius: MIN_RADIUS_FRACTION * u.scene_radius,
            bucket_mask,
            center,
        });
        Ok(())
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        // pppm's schedule: the same product, stepped in the same order on any shard or resume.
        let scale = self.schedule.ratio_at(ctx.iteration).sqrt();
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        let radius = ((p.first_radius * scale) as f32).max(p.min_radius);
        let params = PhotonGridUniform {
            radius,
            inv_cell: 1.0 / (2.0 * radius * (1.0 + CELL_MARGIN)),
            bucket_mask: p.bucket_mask,
            _pad_a: 0,
            center: p.center,
            _pad_b: 0,
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&params));
        recorder.dispatch("photon_grid", &p.pipeline, &[&p.bind_group], p.groups);
        Ok(())
    }

    fn follows_pixels(&self) -> bool {
        false
    }

    /// The photons' caustics, as looked up at diffuse vertices past the camera's hit points.
    fn transport(&self, _slot: &str, ctx: &TransportCtx<'_>) -> Option<Transport> {
        use crate::passes::paths::{CAUSTIC, DEEP_CAUSTIC};
        let photons = ctx.inputs.get("photon_hits")?;
        Some(photons.relabel(CAUSTIC, DEEP_CAUSTIC))
    }
}
