//! The BSDF interface: what the scene, the light-transport partition, the CPU reference and the
//! GPU layout ask of a BSDF ([`BsdfModel`]), the handle a material holds ([`Bsdf`]) and the
//! record a BSDF packs itself into for the GPU ([`GpuMaterial`]). The BSDFs themselves are
//! units, one folder each under src/bsdfs/ (or in another crate), and the scene names none of
//! them.
//!
//! Directions are local (z along the normal of the side the BSDF sees) and named as in Mitsuba:
//! `wi` points towards the previous vertex (the camera when tracing radiance, the light when
//! tracing photons), `wo` towards the next. `eval` returns f(wi, wo) |cos wo| of the non-delta
//! lobes; `sample` returns the weight f |cos wo| / pdf of its choice (delta lobes included).

use std::any::Any;
use std::fmt::Debug;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use super::SideTextures;

/// What the path is carrying, which only refraction's solid-angle compression depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Camera paths: radiance is scaled by (eta_t / eta_i)^2 crossing an interface.
    Radiance,
    /// Photons (flux): no scaling.
    Importance,
}

/// One sampled direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub wo: Vec3,
    /// f |cos wo| / pdf (delta lobes: their weight over their choice probability).
    pub weight: Vec3,
    /// Solid-angle density for non-delta choices; the choice probability for delta ones.
    pub pdf: f32,
    pub delta: bool,
}

/// How the light-transport partition sees a BSDF kind (docs/light-transport.md): which of its
/// lobes make a specular (S) vertex and which a path-traced one. A Lambertian lobe is the
/// photon-mapped diffuse (D) vertex, which only the `diffuse` kind has.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Lobes {
    /// A delta lobe: an S vertex whenever it is sampled (mirror, smooth dielectric, plastic's
    /// smooth coating).
    pub delta: bool,
    /// A microfacet lobe: an S vertex when its roughness is below a graph's `glossy_threshold`.
    pub microfacet: bool,
    /// A lobe that light sampling can reach (next-event estimation), other than Lambertian.
    pub continuous: bool,
    /// Light passes to the other side (such a BSDF has no back face to be given).
    pub transmits: bool,
    /// Lets light through unchanged (`null`, a mask's pass-through): neither S nor D.
    pub pass_through: bool,
}

/// Comparison and downcasting of trait objects, for any model that is `PartialEq`: a unit
/// derives `PartialEq` and gets this.
pub trait DynEq: Any {
    fn as_any(&self) -> &dyn Any;
    fn dyn_eq(&self, other: &dyn Any) -> bool;
}

impl<T: Any + PartialEq> DynEq for T {
    fn as_any(&self) -> &dyn Any {
        self
    }

    fn dyn_eq(&self, other: &dyn Any) -> bool {
        other.downcast_ref::<T>().is_some_and(|o| self == o)
    }
}

/// One BSDF with its parameters, as a unit reads it from a scene file. Everything hppm does
/// with a BSDF goes through this: the partition's questions, the CPU reference the tests hold
/// the WGSL to, and its packing into the GPU record.
pub trait BsdfModel: DynEq + Debug + Send + Sync {
    /// The name of its kind in the BSDF registry (`"roughconductor"`): the GPU record's kind
    /// number and the WGSL that evaluates it are that kind's.
    fn kind(&self) -> &'static str;

    /// Its kind's lobes (the unit's one constant, also in its registry entry).
    fn lobes(&self) -> Lobes;

    /// The roughness a `glossy_threshold` is compared with (the larger of alpha_u and alpha_v,
    /// untextured), for a kind with a microfacet lobe.
    fn roughness(&self) -> Option<f32> {
        None
    }

    /// Every number it holds is finite and in range (indices of refraction positive).
    fn is_valid(&self) -> bool;

    /// f(wi, wo) |cos wo| of the non-delta lobes.
    fn eval(&self, _wi: Vec3, _wo: Vec3, _mode: Mode) -> Vec3 {
        Vec3::ZERO
    }

    /// Density of `sample` choosing `wo` (non-delta lobes; delta choices have none).
    fn pdf(&self, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    /// Samples `wo` given `wi`, with `u1` choosing a lobe and `u2` the direction within it.
    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample>;

    /// Writes its parameters into the GPU record (whose kind, emission, back side, frame and
    /// texture slots the layout fills); tables it needs (rough plastic's transmittance) go at
    /// the end of `tables`, which the record then points into.
    fn pack(&self, record: &mut GpuMaterial, textures: &SideTextures, tables: &mut Vec<f32>);

    /// The materials (indices into `Scene::materials`, below its own) a blend chooses between.
    fn children(&self) -> &[u32] {
        &[]
    }
}

/// A material side's BSDF: a shared handle to its model.
#[derive(Clone, Debug)]
pub struct Bsdf(Arc<dyn BsdfModel>);

impl Bsdf {
    pub fn new(model: impl BsdfModel) -> Self {
        Bsdf(Arc::new(model))
    }

    pub fn model(&self) -> &dyn BsdfModel {
        self.0.as_ref()
    }

    /// The model as its own type, when it is one.
    pub fn get<T: BsdfModel>(&self) -> Option<&T> {
        self.0.as_any().downcast_ref::<T>()
    }

    /// A BSDF with a delta lobe can make an S vertex of the light-transport partition.
    pub fn is_delta(&self) -> bool {
        self.0.lobes().delta
    }

