//! Mitsuba's smooth `dielectric`: Fresnel-weighted reflection and refraction, both delta lobes,
//! no absorption. The caustic paths' specular vertex: the passes sample it in world space
//! (common::path_step imports `dielectric.wgsl`), so the dispatch has no entry for it.

use glam::{Vec2, Vec3};

use crate::bsdfs::shared::fresnel::fresnel;
use crate::bsdfs::shared::tint::Tint;
use crate::bsdfs::shared::{AIR, BK7, dielectric_tint, ior};
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::{Property, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: true,
    microfacet: false,
    continuous: false,
    transmits: true,
    pass_through: false,
};

/// The properties the smooth dielectrics read (`thindielectric` too).
pub const PROPERTIES: &[Property] = &[
    p("int_ior", "bk7"),
    p("ext_ior", "air"),
    p("specular_reflectance", "1"),
    p("specular_transmittance", "1"),
];

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "dielectric",
    reads: &[crate::scene::plugin::Plugin {
        object: "bsdf",
        kinds: &["dielectric"],
        properties: PROPERTIES,
        notes: "Smooth. An index is a number or one of Mitsuba's named media (`water`, \
                `acrylic glass`, `diamond`, ...). `specular_reflectance` and \
                `specular_transmittance` scale the reflected and transmitted light as in \
                Mitsuba (tinted glass; not energy-conserving), colours or textures.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind::inline("dielectric", LOBES)],
    def: Some("DIELECTRIC"),
    wgsl: Some(crate::shader_file!("src/bsdfs/dielectric/dielectric.wgsl")),
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dielectric {
    pub int_ior: f32,
    pub ext_ior: f32,
    pub tint: Tint,
}

impl Dielectric {
    /// Untinted glass of index `int_ior` in a medium of index `ext_ior`.
    pub fn bsdf(int_ior: f32, ext_ior: f32) -> Bsdf {
        Bsdf::new(Dielectric {
            int_ior,
            ext_ior,
            tint: Tint::NONE,
        })
    }
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let model = Dielectric {
        int_ior: ior(r, "int_ior", BK7)?,
        ext_ior: ior(r, "ext_ior", AIR)?,
        tint: dielectric_tint(r, &mut textures)?,
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

/// Both indices finite and positive.
pub fn iors_valid(int_ior: f32, ext_ior: f32) -> bool {
    int_ior.is_finite() && ext_ior.is_finite() && int_ior > 0.0 && ext_ior > 0.0
}

impl BsdfModel for Dielectric {
    fn kind(&self) -> &'static str {
        "dielectric"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        iors_valid(self.int_ior, self.ext_ior) && self.tint.is_valid()
    }

    fn sample(&self, wi: Vec3, u1: f32, _u2: Vec2, mode: Mode) -> Option<Sample> {
        let ci = wi.z;
        if ci == 0.0 {
            return None;
        }
        let (f, cos_t, _, eta_ti) = fresnel(ci, self.int_ior / self.ext_ior);
        if u1 <= f {
            return Some(Sample {
                wo: Vec3::new(-wi.x, -wi.y, wi.z),
                weight: self.tint.reflectance,
                pdf: f,
                delta: true,
            });
        }
        let scale = match mode {
            Mode::Radiance => eta_ti * eta_ti,
            Mode::Importance => 1.0,
        };
        Some(Sample {
            wo: Vec3::new(-eta_ti * wi.x, -eta_ti * wi.y, cos_t),
            weight: self.tint.transmittance * scale,
            pdf: 1.0 - f,
            delta: true,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        (record.int_ior, record.ext_ior) = (self.int_ior, self.ext_ior);
        pack_tint(record, &self.tint);
    }
}

/// A dielectric's tint: reflectance in `specular`, transmittance in `albedo` (where the
/// specular and diffuse textures replace them).
pub fn pack_tint(record: &mut GpuMaterial, tint: &Tint) {
    (record.specular, record.albedo) = (tint.reflectance.to_array(), tint.transmittance.to_array());
}
