//! Mitsuba 0.6's `hk` (src/bsdfs/hk.cpp of mitsuba-renderer/mitsuba): Hanrahan and Krueger's
//! single scattering in an index-matched layer of thickness d, as 0.6 evaluates it, with
//! tau = (sigma_s + sigma_a) d, the albedo a = sigma_s / sigma_t and the phase function p
//! (isotropic unless a `<phase>` is nested), mu_i = cos wi, mu_o = cos wo:
//!
//! - reflection (same side): a p mu_i / (mu_i + mu_o) (1 - exp(-tau (1/|mu_i| + 1/|mu_o|))),
//! - transmission (other side): a p |mu_i| / (|mu_i| - |mu_o|) (exp(-tau/|mu_i|) -
//!   exp(-tau/|mu_o|)), or a p tau / |mu_o| exp(-tau/|mu_o|) where |mu_i| and |mu_o| are
//!   within 0.6's Epsilon (1e-4),
//!
//! each times |mu_o| (0.6's `eval`, with wi towards the viewer), and the light that crosses
//! unscattered, exp(-tau / |mu_i|) straight through (a delta lobe). 0.6 samples the delta lobe
//! with probability P = the mean over channels of exp(-tau / |mu_i|), else the phase function
//! about the travel direction -wi (so both sides), with density p (1 - P).
//!
//! Hanrahan and Krueger's cos theta_i is the light's; 0.6 takes it from wi, which is the
//! viewer's in its path tracer, so its value is the single-scattering solution times
//! |cos wi| and is not reciprocal. hppm keeps 0.6's value for camera paths and gives photons
//! its adjoint (f(wo, wi)), so that light carried either way agrees.
//!
//! For the light-transport partition the scattering lobes are continuous (path traced; 0.6
//! calls them glossy with infinite roughness) and the straight-through lobe is delta (an S
//! vertex, as a smooth dielectric's refraction: a photon through it is a caustic photon).

use glam::{Vec2, Vec3};

use crate::bsdfs::shared::mitsuba06::only_in_mitsuba06;
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::medium::Phase;
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: true,
    microfacet: false,
    continuous: true,
    transmits: true,
    pass_through: false,
};

const MODULE: &str = "bsdfs::hk";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "hk",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["hk"],
        properties: &[
            p("material", "skin1"),
            p("sigma_s", "the preset's, times 1 - g"),
            p("sigma_a", "the preset's"),
            p("sigma_t", ""),
            p("albedo", ""),
            p("thickness", "1"),
            p("g", "the preset's"),
            p("scale", "1"),
            p("ensure_energy_conservation", "true"),
        ],
        notes: "Mitsuba 0.6's Hanrahan-Krueger layer (files of version 0.x only; Mitsuba 3 has \
                no `hk`): single scattering in an index-matched slab of `thickness`, with a \
                nested `<phase>` (isotropic, hg or rayleigh; isotropic by default), plus the \
                unscattered light straight through as a delta lobe, evaluated and sampled as \
                0.6 does. Coefficients as 0.6 reads them: a `material` preset (its scattering \
                times 1 - g, times `scale`), or `sigma_s`/`sigma_a` (each missing one from the \
                default preset), or `sigma_t` with `albedo`; colours only, no textures; \
                `ensure_energy_conservation` changes nothing here, as in 0.6. The scattering is \
                path traced; the straight-through lobe is specular for the partition.",
    }],
    read,
    objects: &["phase"],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "hk_eval")),
        sample: Some(WgslCall::new(MODULE, "hk_sample")),
        ..GpuKind::inline("hk", LOBES)
    }],
    def: Some("HK"),
    wgsl: Some(crate::shader_file!("src/bsdfs/hk/hk.wgsl")),
};

/// 0.6's `Epsilon` (single precision): where |mu_i| and |mu_o| are this close the transmission
/// term takes its limit.
const EPSILON: f32 = 1e-4;

/// A Hanrahan-Krueger layer with Mitsuba 0.6's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hk {
    /// Scattering and absorption coefficients, per unit of `thickness`.
    pub sigma_s: Vec3,
    pub sigma_a: Vec3,
    pub thickness: f32,
    pub phase: Phase,
}

