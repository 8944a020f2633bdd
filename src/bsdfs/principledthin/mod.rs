//! Mitsuba 3's `principledthin` BSDF (its src/bsdfs/principledthin.cpp and principledhelpers.h,
//! after Burley 2015): a sheet with no inside, so light leaves on either side without bending.
//! Four lobes: Burley's diffuse with sheen (the principled's), a Lambertian transmission
//! (`diff_trans`, 0..2, half of it the share), a GGX reflection with the dielectric Fresnel
//! tinted by `spec_tint`, and a GGX "transmission" that mirrors the reflection through the
//! sheet, its roughness scaled by (0.65 eta - 0.35). Both sides behave alike: a direction from
//! behind is turned to the front first. Lobes are picked with fixed probabilities from
//! `spec_trans`, `diff_trans` and the four sampling rates, so its sampler follows its pdf.
//!
//! Mitsuba's `m_has_*` flags change nothing here: every lobe they switch off has a weight of 0
//! then. The BSDF is the same for radiance and importance (nothing refracts).

use glam::{Vec2, Vec3};

use crate::bsdfs::principled::{
    calc_schlick, compatible, diffuse_lobe, ggx, lerp3, mulsign, schlick_r0, sheen_lobe, tint_of,
};
use crate::bsdfs::shared::fresnel::{fresnel, reflect};
use crate::bsdfs::shared::microfacet::{Microfacet, square_to_cosine_hemisphere};
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

/// The parameters at one surface point (textures already looked up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrincipledThin {
    pub base_color: Vec3,
    pub roughness: f32,
    pub anisotropic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    /// As the file gives it: 0 (diffuse reflection only) to 2 (diffuse transmission only).
    pub diff_trans: f32,
    /// The sheet's index of refraction (its Fresnel term; nothing bends).
    pub eta: f32,
    /// Sampling rates of the specular reflection, specular transmission, diffuse reflection
    /// and diffuse transmission lobes.
    pub spec_reflect_srate: f32,
    pub spec_trans_srate: f32,
    pub diff_reflect_srate: f32,
    pub diff_trans_srate: f32,
}

impl PrincipledThin {
    /// The share of the diffuse part that is transmitted (Mitsuba halves `diff_trans`).
    fn diff_trans_share(&self) -> f32 {
        self.diff_trans / 2.0
    }

    fn reflect_distribution(&self) -> Microfacet {
        ggx(self.anisotropic, self.roughness)
    }

    /// The specular transmission's roughness, scaled by the index (Burley 2015, figure 15).
    fn transmit_distribution(&self) -> Microfacet {
        ggx(self.anisotropic, (0.65 * self.eta - 0.35) * self.roughness)
    }

    /// Probabilities of the (specular reflection, specular transmission, diffuse reflection,
    /// diffuse transmission) lobes, or `None` when no lobe can be picked.
    fn lobe_probabilities(&self) -> Option<[f32; 4]> {
        let (spec, diff) = (self.spec_trans, self.diff_trans_share());
        let weights = [
            spec * self.spec_reflect_srate / 2.0,
            spec * self.spec_trans_srate / 2.0,
            self.diff_reflect_srate * (1.0 - spec) * (1.0 - diff),
            self.diff_trans_srate * (1.0 - spec) * diff,
        ];
        let total: f32 = weights.iter().sum();
        (total > 0.0 && total.is_finite()).then(|| weights.map(|w| w / total))
    }

    /// The specular reflection's Fresnel term: the dielectric one blended towards a Schlick
    /// term of the base colour's hue by `spec_tint` (Mitsuba's thin_fresnel).
    fn reflect_fresnel(&self, f_dielectric: f32, cos_i: f32) -> Vec3 {
        if self.spec_tint == 0.0 {
            return Vec3::splat(f_dielectric);
        }
        let r0 = tint_of(self.base_color) * schlick_r0(self.eta);
        lerp3(
            Vec3::splat(f_dielectric),
            calc_schlick(r0, cos_i, self.eta),
            self.spec_tint,
        )
    }
}

/// (wi, wo) turned so that wi faces +z, and wo's mirror image above the sheet.
fn front_pair(wi: Vec3, wo: Vec3) -> (Vec3, Vec3, Vec3) {
    let (wi, wo) = (mulsign(wi, wi.z), mulsign(wo, wi.z));
    (wi, wo, Vec3::new(wo.x, wo.y, wo.z.abs()))
}

