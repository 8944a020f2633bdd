#define_import_path bsdfs::roughdiffuse

// Mitsuba 0.6's roughdiffuse (src/bsdfs/roughdiffuse.cpp of mitsuba-renderer/mitsuba): Oren and
// Nayar's model with sigma = alpha / sqrt(2), in full (inter-reflections included) or its fast
// approximation, sampled cosine-weighted. The record holds the reflectance in `albedo` (a
// texture may replace it), 0.6's energy-conservation scale in `int_ior`, alpha in `alpha_u` (a
// scalar texture may replace it) and use_fast_approx in `nonlinear`. The CPU reference is
// src/bsdfs/roughdiffuse/mod.rs.

#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}

fn rough_diffuse_value(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let ci = wi.z;
    let co = wo.z;
    let rho = m.albedo * m.int_ior;
    let sigma = m.alpha_u * 0.70710678;
    let sigma2 = sigma * sigma;
    let sin_i = sqrt(max(1.0 - ci * ci, 0.0));
    let sin_o = sqrt(max(1.0 - co * co, 0.0));
    var cos_phi_diff = 0.0;
    if sin_i > 1e-4 && sin_o > 1e-4 {
        cos_phi_diff = clamp(wi.x / sin_i, -1.0, 1.0) * clamp(wo.x / sin_o, -1.0, 1.0)
            + clamp(wi.y / sin_i, -1.0, 1.0) * clamp(wo.y / sin_o, -1.0, 1.0);
    }
    var sin_alpha = sin_i;
    var sin_beta = sin_o;
    var tan_beta = sin_o / co;
    if ci > co {
        sin_alpha = sin_o;
        sin_beta = sin_i;
        tan_beta = sin_i / ci;
    }
    if m.nonlinear != 0u {
        let a = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33);
        let b = 0.45 * sigma2 / (sigma2 + 0.09);
        return rho * (INV_PI * co * (a + b * max(cos_phi_diff, 0.0) * sin_alpha * tan_beta));
    }
    let theta_i = acos(clamp(ci, -1.0, 1.0));
    let theta_o = acos(clamp(co, -1.0, 1.0));
    let alpha = max(theta_i, theta_o);
    let beta = min(theta_i, theta_o);
    let tmp = sigma2 / (sigma2 + 0.09);
    let tmp2 = 4.0 * INV_PI * INV_PI * alpha * beta;
    let tmp3 = 2.0 * beta * INV_PI;
    let c1 = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33);
    var c2 = 0.45 * tmp;
    let c3 = 0.125 * tmp * tmp2 * tmp2;
    let c4 = 0.17 * sigma2 / (sigma2 + 0.13);
    if cos_phi_diff > 0.0 {
        c2 *= sin_alpha;
    } else {
        c2 *= sin_alpha - tmp3 * tmp3 * tmp3;
    }
    let tan_half = (sin_alpha + sin_beta)
        / (sqrt(max(1.0 - sin_alpha * sin_alpha, 0.0)) + sqrt(max(1.0 - sin_beta * sin_beta, 0.0)));
    let single = rho * (c1 + cos_phi_diff * c2 * tan_beta + (1.0 - abs(cos_phi_diff)) * c3 * tan_half);
    let double = rho * rho * (c4 * (1.0 - cos_phi_diff * tmp3 * tmp3));
    return (single + double) * (INV_PI * co);
}

fn rough_diffuse_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    return BsdfEval(rough_diffuse_value(m, wi, wo), wo.z * INV_PI);
}

fn rough_diffuse_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    let wo = square_to_cosine_hemisphere(u2);
    let pdf = wo.z * INV_PI;
    if !(pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, rough_diffuse_value(m, wi, wo) / pdf, pdf, false, true);
}