impl Hk {
    /// Optical thickness per channel.
    pub fn tau(&self) -> Vec3 {
        (self.sigma_s + self.sigma_a) * self.thickness
    }

    /// Single-scattering albedo per channel (0 where nothing is there, as 0.6).
    pub fn albedo(&self) -> Vec3 {
        let sigma_t = self.sigma_s + self.sigma_a;
        Vec3::select(
            sigma_t.cmpgt(Vec3::ZERO),
            self.sigma_s / sigma_t,
            Vec3::ZERO,
        )
    }

    /// The unscattered fraction seen from `wi`, exp(-tau / |cos wi|).
    pub fn unscattered(&self, wi: Vec3) -> Vec3 {
        (-self.tau() / wi.z.abs()).exp()
    }

    /// 0.6's probability of sampling the straight-through lobe: the unscattered fraction's
    /// mean over the channels.
    pub fn straight_probability(&self, wi: Vec3) -> f32 {
        let t = self.unscattered(wi);
        (t.x + t.y + t.z) / 3.0
    }

    /// The scattering lobes' f |cos wo| as 0.6's `eval` gives it (wi the viewer's side).
    pub fn value06(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        let (ci, co) = (wi.z, wo.z);
        let dp = ci * co;
        if dp == 0.0 {
            return Vec3::ZERO;
        }
        let tau = self.tau();
        let phase = self.phase.eval(-wi, wo);
        let albedo = self.albedo();
        let result = if dp > 0.0 {
            albedo
                * (phase * ci / (ci + co))
                * (Vec3::ONE - ((-1.0 / ci.abs() - 1.0 / co.abs()) * tau).exp())
        } else if (ci + co).abs() < EPSILON {
            albedo * phase * tau / co.abs() * (-tau / co.abs()).exp()
        } else {
            albedo
                * (phase * ci.abs() / (ci.abs() - co.abs()))
                * ((-tau / ci.abs()).exp() - (-tau / co.abs()).exp())
        };
        result * co.abs()
    }
}

