//! Mitsuba's `roughplastic`: the diffuse base under a rough (isotropic) dielectric coating, seen
//! through the coating's transmittance, which is tabulated per cos theta at load as Mitsuba
//! does. The coating is a microfacet lobe: specular for the partition below a graph's
//! `glossy_threshold`, while the base is always path traced.

use glam::{Vec2, Vec3};

use crate::bsdfs::plastic::{Coated, diffuse_under_coating, plastic_diffuse_prob, read_nonlinear};
use crate::bsdfs::shared::fresnel::{fresnel, reflect, refract};
use crate::bsdfs::shared::microfacet::{Microfacet, square_to_cosine_hemisphere};
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

const MODULE: &str = "bsdfs::roughplastic";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "roughplastic",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["roughplastic"],
        properties: &[
            p("int_ior", "polypropylene"),
            p("ext_ior", "air"),
            p("diffuse_reflectance", "0.5"),
            p("specular_reflectance", "1"),
            p("nonlinear", "false"),
            p("distribution", "beckmann"),
            p("alpha", "0.1"),
            p("alpha_u", "refused: isotropic only"),
            p("alpha_v", "refused: isotropic only"),
            p("sample_visible", "true"),
        ],
        notes: "Isotropic `alpha` only, a number, as in Mitsuba; the coating's transmittance \
                table is computed at load.",
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
        ..GpuKind::inline("roughplastic", LOBES)
    }],
    def: Some("PLASTIC"),
    wgsl: Some(crate::shader_file!(
        "src/bsdfs/roughplastic/roughplastic.wgsl"
    )),
};

/// `GpuMaterial::table` of a rough coating without a transmittance table: roughplastic.wgsl then
/// takes its base through two smooth refractions (pplastic).
pub const NO_TABLE: u32 = u32::MAX;

/// Entries of the rough plastic's external transmittance table (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`), over cos(theta) from 0 to 1.
pub const TRANSMITTANCE_RES: usize = 64;

#[derive(Debug, Clone, PartialEq)]
pub struct RoughPlastic {
    pub coated: Coated,
    pub nonlinear: bool,
    pub microfacet: Microfacet,
    /// 1 - the coating's directional albedo from outside, per cos(theta).
    pub transmittance: Vec<f32>,
    /// The rough coating's diffuse reflectance from inside (`m_internal_reflectance`).
    pub internal_reflectance: f32,
}

