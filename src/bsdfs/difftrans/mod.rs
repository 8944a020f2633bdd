//! Mitsuba 0.6's `difftrans` (src/bsdfs/difftrans.cpp of mitsuba-renderer/mitsuba): Lambertian
//! transmission, T / pi |cos wo| towards the other side of the surface only, from either side,
//! sampled cosine-weighted on that side. Mitsuba 3 has no such plugin, so it is read from files
//! of version 0.x only. For the light-transport partition it is a continuous lobe that
//! transmits: the camera's hit points and the photons' deposits are Lambertian reflection only,
//! so light through a diffuse transmitter is path traced, never photon mapped (as
//! `roughdiffuse`), and a caustic photon that reaches one stops there.

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
    transmits: true,
    pass_through: false,
};

const MODULE: &str = "bsdfs::difftrans";

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "difftrans",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["difftrans"],
        properties: &[
            p("transmittance", "0.5"),
            p("diffuse_transmittance", "another name for transmittance"),
            p("ensure_energy_conservation", "true"),
        ],
        notes: "Mitsuba 0.6's diffuse transmitter (files of version 0.x only; Mitsuba 3 has no \
                `difftrans`): T / pi towards the other side, from both sides, sampled \
                cosine-weighted; a transmittance above 1 scaled down as 0.6 scales it; it may \
                be a texture. Continuous for the light-transport partition (path traced, never \
                photon mapped); it transmits, so `twosided` refuses it.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        eval: Some(WgslCall::new(MODULE, "difftrans_eval")),
        sample: Some(WgslCall::new(MODULE, "difftrans_sample")),
        ..GpuKind::inline("difftrans", LOBES)
    }],
    def: Some("DIFFTRANS"),
    wgsl: Some(crate::shader_file!("src/bsdfs/difftrans/difftrans.wgsl")),
};

/// Lambertian transmission with Mitsuba 0.6's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffTrans {
    /// As given (a texture's scalar mean where textured).
    pub transmittance: Vec3,
    /// 0.6's energy conservation: the factor `transmittance` is scaled by (1 unless its
    /// largest value is above 1).
    pub scale: f32,
}

impl DiffTrans {
    /// An untextured transmittance, scaled as 0.6 scales one above 1.
    pub fn new(transmittance: Vec3) -> Self {
        DiffTrans {
            transmittance,
            scale: energy_scale(true, transmittance),
        }
    }
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    only_in_mitsuba06(r)?;
    // 0.6 reads `transmittance`, or `diffuseTransmittance` where that is absent.
    let name = match (r.has("transmittance"), r.has("diffuse_transmittance")) {
        (true, true) => {
            return Err(r.error_at(
                "diffuse_transmittance",
                "give transmittance or diffuse_transmittance (the same parameter), not both".into(),
            ));
        }
        (false, true) => "diffuse_transmittance",
        _ => "transmittance",
    };
    let t = reflectance(r, name, 0.5)?;
    let ensure = ensures_energy_conservation(r)?;
    let model = DiffTrans {
        transmittance: t.value,
        scale: energy_scale(ensure, t.maximum),
    };
    let textures = SideTextures {
        diffuse: t.texture,
        ..SideTextures::default()
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

impl BsdfModel for DiffTrans {
    fn kind(&self) -> &'static str {
        "difftrans"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        self.transmittance.is_finite()
            && self.transmittance.min_element() >= 0.0
            && self.scale.is_finite()
    }

    fn eval(&self, wi: Vec3, wo: Vec3, _mode: Mode) -> Vec3 {
        // Only towards the other side (0.6: cos wi cos wo >= 0 is black).
        if wi.z * wo.z >= 0.0 {
            return Vec3::ZERO;
        }
        self.transmittance * (self.scale * std::f32::consts::FRAC_1_PI * wo.z.abs())
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z * wo.z >= 0.0 {
            return 0.0;
        }
        wo.z.abs() * std::f32::consts::FRAC_1_PI
    }

    fn sample(&self, wi: Vec3, _u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        // 0.6 flips the cosine-weighted direction below the surface when wi is above it; a
        // grazing wi (cos 0) has no other side, and its sample would have no density.
        if wi.z == 0.0 {
            return None;
        }
        let mut wo = square_to_cosine_hemisphere(u2);
        if wi.z > 0.0 {
            wo.z = -wo.z;
        }
        sample_from_eval(self, wi, wo, mode)
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        record.albedo = self.transmittance.to_array();
        record.int_ior = self.scale;
    }
}
