#define_import_path bsdfs::difftrans

// Mitsuba 0.6's difftrans (src/bsdfs/difftrans.cpp of mitsuba-renderer/mitsuba): T / pi |cos wo|
// towards the other side of the surface only, from either side, sampled cosine-weighted there.
// The record holds the transmittance in `albedo` (a texture may replace it) and 0.6's
// energy-conservation scale in `int_ior`. The CPU reference is src/bsdfs/difftrans/mod.rs.

#import common::sampling::{INV_PI, square_to_cosine_hemisphere}
#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}

fn difftrans_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z * wo.z >= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let pdf = abs(wo.z) * INV_PI;
    return BsdfEval(m.albedo * (m.int_ior * pdf), pdf);
}

fn difftrans_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z == 0.0 {
        return no_sample();
    }
    var wo = square_to_cosine_hemisphere(u2);
    if wi.z > 0.0 {
        wo.z = -wo.z;
    }
    let pdf = abs(wo.z) * INV_PI;
    if !(pdf > 0.0) {
        return no_sample();
    }
    // f |cos wo| / pdf: the transmittance, as 0.6's sample returns it.
    return BsdfSample(wo, m.albedo * m.int_ior, pdf, false, true);
}
