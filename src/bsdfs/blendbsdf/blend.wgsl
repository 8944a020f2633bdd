#define_import_path bsdfs::blendbsdf

// Which material a surface point scatters with: the back of a twosided material, and one child
// of each blend or mask (Mitsuba's blendbsdf and mask; src/scene/mod.rs, Bsdf::Blend). A blend
// is linear in its children, so choosing one by the weight at every interaction and scattering
// with it alone (its NEE, its sample, its partition class) has the blend's expectation, and a
// diffuse child still gives a plain diffuse vertex to record and gather at.

#import common::scene::{Material, materials, NO_BACK}
#ifdef BLENDS
#import common::scene::{NO_TEXTURE, MATERIAL_BLEND, MATERIAL_DIFFUSE}
#import common::rng::rng_next_f32
#ifdef TEXTURES
#import common::texture::texture_eval_1
#endif
#endif

// The loader puts a blend's children before it, so nesting ends; this only bounds the loop.
const MAX_BLEND_LEVELS: u32 = 8u;

struct ChosenMaterial {
    material: Material,
    // The back of a twosided material was taken: the caller turns the normals over.
    back: bool,
    // A blend chose among children (random numbers were drawn).
    blended: bool,
}

#ifdef BLENDS
fn blend_weight(m: Material, uv: vec2<f32>) -> f32 {
#ifdef TEXTURES
    if m.blend_weight_texture != NO_TEXTURE {
        return clamp(texture_eval_1(m.blend_weight_texture, uv), 0.0, 1.0);
    }
#endif
    return m.blend_weight;
}

// The probability that choose_material picks a diffuse BSDF at this point, summed over the
// blend tree (at most MAX_BLEND_LEVELS pending nodes). A photon deposits what arrives only
// when its choice is diffuse, so it divides by this to deposit the arriving flux in
// expectation, however many of the leaves are diffuse.
fn diffuse_probability(index: u32, facing: f32, uv: vec2<f32>) -> f32 {
    var nodes: array<u32, MAX_BLEND_LEVELS>;
    var probs: array<f32, MAX_BLEND_LEVELS>;
    var flipped: array<bool, MAX_BLEND_LEVELS>;
    nodes[0] = index;
    probs[0] = 1.0;
    flipped[0] = false;
    var pending = 1u;
    var total = 0.0;
    for (var visits = 0u; visits < 4u * MAX_BLEND_LEVELS && pending > 0u; visits++) {
        pending -= 1u;
        var m = materials[nodes[pending]];
        var back = flipped[pending];
        let prob = probs[pending];
        if !back && facing < 0.0 && m.back != NO_BACK {
            m = materials[m.back];
            back = true;
        }
        if m.kind == MATERIAL_DIFFUSE {
            total += prob;
        } else if m.kind == MATERIAL_BLEND && pending + 2u <= MAX_BLEND_LEVELS {
            let weight = blend_weight(m, uv);
            nodes[pending] = m.children.x;
            probs[pending] = prob * (1.0 - weight);
            flipped[pending] = back;
            nodes[pending + 1u] = m.children.y;
            probs[pending + 1u] = prob * weight;
            flipped[pending + 1u] = back;
            pending += 2u;
        }
    }
    return total;
}
#endif

// `facing` is the cosine of the direction towards the previous vertex with the geometric
// normal; random numbers are drawn only at blends.
fn choose_material(index: u32, facing: f32, uv: vec2<f32>, rng: ptr<function, vec4<u32>>) -> ChosenMaterial {
    var m = materials[index];
    var back = false;
    var blended = false;
    for (var level = 0u; level < MAX_BLEND_LEVELS; level++) {
        if !back && facing < 0.0 && m.back != NO_BACK {
            m = materials[m.back];
            back = true;
        }
#ifdef BLENDS
        if m.kind != MATERIAL_BLEND {
            break;
        }
        let weight = blend_weight(m, uv);
        // As Mitsuba: the second child with probability `weight`. Strictly below, so that a
        // zero weight never picks it (a choice of probability 0 would divide by 0).
        let second = rng_next_f32(rng) < weight;
        blended = true;
        m = materials[select(m.children.x, m.children.y, second)];
#else
        break;
#endif
    }
    return ChosenMaterial(m, back, blended);
}
