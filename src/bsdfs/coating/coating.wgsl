#define_import_path bsdfs::coating

// Mitsuba 0.6's coating and roughcoating (src/bsdfs/coating.cpp, roughcoating.cpp): a dielectric
// layer over one nested BSDF, which is evaluated and sampled at the directions refracted into
// the layer. The nested BSDF is its own record (`materials[m.children.x]`); WGSL has no
// recursion, so the generated dispatch cannot be called from here: a Lambertian base is
// evaluated below (the generated dispatches leave it to their callers), the other nested kinds
// through common::leaf_material, generated for the kinds of the units before this one (their
// defs are set, since the nested material is among the scene's materials). Record slots:
// int_ior the relative eta, k sigma_a times thickness, specular the reflection's tint,
// specular_weight 0.6's lobe weight; the rough coating's alpha_u / alpha_v / distribution and its
// transmittance table at `table`. The CPU reference is src/bsdfs/coating/mod.rs.

#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import common::scene::{Material, materials, bsdf_tables, MATERIAL_DIFFUSE}
#import common::bsdf::{BsdfEval, BsdfSample, no_sample, mirror_local}
#import common::fresnel::fresnel_full
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_sample}
#import common::leaf_material::{leaf_material_eval, leaf_material_sample}

const TRANSMITTANCE_RES: u32 = 100u;

fn nested_eval(n: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if n.kind == MATERIAL_DIFFUSE {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return BsdfEval(vec3<f32>(0.0), 0.0);
        }
        return BsdfEval(n.albedo * (wo.z * INV_PI), wo.z * INV_PI);
    }
    return leaf_material_eval(n, wi, wo, radiance);
}

fn nested_sample(n: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if n.kind == MATERIAL_DIFFUSE {
        if wi.z <= 0.0 {
            return no_sample();
        }
        let wo = square_to_cosine_hemisphere(u2);
        if !(wo.z > 0.0) {
            return no_sample();
        }
        return BsdfSample(wo, n.albedo, wo.z * INV_PI, false, true);
    }
    return leaf_material_sample(n, wi, u1, u2, radiance);
}

// A direction refracted through the smooth interface (relative index `eta` as seen from its
// side), its sign kept, with the interface's reflectance there (0.6's refractIn / refractOut);
// `r` is 1 under total internal reflection.
struct Refracted {
    w: vec3<f32>,
    r: f32,
}

fn refract_keeping_side(w: vec3<f32>, eta: f32) -> Refracted {
    let f = fresnel_full(abs(w.z), eta);
    let inv = 1.0 / eta;
    return Refracted(vec3<f32>(inv * w.x, inv * w.y, sign(w.z) * abs(f.cos_t)), f.f);
}

// exp(-sigma_a thickness (1 / |cos wi'| + 1 / |cos wo'|)) inside the layer.
fn layer_absorption(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if all(m.k == vec3<f32>(0.0)) {
        return vec3<f32>(1.0);
    }
    return exp(-m.k * (1.0 / abs(wi.z) + 1.0 / abs(wo.z)));
}

// 0.6's lobe choice: the reflection's probability when the interface reflects `r` at wi.
fn layer_specular_prob(m: Material, r: f32) -> f32 {
    let w = m.specular_weight;
    return r * w / (r * w + (1.0 - r) * (1.0 - w));
}

fn coating_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    let eta = m.int_ior;
    let i = refract_keeping_side(wi, eta);
    let o = refract_keeping_side(wo, eta);
    if i.r >= 1.0 || o.r >= 1.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let e = nested_eval(materials[m.children.x], i.w, o.w, radiance);
    let jacobian = wo.z / (eta * eta * o.w.z);
    let value = e.value * ((1.0 - i.r) * (1.0 - o.r)) * layer_absorption(m, i.w, o.w) * jacobian;
    return BsdfEval(value, e.pdf * jacobian * (1.0 - layer_specular_prob(m, i.r)));
}

fn coating_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    let eta = m.int_ior;
    let i = refract_keeping_side(wi, eta);
    let prob = layer_specular_prob(m, i.r);
    if u1 < prob {
        return BsdfSample(mirror_local(wi), m.specular * (i.r / prob), prob, true, true);
    }
    if i.r >= 1.0 {
        return no_sample();
    }
    let s = nested_sample(materials[m.children.x], i.w, (u1 - prob) / (1.0 - prob), u2, radiance);
    if !s.valid {
        return no_sample();
    }
    let o = refract_keeping_side(s.wo, 1.0 / eta);
    if o.r >= 1.0 {
        return no_sample();
    }
    let weight = s.weight * layer_absorption(m, i.w, s.wo) * ((1.0 - i.r) * (1.0 - o.r)) / (1.0 - prob);
    let pdf = s.pdf * (1.0 - prob) * o.w.z / (eta * eta * s.wo.z);
    return BsdfSample(o.w, weight, pdf, false, true);
}

