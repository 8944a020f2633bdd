#define_import_path bsdfs::principledthin

// Mitsuba 3's principledthin BSDF, lobe for lobe as src/bsdfs/principledthin/mod.rs (the CPU
// reference, which says where each formula comes from). The parameters live where
// principled keeps its own (src/gpu_scene/layout.rs): base colour in albedo, roughness in
// alpha_u, (anisotropic, spec_trans, spec_tint) in specular, (sheen, sheen_tint, flatness) in
// eta, (diff_trans, eta) in k, the four sampling rates in int_ior, ext_ior, specular_weight and
// internal_reflectance.

#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample, reflect_about}
#import common::fresnel::fresnel_full
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_pdf, microfacet_sample}
#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import bsdfs::principled::{ggx, mulsign, tint_of, calc_schlick, schlick_r0, compatible, diffuse_lobe, sheen_lobe}

struct Thin {
    base_color: vec3<f32>,
    roughness: f32,
    anisotropic: f32,
    spec_trans: f32,
    spec_tint: f32,
    sheen: f32,
    sheen_tint: f32,
    flatness: f32,
    // Half of the file's diff_trans: the diffuse part's transmitted share.
    diff_trans: f32,
    eta: f32,
    // (specular reflection, specular transmission, diffuse reflection, diffuse transmission).
    srates: vec4<f32>,
}

fn unpack_thin(m: Material) -> Thin {
    return Thin(m.albedo, m.alpha_u, m.specular.x, m.specular.y, m.specular.z, m.eta.x, m.eta.y, m.eta.z, m.k.x / 2.0, m.k.y, vec4<f32>(m.int_ior, m.ext_ior, m.specular_weight, m.internal_reflectance));
}

fn reflect_distribution(p: Thin) -> Microfacet {
    return ggx(p.anisotropic, p.roughness);
}

// Roughness scaled by the index (Burley 2015, figure 15).
fn transmit_distribution(p: Thin) -> Microfacet {
    return ggx(p.anisotropic, (0.65 * p.eta - 0.35) * p.roughness);
}

// The lobes' probabilities in `srates`' order; all zero when none can be picked.
fn thin_lobe_probabilities(p: Thin) -> vec4<f32> {
    let spec = p.spec_trans;
    let w = p.srates * vec4<f32>(spec / 2.0, spec / 2.0, (1.0 - spec) * (1.0 - p.diff_trans), (1.0 - spec) * p.diff_trans);
    let total = w.x + w.y + w.z + w.w;
    if !(total > 0.0) || !(total < 3.0e38) {
        return vec4<f32>(0.0);
    }
    return w / total;
}

fn reflect_fresnel(p: Thin, f_dielectric: f32, cos_i: f32) -> vec3<f32> {
    if p.spec_tint == 0.0 {
        return vec3<f32>(f_dielectric);
    }
    return mix(vec3<f32>(f_dielectric), calc_schlick(tint_of(p.base_color) * schlick_r0(p.eta), cos_i, p.eta), p.spec_tint);
}

// wo's mirror image above the sheet, for wi and wo already turned so that wi faces +z.
fn above(wo: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(wo.x, wo.y, abs(wo.z));
}

// f |cos wo| for wi facing +z.
fn thin_value(p: Thin, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let cos_i = wi.z;
    let cos_o = wo.z;
    let h = normalize(wi + above(wo));
    let spec = p.spec_trans;
    var value = vec3<f32>(0.0);
    if spec > 0.0 {
        let f = fresnel_full(dot(wi, h), p.eta).f;
        if cos_o > 0.0 && compatible(h, wi, wo, cos_i, true) {
            let mf = reflect_distribution(p);
            let dg = microfacet_d(mf, h) * microfacet_g1(mf, wi, h) * microfacet_g1(mf, wo, h);
            value += spec * reflect_fresnel(p, f, dot(wi, h)) * dg / (4.0 * cos_i);
        }
        if cos_o < 0.0 && compatible(h, wi, wo, cos_i, false) {
            let mf = transmit_distribution(p);
            let dg = microfacet_d(mf, h) * microfacet_g1(mf, wi, h) * microfacet_g1(mf, wo, h);
            value += spec * p.base_color * (1.0 - f) * dg / (4.0 * cos_i);
        }
    }
    if cos_o > 0.0 && spec < 1.0 && p.diff_trans < 1.0 {
        let cos_d = dot(h, wo);
        var lobe = p.base_color * INV_PI * diffuse_lobe(p.roughness, p.flatness, cos_i, cos_o, cos_d);
        if p.sheen > 0.0 {
            lobe += sheen_lobe(p.sheen, p.sheen_tint, p.base_color, cos_d);
        }
        value += (1.0 - spec) * (1.0 - p.diff_trans) * cos_o * lobe;
    }
    if cos_o < 0.0 && spec < 1.0 && p.diff_trans > 0.0 {
        value += (1.0 - spec) * p.diff_trans * p.base_color * INV_PI * abs(cos_o);
    }
    return value;
}

