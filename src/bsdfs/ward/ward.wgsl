#define_import_path bsdfs::ward

// Mitsuba 0.6's ward (src/bsdfs/ward.cpp of mitsuba-renderer/mitsuba): Ward's anisotropic lobe
// in 0.6's variants (`distribution` 0 ward, 1 ward-duer, 2 balanced) over a Lambertian one, the
// half vector sampled as Walter's notes sample it, the lobe picked by the specular sampling
// weight. The record holds kd in `albedo`, ks in `specular` (textures may replace either),
// 0.6's energy-conservation scale in `int_ior`, the weight in `specular_weight`, and alpha_u,
// alpha_v (scalar textures may replace them; floored at 1e-4). The CPU reference is
// src/bsdfs/ward/mod.rs.

#import common::sampling::{PI, INV_PI, square_to_cosine_hemisphere}
#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}

// f |cos wo| of the Ward lobe, both directions above the surface.
fn ward_lobe(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let au = m.alpha_u;
    let av = m.alpha_v;
    let h = wi + wo;
    var factor1: f32;
    if m.distribution == 0u {
        factor1 = 1.0 / (4.0 * PI * au * av * sqrt(wi.z * wo.z));
    } else if m.distribution == 1u {
        factor1 = 1.0 / (4.0 * PI * au * av * wi.z * wo.z);
    } else {
        let hz2 = h.z * h.z;
        factor1 = dot(h, h) / (PI * au * av * (hz2 * hz2));
    }
    let f2 = h.x / au;
    let f3 = h.y / av;
    let spec = factor1 * exp(-(f2 * f2 + f3 * f3) / (h.z * h.z));
    if spec > 1e-10 {
        return m.specular * (m.int_ior * spec * wo.z);
    }
    return vec3<f32>(0.0);
}

fn ward_pdf(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let au = m.alpha_u;
    let av = m.alpha_v;
    let h = normalize(wi + wo);
    let factor1 = 1.0 / (4.0 * PI * au * av * dot(h, wi) * h.z * h.z * h.z);
    let f2 = h.x / au;
    let f3 = h.y / av;
    let specular = factor1 * exp(-(f2 * f2 + f3 * f3) / (h.z * h.z));
    let w = m.specular_weight;
    return w * specular + (1.0 - w) * wo.z * INV_PI;
}

fn ward_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let value = ward_lobe(m, wi, wo) + m.albedo * (m.int_ior * INV_PI * wo.z);
    return BsdfEval(value, ward_pdf(m, wi, wo));
}

fn ward_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    var wo: vec3<f32>;
    if u1 < m.specular_weight {
        let au = m.alpha_u;
        let av = m.alpha_v;
        var phi_h = atan(av / au * tan(2.0 * PI * u2.y));
        if u2.y > 0.5 {
            phi_h += PI;
        }
        let cos_phi = cos(phi_h);
        let sin_phi = sqrt(max(1.0 - cos_phi * cos_phi, 0.0));
        let tan2 = -log(u2.x) / (cos_phi * cos_phi / (au * au) + sin_phi * sin_phi / (av * av));
        let theta_h = atan(sqrt(max(tan2, 0.0)));
        let sin_theta = sin(theta_h);
        let h = vec3<f32>(sin_theta * cos(phi_h), sin_theta * sin(phi_h), cos(theta_h));
        wo = h * (2.0 * dot(wi, h)) - wi;
        if wo.z <= 0.0 {
            return no_sample();
        }
    } else {
        wo = square_to_cosine_hemisphere(u2);
    }
    let e = ward_eval(m, wi, wo, radiance);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}

// The glossy-caustic partition's view: the Ward lobe's f |cos wo|, and its share of the whole
// per channel (0 where the BSDF is 0).
fn ward_specular(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return vec3<f32>(0.0);
    }
    return ward_lobe(m, wi, wo);
}

fn ward_specular_share(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let total = ward_eval(m, wi, wo, true).value;
    return select(vec3<f32>(0.0), ward_specular(m, wi, wo) / total, total > vec3<f32>(0.0));
}
