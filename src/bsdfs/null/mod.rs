//! Mitsuba's `null`: every ray passes through unchanged. A vertex that is neither specular nor
//! diffuse for the partition (a path keeps its class through it); the passes step through it
//! themselves. A `mask` is a blend of this and its BSDF.

use glam::{Vec2, Vec3};

use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::Plugin;
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: false,
    continuous: false,
    transmits: true,
    pass_through: true,
};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "null",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["null"],
        properties: &[],
        notes: "Lets every ray through unchanged, as `mask` with opacity 0.",
    }],
    read,
    objects: &[],
    kinds: &[GpuKind::inline("null", LOBES)],
    def: Some("BLENDS"),
    wgsl: None,
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Null;

impl Null {
    pub fn bsdf() -> Bsdf {
        Bsdf::new(Null)
    }
}

fn read(_r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    Ok(Sides::one(Null::bsdf(), SideTextures::default()))
}

impl BsdfModel for Null {
    fn kind(&self) -> &'static str {
        "null"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        true
    }

    fn sample(&self, wi: Vec3, _u1: f32, _u2: Vec2, _mode: Mode) -> Option<Sample> {
        Some(Sample {
            wo: -wi,
            weight: Vec3::ONE,
            pdf: 1.0,
            delta: true,
        })
    }

    fn pack(&self, _record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {}
}