/// A colour property that must not be negative.
fn coefficient(r: &mut dyn BsdfReader, name: &str) -> Result<Option<Vec3>, SceneError> {
    let Some(v) = r.color(name)? else {
        return Ok(None);
    };
    if v.is_nan() || v.min_element() < 0.0 {
        let what = r.describe_property(name);
        return Err(r.error_at(name, format!("hk: {what} must not be negative")));
    }
    Ok(Some(v))
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    only_in_mitsuba06(r)?;
    let has_as = r.has("sigma_s") || r.has("sigma_a");
    let has_ta = r.has("sigma_t") || r.has("albedo");
    if (has_as || has_ta) && r.has("material") {
        return Err(r.error_at(
            "material",
            "hk: give a material preset or scattering coefficients, not both (as Mitsuba 0.6 \
             requires)"
                .into(),
        ));
    }
    if has_as && has_ta {
        let name = if r.has("sigma_t") {
            "sigma_t"
        } else {
            "albedo"
        };
        return Err(r.error_at(
            name,
            "hk: give sigma_s and sigma_a, or sigma_t and albedo, not a mix (as Mitsuba 0.6 \
             requires)"
                .into(),
        ));
    }
    // 0.6's lookupMaterial: the preset (skin1 by default), its g unless `g` is given, `scale`.
    let name = r.string("material")?.unwrap_or_else(|| "skin1".into());
    let Some((preset_s, preset_a, preset_g)) = r.medium_preset(&name) else {
        let names = r.medium_preset_names();
        return Err(r.error_at(
            "material",
            format!("hk: no material preset \"{name}\" (Mitsuba 0.6's are {names})"),
        ));
    };
    let g = match r.color("g")? {
        Some(g) => {
            if !(g.min_element() > -1.0 && g.max_element() < 1.0) {
                let what = r.describe_property("g");
                return Err(r.error_at(
                    "g",
                    format!("hk: {what} must lie between -1 and 1, exclusive (as in Mitsuba 0.6)"),
                ));
            }
            g
        }
        None => preset_g,
    };
    let scale = r.float("scale")?.unwrap_or(1.0);
    if scale < 0.0 {
        let what = r.describe_property("scale");
        return Err(r.error_at("scale", format!("hk: {what} must not be negative")));
    }
    // A coefficient the file gives replaces the preset's whole: 0.6 reads it again after
    // scaling the preset's.
    let mut sigma_s = coefficient(r, "sigma_s")?.unwrap_or(preset_s * scale * (Vec3::ONE - g));
    let mut sigma_a = coefficient(r, "sigma_a")?.unwrap_or(preset_a * scale);
    if has_ta {
        let (Some(sigma_t), Some(albedo)) = (coefficient(r, "sigma_t")?, r.color("albedo")?) else {
            let missing = if r.has("sigma_t") {
                "albedo"
            } else {
                "sigma_t"
            };
            return Err(r.error(format!(
                "hk: give both sigma_t and albedo ({missing} is missing), as Mitsuba 0.6 requires"
            )));
        };
        if albedo.is_nan() || albedo.min_element() < 0.0 || albedo.max_element() > 1.0 {
            let what = r.describe_property("albedo");
            return Err(r.error_at(
                "albedo",
                format!(
                    "hk: {what} must lie in [0, 1] (above 1 Mitsuba 0.6 makes sigma_a \
                     negative, a layer that creates light)"
                ),
            ));
        }
        sigma_s = sigma_t * albedo;
        sigma_a = sigma_t - sigma_s;
    }
    let thickness = r.float("thickness")?.unwrap_or(1.0);
    if thickness < 0.0 {
        let what = r.describe_property("thickness");
        return Err(r.error_at("thickness", format!("hk: {what} must not be negative")));
    }
    // Every 0.6 BSDF reads it; hk has nothing to scale.
    let _ = r.boolean("ensure_energy_conservation")?;
    let phase = r.phase()?.unwrap_or(Phase::Isotropic);
    let model = Hk {
        sigma_s,
        sigma_a: sigma_a.max(Vec3::ZERO),
        thickness,
        phase,
    };
    Ok(Sides::one(Bsdf::new(model), SideTextures::default()))
}

impl BsdfModel for Hk {
    fn kind(&self) -> &'static str {
        "hk"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        let g_ok = match self.phase {
            Phase::HenyeyGreenstein { g } => g > -1.0 && g < 1.0,
            _ => true,
        };
        self.sigma_s.is_finite()
            && self.sigma_a.is_finite()
            && self.sigma_s.min_element() >= 0.0
            && self.sigma_a.min_element() >= 0.0
            && self.thickness.is_finite()
            && self.thickness >= 0.0
            && g_ok
    }

    /// 0.6's value for radiance; for importance its adjoint f(wo, wi) |cos wo|.
    fn eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        match mode {
            Mode::Radiance => self.value06(wi, wo),
            Mode::Importance => {
                if wi.z == 0.0 {
                    return Vec3::ZERO;
                }
                self.value06(wo, wi) * (wo.z.abs() / wi.z.abs())
            }
        }
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z == 0.0 {
            return 0.0;
        }
        self.phase.eval(-wi, wo) * (1.0 - self.straight_probability(wi))
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        if wi.z == 0.0 {
            return None;
        }
        let straight = self.straight_probability(wi);
        // 0.6 takes the straight lobe unless u1 > P; strictly below here, so that a lobe of
        // probability 0 is never taken (its weight would divide by 0).
        if u1 < straight {
            return Some(Sample {
                wo: -wi,
                weight: self.unscattered(wi) / straight,
                pdf: straight,
                delta: true,
            });
        }
        let wo = self.phase.sample(-wi, u2);
        let pdf = self.pdf(wi, wo);
        (pdf > 0.0).then(|| Sample {
            wo,
            weight: self.eval(wi, wo, mode) / pdf,
            pdf,
            delta: false,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        let (phase, g) = self.phase.gpu();
        record.albedo = self.sigma_s.to_array();
        record.specular = self.sigma_a.to_array();
        record.int_ior = self.thickness;
        record.nonlinear = phase;
        record.ext_ior = g;
    }
}
