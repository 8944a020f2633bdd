#define_import_path bsdfs::pplastic

// Mitsuba 3's pplastic (src/bsdfs/pplastic.cpp) as its RGB variants render it: roughplastic's
// rough coating over a base weighted by two smooth refractions, nothing reflected back, its
// lobes chosen with fixed probabilities. The CPU reference is src/bsdfs/pplastic/mod.rs.

#import common::sampling::INV_PI
#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}
#import common::fresnel::fresnel_full
#import bsdfs::roughplastic::{RoughPlasticParts, rough_coating, rough_coating_pdf, rough_coating_direction, coating_share}

fn pplastic_eval_parts(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> RoughPlasticParts {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return RoughPlasticParts(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    }
    let eta = m.int_ior / m.ext_ior;
    let coating = rough_coating(m, wi, wo, eta);
    let fi = fresnel_full(wi.z, eta).f;
    let fo = fresnel_full(wo.z, eta).f;
    let base = m.albedo * (INV_PI * wo.z * (1.0 - fi) * (1.0 - fo));
    let prob_diffuse = 1.0 - m.specular_weight;
    return RoughPlasticParts(coating.value, base, rough_coating_pdf(coating, prob_diffuse, wi, wo));
}

fn pplastic_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    let parts = pplastic_eval_parts(m, wi, wo);
    return BsdfEval(parts.coating + parts.base, parts.pdf);
}

fn pplastic_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    let wo = rough_coating_direction(m, wi, u1, u2, 1.0 - m.specular_weight);
    let e = pplastic_eval(m, wi, wo, radiance);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}

fn pplastic_coating(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return pplastic_eval_parts(m, wi, wo).coating;
}

fn pplastic_coating_share(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return coating_share(pplastic_eval_parts(m, wi, wo));
}
