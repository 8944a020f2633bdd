//! `photon_trace`: emits `photons_per_iteration` photons, traces them through specular surfaces
//! and writes a photon hit wherever one deposits (`photon_hits`, emptied by the graph before
//! every iteration). Which hit points receive each photon is the gather's business: the
//! hit-point structure nodes (`hit_point_bvh_sah`, `hit_point_bvh_lbvh`, `hit_point_grid`).

use serde::Deserialize;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{
    Counters, ExecCtx, Pass, PassKind, PrepareCtx, Recorder, SceneNeed, Size, SlotDecl,
    params_error, parse_params,
};
use crate::graph::transport::{Transport, TransportCtx};
use crate::passes::hit_points::PHOTON_HITS;
use crate::passes::lanes::items_per_invocation;
use crate::passes::{
    SPECULAR_OR_GLOSSY_SURFACE, SPECULAR_SURFACE, check_glossy_threshold, depth_rule, glossy_defs,
    resolve_depths,
};
use crate::shader_file;

const SHADER: crate::gpu::shaders::ShaderFile = shader_file!("shaders/passes/photon_trace.wgsl");
const WORKGROUP: u32 = 64;
/// Workgroups per row of the dispatch grid (wgpu's limit per dimension is 65535).
const GROUPS_PER_ROW: u32 = 32768;
/// Photons per iteration per image pixel when the graph does not say, by mode. Caustic: of 1/2,
/// 1 and 4 per pixel, 1 gave the lowest error after equal time on both the glass Cornell box and
/// the point-light caustic (BENCHMARKS.md). All (photon mapping alone, where photons carry every
/// bounce of indirect light): 4.
pub const DEFAULT_PHOTONS_PER_PIXEL_CAUSTIC: u32 = 1;
pub const DEFAULT_PHOTONS_PER_PIXEL_ALL: u32 = 4;
/// Photon hits stored per photon in mode All (a photon deposits at every diffuse vertex); hits
/// beyond are counted as `photon_hits_dropped`. Caustic mode deposits at most once per photon.
pub const ALL_MODE_HITS_PER_PHOTON: u64 = 8;

static SLOTS: &[SlotDecl] = &[SlotDecl::output("photon_hits", PHOTON_HITS, Size::Computed)];

/// `PhotonUniform` against its namesake in the shader.
const PARAMS_LAYOUT: crate::gpu::layout::StructLayout = crate::struct_layout!(PhotonUniform => "PhotonUniform" in SHADER, {
    photons, seed, iteration, mode, max_depth, rr_depth, flux_scale, groups_per_row, aim,
    glossy_threshold, invocations, aim_center, aim_radius
});

pub const KIND: PassKind = PassKind {
    name: "photon_trace",
    description: "photons from the lights through specular surfaces, to where they deposit",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: &[PARAMS_LAYOUT],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let params: PhotonTraceParams = parse_params(params)?;
    if params.photons_per_iteration == Some(0) {
        return Err(params_error(
            "photons_per_iteration must be at least 1 (leave it out for the default)".into(),
        ));
    }
    if params.max_depth == Some(0) {
        return Err(params_error("max_depth must be at least 1".into()));
    }
    check_glossy_threshold(params.glossy_threshold)?;
    Ok(Box::new(PhotonTrace::new(params)))
}

/// Where photons are deposited.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum PhotonMode {
    /// Only at the first diffuse vertex after one or more specular ones, then stop (hybrid).
    Caustic,
    /// At every diffuse vertex, continuing the path (photon mapping alone).
    All,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhotonTraceParams {
    pub mode: PhotonMode,
    /// `None`: DEFAULT_PHOTONS_PER_PIXEL_CAUSTIC or _ALL per pixel of the whole image, cut to
    /// the photon hits one storage binding holds.
    pub photons_per_iteration: Option<u32>,
    /// Longest full path (camera segments + photon segments); `None` takes the scene's.
    pub max_depth: Option<u32>,
    /// Photon segments after which Russian roulette starts; `None` takes the scene's.
    pub rr_depth: Option<u32>,
    /// Caustic mode: emit only towards the sphere around the specular surfaces (unbiased: other
    /// photons could not become caustic photons). `false` emits over the whole emission lobe.
    pub aim: bool,
    /// Caustic mode: microfacet lobes whose roughness (the larger of alpha_u and alpha_v, at
    /// the surface point) is below this are specular vertices, through which caustic photons
    /// continue (docs/design.md section 1). Must equal the camera pass's; 0 (the default): only
    /// delta lobes.
    pub glossy_threshold: f32,
}

