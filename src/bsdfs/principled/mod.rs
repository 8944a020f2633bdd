//! Mitsuba 3's `principled` BSDF (its src/bsdfs/principled.cpp and principledhelpers.h, after
//! Burley's "Physically Based Shading at Disney", 2012, and "Extending the Disney BRDF to a BSDF
//! with Integrated Subsurface Scattering", 2015): a diffuse lobe with retro-reflection and a
//! fake subsurface blend, sheen, a GGX specular reflection whose Fresnel blends dielectric,
//! tinted and metallic terms, a GGX specular transmission and a GTR1 clearcoat. This is the CPU
//! reference that src/bsdfs/principled/principled.wgsl must equal, lobe by lobe, including Mitsuba's
//! own choices (the clearcoat's missing 1/(4 cos cos), lobe choice by the Fresnel of the
//! sampled specular normal).

use glam::{Vec2, Vec3};

use crate::bsdfs::shared::fresnel::{fresnel, reflect, refract};
use crate::bsdfs::shared::microfacet::{Distribution, Microfacet, square_to_cosine_hemisphere};
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::{Plugin, p};
use crate::scene::texture::luminance;
use crate::scene::{SceneError, SideTextures};

/// Bits of [`Principled`]'s `has`: Mitsuba's `m_has_*`, set when the file gives the parameter (a
/// texture, or a float other than 0). They change more than the weight: a lobe's sampling
/// probability, the roughness's aspect, which Fresnel terms exist.
pub const HAS_ANISOTROPIC: u32 = 1;
pub const HAS_SPEC_TRANS: u32 = 2;
pub const HAS_SHEEN: u32 = 4;
pub const HAS_SHEEN_TINT: u32 = 8;
pub const HAS_FLATNESS: u32 = 16;
pub const HAS_SPEC_TINT: u32 = 32;
pub const HAS_METALLIC: u32 = 64;
pub const HAS_CLEARCOAT: u32 = 128;

/// The parameters at one surface point (textures already looked up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Principled {
    pub base_color: Vec3,
    pub roughness: f32,
    pub anisotropic: f32,
    pub metallic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    /// Interior over exterior index, given as `eta` or derived from `specular`.
    pub eta: f32,
    /// Sampling rates of the main specular lobes, the clearcoat and the diffuse lobe.
    pub spec_srate: f32,
    pub clearcoat_srate: f32,
    pub diffuse_srate: f32,
    /// `HAS_*` bits.
    pub has: u32,
}

impl Principled {
    fn has(&self, bit: u32) -> bool {
        self.has & bit != 0
    }

    /// The main lobes' GGX distribution.
    fn specular_distribution(&self) -> Microfacet {
        let anisotropic = if self.has(HAS_ANISOTROPIC) {
            self.anisotropic
        } else {
            0.0
        };
        ggx(anisotropic, self.roughness)
    }

    fn clearcoat_alpha(&self) -> f32 {
        lerp(0.1, 0.001, self.clearcoat_gloss)
    }

    /// Weights of the diffuse (BRDF) and transmissive (BSDF) major lobes.
    fn major_weights(&self) -> (f32, f32) {
        let brdf = (1.0 - self.metallic) * (1.0 - self.spec_trans);
        let bsdf = (1.0 - self.metallic) * self.spec_trans;
        (brdf, bsdf)
    }

    /// Lobe probabilities (diffuse, clearcoat, transmission, reflection) given the dielectric
    /// Fresnel `f` of the specular normal.
    fn lobe_probabilities(&self, front: bool, f: f32) -> [f32; 4] {
        let (brdf, bsdf) = self.major_weights();
        let reflect = if front {
            self.spec_srate * (1.0 - bsdf * (1.0 - f))
        } else {
            f
        };
        let trans = match (self.has(HAS_SPEC_TRANS), front) {
            (false, _) => 0.0,
            (true, true) => self.spec_srate * bsdf * (1.0 - f),
            (true, false) => 1.0 - f,
        };
        let clearcoat = if self.has(HAS_CLEARCOAT) && front {
            0.25 * self.clearcoat * self.clearcoat_srate
        } else {
            0.0
        };
        let diffuse = if front {
            brdf * self.diffuse_srate
        } else {
            0.0
        };
        let total = reflect + trans + clearcoat + diffuse;
        [
            diffuse / total,
            clearcoat / total,
            trans / total,
            reflect / total,
        ]
    }
}

