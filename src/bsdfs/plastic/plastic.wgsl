#define_import_path bsdfs::plastic

// Mitsuba 3's plastic (src/bsdfs/plastic.cpp): a diffuse base under a smooth dielectric coating,
// with the coating's internal reflections folded into the base (`nonlinear` as Mitsuba) and its
// lobe chosen by the specular sampling weight. The CPU reference is src/bsdfs/plastic/mod.rs.

#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample, mirror_local}
#import common::fresnel::fresnel_full

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

fn plastic_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let eta = m.int_ior / m.ext_ior;
    let fi = fresnel_full(wi.z, eta).f;
    let fo = fresnel_full(wo.z, eta).f;
    let value = diffuse_under_coating(m) * (wo.z * INV_PI / (eta * eta) * (1.0 - fi) * (1.0 - fo));
    return BsdfEval(value, wo.z * INV_PI * plastic_diffuse_prob(fi, m.specular_weight));
}

fn plastic_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
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
    let e = plastic_eval(m, wi, wo, radiance);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}
