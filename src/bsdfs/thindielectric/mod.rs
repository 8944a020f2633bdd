//! Mitsuba's `thindielectric`: a thin slab of dielectric whose internal reflections are summed;
//! it reflects or lets light straight through, both delta lobes.

use glam::{Vec2, Vec3};

use crate::bsdfs::dielectric::{PROPERTIES, iors_valid, pack_tint};
use crate::bsdfs::shared::fresnel::fresnel;
use crate::bsdfs::shared::tint::Tint;
use crate::bsdfs::shared::{AIR, BK7, dielectric_tint, ior};
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::Plugin;
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: true,
    microfacet: false,
    continuous: false,
    transmits: true,
    pass_through: false,
};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "thindielectric",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["thindielectric"],
        properties: PROPERTIES,
        notes: "As `dielectric`: a slab that reflects (r' = 2r / (1 + r), its internal \
                reflections summed) or passes light straight through, unbent.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind {
        sample: Some(WgslCall::new(
            "bsdfs::thindielectric",
            "thindielectric_sample",
        )),
        ..GpuKind::inline("thindielectric", LOBES)
    }],
    def: Some("DIELECTRIC"),
    wgsl: Some(crate::shader_file!(
        "src/bsdfs/thindielectric/thindielectric.wgsl"
    )),
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinDielectric {
    pub int_ior: f32,
    pub ext_ior: f32,
    pub tint: Tint,
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mut textures = SideTextures::default();
    let model = ThinDielectric {
        int_ior: ior(r, "int_ior", BK7)?,
        ext_ior: ior(r, "ext_ior", AIR)?,
        tint: dielectric_tint(r, &mut textures)?,
    };
    Ok(Sides::one(Bsdf::new(model), textures))
}

impl BsdfModel for ThinDielectric {
    fn kind(&self) -> &'static str {
        "thindielectric"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        iors_valid(self.int_ior, self.ext_ior) && self.tint.is_valid()
    }

    fn sample(&self, wi: Vec3, u1: f32, _u2: Vec2, _mode: Mode) -> Option<Sample> {
        let mut r = fresnel(wi.z.abs(), self.int_ior / self.ext_ior).0;
        r *= 2.0 / (1.0 + r);
        let reflected = u1 <= r;
        Some(Sample {
            wo: if reflected {
                Vec3::new(-wi.x, -wi.y, wi.z)
            } else {
                -wi
            },
            weight: self.tint.factor(reflected),
            pdf: if reflected { r } else { 1.0 - r },
            delta: true,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        (record.int_ior, record.ext_ior) = (self.int_ior, self.ext_ior);
        pack_tint(record, &self.tint);
    }
}
