//! Mitsuba's smooth `conductor`: the Fresnel reflectance of a complex index eta + i k times
//! `specular_reflectance`, a delta lobe; one-sided. Its `material="none"` (the default) is a
//! perfect mirror, a kind of its own that the passes reflect themselves (`mirror`).

mod named;

use glam::{Vec2, Vec3};

pub use named::{NAMED_CONDUCTORS, named_conductor};

use crate::bsdfs::shared::fresnel::fresnel_conductor;
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides, WgslCall};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

const LOBES: Lobes = Lobes {
    delta: true,
    microfacet: false,
    continuous: false,
    transmits: false,
    pass_through: false,
};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "conductor",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["conductor"],
        properties: &[
            p("material", "none"),
            p("eta", ""),
            p("k", ""),
            p("specular_reflectance", "1"),
        ],
        notes: "`material` one of the 71 measured metals of Mitsuba's data (`Au`, `Ag`, `Cu`, \
                ...) or `none` (a perfect mirror), or `eta` + `k`; `specular_reflectance` may \
                be a texture.",
    }],
    read,
    objects: &[],
    kinds: &[
        GpuKind {
            needs_wgsl: false,
            ..GpuKind::inline("mirror", LOBES)
        },
        GpuKind {
            sample: Some(WgslCall::new("bsdfs::conductor", "conductor_sample")),
            ..GpuKind::inline("conductor", LOBES)
        },
    ],
    def: Some("CONDUCTOR"),
    wgsl: Some(crate::shader_file!("src/bsdfs/conductor/conductor.wgsl")),
};

/// A perfect mirror of reflectance 1 (Mitsuba's `conductor` with `material="none"`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mirror;

impl Mirror {
    pub fn bsdf() -> Bsdf {
        Bsdf::new(Mirror)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conductor {
    pub eta: Vec3,
    pub k: Vec3,
    pub specular: Vec3,
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let (eta, k) = read_index(r)?;
    let (specular, texture) = r.color_or_texture("specular_reflectance", 1.0)?;
    let textures = SideTextures {
        specular: texture,
        ..SideTextures::default()
    };
    let perfect = eta == Vec3::ZERO && k == Vec3::ONE && specular == Vec3::ONE;
    let bsdf = if perfect && texture.is_none() {
        Mirror::bsdf()
    } else {
        Bsdf::new(Conductor { eta, k, specular })
    };
    Ok(Sides::one(bsdf, textures))
}

/// A conductor's complex index: `material` (Mitsuba's measured tables at RGB, default "none",
/// a perfect mirror: eta 0, k 1) or explicit `eta` and `k`.
pub fn read_index(r: &mut dyn BsdfReader) -> Result<(Vec3, Vec3), SceneError> {
    if r.legacy() {
        return read_legacy_index(r);
    }
    let material = r.string("material")?;
    if let Some(name) = material.filter(|name| name != "none") {
        if let Some(given) = ["eta", "k"].into_iter().find(|n| r.has(n)) {
            return Err(r.error_at(
                given,
                "give either a conductor material or eta and k, not both".into(),
            ));
        }
        return named_conductor(&name).ok_or_else(|| {
            let names: Vec<&str> = NAMED_CONDUCTORS.iter().map(|(n, _, _)| *n).collect();
            r.error_at(
                "material",
                format!(
                    "conductor material \"{name}\" is not one of Mitsuba's: none, {}",
                    names.join(", ")
                ),
            )
        });
    }
    let eta = r.color("eta")?.unwrap_or(Vec3::ZERO);
    let k = r.color("k")?.unwrap_or(Vec3::ONE);
    Ok((eta, k))
}

/// A conductor's index as Mitsuba 0.6 reads it (src/bsdfs/conductor.cpp of 0.6): `material`
/// defaults to copper, `eta` and `k` each replace the material's where given, and both are
/// divided by `ext_eta` (the outside medium's index, a number or a named dielectric, default
/// air).
fn read_legacy_index(r: &mut dyn BsdfReader) -> Result<(Vec3, Vec3), SceneError> {
    let given = r.has("material");
    let material = r.string("material")?.unwrap_or_else(|| "Cu".into());
    let (table_eta, table_k) = if material.eq_ignore_ascii_case("none") {
        (Vec3::ZERO, Vec3::ONE)
    } else {
        named_conductor(&material).ok_or_else(|| {
            let names: Vec<&str> = NAMED_CONDUCTORS.iter().map(|(n, _, _)| *n).collect();
            r.error_at(
                "material",
                format!(
                    "conductor material \"{material}\" is not one of Mitsuba's: none, {}",
                    names.join(", ")
                ),
            )
        })?
    };
    let eta = r.color("eta")?;
    let k = r.color("k")?;
    if !given && (eta.is_none() || k.is_none()) {
        r.upgrade(
            "material",
            "conductor: Mitsuba 0.6's default material Cu (copper) where eta or k is not given"
                .into(),
        );
    }
    let ext_eta = crate::bsdfs::shared::ior(r, "ext_eta", 1.000277)?;
    Ok((
        eta.unwrap_or(table_eta) / ext_eta,
        k.unwrap_or(table_k) / ext_eta,
    ))
}

/// A conductor's index and tint into the GPU record.
pub fn pack_index(record: &mut GpuMaterial, eta: Vec3, k: Vec3, specular: Vec3) {
    (record.eta, record.k, record.specular) = (eta.to_array(), k.to_array(), specular.to_array());
}

impl BsdfModel for Mirror {
    fn kind(&self) -> &'static str {
        "mirror"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        true
    }

    fn sample(&self, wi: Vec3, _u1: f32, _u2: Vec2, _mode: Mode) -> Option<Sample> {
        (wi.z > 0.0).then(|| Sample {
            wo: Vec3::new(-wi.x, -wi.y, wi.z),
            weight: Vec3::ONE,
            pdf: 1.0,
            delta: true,
        })
    }

    fn pack(&self, _record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {}
}

impl BsdfModel for Conductor {
    fn kind(&self) -> &'static str {
        "conductor"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        self.eta.is_finite() && self.k.is_finite() && self.specular.is_finite()
    }

    fn sample(&self, wi: Vec3, _u1: f32, _u2: Vec2, _mode: Mode) -> Option<Sample> {
        (wi.z > 0.0).then(|| Sample {
            wo: Vec3::new(-wi.x, -wi.y, wi.z),
            weight: self.specular * fresnel_conductor(wi.z, self.eta, self.k),
            pdf: 1.0,
            delta: true,
        })
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        pack_index(record, self.eta, self.k, self.specular);
    }
}