/// The GGX distribution of a roughness and anisotropy (Mitsuba's calc_dist_params; an
/// anisotropy of 0 is its isotropic case).
pub(crate) fn ggx(anisotropic: f32, roughness: f32) -> Microfacet {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    Microfacet {
        distribution: Distribution::Ggx,
        alpha_u: (r2 / aspect).max(0.001),
        alpha_v: (r2 * aspect).max(0.001),
    }
}

pub(crate) fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

pub(crate) fn lerp3(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    a * (1.0 - t) + b * t
}

/// `a` with the sign of `b` flipped in when `b` is negative (drjit's mulsign).
pub(crate) fn mulsign(a: Vec3, b: f32) -> Vec3 {
    if b.is_sign_negative() { -a } else { a }
}

pub(crate) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    m * m * m * m * m
}

/// Schlick's Fresnel from `r0`, taken at the transmitted angle when light leaves the denser
/// side (Mitsuba's calc_schlick).
pub(crate) fn calc_schlick(r0: Vec3, cos_i: f32, eta: f32) -> Vec3 {
    let outside = cos_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_t = (1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti)
        .max(0.0)
        .sqrt();
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        schlick_weight(cos_t)
    };
    Vec3::splat(w) * (Vec3::ONE - r0) + r0
}

pub(crate) fn schlick_r0(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

/// Micro- and macro-surface agree on the sides of `wi` and `wo` (Mitsuba's
/// mac_mic_compatibility).
pub(crate) fn compatible(m: Vec3, wi: Vec3, wo: Vec3, cos_i: f32, reflection: bool) -> bool {
    let m_i = mulsign(m, cos_i);
    let m_o = if reflection { m_i } else { -m_i };
    wi.dot(m_i) > 0.0 && wo.dot(m_o) > 0.0
}

fn principled_fresnel(p: &Principled, f_dielectric: f32, cos_i: f32, front: bool) -> Vec3 {
    let (_, bsdf) = p.major_weights();
    if !front {
        return Vec3::splat(bsdf * f_dielectric);
    }
    let eta_it = if cos_i >= 0.0 { p.eta } else { 1.0 / p.eta };
    let mut schlick = Vec3::ZERO;
    if p.has(HAS_METALLIC) {
        schlick += p.metallic * calc_schlick(p.base_color, cos_i, p.eta);
    }
    if p.has(HAS_SPEC_TINT) {
        let tint = tint_of(p.base_color);
        schlick += (1.0 - p.metallic)
            * p.spec_tint
            * calc_schlick(tint * schlick_r0(eta_it), cos_i, p.eta);
    }
    Vec3::splat((1.0 - p.metallic) * (1.0 - p.spec_tint) * f_dielectric) + schlick
}

/// The base colour's hue at luminance 1 (white for black).
pub(crate) fn tint_of(c: Vec3) -> Vec3 {
    let lum = luminance(c);
    if lum > 0.0 { c / lum } else { Vec3::ONE }
}

/// GTR1, the clearcoat's isotropic distribution.
fn gtr1_d(alpha: f32, m: Vec3) -> f32 {
    let a2 = alpha * alpha;
    let r = (a2 - 1.0) / (std::f32::consts::PI * a2.ln() * (1.0 + (a2 - 1.0) * m.z * m.z));
    if r * m.z > 1e-20 { r } else { 0.0 }
}

fn gtr1_pdf(alpha: f32, m: Vec3) -> f32 {
    if m.z < 0.0 {
        0.0
    } else {
        m.z * gtr1_d(alpha, m)
    }
}

fn gtr1_sample(alpha: f32, u: Vec2) -> Vec3 {
    let phi = 2.0 * std::f32::consts::PI * u.x;
    let a2 = alpha * alpha;
    let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
    let sin = (1.0 - cos2).max(0.0).sqrt();
    Vec3::new(phi.cos() * sin, phi.sin() * sin, cos2.max(0.0).sqrt())
}

fn smith_ggx1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The diffuse lobe's shape (times base colour / pi it is f): Burley's diffuse with its
/// retro-reflection, blended towards the fake subsurface term by `flatness` (Hanrahan-Krueger
/// based; Mitsuba's principledhelpers). `cos_d` is the half vector's cosine with wo.
pub(crate) fn diffuse_lobe(
    roughness: f32,
    flatness: f32,
    cos_i: f32,
    cos_o: f32,
    cos_d: f32,
) -> f32 {
    let (fo, fi) = (schlick_weight(cos_o), schlick_weight(cos_i));
    let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * roughness * cos_d * cos_d;
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    if flatness == 0.0 {
        return f_diff + f_retro;
    }
    let fss90 = rr / 2.0;
    let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
    let f_ss = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
    lerp(f_diff + f_retro, f_ss, flatness)
}

/// The sheen lobe's f (before its weight against the other lobes), white tinted towards the
/// base colour's hue by `sheen_tint`.
pub(crate) fn sheen_lobe(sheen: f32, sheen_tint: f32, base_color: Vec3, cos_d: f32) -> Vec3 {
    let tint = if sheen_tint == 0.0 {
        Vec3::ONE
    } else {
        lerp3(Vec3::ONE, tint_of(base_color), sheen_tint)
    };
    sheen * schlick_weight(cos_d.abs()) * tint
}

/// The half vector of (wi, wo), facing +z, whether they reflect, and the index along the path.
fn half_vector(p: &Principled, wi: Vec3, wo: Vec3) -> (Vec3, bool, f32) {
    let reflect = wi.z * wo.z > 0.0;
    let eta_path = if wi.z > 0.0 { p.eta } else { 1.0 / p.eta };
    let h = (wi + wo * if reflect { 1.0 } else { eta_path }).normalize();
    (mulsign(h, h.z), reflect, eta_path)
}

/// f(wi, wo) |cos wo|.
pub fn eval(p: &Principled, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
    let (ci, co) = (wi.z, wo.z);
    if ci == 0.0 {
        return Vec3::ZERO;
    }
    let (brdf, bsdf) = p.major_weights();
    let front = ci > 0.0;
    let refract_pair = ci * co < 0.0;
    let (h, reflect_pair, eta_path) = half_vector(p, wi, wo);
    let mf = p.specular_distribution();
    let f = fresnel(wi.dot(h), p.eta).0;
    let reflection_ok = compatible(h, wi, wo, ci, true);
    let refraction_ok = compatible(h, wi, wo, ci, false);
    let d = mf.d(h);
    let g = mf.g1(wi, h) * mf.g1(wo, h);
    let mut value = Vec3::ZERO;
    if reflect_pair && reflection_ok && f > 0.0 {
        value += principled_fresnel(p, f, wi.dot(h), front) * d * g / (4.0 * ci.abs());
    }
    if p.has(HAS_SPEC_TRANS) && bsdf > 0.0 && refract_pair && refraction_ok && f < 1.0 {
        let scale = match mode {
            Mode::Radiance => 1.0 / (eta_path * eta_path),
            Mode::Importance => 1.0,
        };
        let denom = wi.dot(h) + eta_path * wo.dot(h);
        let t = (scale * (1.0 - f) * d * g * eta_path * eta_path * wi.dot(h) * wo.dot(h)
            / (ci * denom * denom))
            .abs();
        value += p.base_color.max(Vec3::ZERO).powf(0.5) * bsdf * t;
    }
    if p.has(HAS_CLEARCOAT) && p.clearcoat > 0.0 && reflect_pair && reflection_ok && front {
        let fcc = calc_schlick(Vec3::splat(0.04), wi.dot(h), p.eta).x;
        let dcc = gtr1_d(p.clearcoat_alpha(), h);
        let gcc = smith_ggx1(wi, h, 0.25) * smith_ggx1(wo, h, 0.25);
        value += Vec3::splat(p.clearcoat * 0.25 * fcc * dcc * gcc * co.abs());
    }
    if brdf > 0.0 && reflect_pair && front {
        let flatness = if p.has(HAS_FLATNESS) { p.flatness } else { 0.0 };
        let lobe = diffuse_lobe(p.roughness, flatness, ci.abs(), co.abs(), h.dot(wo));
        value += brdf * co.abs() * p.base_color * std::f32::consts::FRAC_1_PI * lobe;
    }
    // Mitsuba adds the sheen under the diffuse lobe's mask in scalar code but its own mask
    // alone in vectorised variants (any lane with a diffuse lobe runs it): the latter, which
    // is what its LLVM and CUDA variants render.
    if p.has(HAS_SHEEN) && p.sheen > 0.0 && reflect_pair && 1.0 - p.metallic > 0.0 && front {
        let sheen_tint = if p.has(HAS_SHEEN_TINT) {
            p.sheen_tint
        } else {
            0.0
        };
        value += (1.0 - p.metallic)
            * sheen_lobe(p.sheen, sheen_tint, p.base_color, h.dot(wo))
            * co.abs();
    }
    if value.is_finite() { value } else { Vec3::ZERO }
}

/// The density [`sample`] reports for `wo` (Mitsuba's pdf()).
pub fn pdf(p: &Principled, wi: Vec3, wo: Vec3) -> f32 {
    let ci = wi.z;
    if ci == 0.0 {
        return 0.0;
    }
    let front = ci > 0.0;
    let refract_pair = ci * wo.z < 0.0;
    let (h, reflect_pair, eta_path) = half_vector(p, wi, wo);
    let mf = p.specular_distribution();
    let f = fresnel(wi.dot(h), p.eta).0;
    let [diffuse, clearcoat, trans, reflect] = p.lobe_probabilities(front, f);
    let (dot_i, dot_o) = (wi.dot(h), wo.dot(h));
    let dwh_dwo = if p.has(HAS_SPEC_TRANS) && !reflect_pair {
        eta_path * eta_path * dot_o / (dot_i + eta_path * dot_o).powi(2)
    } else {
        1.0 / (4.0 * dot_o)
    }
    .abs();
    let visible = mf.pdf(mulsign(wi, ci), h);
    let mut pdf = 0.0;
    let reflection_ok = compatible(h, wi, wo, ci, true) && reflect_pair;
    if reflection_ok {
        pdf += reflect * visible * dwh_dwo;
    }
    if reflect_pair {
        pdf += diffuse * wo.z * std::f32::consts::FRAC_1_PI;
    }
    if p.has(HAS_SPEC_TRANS) && compatible(h, wi, wo, ci, false) && refract_pair {
        pdf += trans * visible * dwh_dwo;
    }
    if p.has(HAS_CLEARCOAT) && reflection_ok {
        pdf += clearcoat * gtr1_pdf(p.clearcoat_alpha(), h) * dwh_dwo;
    }
    if pdf.is_finite() { pdf } else { 0.0 }
}

/// A direction sampled as Mitsuba samples it: the specular normal first, the lobe chosen by
/// `u1` with probabilities that use its Fresnel, then the lobe's direction from `u2` (reused).
/// Returns (wo, f |cos wo| / pdf, pdf).
pub fn sample(
    p: &Principled,
    wi: Vec3,
    u1: f32,
    u2: Vec2,
    mode: Mode,
) -> Option<(Vec3, Vec3, f32)> {
    let ci = wi.z;
    if ci == 0.0 {
        return None;
    }
    let front = ci > 0.0;
    let bsdf = if p.has(HAS_SPEC_TRANS) {
        p.major_weights().1
    } else {
        0.0
    };
    if !front && bsdf <= 0.0 {
        return None;
    }
    let mf = p.specular_distribution();
    let m = mf.sample(mulsign(wi, ci), u2);
    let (f, cos_t, _, eta_ti) = fresnel(wi.dot(m), p.eta);
    let [diffuse, clearcoat, trans, _] = p.lobe_probabilities(front, f);
    let wo = if u1 < diffuse {
        let wo = square_to_cosine_hemisphere(u2);
        (ci * wo.z > 0.0).then_some(wo)?
    } else if p.has(HAS_CLEARCOAT) && u1 < diffuse + clearcoat {
        let m = gtr1_sample(p.clearcoat_alpha(), u2);
        let wo = reflect(wi, m);
        (compatible(m, wi, wo, ci, true) && ci * wo.z > 0.0).then_some(wo)?
    } else if p.has(HAS_SPEC_TRANS) && u1 < diffuse + clearcoat + trans {
        let wo = refract(wi, m, cos_t, eta_ti);
        (compatible(m, wi, wo, ci, false) && ci * wo.z < 0.0).then_some(wo)?
    } else {
        let wo = reflect(wi, m);
        (compatible(m, wi, wo, ci, true) && ci * wo.z > 0.0).then_some(wo)?
    };
    let density = pdf(p, wi, wo);
    if density.is_nan() || density <= 0.0 {
        return None;
    }
    Some((wo, eval(p, wi, wo, mode) / density, density))
}

/// The `eta` a `specular` of 0..1 stands for (Mitsuba: eta = 2 / (1 - sqrt(0.08 specular)) - 1).
pub fn eta_from_specular(specular: f32) -> f32 {
    2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
}

/// Continuous: caustics through it or onto it are path traced, never photon mapped, whatever
/// its roughness.
const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: false,
    continuous: true,
    transmits: false,
    pass_through: false,
};

