#define_import_path custom_bsdf::minnaert

// Minnaert's darkening law as a BSDF, f = reflectance (k + 1) / (2 pi) (cos_i cos_o)^(k - 1)
// for k >= 1 (k = 1 is Lambertian). The reflectance is the record's `albedo` (a texture may
// replace it), k its `alpha_u`. Directions are sampled from cos^k about the normal. The CPU
// reference is src/lib.rs, which tests/minnaert.rs holds this to.

#import common::scene::Material
#import common::sampling::PI
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}

// The density of a direction with cosine `cos_o` drawn from cos^k.
fn minnaert_pdf(k: f32, cos_o: f32) -> f32 {
    return (k + 1.0) / (2.0 * PI) * pow(cos_o, k);
}

fn minnaert_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let k = m.alpha_u;
    let value = m.albedo * ((k + 1.0) / (2.0 * PI) * pow(wi.z * wo.z, k - 1.0) * wo.z);
    return BsdfEval(value, minnaert_pdf(k, wo.z));
}

fn minnaert_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    let k = m.alpha_u;
    let cos_o = pow(u2.x, 1.0 / (k + 1.0));
    let sin_o = sqrt(max(0.0, 1.0 - cos_o * cos_o));
    let phi = 2.0 * PI * u2.y;
    let wo = vec3<f32>(sin_o * cos(phi), sin_o * sin(phi), cos_o);
    let pdf = minnaert_pdf(k, cos_o);
    if !(pdf > 0.0) {
        return no_sample();
    }
    // f cos_o / pdf: the (k + 1) / (2 pi) and cos_o^k cancel.
    return BsdfSample(wo, m.albedo * pow(wi.z, k - 1.0), pdf, false, true);
}
