//! A BSDF written outside hppm: Minnaert's darkening law (Minnaert 1941, "The reciprocity
//! principle in lunar photometry"), read from Mitsuba XML as `<bsdf type="minnaert">`, with
//! `reflectance` (a colour or a texture, 0.5 by default) and `k` (1 by default, Lambertian;
//! at least 1, darker towards grazing). Normalised so that its albedo seen from straight above
//! is its reflectance:
//!
//! f(wi, wo) = reflectance (k + 1) / (2 pi) (cos wi cos wo)^(k - 1).
//!
//! Everything about it is here: the properties it reads ([`PLUGIN`]'s `reads` and `read`), its
//! model (the CPU eval, pdf and sample, its lobes for the light-transport partition, its packing
//! into the GPU record) and its WGSL (`minnaert.wgsl`). hppm's source never names it: a program
//! registers it ([`registry`]), and its scenes, `pt`, the hybrid and every other graph then
//! render it. For the partition it is continuous (path traced, never photon mapped).

use glam::{Vec2, Vec3};
use hppm::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use hppm::passes::Registry;
use hppm::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use hppm::scene::plugin::{Plugin, p};
use hppm::scene::{SceneError, SideTextures};

const MODULE: &str = "custom_bsdf::minnaert";

/// A continuous lobe that light sampling reaches: path traced at every vertex.
const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: false,
    continuous: true,
    transmits: false,
    pass_through: false,
};

/// The unit: what hppm's registry needs to read, number, compile and dispatch it.
pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "minnaert",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["minnaert"],
        properties: &[p("reflectance", "0.5"), p("k", "1")],
        notes: "Minnaert's darkening law (examples/custom_bsdf): `reflectance` a colour or \
                texture, `k` at least 1.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "minnaert_eval")),
        sample: Some(WgslCall::new(MODULE, "minnaert_sample")),
        ..GpuKind::inline("minnaert", LOBES)
    }],
    def: Some("MINNAERT"),
    wgsl: Some(hppm::shader_file!("src/minnaert.wgsl")),
};

/// hppm's built-in registry with `minnaert` added.
pub fn registry() -> Registry {
    Registry::builtin().with_bsdf(&PLUGIN)
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Minnaert {
    pub reflectance: Vec3,
    pub k: f32,
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let (reflectance, texture) = r.color_or_texture("reflectance", 0.5)?;
    let k = r.float("k")?.unwrap_or(1.0);
    if !(k >= 1.0 && k.is_finite()) {
        return Err(r.error_at("k", format!("k {k}: must be at least 1 (1 is Lambertian)")));
    }
    let textures = SideTextures {
        diffuse: texture,
        ..SideTextures::default()
    };
    Ok(Sides::one(Bsdf::new(Minnaert { reflectance, k }), textures))
}

impl Minnaert {
    /// The density of a direction with cosine `cos_o` drawn from cos^k.
    fn density(&self, cos_o: f32) -> f32 {
        (self.k + 1.0) / (2.0 * std::f32::consts::PI) * cos_o.powf(self.k)
    }
}

impl BsdfModel for Minnaert {
    fn kind(&self) -> &'static str {
        "minnaert"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        self.reflectance.is_finite() && self.k.is_finite() && self.k >= 1.0
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let norm = (self.k + 1.0) / (2.0 * std::f32::consts::PI);
        self.reflectance * (norm * (wi.z * wo.z).powf(self.k - 1.0) * wo.z)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        self.density(wo.z)
    }

    fn sample(&self, wi: Vec3, _u1: f32, u2: Vec2, _mode: Mode) -> Option<Sample> {
        if wi.z <= 0.0 {
            return None;
        }
        let cos_o = u2.x.powf(1.0 / (self.k + 1.0));
        let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u2.y;
        let wo = Vec3::new(sin_o * phi.cos(), sin_o * phi.sin(), cos_o);
        let pdf = self.density(cos_o);
        (pdf > 0.0).then(|| Sample {
            wo,
            weight: self.reflectance * wi.z.powf(self.k - 1.0),
            pdf,
            delta: false,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        record.albedo = self.reflectance.to_array();
        record.alpha_u = self.k;
    }
}
