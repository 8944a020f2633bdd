//! Mitsuba 0.6's `mixturebsdf` (src/bsdfs/mixturebsdf.cpp of mitsuba-renderer/mitsuba): the
//! weighted sum sum_i w_i f_i of its nested BSDFs, sampled by picking child i with probability
//! w_i / sum_j w_j. Mitsuba 3 has no such plugin, so it is read from files of version 0.x only.
//!
//! It adds no kind: the mixture becomes a balanced tree of `blend` records (src/bsdfs/blendbsdf),
//! each choosing between two subtrees by their shares of the weight, so that child i is chosen
//! with probability w_i / W (W the weights' sum) and scatters alone: the mixture's value in
//! expectation, and each child keeps its own class in the light-transport partition (a diffuse
//! child gives ordinary hit points and photon deposits). Where the weights sum to less than 1,
//! 0.6's mixture reflects only W of what its children would; a black Lambertian child of weight
//! 1 - W stands for that (picked, it absorbs), so the tree's expectation is sum_i w_i f_i
//! exactly. A sum above 1 is scaled to 1 as 0.6's `ensureEnergyConservation` does (with a
//! note); where the file turns that off, such a mixture would create light and is refused.

use glam::Vec3;

use crate::bsdfs::blendbsdf::Blend;
use crate::bsdfs::diffuse::Diffuse;
use crate::bsdfs::shared::mitsuba06::{ensures_energy_conservation, only_in_mitsuba06};
use crate::bsdfs::{BsdfPlugin, BsdfReader, Sides};
use crate::scene::bsdf::Bsdf;
use crate::scene::plugin::{Plugin, p};
use crate::scene::{SceneError, SideTextures};

pub static PLUGIN: BsdfPlugin = BsdfPlugin {
    name: "mixturebsdf",
    reads: &[Plugin {
        object: "bsdf",
        kinds: &["mixturebsdf"],
        properties: &[p("weights", ""), p("ensure_energy_conservation", "true")],
        notes: "Mitsuba 0.6's mixture (files of version 0.x only; Mitsuba 3 has no \
                `mixturebsdf`): `weights` lists one non-negative weight per nested BSDF \
                (separated by spaces, commas or semicolons); the BSDF is their weighted sum. \
                Weights summing above 1 are scaled to sum to 1 as 0.6 scales them (refused \
                with `ensure_energy_conservation` false). Each interaction picks one child by \
                its share of the weight and scatters with it alone, as `blendbsdf`; a sum below \
                1 leaves the rest to a black child.",
    }],
    read,
    objects: &["bsdf", "ref"],
    kinds: &[],
    def: None,
    wgsl: None,
};

/// The deepest blend tree the GPU's choice follows (`MAX_BLEND_LEVELS` in
/// src/bsdfs/blendbsdf/blend.wgsl): a deeper one would stop at a blend.
const MAX_BLEND_LEVELS: usize = 8;

/// Below this the weights' shortfall from 1 is rounding, not a darker mixture.
const SUM_TOLERANCE: f32 = 1e-6;

/// The weights as 0.6 parses them (`tokenize(weights, " ,;")`, each token a whole number),
/// not negative.
fn parse_weights(r: &dyn BsdfReader, text: &str) -> Result<Vec<f32>, SceneError> {
    let tokens: Vec<&str> = text
        .split([' ', ',', ';'])
        .filter(|t| !t.is_empty())
        .collect();
    if tokens.is_empty() {
        return Err(r.error_at(
            "weights",
            "mixturebsdf: no weights were given (one per nested BSDF, as Mitsuba 0.6 requires)"
                .into(),
        ));
    }
    tokens
        .iter()
        .map(|token| match token.parse::<f32>() {
            Ok(w) if w.is_finite() && w >= 0.0 => Ok(w),
            Ok(w) if w.is_finite() => Err(r.error_at(
                "weights",
                format!("mixturebsdf: weight {w} is negative (Mitsuba 0.6 refuses it)"),
            )),
            _ => Err(r.error_at(
                "weights",
                format!("mixturebsdf: \"{token}\" is not a finite number"),
            )),
        })
        .collect()
}

