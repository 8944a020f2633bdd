#define_import_path bsdfs::thindielectric

// Mitsuba's `thindielectric`; the CPU reference is src/bsdfs/thindielectric/mod.rs.

#import common::scene::Material
#import common::bsdf::{BsdfSample, mirror_local}
#import bsdfs::dielectric::fresnel_dielectric

// Mitsuba's thindielectric: a slab whose internal reflections are summed, r' = 2r / (1 + r);
// what is not reflected passes straight through, unbent.
fn sample_thin_dielectric(wi: vec3<f32>, int_ior: f32, ext_ior: f32, u: f32) -> BsdfSample {
    var r = fresnel_dielectric(abs(wi.z), ext_ior / int_ior);
    r *= 2.0 / (1.0 + r);
    if u <= r {
        return BsdfSample(mirror_local(wi), vec3<f32>(1.0), r, true, true);
    }
    return BsdfSample(-wi, vec3<f32>(1.0), 1.0 - r, true, true);
}

// Tinted by specular_reflectance (`specular`) or specular_transmittance (`albedo`).
fn thindielectric_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    var s = sample_thin_dielectric(wi, m.int_ior, m.ext_ior, u1);
    s.weight *= select(m.albedo, m.specular, s.wo.z * wi.z > 0.0);
    return s;
}
