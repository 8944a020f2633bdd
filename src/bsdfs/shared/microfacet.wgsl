#define_import_path common::microfacet

// Beckmann and GGX microfacet distributions with visible-normal sampling, as Mitsuba 3 writes
// them (include/mitsuba/render/microfacet.h: Walter et al. 2007; Heitz and d'Eon 2014). Local
// frame: z is the normal. The CPU reference is src/bsdfs/shared/microfacet.rs.

#import common::sampling::{PI, square_to_disk_concentric}

struct Microfacet {
    alpha_u: f32,
    alpha_v: f32,
    ggx: bool,
}

const INV_SQRT_PI: f32 = 0.5641896;

fn microfacet_d(mf: Microfacet, m: vec3<f32>) -> f32 {
    let c2 = m.z * m.z;
    var r: f32;
    if mf.ggx {
        let t = (m.x / mf.alpha_u) * (m.x / mf.alpha_u) + (m.y / mf.alpha_v) * (m.y / mf.alpha_v) + c2;
        r = 1.0 / (PI * mf.alpha_u * mf.alpha_v * t * t);
    } else {
        let e = ((m.x / mf.alpha_u) * (m.x / mf.alpha_u) + (m.y / mf.alpha_v) * (m.y / mf.alpha_v)) / c2;
        r = exp(-e) / (PI * mf.alpha_u * mf.alpha_v * c2 * c2);
    }
    return select(0.0, r, r * m.z > 1e-20);
}

// Smith's masking of `v` by microfacets of normal `m`; zero where v sees m's back.
fn microfacet_g1(mf: Microfacet, v: vec3<f32>, m: vec3<f32>) -> f32 {
    if dot(v, m) * v.z <= 0.0 {
        return 0.0;
    }
    let xy = (mf.alpha_u * v.x) * (mf.alpha_u * v.x) + (mf.alpha_v * v.y) * (mf.alpha_v * v.y);
    if xy == 0.0 {
        return 1.0;
    }
    let tan2 = xy / (v.z * v.z);
    if mf.ggx {
        return 2.0 / (1.0 + sqrt(1.0 + tan2));
    }
    let a = inverseSqrt(tan2);
    if a >= 1.6 {
        return 1.0;
    }
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

// Density of the visible normal `m` seen from `wi` (wi.z > 0).
fn microfacet_pdf(mf: Microfacet, wi: vec3<f32>, m: vec3<f32>) -> f32 {
    return microfacet_d(mf, m) * microfacet_g1(mf, wi, m) * abs(dot(wi, m)) / wi.z;
}

fn erf_approx(x: f32) -> f32 {
    let z = abs(x);
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t * exp(-z * z - 1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418 + t * (-0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))));
    return select(r - 1.0, 1.0 - r, x >= 0.0);
}

// Giles 2010, single precision.
fn erfinv_approx(x: f32) -> f32 {
    var w = -log(max((1.0 - x) * (1.0 + x), 1e-30));
    var p: f32;
    if w < 5.0 {
        w = w - 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

// Slopes of visible normals of the unit-roughness distribution seen at cos `cos_i`.
fn sample_visible_11(mf: Microfacet, cos_i: f32, u_in: vec2<f32>) -> vec2<f32> {
    if mf.ggx {
        var p = square_to_disk_concentric(u_in);
        let s = 0.5 * (1.0 + cos_i);
        let h = sqrt(max(1.0 - p.x * p.x, 0.0));
        p.y = h + (p.y - h) * s;
        let z = sqrt(max(1.0 - dot(p, p), 0.0));
        let sin_i = sqrt(max(1.0 - cos_i * cos_i, 0.0));
        let norm = 1.0 / (sin_i * p.y + cos_i * z);
        return vec2<f32>(cos_i * p.y - sin_i * z, p.x) * norm;
    }
    // Mitsuba's numerical inversion (continuous in u, unlike the paper's original).
    let tan_i = sqrt(max(1.0 - cos_i * cos_i, 0.0)) / cos_i;
    let cot_i = 1.0 / tan_i;
    let maxval = erf_approx(cot_i);
    let u = clamp(u_in, vec2<f32>(1e-6), vec2<f32>(1.0 - 1e-6));
    var x = maxval - (maxval + 1.0) * erf_approx(sqrt(-log(u.x)));
    let ux = u.x * (1.0 + maxval + INV_SQRT_PI * tan_i * exp(-cot_i * cot_i));
    for (var i = 0; i < 3; i++) {
        let slope = erfinv_approx(x);
        let value = 1.0 + x + INV_SQRT_PI * tan_i * exp(-slope * slope) - ux;
        let derivative = 1.0 - slope * tan_i;
        x -= value / derivative;
    }
    return vec2<f32>(erfinv_approx(x), erfinv_approx(2.0 * u.y - 1.0));
}

// A visible normal seen from `wi` (wi.z > 0).
fn microfacet_sample(mf: Microfacet, wi: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let wi_p = normalize(vec3<f32>(mf.alpha_u * wi.x, mf.alpha_v * wi.y, wi.z));
    let sin_t = sqrt(max(1.0 - wi_p.z * wi_p.z, 0.0));
    var sin_phi = 0.0;
    var cos_phi = 1.0;
    if sin_t > 0.0 {
        sin_phi = clamp(wi_p.y / sin_t, -1.0, 1.0);
        cos_phi = clamp(wi_p.x / sin_t, -1.0, 1.0);
    }
    let s = sample_visible_11(mf, wi_p.z, u);
    let slope = vec2<f32>((cos_phi * s.x - sin_phi * s.y) * mf.alpha_u, (sin_phi * s.x + cos_phi * s.y) * mf.alpha_v);
    return normalize(vec3<f32>(-slope.x, -slope.y, 1.0));
}