impl RoughPlastic {
    /// The plastic with its coating's tables computed (Mitsuba's `eval_transmittance` and
    /// `eval_reflectance`).
    pub fn new(coated: Coated, nonlinear: bool, microfacet: Microfacet) -> Self {
        let eta = coated.int_ior / coated.ext_ior;
        let mu = |i: usize| (i as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
        let transmittance = (0..TRANSMITTANCE_RES)
            .map(|i| rough_transmittance(microfacet, mu(i), eta))
            .collect();
        let internal: f32 = (0..TRANSMITTANCE_RES)
            .map(|i| rough_reflectance(microfacet, mu(i), 1.0 / eta) * mu(i))
            .sum();
        RoughPlastic {
            coated,
            nonlinear,
            microfacet,
            transmittance,
            internal_reflectance: 2.0 * internal / TRANSMITTANCE_RES as f32,
        }
    }
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let coated = Coated::read(r, &mut textures)?;
    let nonlinear = read_nonlinear(r)?;
    distinct_iors(r, coated.int_ior, coated.ext_ior)?;
    let microfacet = microfacet(r, Alphas::Isotropic, &mut textures)?;
    let model = RoughPlastic::new(coated, nonlinear, microfacet);
    Ok(Sides::one(Bsdf::new(model), textures))
}

/// f |cos wo| of a rough dielectric interface's reflection (both directions above it): the
/// coating of rough plastic and pplastic.
pub fn rough_reflection(microfacet: &Microfacet, eta: f32, wi: Vec3, wo: Vec3) -> f32 {
    let h = (wi + wo).normalize();
    let f = fresnel(wi.dot(h), eta).0;
    let g = microfacet.g1(wi, h) * microfacet.g1(wo, h);
    f * microfacet.d(h) * g / (4.0 * wi.z)
}

/// The density of sampling the coating's normal for wo (its visible normals) at (wi, wo).
pub fn coating_pdf(microfacet: &Microfacet, wi: Vec3, wo: Vec3) -> f32 {
    let h = (wi + wo).normalize();
    microfacet.d(h) * microfacet.g1(wi, h) / (4.0 * wi.z)
}

/// A direction from the coating (`u1` below `1 - prob_diffuse`) or the cosine-weighted base.
pub fn coating_or_base(
    microfacet: &Microfacet,
    wi: Vec3,
    u1: f32,
    u2: Vec2,
    prob_diffuse: f32,
) -> Vec3 {
    if u1 < 1.0 - prob_diffuse {
        reflect(wi, microfacet.sample(wi, u2))
    } else {
        square_to_cosine_hemisphere(u2)
    }
}

fn lerp_table(table: &[f32], x: f32) -> f32 {
    let n = table.len();
    let x = x * (n - 1) as f32;
    let i = (x.max(0.0) as usize).min(n - 2);
    let t = x - i as f32;
    table[i] * (1.0 - t) + table[i + 1] * t
}

impl BsdfModel for RoughPlastic {
    fn kind(&self) -> &'static str {
        "roughplastic"
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
        let ti = lerp_table(&self.transmittance, ci);
        let to = lerp_table(&self.transmittance, co);
        spec + diffuse_under_coating(c.diffuse, self.nonlinear, self.internal_reflectance)
            * (std::f32::consts::FRAC_1_PI / (eta * eta) * co * ti * to)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return 0.0;
        }
        let ti = lerp_table(&self.transmittance, ci);
        let prob_diffuse = plastic_diffuse_prob(1.0 - ti, self.coated.specular_weight());
        let cosine = co.max(0.0) * std::f32::consts::FRAC_1_PI;
        (1.0 - prob_diffuse) * coating_pdf(&self.microfacet, wi, wo) + prob_diffuse * cosine
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        if wi.z <= 0.0 {
            return None;
        }
        let ti = lerp_table(&self.transmittance, wi.z);
        let prob_diffuse = plastic_diffuse_prob(1.0 - ti, self.coated.specular_weight());
        let wo = coating_or_base(&self.microfacet, wi, u1, u2, prob_diffuse);
        sample_from_eval(self, wi, wo, mode)
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, tables: &mut Vec<f32>) {
        self.coated.pack(record);
        record.nonlinear = self.nonlinear as u32;
        record.internal_reflectance = self.internal_reflectance;
        self.microfacet.pack(record);
        record.table = tables.len() as u32;
        tables.extend_from_slice(&self.transmittance);
    }
}

// --- The coating's tables (Mitsuba's eval_transmittance / eval_reflectance) ---

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Integrates `f(visible normal)` over the visible-normal samples of the unit square.
fn integrate_visible(mf: Microfacet, wi: Vec3, eta: f32, f: impl Fn(Vec3) -> f32) -> f32 {
    let nodes = gauss_legendre(if eta > 1.0 { 32 } else { 128 });
    let mut sum = 0.0f64;
    for &(x, wx) in &nodes {
        for &(y, wy) in &nodes {
            let u = Vec2::new((0.5 * x + 0.5) as f32, (0.5 * y + 0.5) as f32);
            sum += f(mf.sample(wi, u)) as f64 * wx * wy * 0.25;
        }
    }
    sum as f32
}

/// Fraction of light from direction cos `mu` that a rough interface of relative index `eta`
/// transmits (single scattering).
pub fn rough_transmittance(mf: Microfacet, mu: f32, eta: f32) -> f32 {
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    integrate_visible(mf, wi, eta, |m| {
        let (f, cos_t, _, eta_ti) = fresnel(wi.dot(m), eta);
        let wo = refract(wi, m, cos_t, eta_ti);
        if wo.z * wi.z >= 0.0 {
            0.0
        } else {
            mf.g1(wo, m) * (1.0 - f)
        }
    })
}

/// Fraction of light from direction cos `mu` that a rough interface reflects.
pub fn rough_reflectance(mf: Microfacet, mu: f32, eta: f32) -> f32 {
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    integrate_visible(mf, wi, eta, |m| {
        let wo = reflect(wi, m);
        if wo.z <= 0.0 || wi.z <= 0.0 {
            0.0
        } else {
            mf.g1(wo, m) * fresnel(wi.dot(m), eta).0
        }
    })
}
