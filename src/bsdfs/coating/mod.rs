//! Mitsuba 0.6's `coating` and `roughcoating` (src/bsdfs/coating.cpp and roughcoating.cpp of
//! mitsuba-renderer/mitsuba, whose `eval`, `pdf` and `sample` the code below transcribes): a
//! dielectric layer, optionally absorbing (`sigmaA` times `thickness` along each refracted
//! direction), over one nested BSDF. The nested BSDF is evaluated and sampled at the directions
//! refracted into the layer (sign kept), seen through the interface's transmittance at wi and
//! wo and compressed by 1 / eta^2 into the outer solid angle. `coating`'s interface is smooth
//! (a delta reflection lobe with Fresnel's reflectance, two smooth refractions for the nested
//! lobe); `roughcoating`'s is a microfacet interface (its reflection lobe is rough plastic's,
//! the nested lobe seen through the rough interface's transmittance, which 0.6 reads from its
//! precomputed tables and hppm computes at load for the file's eta and alpha). Mitsuba 3 has no
//! such plugin, so they are read from files of version 0.x only.
//!
//! The nested BSDF is a material of its own (added before the coating, as a blend's children
//! are), and the coating's GPU record points at it (`children.x`): `coating.wgsl` reads that
//! record and calls the nested kind's WGSL through `common::leaf_material`, the dispatch the
//! registry generates for kinds that nest ([`GpuKind::nests`]; WGSL has no recursion, so the
//! main dispatch cannot call itself). The nested kinds accepted are the one-sided, non-delta,
//! non-transmitting ones that need no texture: `diffuse` (Lambertian, which the coating's WGSL
//! evaluates itself, as the passes do), `roughconductor`, `roughplastic`, `roughdiffuse`,
//! `phong`, `ward`; the others are refused at the element.
//!
//! For the light-transport partition the smooth coating's reflection is a delta lobe (an S
//! vertex when sampled) and the nested lobe seen through the interface is continuous (path
//! traced, reached by next-event estimation, never photon-mapped), as `plastic`'s base is,
//! whatever the nested kind. The rough coating's reflection is a microfacet lobe split at a
//! graph's `glossy_threshold` as rough plastic's coating is (`Glossy::Split`), its nested lobe
//! continuous as above.

use glam::{Vec2, Vec3};

use crate::bsdfs::roughplastic::rough_transmittance;
use crate::bsdfs::shared::fresnel::{fresnel, reflect};
use crate::bsdfs::shared::microfacet::Microfacet;
use crate::bsdfs::shared::mitsuba06::{
    energy_scale, ensures_energy_conservation, only_in_mitsuba06,
};
use crate::bsdfs::shared::{AIR, Alphas, BK7, ior, microfacet};
use crate::bsdfs::{BsdfPlugin, BsdfReader, Glossy, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample, sample_from_eval};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const SMOOTH_LOBES: Lobes = Lobes {
    delta: true,
    microfacet: false,
    continuous: true,
    transmits: false,
    pass_through: false,
};

const ROUGH_LOBES: Lobes = Lobes {
    delta: false,
    microfacet: true,
    continuous: true,
    transmits: false,
    pass_through: false,
};

const MODULE: &str = "bsdfs::coating";

/// The nested kinds the coating's WGSL dispatches to (see the module's doc).
pub const NESTED_KINDS: &[&str] = &[
    "diffuse",
    "roughconductor",
    "roughplastic",
    "roughdiffuse",
    "phong",
    "ward",
];

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "coating",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["coating"],
        properties: &[
            p("int_ior", "bk7"),
            p("ext_ior", "air"),
            p("thickness", "1"),
            p("sigma_a", "0"),
            p("specular_reflectance", "1"),
            p("ensure_energy_conservation", "true"),
        ],
        notes: "Mitsuba 0.6's smooth dielectric coating (files of version 0.x only; Mitsuba 3 \
                has no `coating`) over one nested BSDF (diffuse, roughconductor, roughplastic, \
                roughdiffuse, phong or ward, untextured); `sigma_a` a colour. Its reflection is \
                a delta lobe, the nested BSDF seen through it a continuous one.",
    }],
    read,
    objects: &["bsdf", "ref"],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "coating_eval")),
        sample: Some(WgslCall::new(MODULE, "coating_sample")),
        nests: true,
        ..GpuKind::inline("coating", SMOOTH_LOBES)
    }],
    def: Some("COATING"),
    wgsl: Some(crate::shader_file!("src/bsdfs/coating/coating.wgsl")),
};