impl Default for PhotonTraceParams {
    fn default() -> Self {
        Self {
            mode: PhotonMode::Caustic,
            photons_per_iteration: None,
            max_depth: None,
            rr_depth: None,
            aim: true,
            glossy_threshold: 0.0,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PhotonUniform {
    photons: u32,
    seed: u32,
    iteration: u32,
    mode: u32,
    max_depth: u32,
    rr_depth: u32,
    flux_scale: f32,
    groups_per_row: u32,
    aim: u32,
    glossy_threshold: f32,
    invocations: u32,
    _pad: u32,
    aim_center: [f32; 3],
    aim_radius: f32,
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    scene: wgpu::BindGroup,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    counters: wgpu::Buffer,
    emitted: wgpu::Buffer,
    photons: u32,
    /// The dispatch: workgroups, and per row of the grid; each lane takes every
    /// `invocations`-th photon (several in turn on CPU adapters, `lanes`).
    groups: u32,
    groups_per_row: u32,
    invocations: u32,
    max_depth: u32,
    rr_depth: u32,
    /// The sphere photons aim at (centre, radius): around the specular surfaces, and the glossy
    /// ones too when they can be specular vertices.
    aim_sphere: [f32; 4],
}

pub struct PhotonTrace {
    params: PhotonTraceParams,
    prepared: Option<Prepared>,
}

impl PhotonTrace {
    pub fn new(params: PhotonTraceParams) -> Self {
        Self {
            params,
            prepared: None,
        }
    }

    /// RGB flux emitted so far, summed over iterations (each iteration's photons carry the
    /// lights' total power between them). Reads back.
    pub fn emitted_flux(&self, gpu: &GpuContext) -> Result<[f32; 3], Error> {
        let Some(p) = &self.prepared else {
            return Ok([0.0; 3]);
        };
        let v: Vec<f32> = gpu.read_pod(&p.emitted, 3)?;
        Ok([v[0], v[1], v[2]])
    }
}

impl PhotonTrace {
    /// Photons per iteration: the param, else a default per pixel of the whole image (not of a
    /// tile: every tile then traces the very photons the whole image would, so a tiled render
    /// is the untiled one), by mode, cut to what one storage binding of photon hits holds.
    fn photons(&self, ctx: &PrepareCtx<'_>) -> u32 {
        self.params.photons_per_iteration.unwrap_or_else(|| {
            let (per_pixel, hits_per_photon) = match self.params.mode {
                PhotonMode::Caustic => (DEFAULT_PHOTONS_PER_PIXEL_CAUSTIC, 1),
                PhotonMode::All => (DEFAULT_PHOTONS_PER_PIXEL_ALL, ALL_MODE_HITS_PER_PHOTON),
            };
            let binding = ctx.gpu.limits.max_storage_buffer_binding_size;
            let fit = binding.saturating_sub(PHOTON_HITS.header_bytes)
                / PHOTON_HITS.element_bytes
                / hits_per_photon;
            let wanted = ctx.film_pixels.saturating_mul(per_pixel as u64);
            u32::try_from(wanted.min(fit).max(1)).unwrap_or(u32::MAX)
        })
    }
}

/// (workgroups, workgroups per row, invocations launched) for `photons`: rows of at most
/// `GROUPS_PER_ROW`, and no more invocations than a u32 counts.
fn dispatch_grid(device: wgpu::DeviceType, photons: u32) -> (u32, u32, u32) {
    let row = WORKGROUP * GROUPS_PER_ROW;
    let per_invocation = items_per_invocation(device, photons, 1, (u32::MAX / row) * row);
    let groups = photons.div_ceil(per_invocation).div_ceil(WORKGROUP);
    let groups_per_row = groups.clamp(1, GROUPS_PER_ROW);
    let invocations = groups.div_ceil(groups_per_row) * groups_per_row * WORKGROUP;
    (groups, groups_per_row, invocations)
}

impl Pass for PhotonTrace {
    fn output_len(&self, _slot: &str, ctx: &PrepareCtx<'_>) -> Result<u64, Error> {
        let photons = self.photons(ctx) as u64;
        Ok(match self.params.mode {
            PhotonMode::Caustic => photons,
            PhotonMode::All => photons * ALL_MODE_HITS_PER_PHOTON,
        })
    }

    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        if scene.media && self.params.mode == PhotonMode::All {
            return Err(Error::Other(
                "photon_trace mode All (photon mapping alone) cannot render participating \
                 media: its photons would have to deposit in media too; render the scene with \
                 the hybrid or pt"
                    .into(),
            ));
        }
        let photon_hits = ctx.output("photon_hits")?;
        let photons = self.photons(&ctx);
        let params = gpu.create_buffer(
            "photon_trace params",
            std::mem::size_of::<PhotonUniform>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let counters = gpu.create_buffer(
            "photon_trace counters",
            16,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let emitted = gpu.create_buffer(
            "photon_trace emitted",
            16,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let (layout, bind_group) = bind_buffers(
            gpu,
            "photon_trace",
            &[
                (Access::Uniform, &params),
                (Access::ReadWrite, &photon_hits.buffer),
                (Access::ReadWrite, &counters),
                (Access::ReadWrite, &emitted),
            ],
        );
        let glossy = glossy_defs(self.params.glossy_threshold, scene);
        let pipeline = ctx.shaders.compute_pipeline_with(
            gpu,
            &SHADER,
            "main",
            &[&scene.layout, &layout],
            glossy,
        )?;
        let aim_sphere = if glossy.is_empty() {
            let [x, y, z] = scene.uniform.specular_center;
            [x, y, z, scene.uniform.specular_radius]
        } else {
            // Conservative: every microfacet surface, whatever its roughness.
            scene.glossy_sphere
        };
        let (max_depth, rr_depth) =
            resolve_depths(self.params.max_depth, self.params.rr_depth, &scene.uniform);
        let (groups, groups_per_row, invocations) = dispatch_grid(gpu.info.device_type, photons);
        self.prepared = Some(Prepared {
            pipeline,
            scene: scene.bind_group.clone(),
            bind_group,
            params,
            counters,
            emitted,
            photons,
            groups,
            groups_per_row,
            invocations,
            max_depth,
            rr_depth,
            aim_sphere,
        });
        Ok(())
    }

    fn execute(&mut self, ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        let gpu_params = PhotonUniform {
            photons: p.photons,
            seed: crate::passes::rng::photon_seed(ctx.seed),
            iteration: ctx.iteration as u32,
            mode: match self.params.mode {
                PhotonMode::Caustic => 0,
                PhotonMode::All => 1,
            },
            max_depth: p.max_depth,
            rr_depth: p.rr_depth,
            flux_scale: (1.0 / p.photons.max(1) as f64) as f32,
            groups_per_row: p.groups_per_row,
            aim: self.params.aim as u32,
            glossy_threshold: self.params.glossy_threshold,
            invocations: p.invocations,
            _pad: 0,
            aim_center: [p.aim_sphere[0], p.aim_sphere[1], p.aim_sphere[2]],
            aim_radius: p.aim_sphere[3],
        };
        ctx.gpu
            .queue
            .write_buffer(&p.params, 0, bytemuck::bytes_of(&gpu_params));
        if p.groups > 0 {
            recorder.dispatch(
                "photon_trace",
                &p.pipeline,
                &[&p.scene, &p.bind_group],
                [p.groups_per_row, p.groups.div_ceil(p.groups_per_row), 1],
            );
        }
        Ok(())
    }

    fn needs(&self) -> Vec<SceneNeed> {
        match self.params.mode {
            // Without a specular surface no photon is ever deposited.
            PhotonMode::Caustic if self.params.glossy_threshold > 0.0 => vec![SceneNeed {
                glossy_below: self.params.glossy_threshold,
                ..SPECULAR_OR_GLOSSY_SURFACE
            }],
            PhotonMode::Caustic => vec![SPECULAR_SURFACE],
            PhotonMode::All => Vec::new(),
        }
    }

    fn transport(&self, _slot: &str, ctx: &TransportCtx<'_>) -> Option<Transport> {
        use crate::passes::paths::{CAUSTIC, DEEP_CAUSTIC, DIRECT, INDIRECT};
        let paths = match self.params.mode {
            PhotonMode::Caustic => CAUSTIC,
            // Everything that reaches a hit point, deeper caustics included.
            PhotonMode::All => DIRECT | CAUSTIC | INDIRECT | DEEP_CAUSTIC,
        };
        let depth = depth_rule(self.params.max_depth);
        Some(match self.params.mode {
            // Which lobes are specular decides which photons are caustic photons.
            PhotonMode::Caustic => {
                ctx.source_specular_below(paths, depth, self.params.glossy_threshold)
            }
            PhotonMode::All => ctx.source(paths, depth),
        })
    }

    fn follows_pixels(&self) -> bool {
        false
    }

    fn photons_per_iteration(&self) -> u64 {
        self.prepared.as_ref().map_or(0, |p| p.photons as u64)
    }

    fn state(&self) -> Vec<(&'static str, &wgpu::Buffer)> {
        match &self.prepared {
            Some(p) => vec![("counters", &p.counters), ("emitted", &p.emitted)],
            None => Vec::new(),
        }
    }

    fn counters(&self, gpu: &GpuContext) -> Result<Counters, Error> {
        let Some(p) = &self.prepared else {
            return Ok(Counters::default());
        };
        let c: Vec<u32> = gpu.read_pod(&p.counters, 4)?;
        let wide = |lo: u32, hi: u32| (hi as u64) << 32 | lo as u64;
        Ok(Counters::of(&[
            ("photon_segments", wide(c[0], c[1])),
            ("photon_hits_dropped", wide(c[2], c[3])),
        ]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Catches a grid whose rows pass wgpu's 65535 limit, or whose invocation count wraps u32
    // (lanes would then skip or repeat photons).
    #[test]
    fn dispatch_grid_stays_within_limits() {
        use wgpu::DeviceType::{Cpu, DiscreteGpu};
        for device in [Cpu, DiscreteGpu] {
            for photons in [1, 64, 65, 16384, 1 << 26, u32::MAX / 2, u32::MAX] {
                let (groups, per_row, invocations) = dispatch_grid(device, photons);
                assert!(
                    groups.div_ceil(per_row) <= 65535,
                    "{photons}: {groups} groups"
                );
                assert!(per_row <= GROUPS_PER_ROW);
                assert!(invocations >= groups.saturating_mul(WORKGROUP).min(u32::MAX - 63));
                assert!(invocations > 0);
            }
        }
        assert_eq!(dispatch_grid(Cpu, 16384).2, 512);
        assert_eq!(dispatch_grid(DiscreteGpu, 16384).2, 16384);
    }
}
