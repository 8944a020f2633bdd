#define_import_path bsdfs::roughplastic

// Mitsuba 3's roughplastic (src/bsdfs/roughplastic.cpp): the diffuse base under a rough
// dielectric coating, seen through the coating's tabulated transmittance at wi and wo. The
// rough coating's reflection is shared with pplastic. The CPU reference is
// src/bsdfs/roughplastic/mod.rs.

#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import common::scene::{Material, bsdf_tables}
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}
#import common::fresnel::fresnel_full
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_sample}
#import bsdfs::plastic::{diffuse_under_coating, plastic_diffuse_prob}

const TRANSMITTANCE_RES: u32 = 64u;

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

// A rough plastic's f |cos wo| split by lobe (the glossy-caustic partition drops the coating's
// part alone), and the pdf of sampling wo with both.
struct RoughPlasticParts {
    coating: vec3<f32>,
    base: vec3<f32>,
    pdf: f32,
}

// The rough coating's reflection (f |cos wo|) with the distribution's terms its pdf needs.
struct RoughCoating {
    value: vec3<f32>,
    d: f32,
    g1_i: f32,
}

fn rough_coating(m: Material, wi: vec3<f32>, wo: vec3<f32>, eta: f32) -> RoughCoating {
    let mf = plastic_microfacet(m);
    let h = normalize(wi + wo);
    let d = microfacet_d(mf, h);
    let g1_i = microfacet_g1(mf, wi, h);
    let g = g1_i * microfacet_g1(mf, wo, h);
    let f = fresnel_full(dot(wi, h), eta).f;
    return RoughCoating(m.specular * (f * d * g / (4.0 * wi.z)), d, g1_i);
}

// The pdf of choosing the coating with probability 1 - prob_diffuse and the base otherwise.
fn rough_coating_pdf(c: RoughCoating, prob_diffuse: f32, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return (1.0 - prob_diffuse) * c.d * c.g1_i / (4.0 * wi.z) + prob_diffuse * wo.z * INV_PI;
}

// A direction from the coating (u1 below 1 - prob_diffuse) or the cosine-weighted base.
fn rough_coating_direction(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, prob_diffuse: f32) -> vec3<f32> {
    if u1 < 1.0 - prob_diffuse {
        let h = microfacet_sample(plastic_microfacet(m), wi, u2);
        return 2.0 * dot(wi, h) * h - wi;
    }
    return square_to_cosine_hemisphere(u2);
}

// The base's probability at wi: by the coating's transmittance there.
fn rough_plastic_diffuse_prob(m: Material, wi: vec3<f32>) -> f32 {
    return plastic_diffuse_prob(1.0 - transmittance_at(m, wi.z), m.specular_weight);
}

fn rough_plastic_eval_parts(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> RoughPlasticParts {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return RoughPlasticParts(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    }
    let eta = m.int_ior / m.ext_ior;
    let coating = rough_coating(m, wi, wo, eta);
    let ti = transmittance_at(m, wi.z);
    let to = transmittance_at(m, wo.z);
    let base = diffuse_under_coating(m) * (INV_PI / (eta * eta) * wo.z * ti * to);
    let prob_diffuse = rough_plastic_diffuse_prob(m, wi);
    return RoughPlasticParts(coating.value, base, rough_coating_pdf(coating, prob_diffuse, wi, wo));
}

fn rough_plastic_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    let parts = rough_plastic_eval_parts(m, wi, wo);
    return BsdfEval(parts.coating + parts.base, parts.pdf);
}

fn rough_plastic_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    let wo = rough_coating_direction(m, wi, u1, u2, rough_plastic_diffuse_prob(m, wi));
    let e = rough_plastic_eval(m, wi, wo, radiance);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}

// The coating's share of `parts` per channel (0 where the BSDF is 0).
fn coating_share(parts: RoughPlasticParts) -> vec3<f32> {
    let total = parts.coating + parts.base;
    return select(vec3<f32>(0.0), parts.coating / total, total > vec3<f32>(0.0));
}

// The glossy-caustic partition's view: the coating's f |cos wo|, and its share of the whole.
fn rough_plastic_coating(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return rough_plastic_eval_parts(m, wi, wo).coating;
}

fn rough_plastic_coating_share(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return coating_share(rough_plastic_eval_parts(m, wi, wo));
}