/// f(wi, wo) |cos wo|.
pub fn eval(p: &PrincipledThin, wi: Vec3, wo: Vec3) -> Vec3 {
    if wi.z == 0.0 {
        return Vec3::ZERO;
    }
    let (wi, wo, wo_up) = front_pair(wi, wo);
    let (cos_i, cos_o) = (wi.z, wo.z);
    let (reflects, transmits) = (cos_o > 0.0, cos_o < 0.0);
    let h = (wi + wo_up).normalize();
    let (spec, diff) = (p.spec_trans, p.diff_trans_share());
    let mut value = Vec3::ZERO;
    if spec > 0.0 {
        let f = fresnel(wi.dot(h), p.eta).0;
        if reflects && compatible(h, wi, wo, cos_i, true) {
            let mf = p.reflect_distribution();
            let dg = mf.d(h) * mf.g1(wi, h) * mf.g1(wo, h);
            value += spec * p.reflect_fresnel(f, wi.dot(h)) * dg / (4.0 * cos_i);
        }
        if transmits && compatible(h, wi, wo, cos_i, false) {
            let mf = p.transmit_distribution();
            let dg = mf.d(h) * mf.g1(wi, h) * mf.g1(wo, h);
            value += spec * p.base_color * (1.0 - f) * dg / (4.0 * cos_i);
        }
    }
    if reflects && spec < 1.0 && diff < 1.0 {
        let cos_d = h.dot(wo);
        let lobe = diffuse_lobe(p.roughness, p.flatness, cos_i, cos_o, cos_d);
        let diffuse = p.base_color * std::f32::consts::FRAC_1_PI * lobe;
        let sheen = if p.sheen > 0.0 {
            sheen_lobe(p.sheen, p.sheen_tint, p.base_color, cos_d)
        } else {
            Vec3::ZERO
        };
        value += (1.0 - spec) * (1.0 - diff) * cos_o * (diffuse + sheen);
    }
    if transmits && spec < 1.0 && diff > 0.0 {
        value += (1.0 - spec) * diff * p.base_color * std::f32::consts::FRAC_1_PI * cos_o.abs();
    }
    if value.is_finite() { value } else { Vec3::ZERO }
}

/// The density [`sample`] draws `wo` with.
pub fn pdf(p: &PrincipledThin, wi: Vec3, wo: Vec3) -> f32 {
    if wi.z == 0.0 {
        return 0.0;
    }
    let Some([spec_reflect, spec_trans, diff_reflect, diff_trans]) = p.lobe_probabilities() else {
        return 0.0;
    };
    let (wi, wo, wo_up) = front_pair(wi, wo);
    let (reflects, transmits) = (wo.z > 0.0, wo.z < 0.0);
    let mut pdf = 0.0;
    if p.spec_trans > 0.0 {
        let h = (wi + wo_up).normalize();
        let dh_dwo = (1.0 / (4.0 * wo_up.dot(h))).abs();
        if reflects && compatible(h, wi, wo, wi.z, true) {
            pdf += spec_reflect * p.reflect_distribution().pdf(wi, h) * dh_dwo;
        }
        if transmits && compatible(h, wi, wo, wi.z, false) {
            pdf += spec_trans * p.transmit_distribution().pdf(wi, h) * dh_dwo;
        }
    }
    if reflects {
        pdf += diff_reflect * wo.z * std::f32::consts::FRAC_1_PI;
    }
    if transmits {
        pdf += diff_trans * -wo.z * std::f32::consts::FRAC_1_PI;
    }
    if pdf.is_finite() { pdf } else { 0.0 }
}

/// A direction sampled as Mitsuba samples it: the lobe by `u1`, its direction from `u2`.
/// Returns (wo, f |cos wo| / pdf, pdf).
pub fn sample(p: &PrincipledThin, wi_given: Vec3, u1: f32, u2: Vec2) -> Option<(Vec3, Vec3, f32)> {
    let side = wi_given.z;
    if side == 0.0 {
        return None;
    }
    let [spec_reflect, spec_trans, diff_reflect, diff_trans] = p.lobe_probabilities()?;
    let wi = mulsign(wi_given, side);
    let wo = if u1 < spec_reflect {
        let m = p.reflect_distribution().sample(wi, u2);
        let wo = reflect(wi, m);
        (compatible(m, wi, wo, wi.z, true) && wo.z > 0.0).then_some(wo)?
    } else if u1 < spec_reflect + spec_trans {
        // Reflected, then through the sheet.
        let m = p.transmit_distribution().sample(wi, u2);
        let up = reflect(wi, m);
        let wo = Vec3::new(up.x, up.y, -up.z);
        (compatible(m, wi, wo, wi.z, false) && wo.z < 0.0).then_some(wo)?
    } else if u1 < spec_reflect + spec_trans + diff_reflect {
        square_to_cosine_hemisphere(u2)
    } else if diff_trans > 0.0 {
        -square_to_cosine_hemisphere(u2)
    } else {
        return None;
    };
    let wo = mulsign(wo, side);
    let density = pdf(p, wi_given, wo);
    if density.is_nan() || density <= 0.0 {
        return None;
    }
    Some((wo, eval(p, wi_given, wo) / density, density))
}

/// Continuous, as `principled`; it transmits, so `twosided` refuses it (as Mitsuba does).
const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: false,
    continuous: true,
    transmits: true,
    pass_through: false,
};