    /// A BSDF with a microfacet lobe: an S vertex of the partition when its roughness is below
    /// a graph's `glossy_threshold`.
    pub fn has_microfacet_lobe(&self) -> bool {
        self.0.lobes().microfacet
    }

    /// The roughness `glossy_threshold` is compared with, or `None` without a microfacet lobe.
    pub fn microfacet_roughness(&self) -> Option<f32> {
        self.has_microfacet_lobe()
            .then(|| self.0.roughness())
            .flatten()
    }

    /// Transmits light to the other side.
    pub fn transmits(&self) -> bool {
        self.0.lobes().transmits
    }
}

impl std::ops::Deref for Bsdf {
    type Target = dyn BsdfModel;

    fn deref(&self) -> &Self::Target {
        self.0.as_ref()
    }
}

impl PartialEq for Bsdf {
    fn eq(&self, other: &Self) -> bool {
        self.0.dyn_eq(other.0.as_any())
    }
}

/// A sample of a lobe with a density: its direction weighted by eval / pdf, or none where the
/// density is 0 (what a BSDF's `sample` returns for its continuous lobes).
pub fn sample_from_eval(model: &dyn BsdfModel, wi: Vec3, wo: Vec3, mode: Mode) -> Option<Sample> {
    let pdf = model.pdf(wi, wo);
    (pdf > 0.0).then(|| Sample {
        wo,
        weight: model.eval(wi, wo, mode) / pdf,
        pdf,
        delta: false,
    })
}

/// One material side as the GPU reads it (`Material` in src/gpu_scene/scene.wgsl; std430: a
/// `vec3<f32>` aligns to 16 bytes, so each is followed by a 4-byte scalar). The fields are slots
/// a BSDF unit packs its parameters into ([`BsdfModel::pack`]) and its WGSL reads back; their
/// names say what the built-in BSDFs keep there. `tests/shaders.rs` checks the layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuMaterial {
    /// Diffuse reflectance (diffuse, and plastic's base).
    pub albedo: [f32; 3],
    pub kind: u32,
    pub emission: [f32; 3],
    pub int_ior: f32,
    /// Specular reflectance (conductors, plastic's coating).
    pub specular: [f32; 3],
    pub ext_ior: f32,
    /// A conductor's complex index of refraction eta + i k.
    pub eta: [f32; 3],
    pub alpha_u: f32,
    pub k: [f32; 3],
    pub alpha_v: f32,
    /// 0 Beckmann, 1 GGX.
    pub distribution: u32,
    /// The material the back side sees (twosided), or `NO_BACK`.
    pub back: u32,
    pub nonlinear: u32,
    /// Plastic: probability weight of the coating's lobe.
    pub specular_weight: f32,
    /// Plastic: the coating's diffuse reflectance from inside.
    pub internal_reflectance: f32,
    /// Rough plastic: first entry of its transmittance table in `bsdf_tables`.
    pub table: u32,
    /// The textures that replace `albedo` and `specular` at each surface point (indices of
    /// the scene's texture headers), or `NO_TEXTURE`.
    pub diffuse_texture: u32,
    pub specular_texture: u32,
    /// The scalar textures that replace `alpha_u` and `alpha_v`, or `NO_TEXTURE`.
    pub alpha_u_texture: u32,
    pub alpha_v_texture: u32,
    /// A `normalmap` or `bumpmap` around the BSDF (`FRAME_*`), its texture (or NO_TEXTURE),
    /// the bump map's scale and `FRAME_FLAG_*` bits.
    pub frame_kind: u32,
    pub frame_texture: u32,
    pub frame_scale: f32,
    pub frame_flags: u32,
    /// Blend: the two materials it chooses between (indices of this table), the probability
    /// of the second and the scalar texture replacing it (or NO_TEXTURE).
    pub children: [u32; 2],
    pub blend_weight: f32,
    pub blend_weight_texture: u32,
    /// Scalar textures that replace one component each of `specular`, `eta` and `k` (principled
    /// keeps eight parameters there): `field_texture_count` pairs of `bsdf_tables` entries from
    /// `field_textures`, each the component (of the three taken as one array of nine) and the
    /// texture, as floats (exact below 2^24; shaders/common/texture.wgsl).
    pub field_textures: u32,
    pub field_texture_count: u32,
    /// The media inside and outside the shape (offsets of their records in the scene's float
    /// tables), or `NO_MEDIUM`; set by the scene's layout, not by a BSDF.
    pub interior: u32,
    pub exterior: u32,
    pub _pad_media: [u32; 2],
}

impl GpuMaterial {
    /// Scalar textures on components of `specular`, `eta` and `k` (`fields` in their order),
    /// appended to `tables` as (component, texture) pairs the record points at.
    pub fn set_field_textures(&mut self, fields: &[Option<u32>], tables: &mut Vec<f32>) {
        self.field_textures = tables.len() as u32;
        for (component, texture) in fields.iter().enumerate() {
            if let Some(texture) = *texture {
                tables.extend([component as f32, texture as f32]);
                self.field_texture_count += 1;
            }
        }
    }
}

/// The mean of a colour's channels (a plastic's lobe weights are taken from it, as Mitsuba's).
pub fn mean(v: Vec3) -> f32 {
    (v.x + v.y + v.z) / 3.0
}
