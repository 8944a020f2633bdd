#define_import_path common::bsdf

// What every BSDF's WGSL shares: the records eval and sample return, and mirroring. Local
// directions are named as in Mitsuba: `wi` towards the previous vertex (the camera for
// radiance, the light for photons), `wo` the next; z is the normal of the side the BSDF sees.
// Values are f |cos wo| (eval) or f |cos wo| / pdf (samples). Each BSDF's CPU reference is its
// unit's model (src/bsdfs/<name>/mod.rs).

struct BsdfEval {
    // f(wi, wo) |cos wo| of the non-delta lobes.
    value: vec3<f32>,
    // Density of sampling wo (solid angle), lobe choice included.
    pdf: f32,
}

struct BsdfSample {
    wo: vec3<f32>,
    weight: vec3<f32>,
    // Solid-angle density, or the choice probability of a delta lobe.
    pdf: f32,
    delta: bool,
    valid: bool,
}

fn no_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), 0.0, false, false);
}

fn mirror_local(wi: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(-wi.x, -wi.y, wi.z);
}

fn reflect_about(wo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot(wo, n) * n - wo;
}
