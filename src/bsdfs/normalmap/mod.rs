//! Mitsuba's `normalmap` and `bumpmap` (two plugins of one unit): one nested BSDF evaluated and
//! sampled in a shading frame a bitmap perturbs. They add no kind: the perturbation is the material side's `frame` (its
//! texture slot and the GPU record's frame fields), which `normalmap.wgsl` applies before any
//! BSDF sees a direction; `frame.rs` is its CPU reference.

pub mod frame;

use crate::bsdfs::blendbsdf::Blend;
use crate::bsdfs::{BsdfPlugin, BsdfReader, Sides};
use crate::scene::bsdf::Bsdf;
use crate::scene::plugin::{Plugin, p};
use crate::scene::{FramePerturbation, PerturbationKind, SceneError};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "normalmap",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["normalmap"],
        properties: &[
            p("normalmap", ""),
            p("flip_invalid_normals", "true"),
            p("use_shadowing_function", "true"),
        ],
        notes: "A bitmap `normalmap` (x -> 2x - 1, the normal in the shading frame; `raw` as \
                Mitsuba's docs ask) and one nested BSDF (inline or `<ref>`), evaluated and \
                sampled in the perturbed frame with Mitsuba's masking and shadow terminator; \
                `twosided` inside or outside it.",
    }],
    read,
    objects: &["bsdf", "ref"],
    kinds: &[],
    // Set from the scene's perturbed sides (`SceneFeatures::normal_maps`), not from a kind.
    def: None,
    wgsl: Some(crate::shader_file!("src/bsdfs/normalmap/normalmap.wgsl")),
};

/// `bumpmap`: the same perturbation, its normal from a height map's gradient. Its texture is an
/// object of any name (Mitsuba takes the one it finds), so it reads textures as objects, which
/// `normalmap` does not; its WGSL is `normalmap`'s.
pub static BUMP_PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "bumpmap",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["bumpmap"],
        properties: &[
            p("scale", "1"),
            p("flip_invalid_normals", "true"),
            p("use_shadowing_function", "true"),
        ],
        notes: "One bitmap (any name: the height, its luminance) and one nested BSDF; the \
                normal from the texture's bilinear gradient (Mitsuba's `eval_1_grad`) along \
                dp/du and dp/dv, otherwise as `normalmap`.",
    }],
    read,
    objects: &["bsdf", "ref", "texture"],
    kinds: &[],
    def: None,
    wgsl: None,
};

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    let kind = r.plugin().to_string();
    let bump = kind == "bumpmap";
    let mut textures = Vec::new();
    if !bump && let Some(t) = r.texture("normalmap")? {
        textures.push(t);
    }
    if bump {
        textures.extend(r.texture_objects()?);
    }
    let nested = r.nested()?;
    if nested.len() > 1 {
        return Err(r.error_at_nested(
            1,
            format!("{kind}: only one nested BSDF can be given (as in Mitsuba)"),
        ));
    }
    if let Some(i) = nested
        .iter()
        .position(|s| s.textures.front.frame.is_some() || s.textures.back.frame.is_some())
    {
        return Err(r.error_at_nested(
            i,
            format!("{kind}: a nested normalmap or bumpmap is not supported"),
        ));
    }
    let scale = if bump {
        r.float("scale")?.unwrap_or(1.0)
    } else {
        1.0
    };
    let flip_invalid_normals = r.boolean("flip_invalid_normals")?.unwrap_or(true);
    let shadowing = r.boolean("use_shadowing_function")?.unwrap_or(true);
    if textures.len() > 1 {
        return Err(r.error(format!(
            "{kind}: only one texture can be given (as in Mitsuba)"
        )));
    }
    let Some(&texture) = textures.first() else {
        let needed = if bump {
            "a <texture type=\"bitmap\"> (the height map)"
        } else {
            "<texture name=\"normalmap\" type=\"bitmap\">"
        };
        return Err(r.error(format!("{kind} needs {needed}")));
    };
    if !r.is_bitmap(texture) {
        return Err(r.error(format!(
            "{kind}: the texture must be a bitmap (Mitsuba's other textures have no {})",
            if bump { "gradient" } else { "RGB lookup" }
        )));
    }
    let Some(sides) = nested.into_iter().next() else {
        return Err(r.error(format!(
            "{kind}: a nested <bsdf> is required (as in Mitsuba)"
        )));
    };
    let frame = FramePerturbation {
        kind: if bump {
            PerturbationKind::Bump { scale }
        } else {
            PerturbationKind::Normal
        },
        texture,
        flip_invalid_normals,
        shadowing,
        outside_twosided: false,
    };
    perturbed(r, sides, frame)
}

/// `sides` in the frame `frame` perturbs. A blend's or mask's children each get the frame
/// instead (the same surface: a blend is linear in its children), as copies, since a
/// `<ref>`'d child may be used elsewhere without it.
fn perturbed(
    r: &mut dyn BsdfReader,
    mut sides: Sides,
    frame: FramePerturbation,
) -> Result<Sides, SceneError> {
    let Some(blend) = sides.front.get::<Blend>().copied() else {
        if sides.textures.front.frame.is_some() || sides.textures.back.frame.is_some() {
            return Err(r.error(
                "a normalmap or bumpmap inside another (here through a blendbsdf or mask) is \
                 not supported"
                    .into(),
            ));
        }
        sides.textures.front.frame = Some(frame);
        if sides.back.is_some() {
            sides.textures.back.frame = Some(FramePerturbation {
                outside_twosided: true,
                ..frame
            });
        }
        return Ok(sides);
    };
    if sides.back.is_some() {
        return Err(r.error(
            "a normalmap or bumpmap around a twosided blendbsdf is not supported: put it around \
             the BSDFs nested in the blend"
                .into(),
        ));
    }
    let mut children = blend.children;
    for child in &mut children {
        let Some(material) = r.material(*child) else {
            return Err(r.error("internal: a blend's child is missing".into()));
        };
        let emission = material.emission;
        let nested = Sides {
            front: material.bsdf,
            back: material.back,
            textures: material.textures,
        };
        let turned = perturbed(r, nested, frame)?;
        *child = r.add_material(turned.material(emission));
    }
    sides.front = Bsdf::new(Blend { children, ..blend });
    Ok(sides)
}
