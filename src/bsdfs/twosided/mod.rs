//! Mitsuba's `twosided`: one nested BSDF seen from both sides, or two (front, back). It adds no
//! kind: the back side's BSDF is the material's `back`, which the GPU record points at, and the
//! passes turn the normals over before using it.

use crate::bsdfs::{BsdfPlugin, BsdfReader, Sides};
use crate::scene::MaterialTextures;
use crate::scene::SceneError;
use crate::scene::bsdf::Bsdf;
use crate::scene::plugin::{Plugin, p};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "twosided",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["twosided"],
        properties: &[p("allow_transmission", "false")],
        notes: "One nested BSDF (both sides) or two (front, back); they must not transmit, as \
                in Mitsuba; `allow_transmission` true (which lets Mitsuba mirror a \
                transmitting one) is refused.",
    }],
    read,
    objects: &["bsdf", "ref"],
    kinds: &[],
    def: None,
    wgsl: None,
};

/// Whether `bsdf`, or any BSDF a blend or mask of it may choose, transmits.
pub fn transmits(r: &dyn BsdfReader, bsdf: &Bsdf) -> bool {
    if bsdf.children().is_empty() {
        return bsdf.transmits();
    }
    bsdf.children()
        .iter()
        .filter_map(|&i| r.material(i))
        .any(|m| m.bsdfs().any(|b| transmits(r, b)))
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    if r.boolean("allow_transmission")? == Some(true) {
        return Err(r.error_at(
            "allow_transmission",
            "twosided allow_transmission: a transmitting BSDF mirrored onto both sides is not \
             supported"
                .into(),
        ));
    }
    let nested = r.nested()?;
    for (i, sides) in nested.iter().enumerate() {
        if sides.back.is_some() {
            return Err(r.error_at_nested(i, "twosided: a nested BSDF is already twosided".into()));
        }
        if transmits(r, &sides.front) {
            return Err(r.error_at_nested(
                i,
                "twosided: only BSDFs without transmission can be nested (as in Mitsuba; a \
                 mask's pass-through counts); a dielectric is two-sided already"
                    .into(),
            ));
        }
        if i == 2 {
            return Err(r.error_at_nested(i, "twosided: at most two nested BSDFs".into()));
        }
    }
    match nested.as_slice() {
        [one] => Ok(Sides {
            front: one.front.clone(),
            back: Some(one.front.clone()),
            textures: MaterialTextures {
                front: one.textures.front,
                back: one.textures.front,
            },
        }),
        [front, back] => Ok(Sides {
            front: front.front.clone(),
            back: Some(back.front.clone()),
            textures: MaterialTextures {
                front: front.textures.front,
                back: back.textures.front,
            },
        }),
        _ => Err(r.error("twosided: a nested <bsdf> is required".into())),
    }
}
