//! What a BSDF unit declares in one place: the Mitsuba plugins it reads, the material kinds it
//! adds to the GPU record with their WGSL entry points, and the shader def of its WGSL.

use super::reader::{BsdfReader, Sides};
use crate::gpu::shaders::ShaderFile;
use crate::scene::SceneError;
use crate::scene::bsdf::Lobes;
use crate::scene::plugin::Plugin;

/// A WGSL function of a unit's module: the module's import path and the function's name. The
/// generated dispatch imports and calls it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WgslCall {
    pub module: &'static str,
    pub function: &'static str,
}

impl WgslCall {
    pub const fn new(module: &'static str, function: &'static str) -> Self {
        WgslCall { module, function }
    }
}

/// How the glossy-caustic partition (a graph's `glossy_threshold`, the `GLOSSY` def) splits a
/// kind's light between photons and path tracing when its roughness is below the threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Glossy {
    /// No microfacet lobe: nothing to split.
    None,
    /// The whole BSDF is the microfacet lobe: all of it is specular below the threshold.
    Whole,
    /// A microfacet lobe over another (a rough coating over a diffuse base): `eval(m, wi, wo)
    /// -> vec3<f32>` gives the specular lobe's f |cos wo|, `share(m, wi, wo) -> vec3<f32>` its
    /// share of the whole BSDF's value, per channel.
    Split { eval: WgslCall, share: WgslCall },
}

/// A material kind: a value of the GPU record's `kind`, numbered by the registry's order. The
/// model a unit reads names its kind ([`crate::scene::bsdf::BsdfModel::kind`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpuKind {
    /// Its name: the WGSL constant is `MATERIAL_` and the name in capitals.
    pub name: &'static str,
    pub lobes: Lobes,
    /// `fn(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval`, the
    /// non-delta lobes' f |cos wo| and pdf; `None` where it has none or the passes evaluate it
    /// themselves (Lambertian: the partition's diffuse vertex).
    pub eval: Option<WgslCall>,
    /// `fn(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample`;
    /// `None` where the passes sample it themselves (Lambertian, mirror, smooth dielectric,
    /// pass-through, blend).
    pub sample: Option<WgslCall>,
    pub glossy: Glossy,
    /// The least a textured roughness is taken to be (the untextured one is floored the same
    /// way when packed); 0 keeps it as looked up.
    pub alpha_floor: f32,
    /// A scene with this kind needs its unit's WGSL, so its def is set; false for a kind the
    /// passes handle with none of it (a perfect mirror, which the conductor unit reads).
    pub needs_wgsl: bool,
    /// Its WGSL evaluates and samples a BSDF nested in it (Mitsuba 0.6's coatings) through
    /// `common::leaf_material` (`leaf_material_eval`, `leaf_material_sample`), which the registry
    /// generates from the kinds of the units registered before the first such unit and composes
    /// just before that unit's WGSL: WGSL has no recursion, so it cannot call the dispatch that
    /// calls it.
    pub nests: bool,
}

impl GpuKind {
    /// A kind the passes handle themselves: no dispatch entry.
    pub const fn inline(name: &'static str, lobes: Lobes) -> Self {
        GpuKind {
            name,
            lobes,
            eval: None,
            sample: None,
            glossy: Glossy::None,
            alpha_floor: 1e-4,
            needs_wgsl: true,
            nests: false,
        }
    }

    /// The WGSL constant holding its number.
    pub fn constant(&self) -> String {
        format!("MATERIAL_{}", self.name.to_ascii_uppercase())
    }
}

/// Reads one `<bsdf>` element of one of a unit's types into the BSDFs of its sides.
pub type ReadFn = fn(&mut dyn BsdfReader) -> Result<Sides, SceneError>;

/// One BSDF unit as the registry holds it.
#[derive(Debug)]
pub struct BsdfPlugin {
    /// The unit's name (its folder's).
    pub name: &'static str,
    /// The Mitsuba plugins it reads, each with its `type`s, properties and notes: its rows of
    /// docs/scenes.md, and what the loader's messages list.
    pub reads: &'static [Plugin],
    /// Reads an element of one of those types.
    pub read: ReadFn,
    /// Child elements it reads as objects rather than as properties (`bsdf` and `ref` for the
    /// BSDFs it nests, `texture` for a bump map's height); a `<ref name="P">` whose name is one
    /// of its properties stays a property.
    pub objects: &'static [&'static str],
    /// The material kinds it adds (none for a unit that only composes others, as `twosided`).
    pub kinds: &'static [GpuKind],
    /// The shader def that compiles its WGSL in, set when a scene uses one of its kinds;
    /// several units may share one.
    pub def: Option<&'static str>,
    /// Its WGSL module (`#define_import_path bsdfs::<name>`), composed after the units before
    /// it in the registry.
    pub wgsl: Option<ShaderFile>,
}

impl BsdfPlugin {
    /// Whether it reads the Mitsuba type `kind`.
    pub fn reads_type(&self, kind: &str) -> bool {
        self.reads.iter().any(|p| p.kinds.contains(&kind))
    }

    /// The properties its type `kind` reads, for messages: "int_ior, ext_ior".
    pub fn properties_of(&self, kind: &str) -> String {
        let names: Vec<&str> = self
            .reads
            .iter()
            .filter(|p| p.kinds.contains(&kind))
            .flat_map(|p| p.properties.iter().map(|p| p.name))
            .collect();
        if names.is_empty() {
            "no properties".into()
        } else {
            names.join(", ")
        }
    }

    /// Whether `name` is a property its type `kind` reads.
    pub fn has_property(&self, kind: &str, name: &str) -> bool {
        self.reads
            .iter()
            .filter(|p| p.kinds.contains(&kind))
            .any(|p| p.properties.iter().any(|q| q.name == name))
    }
}
