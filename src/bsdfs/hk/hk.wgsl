#define_import_path bsdfs::hk

// Mitsuba 0.6's hk (src/bsdfs/hk.cpp of mitsuba-renderer/mitsuba): single scattering in an
// index-matched layer plus the unscattered light straight through (a delta lobe), evaluated and
// sampled as 0.6 does; photons take the adjoint of 0.6's value (src/bsdfs/hk/mod.rs says why,
// and is the CPU reference). The record holds sigma_s in `albedo`, sigma_a in `specular`, the
// thickness in `int_ior`, the phase function's kind in `nonlinear` (0 isotropic, 1
// Henyey-Greenstein, 2 Rayleigh: common::medium's numbers) and its g in `ext_ior`.

#import common::sampling::{PI, basis_from_normal}
#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}

// 0.6's Epsilon: |mu_i| and |mu_o| this close take the transmission term's limit.
const HK_EPSILON: f32 = 1e-4;

// The phase function's density of leaving along `wo` having travelled along `d_in`, as
// src/scene/medium.rs's Phase::eval.
fn hk_phase_eval(m: Material, d_in: vec3<f32>, wo: vec3<f32>) -> f32 {
    let c = clamp(dot(d_in, wo), -1.0, 1.0);
    if m.nonlinear == 1u {
        let g = m.ext_ior;
        let denom = 1.0 + g * g - 2.0 * g * c;
        return (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom));
    }
    if m.nonlinear == 2u {
        return 3.0 / (16.0 * PI) * (1.0 + c * c);
    }
    return 1.0 / (4.0 * PI);
}

fn hk_cube_root(x: f32) -> f32 {
    return sign(x) * pow(abs(x), 1.0 / 3.0);
}

// A direction drawn from hk_phase_eval about `d_in`, as Phase::sample.
fn hk_phase_sample(m: Material, d_in: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    var c = 1.0 - 2.0 * u.x;
    if m.nonlinear == 1u && abs(m.ext_ior) >= 1e-3 {
        let g = m.ext_ior;
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        c = clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
    } else if m.nonlinear == 2u {
        let q = 4.0 * u.x - 2.0;
        let d = sqrt(q * q + 1.0);
        c = clamp(hk_cube_root(q + d) + hk_cube_root(q - d), -1.0, 1.0);
    }
    let s = sqrt(max(0.0, 1.0 - c * c));
    let phi = 2.0 * PI * u.y;
    return normalize(basis_from_normal(d_in) * vec3<f32>(s * cos(phi), s * sin(phi), c));
}

fn hk_tau(m: Material) -> vec3<f32> {
    return (m.albedo + m.specular) * m.int_ior;
}

// exp(-tau / |cos wi|): what crosses unscattered.
fn hk_unscattered(m: Material, wi: vec3<f32>) -> vec3<f32> {
    return exp(-hk_tau(m) / abs(wi.z));
}

// 0.6's probability of the straight-through lobe: the unscattered fraction's channel mean.
fn hk_straight_probability(m: Material, wi: vec3<f32>) -> f32 {
    let t = hk_unscattered(m, wi);
    return (t.x + t.y + t.z) / 3.0;
}

// The scattering lobes' f |cos wo| as 0.6's eval gives it (wi the viewer's side).
fn hk_value06(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let ci = wi.z;
    let co = wo.z;
    let dp = ci * co;
    if dp == 0.0 {
        return vec3<f32>(0.0);
    }
    let tau = hk_tau(m);
    let sigma_t = m.albedo + m.specular;
    let albedo = select(vec3<f32>(0.0), m.albedo / sigma_t, sigma_t > vec3<f32>(0.0));
    let phase = hk_phase_eval(m, -wi, wo);
    var result: vec3<f32>;
    if dp > 0.0 {
        result = albedo * (phase * ci / (ci + co)) * (vec3<f32>(1.0) - exp((-1.0 / abs(ci) - 1.0 / abs(co)) * tau));
    } else if abs(ci + co) < HK_EPSILON {
        result = albedo * phase * tau / abs(co) * exp(-tau / abs(co));
    } else {
        result = albedo * (phase * abs(ci) / (abs(ci) - abs(co))) * (exp(-tau / abs(ci)) - exp(-tau / abs(co)));
    }
    return result * abs(co);
}

// 0.6's value for radiance; for importance its adjoint f(wo, wi) |cos wo|.
fn hk_value(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> vec3<f32> {
    if radiance {
        return hk_value06(m, wi, wo);
    }
    return hk_value06(m, wo, wi) * (abs(wo.z) / abs(wi.z));
}

fn hk_pdf(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return hk_phase_eval(m, -wi, wo) * (1.0 - hk_straight_probability(m, wi));
}

fn hk_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z == 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    return BsdfEval(hk_value(m, wi, wo, radiance), hk_pdf(m, wi, wo));
}

fn hk_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z == 0.0 {
        return no_sample();
    }
    let straight = hk_straight_probability(m, wi);
    if u1 < straight {
        return BsdfSample(-wi, hk_unscattered(m, wi) / straight, straight, true, true);
    }
    let wo = hk_phase_sample(m, -wi, u2);
    let pdf = hk_pdf(m, wi, wo);
    if !(pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, hk_value(m, wi, wo, radiance) / pdf, pdf, false, true);
}
