#define_import_path bsdfs::roughplastic

// Mitsuba 3's roughplastic (src/bsdfs/roughplastic.cpp): a diffuse base under a rough dielectric
// coating, seen through the coating's tabulated transmittance at wi and wo, its lobes chosen by
// the specular sampling weight. A material without a table (`table` NO_TABLE) is pplastic
// (src/bsdfs/pplastic/): the same coating over a base weighted by two smooth refractions,
// nothing reflected back, its lobes chosen with fixed probabilities. One module serves both so
// that a scene with both compiles the coating's code once. The CPU references are
// src/bsdfs/roughplastic/mod.rs and src/bsdfs/pplastic/mod.rs.

#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import common::scene::{Material, bsdf_tables}
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}
#import common::fresnel::fresnel_full
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_sample}
#import bsdfs::plastic::{diffuse_under_coating, plastic_diffuse_prob}

const TRANSMITTANCE_RES: u32 = 64u;
// `table` of a rough coating whose base is seen through two smooth refractions (pplastic).
const NO_TABLE: u32 = 0xffffffffu;

fn plastic_microfacet(m: Material) -> Microfacet {
    return Microfacet(m.alpha_u, m.alpha_v, m.distribution == 1u);
}

// Linear interpolation in a material's transmittance table at cos `x`.
fn transmittance_at(m: Material, x: f32) -> f32 {
    let t = x * f32(TRANSMITTANCE_RES - 1u);
    let i = min(u32(max(t, 0.0)), TRANSMITTANCE_RES - 2u);
    let a = bsdf_tables[m.table + i];
    let b = bsdf_tables[m.table + i + 1u];
    return mix(a, b, t - f32(i));
}

// The f |cos wo| split by lobe (the glossy-caustic partition drops the coating's part alone),
// and the pdf of sampling wo with both.
struct RoughPlasticParts {
    coating: vec3<f32>,
    base: vec3<f32>,
    pdf: f32,
}

// The base seen through the coating: rough plastic's tabulated rough transmittances at wi and
// wo and its internal reflections; pplastic's two smooth refractions.
fn rough_plastic_base(m: Material, wi: vec3<f32>, wo: vec3<f32>, eta: f32) -> vec3<f32> {
    if m.table == NO_TABLE {
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
    if m.table == NO_TABLE {
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

fn rough_plastic_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    let parts = rough_plastic_eval_parts(m, wi, wo);
    return BsdfEval(parts.coating + parts.base, parts.pdf);
}

fn rough_plastic_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
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
    let e = rough_plastic_eval(m, wi, wo, radiance);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}

// The glossy-caustic partition's view: the coating's f |cos wo|, and its share of the whole
// per channel (0 where the BSDF is 0).
fn rough_plastic_coating(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return rough_plastic_eval_parts(m, wi, wo).coating;
}

fn rough_plastic_coating_share(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let parts = rough_plastic_eval_parts(m, wi, wo);
    let total = parts.coating + parts.base;
    return select(vec3<f32>(0.0), parts.coating / total, total > vec3<f32>(0.0));
}