const MODULE: &str = "bsdfs::principled";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "principled",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["principled"],
        properties: &[
            p("base_color", "0.5"),
            p("roughness", "0.5"),
            p("anisotropic", "0"),
            p("metallic", "0"),
            p("spec_trans", "0"),
            p("eta", "from specular"),
            p("specular", "0.5"),
            p("spec_tint", "0"),
            p("sheen", "0"),
            p("sheen_tint", "0"),
            p("flatness", "0"),
            p("clearcoat", "0"),
            p("clearcoat_gloss", "0"),
            p("main_specular_sampling_rate", "1"),
            p("clearcoat_sampling_rate", "1"),
            p("diffuse_reflectance_sampling_rate", "1"),
        ],
        notes: "Every lobe as Mitsuba 3.9.1 writes it (src/bsdfs/principled/mod.rs), its \
                sampling too. Every parameter but `eta`, `specular` and the sampling rates may \
                be a texture, as in Mitsuba (the rest are numbers there too). A continuous BSDF \
                for the light-transport partition: caustics through it or onto it are path \
                traced, never photon mapped.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "principled_eval")),
        sample: Some(WgslCall::new(MODULE, "principled_sample")),
        // Principled floors its alphas itself (`ggx`).
        alpha_floor: 0.0,
        ..GpuKind::inline("principled", LOBES)
    }],
    def: Some("PRINCIPLED"),
    wgsl: Some(crate::shader_file!("src/bsdfs/principled/principled.wgsl")),
};

