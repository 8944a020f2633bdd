//! Mitsuba 0.6's `roughdiffuse` (src/bsdfs/roughdiffuse.cpp of mitsuba-renderer/mitsuba, the
//! formulas below are its `eval`): Oren and Nayar's rough diffuse reflection, one-sided, in
//! its full form (with the inter-reflection term) or its qualitative approximation
//! (`use_fast_approx`), sampled cosine-weighted. Mitsuba 3 has no such plugin, so it is read
//! from files of version 0.x only. A continuous lobe for the light-transport partition (it is
//! not Lambertian, so it is path traced, never photon mapped); no microfacet lobe (0.6's
//! `getRoughness` calls it infinitely rough).

use glam::{Vec2, Vec3};

use crate::bsdfs::shared::microfacet::square_to_cosine_hemisphere;
use crate::bsdfs::shared::mitsuba06::{
    energy_scale, ensures_energy_conservation, only_in_mitsuba06, reflectance,
};
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample, sample_from_eval};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: false,
    continuous: true,
    transmits: false,
    pass_through: false,
};

const MODULE: &str = "bsdfs::roughdiffuse";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "roughdiffuse",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["roughdiffuse"],
        properties: &[
            p("reflectance", "0.5"),
            p("diffuse_reflectance", "another name for reflectance"),
            p("alpha", "0.2"),
            p("use_fast_approx", "false"),
            p("ensure_energy_conservation", "true"),
        ],
        notes: "Mitsuba 0.6's Oren-Nayar model (files of version 0.x only; Mitsuba 3 has no \
                `roughdiffuse`): sigma = alpha / sqrt(2) as 0.6 converts it, the full model or \
                `use_fast_approx`'s, cosine-weighted sampling; a reflectance above 1 scaled down \
                as 0.6 scales it; `reflectance` and `alpha` may be textures. A continuous BSDF \
                for the light-transport partition, path traced.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "rough_diffuse_eval")),
        sample: Some(WgslCall::new(MODULE, "rough_diffuse_sample")),
        // alpha 0 is the Lambertian, which a textured roughness may reach too.
        alpha_floor: 0.0,
        ..GpuKind::inline("roughdiffuse", LOBES)
    }],
    def: Some("ROUGH_DIFFUSE"),
    wgsl: Some(crate::shader_file!(
        "src/bsdfs/roughdiffuse/roughdiffuse.wgsl"
    )),
};

/// Oren-Nayar reflection with Mitsuba 0.6's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughDiffuse {
    /// The albedo as given (a texture's scalar mean where textured).
    pub reflectance: Vec3,
    /// 0.6's energy conservation: the factor `reflectance` is scaled by (1 unless its largest
    /// channel is above 1).
    pub scale: f32,
    /// Beckmann-style RMS slope, as 0.6 takes it.
    pub alpha: f32,
    /// The qualitative model without inter-reflections (`use_fast_approx`).
    pub fast_approx: bool,
}

