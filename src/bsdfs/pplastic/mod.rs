//! Mitsuba's `pplastic` as its RGB variants render it (no polarisation): roughplastic's rough
//! coating with the dielectric Fresnel term, over a Lambertian base weighted by the two smooth
//! refractions through the interface, (1 - F(cos wi)) (1 - F(cos wo)); no internal reflections,
//! its lobes chosen with fixed probabilities.

use glam::{Vec2, Vec3};

use crate::bsdfs::plastic::Coated;
use crate::bsdfs::roughplastic::NO_TABLE;
use crate::bsdfs::roughplastic::{coating_or_base, coating_pdf, rough_reflection};
use crate::bsdfs::shared::fresnel::fresnel;
use crate::bsdfs::shared::microfacet::Microfacet;
use crate::bsdfs::shared::{Alphas, distinct_iors, microfacet};
use crate::bsdfs::{BsdfPlugin, BsdfReader, Glossy, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample, sample_from_eval};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: true,
    continuous: true,
    transmits: false,
    pass_through: false,
};

/// Its WGSL is roughplastic's, which takes a material without a transmittance table as this.
const MODULE: &str = "bsdfs::roughplastic";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "pplastic",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["pplastic"],
        properties: &[
            p("int_ior", "polypropylene"),
            p("ext_ior", "air"),
            p("diffuse_reflectance", "0.5"),
            p("specular_reflectance", "1"),
            p("distribution", "beckmann"),
            p("alpha", "0.1"),
            p("alpha_u", "0.1"),
            p("alpha_v", "0.1"),
            p("sample_visible", "true"),
        ],
        notes: "As Mitsuba's RGB variants render it (no polarisation): the rough reflection \
                with the dielectric Fresnel term plus the diffuse base weighted by (1 - F) at \
                wi and at wo; `alpha`, `alpha_u`, `alpha_v` numbers as in Mitsuba, both \
                reflectances may be textures.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "rough_plastic_eval")),
        sample: Some(WgslCall::new(MODULE, "rough_plastic_sample")),
        glossy: Glossy::Split {
            eval: WgslCall::new(MODULE, "rough_plastic_coating"),
            share: WgslCall::new(MODULE, "rough_plastic_coating_share"),
        },
        ..GpuKind::inline("pplastic", LOBES)
    }],
    def: Some("PLASTIC"),
    wgsl: None,
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarizedPlastic {
    pub coated: Coated,
    pub microfacet: Microfacet,
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let coated = Coated::read(r, &mut textures)?;
    distinct_iors(r, coated.int_ior, coated.ext_ior)?;
    let microfacet = microfacet(r, Alphas::Anisotropic, &mut textures)?;
    let model = PolarizedPlastic { coated, microfacet };
    Ok(Sides::one(Bsdf::new(model), textures))
}

impl BsdfModel for PolarizedPlastic {
    fn kind(&self) -> &'static str {
        "pplastic"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn roughness(&self) -> Option<f32> {
        Some(self.microfacet.roughness())
    }

    fn is_valid(&self) -> bool {
        self.coated.is_valid() && self.microfacet.is_valid()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return Vec3::ZERO;
        }
        let c = &self.coated;
        let eta = c.int_ior / c.ext_ior;
        let spec = c.specular * rough_reflection(&self.microfacet, eta, wi, wo);
        let (fi, fo) = (fresnel(ci, eta).0, fresnel(co, eta).0);
        spec + c.diffuse * ((1.0 - fi) * (1.0 - fo) * co * std::f32::consts::FRAC_1_PI)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return 0.0;
        }
        // Mitsuba's fixed lobe probabilities (no Fresnel term in them).
        let w = self.coated.specular_weight();
        let cosine = co.max(0.0) * std::f32::consts::FRAC_1_PI;
        w * coating_pdf(&self.microfacet, wi, wo) + (1.0 - w) * cosine
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        if wi.z <= 0.0 {
            return None;
        }
        let prob_diffuse = 1.0 - self.coated.specular_weight();
        let wo = coating_or_base(&self.microfacet, wi, u1, u2, prob_diffuse);
        sample_from_eval(self, wi, wo, mode)
    }

    /// As roughplastic's, without a transmittance table: roughplastic's WGSL then takes the
    /// base through two smooth refractions, as this one.
    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        self.coated.pack(record);
        self.microfacet.pack(record);
        record.table = NO_TABLE;
    }
}
