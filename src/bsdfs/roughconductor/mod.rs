//! Mitsuba's `roughconductor`: a microfacet reflection (Beckmann or GGX, anisotropic along the
//! tangent of the frame built from the normal) with the conductor's Fresnel term; one-sided.

use glam::{Vec2, Vec3};

use crate::bsdfs::conductor::{pack_index, read_index};
use crate::bsdfs::shared::fresnel::{fresnel_conductor, reflect};
use crate::bsdfs::shared::microfacet::Microfacet;
use crate::bsdfs::shared::{Alphas, microfacet};
use crate::bsdfs::{BsdfPlugin, BsdfReader, Glossy, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: true,
    continuous: true,
    transmits: false,
    pass_through: false,
};

const MODULE: &str = "bsdfs::roughconductor";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "roughconductor",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["roughconductor"],
        properties: &[
            p("material", "none"),
            p("eta", ""),
            p("k", ""),
            p("specular_reflectance", "1"),
            p("distribution", "beckmann"),
            p("alpha", "0.1"),
            p("alpha_u", ""),
            p("alpha_v", ""),
            p("sample_visible", "true"),
        ],
        notes: "As `conductor`, rough; anisotropic along the tangent of the frame built from \
                the normal (Mitsuba orients it along dp/du).",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "roughconductor_eval")),
        sample: Some(WgslCall::new(MODULE, "roughconductor_sample")),
        glossy: Glossy::Whole,
        ..GpuKind::inline("roughconductor", LOBES)
    }],
    def: Some("CONDUCTOR"),
    wgsl: Some(crate::shader_file!(
        "src/bsdfs/roughconductor/roughconductor.wgsl"
    )),
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughConductor {
    pub eta: Vec3,
    pub k: Vec3,
    pub specular: Vec3,
    pub microfacet: Microfacet,
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let (eta, k) = read_index(r)?;
    let (specular, texture) = r.color_or_texture("specular_reflectance", 1.0)?;
    textures.specular = texture;
    let microfacet = microfacet(r, Alphas::Textured, &mut textures)?;
    let model = RoughConductor {
        eta,
        k,
        specular,
        microfacet,
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

impl BsdfModel for RoughConductor {
    fn kind(&self) -> &'static str {
        "roughconductor"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn roughness(&self) -> Option<f32> {
        Some(self.microfacet.roughness())
    }

    fn is_valid(&self) -> bool {
        self.eta.is_finite()
            && self.k.is_finite()
            && self.specular.is_finite()
            && self.microfacet.is_valid()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return Vec3::ZERO;
        }
        let mf = &self.microfacet;
        let h = (wi + wo).normalize();
        let d = mf.d(h);
        let g = mf.g1(wi, h) * mf.g1(wo, h);
        fresnel_conductor(wi.dot(h), self.eta, self.k) * self.specular * (d * g / (4.0 * ci))
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return 0.0;
        }
        let h = (wi + wo).normalize();
        self.microfacet.d(h) * self.microfacet.g1(wi, h) / (4.0 * ci)
    }

    fn sample(&self, wi: Vec3, _u1: f32, u2: Vec2, _mode: Mode) -> Option<Sample> {
        if wi.z <= 0.0 {
            return None;
        }
        let mf = &self.microfacet;
        let m = mf.sample(wi, u2);
        let wo = reflect(wi, m);
        let pdf = mf.pdf(wi, m) / (4.0 * wo.dot(m));
        if pdf.is_nan() || pdf <= 0.0 || wo.z <= 0.0 {
            return None;
        }
        let weight = fresnel_conductor(wi.dot(m), self.eta, self.k) * self.specular * mf.g1(wo, m);
        Some(Sample {
            wo,
            weight,
            pdf,
            delta: false,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        pack_index(record, self.eta, self.k, self.specular);
        self.microfacet.pack(record);
    }
}
