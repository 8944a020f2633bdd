#define_import_path common::plastic

// Mitsuba 3's plastic and roughplastic (src/bsdfs/plastic.cpp, roughplastic.cpp): a diffuse
// base under a dielectric coating, with the coating's internal reflections folded into the
// base (`nonlinear` as Mitsuba) and its lobe chosen by the specular sampling weight. And
// pplastic (pplastic.cpp) as its RGB variants render it: the same rough reflection over a base
// weighted by two smooth refractions, its lobes chosen with fixed probabilities.

#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import common::scene::{Material, MATERIAL_POLARIZED_PLASTIC, bsdf_tables}
#import common::bsdf::{BsdfEval, BsdfSample, no_sample, mirror_local}
#import common::fresnel::fresnel_full
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_sample}

const TRANSMITTANCE_RES: u32 = 64u;

fn plastic_microfacet(m: Material) -> Microfacet {
    return Microfacet(m.alpha_u, m.alpha_v, m.distribution == 1u);
}

// The base's albedo seen through the coating's internal reflections.
fn diffuse_under_coating(m: Material) -> vec3<f32> {
    if m.nonlinear != 0u {
        return m.albedo / (vec3<f32>(1.0) - m.albedo * m.internal_reflectance);
    }
    return m.albedo / (1.0 - m.internal_reflectance);
}

// Probability of the diffuse lobe when the coating reflects `f` of the light at wi.
fn plastic_diffuse_prob(f: f32, specular_weight: f32) -> f32 {
    let ps = f * specular_weight;
    let pd = (1.0 - f) * (1.0 - specular_weight);
    return pd / (ps + pd);
}

// Linear interpolation in a material's transmittance table at cos `x`.
fn transmittance_at(m: Material, x: f32) -> f32 {
    let t = x * f32(TRANSMITTANCE_RES - 1u);
    let i = min(u32(max(t, 0.0)), TRANSMITTANCE_RES - 2u);
    let a = bsdf_tables[m.table + i];
    let b = bsdf_tables[m.table + i + 1u];
    return mix(a, b, t - f32(i));
}

fn plastic_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> BsdfEval {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let eta = m.int_ior / m.ext_ior;
    let fi = fresnel_full(wi.z, eta).f;
    let fo = fresnel_full(wo.z, eta).f;
    let value = diffuse_under_coating(m) * (wo.z * INV_PI / (eta * eta) * (1.0 - fi) * (1.0 - fo));
    return BsdfEval(value, wo.z * INV_PI * plastic_diffuse_prob(fi, m.specular_weight));
}

fn plastic_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    let fi = fresnel_full(wi.z, m.int_ior / m.ext_ior).f;
    let prob_diffuse = plastic_diffuse_prob(fi, m.specular_weight);
    if u1 < 1.0 - prob_diffuse {
        let prob = 1.0 - prob_diffuse;
        return BsdfSample(mirror_local(wi), m.specular * (fi / prob), prob, true, true);
    }
    let wo = square_to_cosine_hemisphere(u2);
    let e = plastic_eval(m, wi, wo);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}

// Rough plastic's f |cos wo| split by lobe (the glossy-caustic partition drops the coating's
// part alone), and the pdf of sampling wo with both.
struct RoughPlasticParts {
    coating: vec3<f32>,
    base: vec3<f32>,
    pdf: f32,
}

fn rough_plastic_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> BsdfEval {
    let parts = rough_plastic_eval_parts(m, wi, wo);
    return BsdfEval(parts.coating + parts.base, parts.pdf);
}

// Rough plastic's base seen through the coating: its tabulated rough transmittances at wi and
// wo and the internal reflections; pplastic's: two smooth refractions, nothing reflected back.
fn rough_plastic_base(m: Material, wi: vec3<f32>, wo: vec3<f32>, eta: f32) -> vec3<f32> {
    if m.kind == MATERIAL_POLARIZED_PLASTIC {
        let fi = fresnel_full(wi.z, eta).f;
        let fo = fresnel_full(wo.z, eta).f;
        return m.albedo * (INV_PI * wo.z * (1.0 - fi) * (1.0 - fo));
    }
    let ti = transmittance_at(m, wi.z);
    let to = transmittance_at(m, wo.z);
    return diffuse_under_coating(m) * (INV_PI / (eta * eta) * wo.z * ti * to);
}

// The probability of sampling the base at wi: by the coating's transmittance for rough
// plastic, fixed for pplastic.
fn rough_plastic_diffuse_prob(m: Material, wi: vec3<f32>) -> f32 {
    if m.kind == MATERIAL_POLARIZED_PLASTIC {
        return 1.0 - m.specular_weight;
    }
    return plastic_diffuse_prob(1.0 - transmittance_at(m, wi.z), m.specular_weight);
}

fn rough_plastic_eval_parts(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> RoughPlasticParts {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return RoughPlasticParts(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    }
    let mf = plastic_microfacet(m);
    let eta = m.int_ior / m.ext_ior;
    let h = normalize(wi + wo);
    let d = microfacet_d(mf, h);
    let g1_i = microfacet_g1(mf, wi, h);
    let g = g1_i * microfacet_g1(mf, wo, h);
    let f = fresnel_full(dot(wi, h), eta).f;
    let coating = m.specular * (f * d * g / (4.0 * wi.z));
    let base = rough_plastic_base(m, wi, wo, eta);
    let prob_diffuse = rough_plastic_diffuse_prob(m, wi);
    let pdf = (1.0 - prob_diffuse) * d * g1_i / (4.0 * wi.z) + prob_diffuse * wo.z * INV_PI;
    return RoughPlasticParts(coating, base, pdf);
}

fn rough_plastic_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    let prob_diffuse = rough_plastic_diffuse_prob(m, wi);
    var wo: vec3<f32>;
    if u1 < 1.0 - prob_diffuse {
        let h = microfacet_sample(plastic_microfacet(m), wi, u2);
        wo = 2.0 * dot(wi, h) * h - wi;
    } else {
        wo = square_to_cosine_hemisphere(u2);
    }
    let e = rough_plastic_eval(m, wi, wo);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}