fn read(r: &mut dyn BsdfReader) -> Result<Sides, SceneError> {
    only_in_mitsuba06(r)?;
    let Some(text) = r.string("weights")? else {
        return Err(r.error(
            "mixturebsdf needs weights (a <string name=\"weights\">, one per nested BSDF), as \
             Mitsuba 0.6 does"
                .into(),
        ));
    };
    let mut weights = parse_weights(r, &text)?;
    let ensure = ensures_energy_conservation(r)?;
    let nested = r.nested()?;
    if nested.len() != weights.len() {
        let message = format!(
            "mixturebsdf: {} weight(s) for {} nested BSDF(s); Mitsuba 0.6 needs one each",
            weights.len(),
            nested.len()
        );
        return Err(if nested.len() > weights.len() {
            r.error_at_nested(weights.len(), message)
        } else {
            r.error_at("weights", message)
        });
    }
    let total: f32 = weights.iter().sum();
    if total <= 0.0 {
        return Err(r.error_at(
            "weights",
            "mixturebsdf: the weights must sum to more than 0 (as Mitsuba 0.6 requires)".into(),
        ));
    }
    if total > 1.0 {
        if !ensure {
            return Err(r.error_at(
                "weights",
                format!(
                    "mixturebsdf: the weights sum to {total}, above 1, with \
                     ensure_energy_conservation false: such a mixture reflects more than it \
                     receives, which hppm's choice of one child cannot scale up to"
                ),
            ));
        }
        // 0.6 warns and divides each by the sum.
        r.upgrade(
            "weights",
            format!("mixturebsdf: the weights sum to {total}; each divided by it, as 0.6 does"),
        );
        weights.iter_mut().for_each(|w| *w /= total);
    }
    let sum: f32 = weights.iter().sum();
    // Children of weight 0 are never chosen, and add nothing to 0.6's sum.
    let mut leaves: Vec<(Sides, f32)> = nested
        .into_iter()
        .zip(weights)
        .filter(|(_, w)| *w > 0.0)
        .collect();
    if sum < 1.0 - SUM_TOLERANCE {
        let black = Sides::one(Diffuse::bsdf(Vec3::ZERO), SideTextures::default());
        leaves.push((black, 1.0 - sum));
    }
    let depth = levels(leaves.len())
        + leaves
            .iter()
            .map(|(s, _)| blend_depth(r, &s.front))
            .max()
            .unwrap_or(0);
    if depth > MAX_BLEND_LEVELS {
        return Err(r.error(format!(
            "mixturebsdf: its choice goes {depth} blends deep with the blends nested in it; \
             hppm follows at most {MAX_BLEND_LEVELS}"
        )));
    }
    if leaves.len() == 1 {
        // One child with all the weight is that child.
        let Some((only, _)) = leaves.pop() else {
            return Err(r.error("mixturebsdf: no child with a weight".into()));
        };
        return Ok(only);
    }
    let (blend, _) = tree(r, leaves);
    Ok(Sides::one(Bsdf::new(blend), SideTextures::default()))
}

/// Blend levels of a balanced tree over `n` leaves.
fn levels(n: usize) -> usize {
    n.max(1).next_power_of_two().trailing_zeros() as usize
}

/// How many blends deep a choice through `bsdf` may go (0 for anything but a blend).
fn blend_depth(r: &dyn BsdfReader, bsdf: &Bsdf) -> usize {
    let Some(blend) = bsdf.get::<Blend>() else {
        return 0;
    };
    1 + blend
        .children
        .iter()
        .filter_map(|&c| r.material(c))
        .map(|m| blend_depth(r, &m.bsdf))
        .max()
        .unwrap_or(0)
}

/// A blend over `leaves` (at least two, with positive weights) choosing each with its share of
/// their sum, as two halves, each a blend again or a leaf added as a material; the blend is
/// returned with that sum, not added.
fn tree(r: &mut dyn BsdfReader, mut leaves: Vec<(Sides, f32)>) -> (Blend, f32) {
    let right = leaves.split_off(leaves.len() / 2);
    let (first, w_first) = subtree(r, leaves);
    let (second, w_second) = subtree(r, right);
    let sum = w_first + w_second;
    (
        Blend {
            weight: w_second / sum,
            children: [first, second],
        },
        sum,
    )
}

/// One half of a [`tree`]: its one leaf, or a blend over its leaves, added as a material; its
/// index and weight.
fn subtree(r: &mut dyn BsdfReader, mut part: Vec<(Sides, f32)>) -> (u32, f32) {
    let (sides, w) = if part.len() == 1 {
        part.remove(0)
    } else {
        let (blend, w) = tree(r, part);
        (Sides::one(Bsdf::new(blend), SideTextures::default()), w)
    };
    (r.add_material(sides.material(Vec3::ZERO)), w)
}
