#define_import_path common::material

// The BSDFs other than Lambertian, mirror and smooth dielectric (which the passes handle
// inline), dispatched on the material's kind; kinds the scene lacks are compiled out.

#import common::scene::{Material, MATERIAL_CONDUCTOR, MATERIAL_ROUGH_CONDUCTOR, MATERIAL_PLASTIC, MATERIAL_ROUGH_PLASTIC, MATERIAL_ROUGH_DIELECTRIC, MATERIAL_THIN_DIELECTRIC}
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}
#ifdef DIELECTRIC
#import common::bsdf::sample_thin_dielectric
#endif
#ifdef CONDUCTOR
#import common::conductor::{conductor_sample, rough_conductor_eval, rough_conductor_sample}
#endif
#ifdef PLASTIC
#import common::plastic::{plastic_eval, plastic_sample, rough_plastic_eval, rough_plastic_sample}
#endif
#ifdef ROUGH_DIELECTRIC
#import common::rough_dielectric::{rough_dielectric_eval, rough_dielectric_sample}
#endif

// f |cos wo| and pdf of the non-delta lobes (zero for delta-only kinds).
fn material_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
#ifdef CONDUCTOR
    if m.kind == MATERIAL_ROUGH_CONDUCTOR {
        return rough_conductor_eval(m, wi, wo);
    }
#endif
#ifdef PLASTIC
    if m.kind == MATERIAL_PLASTIC {
        return plastic_eval(m, wi, wo);
    }
    if m.kind == MATERIAL_ROUGH_PLASTIC {
        return rough_plastic_eval(m, wi, wo);
    }
#endif
#ifdef ROUGH_DIELECTRIC
    if m.kind == MATERIAL_ROUGH_DIELECTRIC {
        return rough_dielectric_eval(m, wi, wo, radiance);
    }
#endif
    return BsdfEval(vec3<f32>(0.0), 0.0);
}

// Whether the kind has a non-delta lobe, which next-event estimation can reach.
fn material_has_continuous_lobe(kind: u32) -> bool {
    return kind == MATERIAL_ROUGH_CONDUCTOR || kind == MATERIAL_PLASTIC || kind == MATERIAL_ROUGH_PLASTIC || kind == MATERIAL_ROUGH_DIELECTRIC;
}

fn material_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
#ifdef DIELECTRIC
    if m.kind == MATERIAL_THIN_DIELECTRIC {
        return sample_thin_dielectric(wi, m.int_ior, m.ext_ior, u1);
    }
#endif
#ifdef CONDUCTOR
    if m.kind == MATERIAL_CONDUCTOR {
        return conductor_sample(m, wi);
    }
    if m.kind == MATERIAL_ROUGH_CONDUCTOR {
        return rough_conductor_sample(m, wi, u2);
    }
#endif
#ifdef PLASTIC
    if m.kind == MATERIAL_PLASTIC {
        return plastic_sample(m, wi, u1, u2);
    }
    if m.kind == MATERIAL_ROUGH_PLASTIC {
        return rough_plastic_sample(m, wi, u1, u2);
    }
#endif
#ifdef ROUGH_DIELECTRIC
    if m.kind == MATERIAL_ROUGH_DIELECTRIC {
        return rough_dielectric_sample(m, wi, u1, u2, radiance);
    }
#endif
    return no_sample();
}
