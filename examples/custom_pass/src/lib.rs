//! A pass kind written outside hppm: `tonemap`, which takes an image (a graph's radiance) and
//! writes it scaled by 2^`exposure` through a tone curve, with its own WGSL module
//! (`custom::tone_curves`, which imports one of hppm's). [`registry`] is hppm's built-in
//! registry with this kind and module added; `src/main.rs` runs hppm's whole command line with
//! it, and `graphs/hybrid_tonemapped.ron` is a graph that uses the node.
//!
//! A pass declares everything the graph checks in its [`PassKind`]: slots, the shaders it
//! compiles, the structs it uploads (checked against the WGSL by
//! [`Registry::check_layouts`]) and a constructor that parses its `params`.

use hppm::Error;
use hppm::gpu::binding::{Access, bind_buffers};
use hppm::gpu::layout::StructLayout;
use hppm::gpu::shaders::ShaderFile;
use hppm::graph::pass::{
    ExecCtx, IMAGE, Pass, PassKind, PrepareCtx, Recorder, Size, SlotDecl, params_error,
    parse_params,
};
use hppm::passes::Registry;
use serde::Deserialize;

/// The WGSL module of tone curves this crate adds to the registry.
pub const TONE_CURVES: ShaderFile = hppm::shader_file!("shaders/tone_curves.wgsl");
const SHADER: ShaderFile = hppm::shader_file!("shaders/tonemap.wgsl");
const WORKGROUP: u32 = 8;

static SLOTS: &[SlotDecl] = &[
    SlotDecl::input("image", IMAGE),
    SlotDecl::output("mapped", IMAGE, Size::Pixels),
];

const PARAMS_LAYOUT: StructLayout = hppm::struct_layout!(TonemapUniform => "TonemapUniform" in SHADER, {
    width, height, curve, scale
});

pub const KIND: PassKind = PassKind {
    name: "tonemap",
    description: "display image: radiance times 2^exposure through a tone curve (linear, \
                  Reinhard, ACES)",
    slots: SLOTS,
    shaders: &[SHADER],
    layouts: &[PARAMS_LAYOUT],
    construct,
};

/// hppm's built-in passes, modules and scene needs, with `tonemap` and its module.
pub fn registry() -> Registry {
    Registry::builtin().with_module(TONE_CURVES).with(&KIND)
}

/// The curve from scaled radiance to display values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
pub enum Curve {
    /// None: the scaled radiance as it is.
    Linear,
    /// Reinhard et al. 2002 on luminance: c / (1 + L(c)).
    Reinhard,
    /// Narkowicz's 2016 fit of the ACES filmic curve, per channel.
    #[default]
    Aces,
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TonemapParams {
    /// Stops: the radiance is scaled by 2^exposure before the curve.
    pub exposure: f32,
    pub curve: Curve,
}

impl Default for TonemapParams {
    fn default() -> Self {
        Self {
            exposure: 0.0,
            curve: Curve::default(),
        }
    }
}

fn construct(params: &str) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    let params: TonemapParams = parse_params(params)?;
    if !params.exposure.is_finite() {
        return Err(params_error(format!(
            "exposure is a number of stops, got {}",
            params.exposure
        )));
    }
    Ok(Box::new(Tonemap {
        params,
        prepared: None,
    }))
}

/// What the CPU computes for one pixel's mean radiance `rgb`: the kernel's reference.
pub fn tonemap(rgb: [f32; 3], params: TonemapParams) -> [f32; 3] {
    let scale = params.exposure.exp2();
    let c = rgb.map(|v| v * scale);
    match params.curve {
        Curve::Linear => c,
        Curve::Reinhard => {
            let l = hppm::scene::texture::luminance(glam::Vec3::from(c));
            c.map(|v| v / (1.0 + l))
        }
        Curve::Aces => c.map(|v| {
            let x = v.max(0.0);
            (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
        }),
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TonemapUniform {
    width: u32,
    height: u32,
    curve: u32,
    scale: f32,
}

struct Prepared {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    width: u32,
    height: u32,
}

struct Tonemap {
    params: TonemapParams,
    prepared: Option<Prepared>,
}

impl Pass for Tonemap {
    fn prepare(&mut self, ctx: PrepareCtx<'_>) -> Result<(), Error> {
        let gpu = ctx.gpu;
        let image = ctx.input("image")?;
        let mapped = ctx.output("mapped")?;
        let curve = match self.params.curve {
            Curve::Linear => 0,
            Curve::Reinhard => 1,
            Curve::Aces => 2,
        };
        let params = TonemapUniform {
            width: ctx.width,
            height: ctx.height,
            curve,
            scale: self.params.exposure.exp2(),
        };
        let params = gpu.create_buffer_init(
            "tonemap params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let (layout, bind_group) = bind_buffers(
            gpu,
            "tonemap",
            &[
                (Access::Uniform, &params),
                (Access::Read, &image.buffer),
                (Access::ReadWrite, &mapped.buffer),
            ],
        );
        let pipeline = ctx
            .shaders
            .compute_pipeline(gpu, &SHADER, "main", &[&layout])?;
        self.prepared = Some(Prepared {
            pipeline,
            bind_group,
            width: ctx.width,
            height: ctx.height,
        });
        Ok(())
    }

    fn execute(&mut self, _ctx: &ExecCtx<'_>, recorder: &mut Recorder<'_>) -> Result<(), Error> {
        let Some(p) = &self.prepared else {
            return Ok(());
        };
        recorder.dispatch(
            "tonemap",
            &p.pipeline,
            &[&p.bind_group],
            [p.width.div_ceil(WORKGROUP), p.height.div_ceil(WORKGROUP), 1],
        );
        Ok(())
    }

    // A display image is not a sum over iterations: shards of it cannot be added up.
    fn shard_refusal(&self) -> Option<&'static str> {
        Some("a tone-mapped image is not a sum of its iterations' radiance")
    }
}
