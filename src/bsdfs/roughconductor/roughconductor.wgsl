#define_import_path bsdfs::roughconductor

// Mitsuba 3's roughconductor (src/bsdfs/roughconductor.cpp): a microfacet reflection with the
// conductor's Fresnel term times specular_reflectance; one-sided. The CPU reference is
// src/bsdfs/roughconductor/mod.rs.

#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}
#import common::fresnel::fresnel_conductor
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_pdf, microfacet_sample}

fn material_microfacet(m: Material) -> Microfacet {
    return Microfacet(m.alpha_u, m.alpha_v, m.distribution == 1u);
}

fn roughconductor_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let mf = material_microfacet(m);
    let h = normalize(wi + wo);
    let d = microfacet_d(mf, h);
    let g1_i = microfacet_g1(mf, wi, h);
    let g = g1_i * microfacet_g1(mf, wo, h);
    let value = fresnel_conductor(dot(wi, h), m.eta, m.k) * m.specular * (d * g / (4.0 * wi.z));
    return BsdfEval(value, d * g1_i / (4.0 * wi.z));
}

fn roughconductor_sample(m: Material, wi: vec3<f32>, u1: f32, u: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    let mf = material_microfacet(m);
    let h = microfacet_sample(mf, wi, u);
    let wo = 2.0 * dot(wi, h) * h - wi;
    let pdf = microfacet_pdf(mf, wi, h) / (4.0 * dot(wo, h));
    if !(pdf > 0.0) || wo.z <= 0.0 {
        return no_sample();
    }
    let weight = fresnel_conductor(dot(wi, h), m.eta, m.k) * m.specular * microfacet_g1(mf, wo, h);
    return BsdfSample(wo, weight, pdf, false, true);
}