/// `roughcoating`: the same layer under a rough interface; its WGSL is `coating`'s.
pub static ROUGH_PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "roughcoating",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["roughcoating"],
        properties: &[
            p("int_ior", "bk7"),
            p("ext_ior", "air"),
            p("thickness", "1"),
            p("sigma_a", "0"),
            p("specular_reflectance", "1"),
            p("ensure_energy_conservation", "true"),
            p("distribution", "beckmann"),
            p("alpha", "0.1"),
            p("alpha_u", "refused: isotropic only"),
            p("alpha_v", "refused: isotropic only"),
            p("sample_visible", "true"),
        ],
        notes: "Mitsuba 0.6's rough dielectric coating (files of version 0.x only) over one \
                nested BSDF (diffuse, roughconductor, roughplastic, roughdiffuse, phong or \
                ward, untextured); `alpha` a number in 0.6's tabulated range [0, 4], the \
                interface's transmittance computed at load for its eta and alpha. Its \
                reflection lobe is glossy for the partition, as rough plastic's coating.",
    }],
    read,
    objects: &["bsdf", "ref"],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "rough_coating_eval")),
        sample: Some(WgslCall::new(MODULE, "rough_coating_sample")),
        glossy: Glossy::Split {
            eval: WgslCall::new(MODULE, "rough_coating_reflection"),
            share: WgslCall::new(MODULE, "rough_coating_reflection_share"),
        },
        nests: true,
        ..GpuKind::inline("roughcoating", ROUGH_LOBES)
    }],
    def: Some("COATING"),
    wgsl: None,
};

/// Entries of the rough interface's transmittance table, over cos(theta)^(1/4) from 0 to 1:
/// 0.6's tables' resolution in theta and their warping (data/microfacet/*.dat).
pub const TRANSMITTANCE_RES: usize = 100;

/// The roughness range 0.6's transmittance tables cover (their header; `checkAlpha` refuses
/// the rest), and the range of relative indices (`checkEta`, eta or 1 / eta).
pub const ALPHA_RANGE: (f32, f32) = (0.0, 4.0);
pub const ETA_RANGE: (f32, f32) = (1.0001, 4.0);

/// The layer and what it covers, as both plugins read them.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// int_ior / ext_ior.
    pub eta: f32,
    /// sigma_a times thickness, per channel.
    pub optical_depth: Vec3,
    /// `specular_reflectance` after 0.6's energy check.
    pub specular: Vec3,
    /// 0.6's `m_specularSamplingWeight`: 1 / (1 + the mean of exp(-2 sigma_a thickness)).
    pub specular_weight: f32,
    pub nested: Bsdf,
    /// The nested BSDF's material (its index in the scene), which the GPU record points at.
    pub nested_index: u32,
}

/// The smooth `coating`.
#[derive(Debug, Clone, PartialEq)]
pub struct Coating {
    pub layer: Layer,
}

/// `roughcoating`.
#[derive(Debug, Clone, PartialEq)]
pub struct RoughCoating {
    pub layer: Layer,
    pub microfacet: Microfacet,
    /// The interface's transmittance from outside at cos(theta) = (i / (RES - 1))^4.
    pub transmittance: Vec<f32>,
}

impl Layer {
    pub fn new(eta: f32, optical_depth: Vec3, specular: Vec3, nested: Bsdf, index: u32) -> Self {
        let average_absorption = {
            let t = (-2.0 * optical_depth).exp();
            (t.x + t.y + t.z) / 3.0
        };
        Layer {
            eta,
            optical_depth,
            specular,
            specular_weight: 1.0 / (average_absorption + 1.0),
            nested,
            nested_index: index,
        }
    }

    fn is_valid(&self) -> bool {
        self.eta.is_finite()
            && self.eta > 0.0
            && self.eta != 1.0
            && self.optical_depth.is_finite()
            && self.optical_depth.min_element() >= 0.0
            && self.specular.is_finite()
            && self.specular.min_element() >= 0.0
            && self.nested.is_valid()
    }

    /// exp(-sigma_a thickness (1 / |cos wi'| + 1 / |cos wo'|)) inside the layer.
    fn absorption(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if self.optical_depth == Vec3::ZERO {
            return Vec3::ONE;
        }
        (-self.optical_depth * (1.0 / wi.z.abs() + 1.0 / wo.z.abs())).exp()
    }