/// The parameters besides base colour, roughness and metallic that Mitsuba's plugin reads as
/// textures (`eta` and `specular` are plain floats there), in the order of the record's field
/// textures.
pub const TEXTURED: [&str; 8] = [
    "anisotropic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "clearcoat",
    "clearcoat_gloss",
];

/// Every property its plugin reads; each parameter its plugin reads as a texture may be one.
fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let (base_color, base_texture) = r.color_or_texture("base_color", 0.5)?;
    textures.diffuse = base_texture;
    let mut has = 0;
    // (value, texture), and whether Mitsuba counts it as given (m_has_*: a texture, or a float
    // other than 0; every parameter with a bit defaults to 0).
    let mut scalar = |r: &mut dyn BsdfReader, name: &str, default: f32, bit: u32| {
        let (value, texture) = r.scalar_or_texture(name, default)?;
        if texture.is_some() || value != 0.0 {
            has |= bit;
        }
        Ok::<_, SceneError>((value, texture))
    };
    let (roughness, roughness_texture) = scalar(r, "roughness", 0.5, 0)?;
    let (metallic, metallic_texture) = scalar(r, "metallic", 0.0, HAS_METALLIC)?;
    (textures.alpha_u, textures.alpha_v) = (roughness_texture, metallic_texture);
    let bits = [
        HAS_ANISOTROPIC,
        HAS_SPEC_TRANS,
        HAS_SPEC_TINT,
        HAS_SHEEN,
        HAS_SHEEN_TINT,
        HAS_FLATNESS,
        HAS_CLEARCOAT,
        0,
    ];
    let mut values = [0.0; TEXTURED.len()];
    for (i, (name, bit)) in TEXTURED.iter().zip(bits).enumerate() {
        (values[i], textures.fields[i]) = scalar(r, name, 0.0, bit)?;
    }
    let [
        anisotropic,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        clearcoat,
        clearcoat_gloss,
    ] = values;
    let mut rate = |name: &str| Ok::<_, SceneError>(r.float(name)?.unwrap_or(1.0));
    let spec_srate = rate("main_specular_sampling_rate")?;
    let clearcoat_srate = rate("clearcoat_sampling_rate")?;
    let diffuse_srate = rate("diffuse_reflectance_sampling_rate")?;
    let transmits = has & HAS_SPEC_TRANS != 0;
    let eta = match (r.has("eta"), r.has("specular")) {
        (true, true) => {
            return Err(r.error_at(
                "specular",
                "principled: give eta or specular, not both (as in Mitsuba)".into(),
            ));
        }
        (true, false) => {
            let eta = r.float("eta")?.unwrap_or(1.5);
            if eta.is_nan() || eta <= 0.0 {
                return Err(r.error_at("eta", format!("eta {eta}: must be positive")));
            }
            // Mitsuba's nudge: eta 1 cannot refract.
            if transmits && eta == 1.0 { 1.001 } else { eta }
        }
        (false, _) => {
            let specular = r.float("specular")?.unwrap_or(0.5);
            let specular = if transmits && specular == 0.0 {
                1e-3
            } else {
                specular
            };
            eta_from_specular(specular)
        }
    };
    let model = Principled {
        base_color,
        roughness,
        anisotropic,
        metallic,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        clearcoat,
        clearcoat_gloss,
        eta,
        spec_srate,
        clearcoat_srate,
        diffuse_srate,
        has,
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

impl BsdfModel for Principled {
    fn kind(&self) -> &'static str {
        "principled"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        let scalars = [
            self.roughness,
            self.anisotropic,
            self.metallic,
            self.spec_trans,
            self.spec_tint,
            self.sheen,
            self.sheen_tint,
            self.flatness,
            self.clearcoat,
            self.clearcoat_gloss,
            self.spec_srate,
            self.clearcoat_srate,
            self.diffuse_srate,
        ];
        self.base_color.is_finite() && scalars.iter().all(|v| v.is_finite()) && self.eta > 0.0
    }

    fn eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        eval(self, wi, wo, mode)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        pdf(self, wi, wo)
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        sample(self, wi, u1, u2, mode).map(|(wo, weight, pdf)| Sample {
            wo,
            weight,
            pdf,
            delta: false,
        })
    }

    /// The parameters in the slots of the other kinds (principled.wgsl reads them back): base
    /// colour, roughness and metallic where the fixed texture slots replace them (`albedo`,
    /// `alpha_u`, `alpha_v`), the rest where field textures do.
    fn pack(&self, record: &mut GpuMaterial, textures: &SideTextures, tables: &mut Vec<f32>) {
        record.albedo = self.base_color.to_array();
        (record.alpha_u, record.alpha_v) = (self.roughness, self.metallic);
        record.specular = [self.anisotropic, self.spec_trans, self.spec_tint];
        record.eta = [self.sheen, self.sheen_tint, self.flatness];
        record.k = [self.clearcoat, self.clearcoat_gloss, self.eta];
        (record.int_ior, record.ext_ior) = (self.spec_srate, self.clearcoat_srate);
        record.specular_weight = self.diffuse_srate;
        record.nonlinear = self.has;
        record.set_field_textures(&textures.fields, tables);
    }
}
