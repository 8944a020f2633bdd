//! Mitsuba's `roughdielectric`: microfacet reflection and refraction through a rough interface
//! (Walter et al. 2007), tinted as `dielectric`. A microfacet lobe: specular for the partition
//! below a graph's `glossy_threshold`.

use glam::{Vec2, Vec3};

use crate::bsdfs::dielectric::{iors_valid, pack_tint};
use crate::bsdfs::shared::fresnel::{fresnel, reflect, refract};
use crate::bsdfs::shared::microfacet::Microfacet;
use crate::bsdfs::shared::tint::Tint;
use crate::bsdfs::shared::{AIR, Alphas, BK7, dielectric_tint, distinct_iors, ior, microfacet};
use crate::bsdfs::{BsdfPlugin, BsdfReader, Glossy, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: true,
    continuous: true,
    transmits: true,
    pass_through: false,
};

const MODULE: &str = "bsdfs::roughdielectric";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "roughdielectric",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["roughdielectric"],
        properties: &[
            p("int_ior", "bk7"),
            p("ext_ior", "air"),
            p("distribution", "beckmann"),
            p("alpha", "0.1"),
            p("alpha_u", ""),
            p("alpha_v", ""),
            p("sample_visible", "true"),
            p("specular_reflectance", "1"),
            p("specular_transmittance", "1"),
        ],
        notes: "`distribution` beckmann or ggx; `alpha` or `alpha_u` + `alpha_v` (numbers or \
                textures); `sample_visible` true only; tints as `dielectric`.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "rough_dielectric_eval")),
        sample: Some(WgslCall::new(MODULE, "rough_dielectric_sample")),
        glossy: Glossy::Whole,
        ..GpuKind::inline("roughdielectric", LOBES)
    }],
    def: Some("ROUGH_DIELECTRIC"),
    wgsl: Some(crate::shader_file!(
        "src/bsdfs/roughdielectric/roughdielectric.wgsl"
    )),
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughDielectric {
    pub int_ior: f32,
    pub ext_ior: f32,
    pub microfacet: Microfacet,
    pub tint: Tint,
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let int_ior = ior(r, "int_ior", BK7)?;
    let ext_ior = ior(r, "ext_ior", AIR)?;
    distinct_iors(r, int_ior, ext_ior)?;
    let model = RoughDielectric {
        int_ior,
        ext_ior,
        microfacet: microfacet(r, Alphas::Textured, &mut textures)?,
        tint: dielectric_tint(r, &mut textures)?,
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

/// The half vector of a rough dielectric's (wi, wo) pair, facing +z, and the relative index
/// across it seen from wi.
fn dielectric_half(m_eta: f32, wi: Vec3, wo: Vec3) -> (Vec3, f32, bool) {
    let reflect = wi.z * wo.z > 0.0;
    let eta = if wi.z > 0.0 { m_eta } else { 1.0 / m_eta };
    let m = (wi + wo * if reflect { 1.0 } else { eta }).normalize();
    let m = if m.z < 0.0 { -m } else { m };
    (m, eta, reflect)
}

impl RoughDielectric {
    fn untinted_eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        let (m_eta, mf) = (self.int_ior / self.ext_ior, self.microfacet);
        let ci = wi.z;
        if ci == 0.0 {
            return Vec3::ZERO;
        }
        let (m, eta, reflect) = dielectric_half(m_eta, wi, wo);
        let d = mf.d(m);
        let f = fresnel(wi.dot(m), m_eta).0;
        let g = mf.g1(wi, m) * mf.g1(wo, m);
        let v = if reflect {
            f * d * g / (4.0 * ci.abs())
        } else {
            let scale = match mode {
                Mode::Radiance => 1.0 / (eta * eta),
                Mode::Importance => 1.0,
            };
            let denom = wi.dot(m) + eta * wo.dot(m);
            (scale * (1.0 - f) * d * g * eta * eta * wi.dot(m) * wo.dot(m) / (ci * denom * denom))
                .abs()
        };
        if v.is_finite() {
            Vec3::splat(v)
        } else {
            Vec3::ZERO
        }
    }
}

impl BsdfModel for RoughDielectric {
    fn kind(&self) -> &'static str {
        "roughdielectric"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn roughness(&self) -> Option<f32> {
        Some(self.microfacet.roughness())
    }

    fn is_valid(&self) -> bool {
        iors_valid(self.int_ior, self.ext_ior) && self.microfacet.is_valid() && self.tint.is_valid()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        // Reflection when both directions are on one side.
        self.tint.factor(wi.z * wo.z > 0.0) * self.untinted_eval(wi, wo, mode)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let (ci, co) = (wi.z, wo.z);
        if ci == 0.0 {
            return 0.0;
        }
        let m_eta = self.int_ior / self.ext_ior;
        let (m, eta, reflect) = dielectric_half(m_eta, wi, wo);
        if wi.dot(m) * ci <= 0.0 || wo.dot(m) * co <= 0.0 {
            return 0.0;
        }
        let dwh_dwo = if reflect {
            1.0 / (4.0 * wo.dot(m))
        } else {
            let denom = wi.dot(m) + eta * wo.dot(m);
            eta * eta * wo.dot(m) / (denom * denom)
        };
        let wi_up = if ci < 0.0 { -wi } else { wi };
        let f = fresnel(wi.dot(m), m_eta).0;
        let prob = self.microfacet.pdf(wi_up, m) * if reflect { f } else { 1.0 - f };
        let v = prob * dwh_dwo.abs();
        if v.is_finite() { v } else { 0.0 }
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        let ci = wi.z;
        if ci == 0.0 {
            return None;
        }
        let mf = &self.microfacet;
        let m_eta = self.int_ior / self.ext_ior;
        let wi_up = if ci < 0.0 { -wi } else { wi };
        let m = mf.sample(wi_up, u2);
        let mut pdf = mf.pdf(wi_up, m);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let (f, cos_t, eta_it, eta_ti) = fresnel(wi.dot(m), m_eta);
        let reflected = u1 <= f;
        let (wo, mut weight, dwh_dwo) = if reflected {
            pdf *= f;
            let wo = reflect(wi, m);
            (wo, 1.0, 1.0 / (4.0 * wo.dot(m)))
        } else {
            pdf *= 1.0 - f;
            let wo = refract(wi, m, cos_t, eta_ti);
            let scale = match mode {
                Mode::Radiance => eta_ti * eta_ti,
                Mode::Importance => 1.0,
            };
            let denom = wi.dot(m) + eta_it * wo.dot(m);
            (wo, scale, eta_it * eta_it * wo.dot(m) / (denom * denom))
        };
        weight *= mf.g1(wo, m);
        pdf *= dwh_dwo.abs();
        (pdf > 0.0 && pdf.is_finite() && weight > 0.0).then_some(Sample {
            wo,
            weight: self.tint.factor(reflected) * weight,
            pdf,
            delta: false,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        (record.int_ior, record.ext_ior) = (self.int_ior, self.ext_ior);
        pack_tint(record, &self.tint);
        self.microfacet.pack(record);
    }
}