    /// 0.6's lobe choice: the reflection's probability when it reflects `r` at wi.
    fn specular_prob(&self, r: f32) -> f32 {
        let w = self.specular_weight;
        r * w / (r * w + (1.0 - r) * (1.0 - w))
    }

    fn pack(&self, record: &mut GpuMaterial) {
        record.int_ior = self.eta;
        record.ext_ior = 1.0;
        record.k = self.optical_depth.to_array();
        record.specular = self.specular.to_array();
        record.specular_weight = self.specular_weight;
        record.children = [self.nested_index; 2];
    }
}

/// 0.6's `refractIn` / `refractOut` of the smooth coating: `w` refracted through the interface
/// of relative index `eta` (the side it comes from taking eta as seen from there) with its
/// sign kept, and the interface's reflectance there; `None` under total internal reflection.
fn refract_keeping_side(w: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let (r, cos_t, _, _) = fresnel(w.z.abs(), eta);
    if r >= 1.0 {
        return None;
    }
    let inv = 1.0 / eta;
    Some((
        Vec3::new(inv * w.x, inv * w.y, w.z.signum() * cos_t.abs()),
        r,
    ))
}

/// 0.6's `refractTo` of the rough coating: Snell's law alone (sign kept), `None` under total
/// internal reflection (where 0.6 returns the zero vector).
fn refract_to(w: Vec3, inv_eta: f32) -> Option<Vec3> {
    let sin2 = inv_eta * inv_eta * (1.0 - w.z * w.z).max(0.0);
    if sin2 >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2).sqrt();
    Some(Vec3::new(
        inv_eta * w.x,
        inv_eta * w.y,
        w.z.signum() * cos_t,
    ))
}

impl BsdfModel for Coating {
    fn kind(&self) -> &'static str {
        "coating"
    }

    fn lobes(&self) -> Lobes {
        SMOOTH_LOBES
    }

    fn is_valid(&self) -> bool {
        self.layer.is_valid()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        let l = &self.layer;
        let (Some((wi_in, r12)), Some((wo_in, r21))) = (
            refract_keeping_side(wi, l.eta),
            refract_keeping_side(wo, l.eta),
        ) else {
            return Vec3::ZERO;
        };
        let nested = l.nested.eval(wi_in, wo_in, mode) * ((1.0 - r12) * (1.0 - r21));
        nested * l.absorption(wi_in, wo_in) * (wo.z / (l.eta * l.eta * wo_in.z))
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let l = &self.layer;
        let (Some((wi_in, r12)), Some((wo_in, _))) = (
            refract_keeping_side(wi, l.eta),
            refract_keeping_side(wo, l.eta),
        ) else {
            return 0.0;
        };
        let nested = l.nested.pdf(wi_in, wo_in) * wo.z / (l.eta * l.eta * wo_in.z);
        nested * (1.0 - l.specular_prob(r12))
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        let l = &self.layer;
        let r12 = fresnel(wi.z.abs(), l.eta).0;
        let prob = l.specular_prob(r12);
        if u1 < prob {
            return Some(Sample {
                wo: Vec3::new(-wi.x, -wi.y, wi.z),
                weight: l.specular * (r12 / prob),
                pdf: prob,
                delta: true,
            });
        }
        let (wi_in, _) = refract_keeping_side(wi, l.eta)?;
        let u1 = (u1 - prob) / (1.0 - prob);
        let s = l.nested.sample(wi_in, u1, u2, mode)?;
        let (wo, r21) = refract_keeping_side(s.wo, 1.0 / l.eta)?;
        let weight =
            s.weight * l.absorption(wi_in, s.wo) * ((1.0 - r12) * (1.0 - r21)) / (1.0 - prob);
        let pdf = s.pdf * (1.0 - prob) * wo.z / (l.eta * l.eta * s.wo.z);
        Some(Sample {
            wo,
            weight,
            pdf,
            delta: false,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        self.layer.pack(record);
    }

    fn children(&self) -> &[u32] {
        std::slice::from_ref(&self.layer.nested_index)
    }
}

impl RoughCoating {
    /// The coating with its interface's transmittance tabulated at 0.6's nodes: (i / (RES -
    /// 1))^4 in cos theta, the first node at a tenth of a step as 0.6's `rdielprec` takes it.
    pub fn new(layer: Layer, microfacet: Microfacet) -> Self {
        let step = 1.0 / (TRANSMITTANCE_RES - 1) as f32;
        let transmittance = (0..TRANSMITTANCE_RES)
            .map(|i| {
                let t = if i == 0 { step / 10.0 } else { i as f32 * step };
                rough_transmittance(microfacet, t.powi(4), layer.eta).clamp(0.0, 1.0)
            })
            .collect();
        RoughCoating {
            layer,
            microfacet,
            transmittance,
        }
    }

    /// The interface's transmittance from outside at |cos theta|, linear in cos^(1/4) between
    /// the nodes (0.6 interpolates its table cubically in the same variable).
    pub fn transmittance_at(&self, cos: f32) -> f32 {
        let table = &self.transmittance;
        let x = cos.abs().sqrt().sqrt() * (table.len() - 1) as f32;
        let i = (x.max(0.0) as usize).min(table.len() - 2);
        let t = x - i as f32;
        table[i] * (1.0 - t) + table[i + 1] * t
    }

    /// f |cos wo| of the interface's reflection, on either side (0.6 takes |cos| throughout).
    pub fn reflection(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z * wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wi + wo).normalize() * wo.z.signum();
        let mf = &self.microfacet;
        let f = fresnel(wi.dot(h).abs(), self.layer.eta).0;
        let g = mf.g1(wi, h) * mf.g1(wo, h);
        self.layer.specular * (f * mf.d(h) * g / (4.0 * wi.z.abs()))
    }

    fn nested_eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        let l = &self.layer;
        let inv = 1.0 / l.eta;
        let (Some(wi_in), Some(wo_in)) = (refract_to(wi, inv), refract_to(wo, inv)) else {
            return Vec3::ZERO;
        };
        let t = self.transmittance_at(wi.z) * self.transmittance_at(wo.z);
        l.nested.eval(wi_in, wo_in, mode) * l.absorption(wi_in, wo_in) * t * inv * inv * wo.z
            / wo_in.z
    }

    fn specular_prob(&self, wi: Vec3) -> f32 {
        self.layer.specular_prob(1.0 - self.transmittance_at(wi.z))
    }
}