// --- roughcoating ---

fn coating_microfacet(m: Material) -> Microfacet {
    return Microfacet(m.alpha_u, m.alpha_v, m.distribution == 1u);
}

// The rough interface's transmittance from outside at |cos|: linear in cos^(1/4) between the
// table's nodes.
fn rough_coating_transmittance(m: Material, cos: f32) -> f32 {
    let x = sqrt(sqrt(abs(cos))) * f32(TRANSMITTANCE_RES - 1u);
    let i = min(u32(max(x, 0.0)), TRANSMITTANCE_RES - 2u);
    let a = bsdf_tables[m.table + i];
    let b = bsdf_tables[m.table + i + 1u];
    return mix(a, b, x - f32(i));
}

// Snell's law alone, sign kept (0.6's refractTo); the zero vector under total internal
// reflection.
fn refract_to(w: vec3<f32>, inv_eta: f32) -> vec3<f32> {
    let sin2 = inv_eta * inv_eta * max(1.0 - w.z * w.z, 0.0);
    if sin2 >= 1.0 {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(inv_eta * w.x, inv_eta * w.y, sign(w.z) * sqrt(1.0 - sin2));
}

// The f |cos wo| split by lobe (the glossy-caustic partition takes the reflection alone), and
// the pdf of sampling wo with both.
struct RoughCoatingParts {
    reflection: vec3<f32>,
    nested: vec3<f32>,
    pdf: f32,
}

fn rough_coating_parts(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> RoughCoatingParts {
    let eta = m.int_ior;
    let mf = coating_microfacet(m);
    let prob = layer_specular_prob(m, 1.0 - rough_coating_transmittance(m, wi.z));
    var parts = RoughCoatingParts(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    if wi.z * wo.z > 0.0 {
        let h = normalize(wi + wo) * sign(wo.z);
        let d = microfacet_d(mf, h);
        let g1_i = microfacet_g1(mf, wi, h);
        let f = fresnel_full(abs(dot(wi, h)), eta).f;
        let g = g1_i * microfacet_g1(mf, wo, h);
        parts.reflection = m.specular * (f * d * g / (4.0 * abs(wi.z)));
        let visible = g1_i * abs(dot(wi, h)) * d / abs(wi.z);
        parts.pdf = visible / (4.0 * abs(dot(wo, h))) * prob;
    }
    let inv = 1.0 / eta;
    let wi_in = refract_to(wi, inv);
    let wo_in = refract_to(wo, inv);
    if wi_in.z != 0.0 && wo_in.z != 0.0 {
        let e = nested_eval(materials[m.children.x], wi_in, wo_in, radiance);
        let jacobian = inv * inv * wo.z / wo_in.z;
        let t = rough_coating_transmittance(m, wi.z) * rough_coating_transmittance(m, wo.z);
        parts.nested = e.value * layer_absorption(m, wi_in, wo_in) * (t * jacobian);
        parts.pdf += e.pdf * jacobian * (1.0 - prob);
    }
    return parts;
}

fn rough_coating_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    let parts = rough_coating_parts(m, wi, wo, radiance);
    return BsdfEval(parts.reflection + parts.nested, parts.pdf);
}

fn rough_coating_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    let prob = layer_specular_prob(m, 1.0 - rough_coating_transmittance(m, wi.z));
    var wo: vec3<f32>;
    if u1 < prob {
        // From below, the mirror image of the sample from above (the lobe is symmetric about
        // the surface; visible normals are sampled from above).
        let flip = vec3<f32>(1.0, 1.0, select(1.0, -1.0, wi.z < 0.0));
        let up = wi * flip;
        let h = microfacet_sample(coating_microfacet(m), up, u2);
        wo = (2.0 * dot(up, h) * h - up) * flip;
        if wo.z * wi.z <= 0.0 {
            return no_sample();
        }
    } else {
        let wi_in = refract_to(wi, 1.0 / m.int_ior);
        if wi_in.z == 0.0 {
            return no_sample();
        }
        let s = nested_sample(materials[m.children.x], wi_in, (u1 - prob) / (1.0 - prob), u2, radiance);
        if !s.valid {
            return no_sample();
        }
        wo = refract_to(s.wo, m.int_ior);
        if wo.z == 0.0 {
            return no_sample();
        }
    }
    let e = rough_coating_eval(m, wi, wo, radiance);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}

// The glossy-caustic partition's view: the reflection's f |cos wo|, and its share of the whole
// per channel (0 where the BSDF is 0).
fn rough_coating_reflection(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return rough_coating_parts(m, wi, wo, true).reflection;
}

fn rough_coating_reflection_share(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let parts = rough_coating_parts(m, wi, wo, true);
    let total = parts.reflection + parts.nested;
    return select(vec3<f32>(0.0), parts.reflection / total, total > vec3<f32>(0.0));
}
