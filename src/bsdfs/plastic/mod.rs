//! Mitsuba's `plastic`: a diffuse base under a smooth dielectric coating. The coating is a
//! delta lobe (a specular vertex of the partition when it is sampled), the base a continuous
//! one that next-event estimation reaches.

use glam::{Vec2, Vec3};

use crate::bsdfs::shared::fresnel::{fresnel, fresnel_diffuse_reflectance};
use crate::bsdfs::shared::microfacet::square_to_cosine_hemisphere;
use crate::bsdfs::shared::{AIR, ior};
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{
    Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample, mean, sample_from_eval,
};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: true,
    microfacet: false,
    continuous: true,
    transmits: false,
    pass_through: false,
};

const MODULE: &str = "bsdfs::plastic";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "plastic",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["plastic"],
        properties: &[
            p("int_ior", "polypropylene"),
            p("ext_ior", "air"),
            p("diffuse_reflectance", "0.5"),
            p("specular_reflectance", "1"),
            p("nonlinear", "false"),
        ],
        notes: "Smooth coating over a diffuse base; both reflectances may be textures.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "plastic_eval")),
        sample: Some(WgslCall::new(MODULE, "plastic_sample")),
        ..GpuKind::inline("plastic", LOBES)
    }],
    def: Some("PLASTIC"),
    wgsl: Some(crate::shader_file!("src/bsdfs/plastic/plastic.wgsl")),
};

/// Mitsuba's default inside a plastic: polypropylene.
pub const POLYPROPYLENE: f32 = 1.49;

/// What the three plastics read alike: the coating's indices and both reflectances (textures
/// in the diffuse and specular slots).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coated {
    pub int_ior: f32,
    pub ext_ior: f32,
    pub diffuse: Vec3,
    pub specular: Vec3,
}

impl Coated {
    pub fn read(r: &mut dyn BsdfReader, textures: &mut SideTextures) -> Result<Self, SceneError> {
        let int_ior = ior(r, "int_ior", POLYPROPYLENE)?;
        let ext_ior = ior(r, "ext_ior", AIR)?;
        let (diffuse, diffuse_texture) = r.color_or_texture("diffuse_reflectance", 0.5)?;
        let (specular, specular_texture) = r.color_or_texture("specular_reflectance", 1.0)?;
        (textures.diffuse, textures.specular) = (diffuse_texture, specular_texture);
        Ok(Coated {
            int_ior,
            ext_ior,
            diffuse,
            specular,
        })
    }

    pub fn is_valid(&self) -> bool {
        crate::bsdfs::dielectric::iors_valid(self.int_ior, self.ext_ior)
            && self.diffuse.is_finite()
            && self.specular.is_finite()
    }

    /// Mitsuba's `m_specular_sampling_weight`: the coating's share of the lobe choice.
    pub fn specular_weight(&self) -> f32 {
        let s = mean(self.specular);
        s / (mean(self.diffuse) + s)
    }

    /// Indices, reflectances and the lobe weight into the GPU record.
    pub fn pack(&self, record: &mut GpuMaterial) {
        (record.int_ior, record.ext_ior) = (self.int_ior, self.ext_ior);
        (record.albedo, record.specular) = (self.diffuse.to_array(), self.specular.to_array());
        record.specular_weight = self.specular_weight();
    }
}

/// Mitsuba's `nonlinear` (plastic, roughplastic; false by default).
pub fn read_nonlinear(r: &mut dyn BsdfReader) -> Result<bool, SceneError> {
    Ok(r.boolean("nonlinear")?.unwrap_or(false))
}

/// The base's albedo seen through the coating's internal reflections (`internal`, the
/// coating's diffuse reflectance from inside).
pub fn diffuse_under_coating(diffuse: Vec3, nonlinear: bool, internal: f32) -> Vec3 {
    if nonlinear {
        diffuse / (Vec3::ONE - diffuse * internal)
    } else {
        diffuse / (1.0 - internal)
    }
}

/// Probability of the plastic's diffuse lobe given the coating's reflectance `f` at wi.
pub fn plastic_diffuse_prob(f: f32, specular_weight: f32) -> f32 {
    let ps = f * specular_weight;
    let pd = (1.0 - f) * (1.0 - specular_weight);
    pd / (ps + pd)
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plastic {
    pub coated: Coated,
    pub nonlinear: bool,
}

impl Plastic {
    /// The coating's diffuse reflectance from inside (Mitsuba's `m_fdr_int`).
    fn internal_reflectance(&self) -> f32 {
        fresnel_diffuse_reflectance(self.coated.ext_ior / self.coated.int_ior)
    }
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let coated = Coated::read(r, &mut textures)?;
    let nonlinear = read_nonlinear(r)?;
    Ok(Sides::one(
        Bsdf::new(Plastic { coated, nonlinear }),
        textures,
    ))
}

impl BsdfModel for Plastic {
    fn kind(&self) -> &'static str {
        "plastic"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        self.coated.is_valid()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return Vec3::ZERO;
        }
        let eta = self.coated.int_ior / self.coated.ext_ior;
        let fi = fresnel(ci, eta).0;
        let fo = fresnel(co, eta).0;
        let base = diffuse_under_coating(
            self.coated.diffuse,
            self.nonlinear,
            self.internal_reflectance(),
        );
        base * (co * std::f32::consts::FRAC_1_PI / (eta * eta) * (1.0 - fi) * (1.0 - fo))
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let (ci, co) = (wi.z, wo.z);
        if ci <= 0.0 || co <= 0.0 {
            return 0.0;
        }
        let fi = fresnel(ci, self.coated.int_ior / self.coated.ext_ior).0;
        let cosine = co.max(0.0) * std::f32::consts::FRAC_1_PI;
        cosine * plastic_diffuse_prob(fi, self.coated.specular_weight())
    }

    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        let ci = wi.z;
        if ci <= 0.0 {
            return None;
        }
        let fi = fresnel(ci, self.coated.int_ior / self.coated.ext_ior).0;
        let prob_diffuse = plastic_diffuse_prob(fi, self.coated.specular_weight());
        if u1 < 1.0 - prob_diffuse {
            let prob = 1.0 - prob_diffuse;
            return Some(Sample {
                wo: Vec3::new(-wi.x, -wi.y, wi.z),
                weight: self.coated.specular * (fi / prob),
                pdf: prob,
                delta: true,
            });
        }
        sample_from_eval(self, wi, square_to_cosine_hemisphere(u2), mode)
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        self.coated.pack(record);
        record.nonlinear = self.nonlinear as u32;
        record.internal_reflectance = self.internal_reflectance();
    }
}
