#define_import_path bsdfs::roughdielectric

// Mitsuba 3's roughdielectric (src/bsdfs/roughdielectric.cpp; Walter et al. 2007): reflection
// and refraction through microfacets sampled by visible normals, chosen by Fresnel. Tracing
// radiance, refraction scales by (eta_t / eta_i)^2; photons carry no such factor. Reflection
// is scaled by the material's specular_reflectance (`specular`), refraction by its
// specular_transmittance (`albedo`), as Mitsuba scales them.

#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}
#import common::fresnel::fresnel_full
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_pdf, microfacet_sample}

fn dielectric_microfacet(m: Material) -> Microfacet {
    return Microfacet(m.alpha_u, m.alpha_v, m.distribution == 1u);
}

fn rough_dielectric_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    let ci = wi.z;
    let co = wo.z;
    if ci == 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let m_eta = m.int_ior / m.ext_ior;
    let reflect = ci * co > 0.0;
    let eta = select(1.0 / m_eta, m_eta, ci > 0.0);
    var h = normalize(wi + wo * select(eta, 1.0, reflect));
    h = select(h, -h, h.z < 0.0);
    // Micro- and macro-surface must agree on the side of both directions.
    if dot(wi, h) * ci <= 0.0 || dot(wo, h) * co <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let mf = dielectric_microfacet(m);
    let d = microfacet_d(mf, h);
    let f = fresnel_full(dot(wi, h), m_eta).f;
    let g = microfacet_g1(mf, wi, h) * microfacet_g1(mf, wo, h);
    let wi_up = select(wi, -wi, ci < 0.0);
    var value: f32;
    var pdf = microfacet_pdf(mf, wi_up, h);
    if reflect {
        value = f * d * g / (4.0 * abs(ci));
        pdf *= f / (4.0 * abs(dot(wo, h)));
    } else {
        let scale = select(1.0, 1.0 / (eta * eta), radiance);
        let denom = dot(wi, h) + eta * dot(wo, h);
        value = abs(scale * (1.0 - f) * d * g * eta * eta * dot(wi, h) * dot(wo, h) / (ci * denom * denom));
        pdf *= (1.0 - f) * abs(eta * eta * dot(wo, h) / (denom * denom));
    }
    if !(value < 3.0e38) || !(pdf < 3.0e38) {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    return BsdfEval(value * select(m.albedo, m.specular, reflect), pdf);
}

fn rough_dielectric_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    let ci = wi.z;
    if ci == 0.0 {
        return no_sample();
    }
    let mf = dielectric_microfacet(m);
    let wi_up = select(wi, -wi, ci < 0.0);
    let h = microfacet_sample(mf, wi_up, u2);
    var pdf = microfacet_pdf(mf, wi_up, h);
    if !(pdf > 0.0) {
        return no_sample();
    }
    let fr = fresnel_full(dot(wi, h), m.int_ior / m.ext_ior);
    var wo: vec3<f32>;
    var weight = 1.0;
    var dwh_dwo: f32;
    let reflected = u1 <= fr.f;
    if reflected {
        pdf *= fr.f;
        wo = 2.0 * dot(wi, h) * h - wi;
        dwh_dwo = 1.0 / (4.0 * dot(wo, h));
    } else {
        pdf *= 1.0 - fr.f;
        wo = h * (dot(wi, h) * fr.eta_ti + fr.cos_t) - wi * fr.eta_ti;
        weight = select(1.0, fr.eta_ti * fr.eta_ti, radiance);
        let denom = dot(wi, h) + fr.eta_it * dot(wo, h);
        dwh_dwo = fr.eta_it * fr.eta_it * dot(wo, h) / (denom * denom);
    }
    weight *= microfacet_g1(mf, wo, h);
    pdf *= abs(dwh_dwo);
    if !(pdf > 0.0) || !(pdf < 3.0e38) || !(weight > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, weight * select(m.albedo, m.specular, reflected), pdf, false, true);
}
