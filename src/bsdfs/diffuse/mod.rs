//! Mitsuba's `diffuse`: Lambertian reflection, one-sided. The light-transport partition's
//! diffuse (D) vertex: the camera pass records hit points at it and photons deposit there, so
//! the passes sample and evaluate it themselves and it has no WGSL of its own.

use glam::{Vec2, Vec3};

use crate::bsdfs::shared::microfacet::square_to_cosine_hemisphere;
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample, sample_from_eval};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

/// A Lambertian lobe is neither specular nor glossy: it is the photon-mapped vertex.
const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: false,
    continuous: false,
    transmits: false,
    pass_through: false,
};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "diffuse",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["diffuse"],
        properties: &[p("reflectance", "0.5")],
        notes: "Lambertian, one-sided. `reflectance` may be a texture.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind::inline("diffuse", LOBES)],
    def: None,
    wgsl: None,
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diffuse {
    pub reflectance: Vec3,
}

impl Diffuse {
    pub fn bsdf(reflectance: Vec3) -> Bsdf {
        Bsdf::new(Diffuse { reflectance })
    }
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let (reflectance, texture) = r.color_or_texture("reflectance", 0.5)?;
    let textures = SideTextures {
        diffuse: texture,
        ..SideTextures::default()
    };
    Ok(Sides::one(Diffuse::bsdf(reflectance), textures))
}

impl BsdfModel for Diffuse {
    fn kind(&self) -> &'static str {
        "diffuse"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        self.reflectance.is_finite()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.reflectance * wo.z * std::f32::consts::FRAC_1_PI
        } else {
            Vec3::ZERO
        }
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z > 0.0 {
            wo.z.max(0.0) * std::f32::consts::FRAC_1_PI
        } else {
            0.0
        }
    }

    fn sample(&self, wi: Vec3, _u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        if wi.z <= 0.0 {
            return None;
        }
        sample_from_eval(self, wi, square_to_cosine_hemisphere(u2), mode)
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        record.albedo = self.reflectance.to_array();
    }
}