// The density for wi facing +z.
fn thin_pdf(p: Thin, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let probs = thin_lobe_probabilities(p);
    var pdf = 0.0;
    if p.spec_trans > 0.0 {
        let up = above(wo);
        let h = normalize(wi + up);
        let dh_dwo = abs(1.0 / (4.0 * dot(up, h)));
        if wo.z > 0.0 && compatible(h, wi, wo, wi.z, true) {
            pdf += probs.x * microfacet_pdf(reflect_distribution(p), wi, h) * dh_dwo;
        }
        if wo.z < 0.0 && compatible(h, wi, wo, wi.z, false) {
            pdf += probs.y * microfacet_pdf(transmit_distribution(p), wi, h) * dh_dwo;
        }
    }
    if wo.z > 0.0 {
        pdf += probs.z * wo.z * INV_PI;
    }
    if wo.z < 0.0 {
        pdf += probs.w * -wo.z * INV_PI;
    }
    return pdf;
}

fn principled_thin_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z == 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let p = unpack_thin(m);
    // Both sides alike: turned so that wi faces +z.
    let wi_f = mulsign(wi, wi.z);
    let wo_f = mulsign(wo, wi.z);
    let value = thin_value(p, wi_f, wo_f);
    let pdf = thin_pdf(p, wi_f, wo_f);
    if !all(value < vec3<f32>(3.0e38)) || !(pdf < 3.0e38) {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    return BsdfEval(value, select(0.0, pdf, pdf >= 0.0));
}

// As Mitsuba: the lobe by `u1` with fixed probabilities, its direction from `u2`.
fn principled_thin_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    let side = wi.z;
    if side == 0.0 {
        return no_sample();
    }
    let p = unpack_thin(m);
    let probs = thin_lobe_probabilities(p);
    let wi_f = mulsign(wi, side);
    var wo: vec3<f32>;
    var ok = true;
    if u1 < probs.x {
        let h = microfacet_sample(reflect_distribution(p), wi_f, u2);
        wo = reflect_about(wi_f, h);
        ok = compatible(h, wi_f, wo, wi_f.z, true) && wo.z > 0.0;
    } else if u1 < probs.x + probs.y {
        // Reflected, then through the sheet.
        let h = microfacet_sample(transmit_distribution(p), wi_f, u2);
        let up = reflect_about(wi_f, h);
        wo = vec3<f32>(up.x, up.y, -up.z);
        ok = compatible(h, wi_f, wo, wi_f.z, false) && wo.z < 0.0;
    } else if u1 < probs.x + probs.y + probs.z {
        wo = square_to_cosine_hemisphere(u2);
    } else if probs.w > 0.0 {
        wo = -square_to_cosine_hemisphere(u2);
    } else {
        ok = false;
    }
    if !ok {
        return no_sample();
    }
    let pdf = thin_pdf(p, wi_f, wo);
    if !(pdf > 0.0) || !(pdf < 3.0e38) {
        return no_sample();
    }
    let weight = thin_value(p, wi_f, wo) / pdf;
    if !all(weight < vec3<f32>(3.0e38)) {
        return no_sample();
    }
    return BsdfSample(mulsign(wo, side), weight, pdf, false, true);
}