impl RoughDiffuse {
    /// A model with 0.6's defaults but `reflectance` and `alpha` (full model, scaled as 0.6
    /// scales a reflectance above 1).
    pub fn new(reflectance: Vec3, alpha: f32, fast_approx: bool) -> Self {
        RoughDiffuse {
            reflectance,
            scale: energy_scale(true, reflectance),
            alpha,
            fast_approx,
        }
    }
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    only_in_mitsuba06(r)?;
    // 0.6 reads `reflectance`, or `diffuseReflectance` where that is absent.
    let name = match (r.has("reflectance"), r.has("diffuse_reflectance")) {
        (true, true) => {
            return Err(r.error_at(
                "diffuse_reflectance",
                "give reflectance or diffuse_reflectance (the same parameter), not both".into(),
            ));
        }
        (false, true) => "diffuse_reflectance",
        _ => "reflectance",
    };
    let rho = reflectance(r, name, 0.5)?;
    let (alpha, alpha_texture) = r.scalar_or_texture("alpha", 0.2)?;
    if alpha_texture.is_none() && (alpha.is_nan() || alpha < 0.0) {
        let what = r.describe_property("alpha");
        return Err(r.error_at("alpha", format!("{what}: must not be negative")));
    }
    let fast_approx = r.boolean("use_fast_approx")?.unwrap_or(false);
    let ensure = ensures_energy_conservation(r)?;
    let model = RoughDiffuse {
        reflectance: rho.value,
        scale: energy_scale(ensure, rho.maximum),
        alpha,
        fast_approx,
    };
    let textures = SideTextures {
        diffuse: rho.texture,
        alpha_u: alpha_texture,
        ..SideTextures::default()
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

/// sin theta of a local direction as 0.6's `Frame::sinTheta` takes it (from z alone).
fn sin_theta(v: Vec3) -> f32 {
    (1.0 - v.z * v.z).max(0.0).sqrt()
}

/// cos(phi_o - phi_i), 0 where either direction is within 1e-4 of the normal in sin theta
/// (0.6's `Epsilon`), each cos phi and sin phi clamped to [-1, 1] as `Frame` clamps them.
fn cos_phi_difference(wi: Vec3, wo: Vec3, sin_i: f32, sin_o: f32) -> f32 {
    if sin_i > 1e-4 && sin_o > 1e-4 {
        let c = |x: f32, s: f32| (x / s).clamp(-1.0, 1.0);
        c(wi.x, sin_i) * c(wo.x, sin_o) + c(wi.y, sin_i) * c(wo.y, sin_o)
    } else {
        0.0
    }
}

impl BsdfModel for RoughDiffuse {
    fn kind(&self) -> &'static str {
        "roughdiffuse"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        self.reflectance.is_finite()
            && self.reflectance.min_element() >= 0.0
            && self.scale.is_finite()
            && self.alpha.is_finite()
            && self.alpha >= 0.0
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return Vec3::ZERO;
        }
        let inv_pi = std::f32::consts::FRAC_1_PI;
        let rho = self.reflectance * self.scale;
        // 0.6's conversion from Beckmann-style RMS slope to Oren-Nayar's slope-area variance.
        let sigma = self.alpha * std::f32::consts::FRAC_1_SQRT_2;
        let sigma2 = sigma * sigma;
        let (sin_i, sin_o) = (sin_theta(wi), sin_theta(wo));
        let cos_phi_diff = cos_phi_difference(wi, wo, sin_i, sin_o);
        // alpha is the larger polar angle, beta the smaller.
        let (sin_alpha, sin_beta, tan_beta) = if ci > co {
            (sin_o, sin_i, sin_i / ci)
        } else {
            (sin_i, sin_o, sin_o / co)
        };
        if self.fast_approx {
            let a = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33);
            let b = 0.45 * sigma2 / (sigma2 + 0.09);
            return rho * (inv_pi * co * (a + b * cos_phi_diff.max(0.0) * sin_alpha * tan_beta));
        }
        let (theta_i, theta_o) = (ci.clamp(-1.0, 1.0).acos(), co.clamp(-1.0, 1.0).acos());
        let (alpha, beta) = (theta_i.max(theta_o), theta_i.min(theta_o));
        let tmp = sigma2 / (sigma2 + 0.09);
        let tmp2 = 4.0 * inv_pi * inv_pi * alpha * beta;
        let tmp3 = 2.0 * beta * inv_pi;
        let c1 = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33);
        let mut c2 = 0.45 * tmp;
        let c3 = 0.125 * tmp * tmp2 * tmp2;
        let c4 = 0.17 * sigma2 / (sigma2 + 0.13);
        if cos_phi_diff > 0.0 {
            c2 *= sin_alpha;
        } else {
            c2 *= sin_alpha - tmp3 * tmp3 * tmp3;
        }
        // tan((alpha + beta) / 2) by the half-angle formula.
        let cos_of = |s: f32| (1.0 - s * s).max(0.0).sqrt();
        let tan_half = (sin_alpha + sin_beta) / (cos_of(sin_alpha) + cos_of(sin_beta));
        let single =
            rho * (c1 + cos_phi_diff * c2 * tan_beta + (1.0 - cos_phi_diff.abs()) * c3 * tan_half);
        let double = rho * rho * (c4 * (1.0 - cos_phi_diff * tmp3 * tmp3));
        (single + double) * (inv_pi * co)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        wo.z * std::f32::consts::FRAC_1_PI
    }

    fn sample(&self, wi: Vec3, _u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        if wi.z <= 0.0 {
            return None;
        }
        sample_from_eval(self, wi, square_to_cosine_hemisphere(u2), mode)
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        record.albedo = self.reflectance.to_array();
        record.int_ior = self.scale;
        record.alpha_u = self.alpha;
        record.nonlinear = self.fast_approx as u32;
    }
}
