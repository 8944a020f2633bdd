#define_import_path common::material

// The BSDFs other than Lambertian, mirror and smooth dielectric (which the passes handle
// inline), dispatched on the material's kind; kinds the scene lacks are compiled out.

#import common::scene::{Material, MATERIAL_CONDUCTOR, MATERIAL_ROUGH_CONDUCTOR, MATERIAL_PLASTIC, MATERIAL_ROUGH_PLASTIC, MATERIAL_POLARIZED_PLASTIC, MATERIAL_ROUGH_DIELECTRIC, MATERIAL_THIN_DIELECTRIC, MATERIAL_PRINCIPLED, MATERIAL_PRINCIPLED_THIN}
#import common::bsdf::{BsdfEval, BsdfSample, no_sample}
#ifdef DIELECTRIC
#import common::bsdf::sample_thin_dielectric
#endif
#ifdef CONDUCTOR
#import common::conductor::{conductor_sample, rough_conductor_eval, rough_conductor_sample}
#endif
#ifdef PLASTIC
#import common::plastic::{plastic_eval, plastic_sample, rough_plastic_eval, rough_plastic_eval_parts, rough_plastic_sample}
#endif
#ifdef ROUGH_DIELECTRIC
#import common::rough_dielectric::{rough_dielectric_eval, rough_dielectric_sample}
#endif
#ifdef PRINCIPLED
#import common::principled::{principled_eval, principled_sample}
#import common::principled_thin::{principled_thin_eval, principled_thin_sample}
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
    if rough_plastic_kind(m.kind) {
        return rough_plastic_eval(m, wi, wo);
    }
#endif
#ifdef ROUGH_DIELECTRIC
    if m.kind == MATERIAL_ROUGH_DIELECTRIC {
        return rough_dielectric_eval(m, wi, wo, radiance);
    }
#endif
#ifdef PRINCIPLED
    if m.kind == MATERIAL_PRINCIPLED {
        return principled_eval(m, wi, wo, radiance);
    }
    if m.kind == MATERIAL_PRINCIPLED_THIN {
        return principled_thin_eval(m, wi, wo);
    }
#endif
    return BsdfEval(vec3<f32>(0.0), 0.0);
}

// Rough plastic and pplastic: a rough reflection over a diffuse base (common::plastic).
fn rough_plastic_kind(kind: u32) -> bool {
    return kind == MATERIAL_ROUGH_PLASTIC || kind == MATERIAL_POLARIZED_PLASTIC;
}

// Whether the kind has a non-delta lobe, which next-event estimation can reach.
fn material_has_continuous_lobe(kind: u32) -> bool {
    return kind == MATERIAL_ROUGH_CONDUCTOR || kind == MATERIAL_PLASTIC || rough_plastic_kind(kind) || kind == MATERIAL_ROUGH_DIELECTRIC || kind == MATERIAL_PRINCIPLED || kind == MATERIAL_PRINCIPLED_THIN;
}

fn material_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
#ifdef DIELECTRIC
    if m.kind == MATERIAL_THIN_DIELECTRIC {
        // Tinted by specular_reflectance (`specular`) or specular_transmittance (`albedo`).
        var s = sample_thin_dielectric(wi, m.int_ior, m.ext_ior, u1);
        s.weight *= select(m.albedo, m.specular, s.wo.z * wi.z > 0.0);
        return s;
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
    if rough_plastic_kind(m.kind) {
        return rough_plastic_sample(m, wi, u1, u2);
    }
#endif
#ifdef ROUGH_DIELECTRIC
    if m.kind == MATERIAL_ROUGH_DIELECTRIC {
        return rough_dielectric_sample(m, wi, u1, u2, radiance);
    }
#endif
#ifdef PRINCIPLED
    if m.kind == MATERIAL_PRINCIPLED {
        return principled_sample(m, wi, u1, u2, radiance);
    }
    if m.kind == MATERIAL_PRINCIPLED_THIN {
        return principled_thin_sample(m, wi, u1, u2);
    }
#endif
    return no_sample();
}

#ifdef GLOSSY
// The light-transport partition's specular lobes (docs/design.md section 1): every delta lobe, and a
// microfacet lobe whose roughness at the surface point (the larger of alpha_u and alpha_v,
// after textures) is below the graph's `glossy_threshold`. Rough plastic's base never is.
fn microfacet_is_specular(m: Material, threshold: f32) -> bool {
    return max(m.alpha_u, m.alpha_v) < threshold;
}

// Of `full` (material_eval towards wo), the f |cos wo| of the specular lobes.
fn material_specular_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, full: BsdfEval, threshold: f32) -> vec3<f32> {
    if (m.kind == MATERIAL_ROUGH_CONDUCTOR || m.kind == MATERIAL_ROUGH_DIELECTRIC) && microfacet_is_specular(m, threshold) {
        return full.value;
    }
#ifdef PLASTIC
    if rough_plastic_kind(m.kind) && microfacet_is_specular(m, threshold) {
        return rough_plastic_eval_parts(m, wi, wo).coating;
    }
#endif
    return vec3<f32>(0.0);
}

// Per channel, the share of a sample's weight that went through specular lobes: 1 for a delta
// lobe or a specular microfacet kind, the coating's share of f for rough plastic (its weight is
// f / pdf with both lobes in f and pdf, so weight x share is the coating's f over the same pdf),
// 0 otherwise.
fn material_specular_share(m: Material, wi: vec3<f32>, s: BsdfSample, threshold: f32) -> vec3<f32> {
    if s.delta {
        return vec3<f32>(1.0);
    }
    if (m.kind == MATERIAL_ROUGH_CONDUCTOR || m.kind == MATERIAL_ROUGH_DIELECTRIC) && microfacet_is_specular(m, threshold) {
        return vec3<f32>(1.0);
    }
#ifdef PLASTIC
    if rough_plastic_kind(m.kind) && microfacet_is_specular(m, threshold) {
        let parts = rough_plastic_eval_parts(m, wi, s.wo);
        let total = parts.coating + parts.base;
        return select(vec3<f32>(0.0), parts.coating / total, total > vec3<f32>(0.0));
    }
#endif
    return vec3<f32>(0.0);
}
#endif
