//! Mitsuba's `blendbsdf` and `mask`: one of two materials, the second with probability
//! `weight`, chosen anew at every interaction; a `mask` is a blend of `null` and its one BSDF by
//! `opacity`. A blend is linear in its children, so choosing one and scattering with it alone
//! (its NEE, its sample, its partition class) has the blend's expectation, and a diffuse child
//! still gives a plain diffuse vertex to record and gather at (`blend.wgsl`, which the passes
//! call before anything else at a surface).

use glam::{Vec2, Vec3};

use crate::bsdfs::null::Null;
use crate::bsdfs::{BsdfPlugin, BsdfReader, GpuKind, Sides};
use crate::scene::bsdf::{Bsdf, BsdfModel, GpuMaterial, Lobes, Mode, Sample};
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

/// Its own lobes are none: the chosen child's are what a vertex has.
const LOBES: Lobes = Lobes {
    delta: false,
    microfacet: false,
    continuous: false,
    transmits: false,
    pass_through: false,
};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "blendbsdf",
    reads: &[
        Plugin {
            object: "bsdf",
            kinds: &["blendbsdf"],
            properties: &[p("weight", "")],
            notes: "Two nested BSDFs; `weight` (a float or scalar texture, clamped to [0, 1]) is \
                    the second's share. Each interaction picks one child by the weight and \
                    scatters with it alone, which is unbiased; Mitsuba 3.9.1 instead samples a \
                    child and divides by both children's densities, which for a delta child (a \
                    smooth conductor or dielectric) next to a continuous one mixes a \
                    probability with a density and renders darker (docs/mitsuba-scenes.md). Not \
                    inside `normalmap` or `bumpmap` (put those around the nested BSDFs).",
        },
        Plugin {
            object: "bsdf",
            kinds: &["mask"],
            properties: &[p("opacity", "0.5")],
            notes: "One nested BSDF; with probability 1 - `opacity` (a float or scalar texture) \
                    the ray passes straight through, as Mitsuba's null lobe: it counts as a \
                    bounce of `max_depth`, shadow rays stop at the surface, and a light path \
                    through it keeps its class (neither S nor D). Not inside `twosided` \
                    (Mitsuba refuses it too).",
        },
    ],
    read,
    objects: &["bsdf", "ref"],
    kinds: &[GpuKind::inline("blend", LOBES)],
    def: Some("BLENDS"),
    wgsl: Some(crate::shader_file!("src/bsdfs/blendbsdf/blend.wgsl")),
};

/// One of two materials (indices into `Scene::materials`, always below the blend's own),
/// `second` with probability `weight` (clamped to [0, 1]; a texture in the side's
/// `blend_weight` replaces it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blend {
    pub weight: f32,
    pub children: [u32; 2],
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let mask = r.plugin() == "mask";
    let (name, wanted) = if mask { ("opacity", 1) } else { ("weight", 2) };
    let kind = r.plugin().to_string();
    let given = r.has(name);
    let (weight, texture) = r.scalar_or_texture(name, 0.5)?;
    let mut nested = r.nested()?;
    if nested.len() > wanted {
        return Err(r.error_at_nested(
            wanted,
            format!("{kind}: at most {wanted} nested BSDF(s), as in Mitsuba"),
        ));
    }
    if nested.len() < wanted {
        let needed = if mask {
            "one nested <bsdf>"
        } else {
            "two nested <bsdf>s"
        };
        return Err(r.error(format!("{kind} needs {needed} (as in Mitsuba)")));
    }
    if !mask && !given {
        return Err(r.error(
            "blendbsdf needs a weight (a <float name=\"weight\"> or a texture), as in Mitsuba"
                .into(),
        ));
    }
    if mask {
        nested.insert(0, Sides::one(Null::bsdf(), SideTextures::default()));
    }
    let mut children = [0; 2];
    for (child, sides) in children.iter_mut().zip(nested) {
        *child = r.add_material(sides.material(Vec3::ZERO));
    }
    let textures = SideTextures {
        blend_weight: texture,
        ..SideTextures::default()
    };
    Ok(Sides::one(Bsdf::new(Blend { weight, children }), textures))
}

impl BsdfModel for Blend {
    fn kind(&self) -> &'static str {
        "blend"
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn is_valid(&self) -> bool {
        self.weight.is_finite()
    }

    /// Never sampled: a child is chosen first.
    fn sample(&self, _wi: Vec3, _u1: f32, _u2: Vec2, _mode: Mode) -> Option<Sample> {
        None
    }

    fn pack(&self, record: &mut GpuMaterial, _textures: &SideTextures, _tables: &mut Vec<f32>) {
        // The fronts of the scene's materials keep their indices in the GPU table.
        (record.children, record.blend_weight) = (self.children, self.weight.clamp(0.0, 1.0));
    }

    fn children(&self) -> &[u32] {
        &self.children
    }
}
