#define_import_path bsdfs::conductor

// Mitsuba 3's smooth conductor (src/bsdfs/conductor.cpp): Fresnel of the complex index eta + i k
// times specular_reflectance, a delta lobe; one-sided. The CPU reference is
// src/bsdfs/conductor/mod.rs. A perfect mirror (material "none") is the passes' own.

#import common::scene::Material
#import common::bsdf::{BsdfSample, no_sample, mirror_local}
#import common::fresnel::fresnel_conductor

fn conductor_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    return BsdfSample(mirror_local(wi), m.specular * fresnel_conductor(wi.z, m.eta, m.k), 1.0, true, true);
}
