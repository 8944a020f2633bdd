//! Mitsuba 0.6's `phong` (src/bsdfs/phong.cpp of mitsuba-renderer/mitsuba, whose `eval`, `pdf`
//! and `sample` the formulas below are): the modified Phong model of Lafortune and Willems,
//! f = kd / pi + ks (n + 2) / (2 pi) cos^n(alpha), alpha the angle between wo and wi's mirror
//! direction; the specular lobe sampled as cos^n about that mirror direction (density
//! (n + 1) / (2 pi) cos^n, its directions below the surface lost), the diffuse one
//! cosine-weighted, picked by 0.6's specular sampling weight. Mitsuba 3 has no such plugin, so
//! it is read from files of version 0.x only.
//!
//! For the light-transport partition the Phong lobe is a glossy lobe (`Glossy::Split`, as
//! rough plastic's coating over its base) whose roughness is its Beckmann-equivalent alpha,
//! sqrt(2 / (n + 2)): Walter et al. 2007's correspondence between a Phong exponent and a
//! Beckmann width (cos^n theta ~ exp(-n theta^2 / 2) against exp(-tan^2 theta / alpha^2) near
//! the peak, with n + 2 for n so that it stays finite at n = 0), which 0.6's own
//! `Phong::getRoughness` gives for this lobe. So a Phong surface meets a graph's
//! `glossy_threshold` where a Beckmann surface of about the same sharpness would; below it the
//! Phong lobe is specular, and the diffuse lobe is always path traced.

use glam::{Vec2, Vec3};

use crate::bsdfs::shared::mitsuba06::{DiffuseAndSpecular, coordinate_system, only_in_mitsuba06};
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

const MODULE: &str = "bsdfs::phong";

/// The field (of `specular`, `eta`, `k` taken as nine; [`GpuMaterial::field_textures`]) that
/// holds the exponent, `eta.x`, which a scalar texture may replace.
const EXPONENT_FIELD: usize = 3;

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "phong",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["phong"],
        properties: &[
            p("exponent", "30"),
            p("specular_reflectance", "0.2"),
            p("diffuse_reflectance", "0.5"),
            p("ensure_energy_conservation", "true"),
        ],
        notes: "Mitsuba 0.6's modified Phong (files of version 0.x only; Mitsuba 3 has no \
                `phong`): its normalisation, lobe-selection weight and sampling; the \
                reflectances scaled as 0.6 scales them when they sum above 1. Every parameter \
                may be a texture. The Phong lobe is glossy for the light-transport partition, \
                with the Beckmann-equivalent roughness sqrt(2 / (exponent + 2)).",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "phong_eval")),
        sample: Some(WgslCall::new(MODULE, "phong_sample")),
        glossy: Glossy::Split {
            eval: WgslCall::new(MODULE, "phong_specular"),
            share: WgslCall::new(MODULE, "phong_specular_share"),
        },
        ..GpuKind::inline("phong", LOBES)
    }],
    def: Some("PHONG"),
    wgsl: Some(crate::shader_file!("src/bsdfs/phong/phong.wgsl")),
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phong {
    pub lobes: DiffuseAndSpecular,
    /// The Phong exponent n (a scalar texture's mean where textured).
    pub exponent: f32,
}

impl Phong {
    /// Untextured reflectances and exponent, scaled and weighted as 0.6 configures them.
    pub fn new(diffuse: Vec3, specular: Vec3, exponent: f32) -> Self {
        Phong {
            lobes: DiffuseAndSpecular::constant(diffuse, specular),
            exponent,
        }
    }

    /// f |cos wo| of the Phong lobe alone (both directions above the surface).
    pub fn specular_eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let cos_alpha = wo.dot(mirror(wi));
        if cos_alpha <= 0.0 {
            return Vec3::ZERO;
        }
        let n = self.exponent;
        self.lobes.specular
            * (self.lobes.scale
                * (n + 2.0)
                * (0.5 * std::f32::consts::FRAC_1_PI)
                * cos_alpha.powf(n)
                * wo.z)
    }
}

/// `wi` mirrored about the normal (0.6's `Phong::reflect`).
fn mirror(wi: Vec3) -> Vec3 {
    Vec3::new(-wi.x, -wi.y, wi.z)
}

/// The Beckmann-equivalent roughness of Phong exponent `n` (0.6's `Phong::getRoughness`).
pub fn equivalent_alpha(n: f32) -> f32 {
    (2.0 / (2.0 + n)).sqrt()
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    only_in_mitsuba06(r)?;
    let mut textures = SideTextures::default();
    let (exponent, exponent_texture) = r.scalar_or_texture("exponent", 30.0)?;
    if exponent_texture.is_none() && (exponent.is_nan() || exponent < 0.0) {
        let what = r.describe_property("exponent");
        return Err(r.error_at("exponent", format!("{what}: must not be negative")));
    }
    textures.fields[EXPONENT_FIELD] = exponent_texture;
    let lobes = DiffuseAndSpecular::read(r, &mut textures)?;
    Ok(Sides::one(Bsdf::new(Phong { lobes, exponent }), textures))
}

impl BsdfModel for Phong {
    fn kind(&self) -> &'static str {
        "phong"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn roughness(&self) -> Option<f32> {
        Some(equivalent_alpha(self.exponent))
    }

    fn is_valid(&self) -> bool {
        self.lobes.is_valid() && self.exponent.is_finite() && self.exponent >= 0.0
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let diffuse = self.lobes.diffuse * (self.lobes.scale * std::f32::consts::FRAC_1_PI * wo.z);
        self.specular_eval(wi, wo) + diffuse
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let cos_alpha = wo.dot(mirror(wi));
        let n = self.exponent;
        let specular = if cos_alpha > 0.0 {
            cos_alpha.powf(n) * (n + 1.0) * (0.5 * std::f32::consts::FRAC_1_PI)
        } else {
            0.0
        };
        let diffuse = wo.z * std::f32::consts::FRAC_1_PI;
        let w = self.lobes.specular_weight;
        w * specular + (1.0 - w) * diffuse
    }

    /// `u1` picks the lobe (0.6 reuses its first random number, rescaled, for that: the same
    /// distribution), `u2` the direction within it.
    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        let n = self.exponent;
        let wo = self.lobes.sample_direction(wi, u1, u2, |u2| {
            let cos_alpha = u2.y.powf(1.0 / (n + 1.0));
            let sin_alpha = (1.0 - u2.y.powf(2.0 / (n + 1.0))).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * u2.x;
            let r = mirror(wi);
            let (s, t) = coordinate_system(r);
            s * (sin_alpha * phi.cos()) + t * (sin_alpha * phi.sin()) + r * cos_alpha
        })?;
        sample_from_eval(self, wi, wo, mode)
    }

    fn pack(&self, record: &mut GpuMaterial, textures: &SideTextures, tables: &mut Vec<f32>) {
        self.lobes.pack(record);
        record.eta = [self.exponent, 0.0, 0.0];
        let alpha = equivalent_alpha(self.exponent);
        (record.alpha_u, record.alpha_v) = (alpha, alpha);
        record.set_field_textures(&textures.fields, tables);
    }
}