impl BsdfModel for RoughCoating {
    fn kind(&self) -> &'static str {
        "roughcoating"
    }

    fn lobes(&self) -> Lobes {
        ROUGH_LOBES
    }

    fn roughness(&self) -> Option<f32> {
        Some(self.microfacet.roughness())
    }

    fn is_valid(&self) -> bool {
        self.layer.is_valid() && self.microfacet.is_valid()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        self.reflection(wi, wo) + self.nested_eval(wi, wo, mode)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let prob = self.specular_prob(wi);
        let mut pdf = 0.0;
        if wi.z * wo.z > 0.0 {
            let h = (wi + wo).normalize() * wo.z.signum();
            let mf = &self.microfacet;
            let visible = mf.g1(wi, h) * wi.dot(h).abs() * mf.d(h) / wi.z.abs();
            pdf = visible / (4.0 * wo.dot(h).abs()) * prob;
        }
        let inv = 1.0 / self.layer.eta;
        if let (Some(wi_in), Some(wo_in)) = (refract_to(wi, inv), refract_to(wo, inv)) {
            let nested = self.layer.nested.pdf(wi_in, wo_in) * inv * inv * wo.z / wo_in.z;
            pdf += nested * (1.0 - prob);
        }
        pdf
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        let prob = self.specular_prob(wi);
        let wo = if u1 < prob {
            // From below, the mirror image of the sample from above: the lobe is symmetric
            // about the surface, and the visible normals are sampled from above only.
            let flip = Vec3::new(1.0, 1.0, wi.z.signum());
            let up = wi * flip;
            let wo = reflect(up, self.microfacet.sample(up, u2)) * flip;
            if wo.z * wi.z <= 0.0 {
                return None;
            }
            wo
        } else {
            let inv = 1.0 / self.layer.eta;
            let wi_in = refract_to(wi, inv)?;
            let u1 = (u1 - prob) / (1.0 - prob);
            let s = self.layer.nested.sample(wi_in, u1, u2, mode)?;
            refract_to(s.wo, self.layer.eta)?
        };
        sample_from_eval(self, wi, wo, mode)
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, tables: &mut Vec<f32>) {
        self.layer.pack(record);
        self.microfacet.pack(record);
        record.table = tables.len() as u32;
        tables.extend_from_slice(&self.transmittance);
    }

    fn children(&self) -> &[u32] {
        std::slice::from_ref(&self.layer.nested_index)
    }
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    only_in_mitsuba06(r)?;
    let kind = r.plugin().to_string();
    let rough = kind == "roughcoating";
    let int_ior = ior(r, "int_ior", BK7)?;
    let ext_ior = ior(r, "ext_ior", AIR)?;
    if int_ior == ext_ior {
        return Err(r.error(format!(
            "{}: int_ior and ext_ior are both {int_ior}; they must differ (as in Mitsuba 0.6)",
            r.describe()
        )));
    }
    let eta = int_ior / ext_ior;
    let thickness = r.float("thickness")?.unwrap_or(1.0);
    if !(thickness >= 0.0 && thickness.is_finite()) {
        let what = r.describe_property("thickness");
        return Err(r.error_at("thickness", format!("{what}: must be a number not below 0")));
    }
    let sigma_a = r.color("sigma_a")?.unwrap_or(Vec3::ZERO);
    if !(sigma_a.is_finite() && sigma_a.min_element() >= 0.0) {
        let what = r.describe_property("sigma_a");
        return Err(r.error_at(
            "sigma_a",
            format!("{what}: every channel must be a number not below 0"),
        ));
    }
    let specular = r.color("specular_reflectance")?.unwrap_or(Vec3::ONE);
    if !(specular.is_finite() && specular.min_element() >= 0.0) {
        let what = r.describe_property("specular_reflectance");
        return Err(r.error_at(
            "specular_reflectance",
            format!("{what}: must not be negative"),
        ));
    }
    let specular = specular * energy_scale(ensures_energy_conservation(r)?, specular);
    let mut unused = SideTextures::default();
    let interface = if rough {
        let mf = microfacet(r, Alphas::Isotropic, &mut unused)?;
        let alpha = mf.alpha_u;
        if !(ALPHA_RANGE.0..=ALPHA_RANGE.1).contains(&alpha) {
            return Err(r.error_at(
                "alpha",
                format!(
                    "roughcoating: alpha {alpha} is outside the range [{}, {}] Mitsuba 0.6's \
                     transmittance tables cover (0.6 refuses it too)",
                    ALPHA_RANGE.0, ALPHA_RANGE.1
                ),
            ));
        }
        let outside = eta.max(1.0 / eta);
        if !(ETA_RANGE.0..=ETA_RANGE.1).contains(&outside) {
            return Err(r.error(format!(
                "{}: the relative index of refraction {eta} is outside the range [{}, {}] \
                 Mitsuba 0.6's transmittance tables cover (0.6 refuses it too)",
                r.describe(),
                ETA_RANGE.0,
                ETA_RANGE.1
            )));
        }
        Some(mf)
    } else {
        None
    };
    let mut nested = r.nested()?;
    if nested.len() > 1 {
        return Err(r.error_at_nested(
            1,
            format!("{kind}: only a single nested BSDF can be given (as in Mitsuba 0.6)"),
        ));
    }
    let Some(sides) = nested.pop() else {
        return Err(r.error(format!(
            "{kind} needs a nested <bsdf> (a child BSDF instance is required, as in Mitsuba 0.6)"
        )));
    };
    let supported = NESTED_KINDS.join(", ");
    let nested_kind = sides.front.kind();
    if !NESTED_KINDS.contains(&nested_kind) {
        return Err(r.error_at_nested(
            0,
            format!(
                "{kind}: a nested {nested_kind} is not supported; hppm coats {supported} \
                 (one-sided, without a delta or transmitting lobe)"
            ),
        ));
    }
    if sides.back.is_some() {
        return Err(r.error_at_nested(
            0,
            format!("{kind}: a nested twosided BSDF is not supported; hppm coats {supported}"),
        ));
    }
    if sides.textures.front.any() {
        return Err(r.error_at_nested(
            0,
            format!(
                "{kind}: a textured nested BSDF is not supported (the coating's record holds \
                 no texture for it); give it numbers or colours"
            ),
        ));
    }
    let bsdf = sides.front.clone();
    let index = r.add_material(sides.material(Vec3::ZERO));
    let layer = Layer::new(eta, sigma_a * thickness, specular, bsdf, index);
    let model = match interface {
        Some(mf) => Bsdf::new(RoughCoating::new(layer, mf)),
        None => Bsdf::new(Coating { layer }),
    };
    Ok(Sides::one(model, SideTextures::default()))
}
