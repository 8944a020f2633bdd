//! `resolve`: the final image, path-traced radiance plus photon-mapped radiance. Without a
//! `caustic` input it is the path-traced image alone. Outputs `combined` and `radius` (each
//! pixel's first hit-point search radius, in scene units, for debugging); with `hppm render
//! --aovs` its `pt` and `caustic` inputs are written too.

use serde::Deserialize;

use crate::Error;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::shaders::ShaderFile;
use crate::gpu_scene::SceneResources;
use crate::graph::pass::{
    ExecCtx, IMAGE, Pass, PassKind, PrepareCtx, Recorder, Size, SlotDecl, parse_params,
};
use crate::passes::hit_points::HIT_POINTS;
use crate::shader_file;

const SHADER: ShaderFile = shader_file!("shaders/passes/resolve.wgsl");
const WORKGROUP: u32 = 8;

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("pt", IMAGE),
    SlotDecl::input("caustic", IMAGE).optional(),
    // Only for the radius AOV: it must not make the camera pass record hit points.
    SlotDecl::input("hit_points", HIT_POINTS)
        .optional()
        .observe_only(),
    SlotDecl::output("combined", IMAGE, Size::Pixels),
    SlotDecl::output("radius", IMAGE, Size::Pixels),
];

/// `ResolveUniform` against its namesake in the shader.
const PARAMS_LAYOUT: crate::gpu::layout::StructLayout = crate::struct_layout!(ResolveUniform => "ResolveUniform" in SHADER, {
    width, height, has_caustic, has_hit_points
});

pub const KIND: PassKind = PassKind {
    name: "resolve",
    description: "final image: path-traced + photon-mapped radiance (AOVs pt, caustic, radius)",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: &[PARAMS_LAYOUT],
    construct,
};

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let _: ResolveParams = parse_params(params)?;
    Ok(Box::new(Resolve { prepared: None }))
}

/// No parameters yet; declared so that unknown ones are rejected.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct ResolveParams {}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ResolveUniform {
    width: u32,
    height: u32,
    has_caustic: u32,
    has_hit_points: u32,
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    scene: wgpu::BindGroup,
    bind_group: wgpu::BindGroup,
    width: u32,
    height: u32,
}

pub struct Resolve {
    prepared: Option<Prepared>,
}

impl Pass for Resolve {
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let scene = ctx.shared.get::<SceneResources>()?;
        let pt = ctx.input("pt")?;
        let caustic = ctx.inputs.get("caustic");
        let hit_points = ctx.inputs.get("hit_points");
        // Unconnected optional inputs are bound to a small placeholder the kernel never reads.
        let placeholder =
            gpu.create_buffer("resolve placeholder", 64, wgpu::BufferUsages::STORAGE)?;
        let combined = ctx.output("combined")?;
        let radius = ctx.output("radius")?;
        let params = ResolveUniform {
            width: ctx.width,
            height: ctx.height,
            has_caustic: caustic.is_some() as u32,
            has_hit_points: hit_points.is_some_and(|h| h.len > 0) as u32,
        };
        let params = gpu.create_buffer_init(
            "resolve params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let (layout, bind_group) = bind_buffers(
            gpu,
            "resolve",
            &[
                (Access::Uniform, &params),
                (Access::Read, &pt.buffer),
                (Access::Read, caustic.map_or(&placeholder, |r| &r.buffer)),
                (Access::Read, hit_points.map_or(&placeholder, |r| &r.buffer)),
                (Access::ReadWrite, &combined.buffer),
                (Access::ReadWrite, &radius.buffer),
            ],
        );
        let pipeline =
            ctx.shaders
                .compute_pipeline(gpu, &SHADER, "main", &[&scene.layout, &layout])?;
        self.prepared = Some(Prepared {
            pipeline,
            scene: scene.bind_group.clone(),
            bind_group,
            width: ctx.width,
            height: ctx.height,
        });
        Ok(())
    }

    fn output_terms(&self, slot: &str) -> Option<&'static [&'static str]> {
        // combined = mean(pt) + mean(caustic), as resolve.wgsl computes it.
        (slot == "combined").then_some(&["pt", "caustic"][..])
    }

    fn execute(&mut self, _ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        recorder.dispatch(
            "resolve",
            &p.pipeline,
            &[&p.scene, &p.bind_group],
            [p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1],
        );
        Ok(())
    }
}