const MODULE: &str = "bsdfs::principledthin";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "principledthin",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["principledthin"],
        properties: &[
            p("base_color", "0.5"),
            p("roughness", "0.5"),
            p("anisotropic", "0"),
            p("spec_trans", "0"),
            p("eta", "1.5"),
            p("spec_tint", "0"),
            p("sheen", "0"),
            p("sheen_tint", "0"),
            p("flatness", "0"),
            p("diff_trans", "0"),
            p("specular_reflectance_sampling_rate", "1"),
            p("specular_transmittance_sampling_rate", "1"),
            p("diffuse_reflectance_sampling_rate", "1"),
            p("diffuse_transmittance_sampling_rate", "1"),
        ],
        notes: "A sheet seen and lit from both sides, as Mitsuba 3.9.1 writes it \
                (src/bsdfs/principledthin/mod.rs): diffuse with sheen, diffuse transmission \
                (`diff_trans` 0 to 2), a GGX reflection and a GGX transmission straight through \
                (no bending). Every parameter but the sampling rates may be a texture, `eta` \
                too. It transmits, so `twosided` refuses it (as in Mitsuba). Continuous for \
                the light-transport partition, as `principled`.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "principled_thin_eval")),
        sample: Some(WgslCall::new(MODULE, "principled_thin_sample")),
        alpha_floor: 0.0,
        ..GpuKind::inline("principledthin", LOBES)
    }],
    def: Some("PRINCIPLED"),
    wgsl: Some(crate::shader_file!(
        "src/bsdfs/principledthin/principledthin.wgsl"
    )),
};

/// The parameters Mitsuba's plugin reads as textures besides base colour and roughness, `eta`
/// last, in the order of the record's field textures.
pub const TEXTURED: [&str; 8] = [
    "anisotropic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "diff_trans",
    "eta",
];

/// Every property its plugin reads; all but the sampling rates may be textures.
fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let (base_color, base_texture) = r.color_or_texture("base_color", 0.5)?;
    textures.diffuse = base_texture;
    let (roughness, roughness_texture) = r.scalar_or_texture("roughness", 0.5)?;
    textures.alpha_u = roughness_texture;
    let mut values = [0.0; TEXTURED.len()];
    // The last is eta, which is checked apart.
    let [params @ .., eta_slot] = &TEXTURED;
    for (i, name) in params.iter().enumerate() {
        (values[i], textures.fields[i]) = r.scalar_or_texture(name, 0.0)?;
    }
    let [
        anisotropic,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        diff_trans,
        _,
    ] = values;
    let (eta, eta_texture) = r.scalar_or_texture(eta_slot, 1.5)?;
    if eta_texture.is_none() && (eta.is_nan() || eta <= 0.0) {
        return Err(r.error_at(eta_slot, format!("eta {eta}: must be positive")));
    }
    textures.fields[params.len()] = eta_texture;
    let mut rate = |name: &str| Ok::<_, SceneError>(r.float(name)?.unwrap_or(1.0));
    let model = PrincipledThin {
        base_color,
        roughness,
        anisotropic,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        diff_trans,
        eta,
        spec_reflect_srate: rate("specular_reflectance_sampling_rate")?,
        spec_trans_srate: rate("specular_transmittance_sampling_rate")?,
        diff_reflect_srate: rate("diffuse_reflectance_sampling_rate")?,
        diff_trans_srate: rate("diffuse_transmittance_sampling_rate")?,
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

impl BsdfModel for PrincipledThin {
    fn kind(&self) -> &'static str {
        "principledthin"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        let scalars = [
            self.roughness,
            self.anisotropic,
            self.spec_trans,
            self.spec_tint,
            self.sheen,
            self.sheen_tint,
            self.flatness,
            self.diff_trans,
            self.spec_reflect_srate,
            self.spec_trans_srate,
            self.diff_reflect_srate,
            self.diff_trans_srate,
        ];
        self.base_color.is_finite() && scalars.iter().all(|v| v.is_finite()) && self.eta > 0.0
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        eval(self, wi, wo)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        pdf(self, wi, wo)
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, _mode: Mode) -> Option<Sample> {
        sample(self, wi, u1, u2).map(|(wo, weight, pdf)| Sample {
            wo,
            weight,
            pdf,
            delta: false,
        })
    }

    /// As principled's, with diff_trans and eta in `k` and the four sampling rates in
    /// int_ior, ext_ior, specular_weight and internal_reflectance (principledthin.wgsl).
    fn pack(&self, record: &mut GpuMaterial, textures: &SideTextures, tables: &mut Vec<f32>) {
        record.albedo = self.base_color.to_array();
        record.alpha_u = self.roughness;
        record.specular = [self.anisotropic, self.spec_trans, self.spec_tint];
        record.eta = [self.sheen, self.sheen_tint, self.flatness];
        record.k = [self.diff_trans, self.eta, 0.0];
        (record.int_ior, record.ext_ior) = (self.spec_reflect_srate, self.spec_trans_srate);
        (record.specular_weight, record.internal_reflectance) =
            (self.diff_reflect_srate, self.diff_trans_srate);
        record.set_field_textures(&textures.fields, tables);
    }
}
