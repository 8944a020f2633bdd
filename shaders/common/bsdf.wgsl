#define_import_path common::bsdf

// What the BSDF modules share, and the smooth dielectrics. Local directions are named as in
// Mitsuba: `wi` towards the previous vertex (the camera for radiance, the light for photons),
// `wo` the next; z is the normal of the side the BSDF sees. Values are f |cos wo| (eval) or
// f |cos wo| / pdf (samples). The CPU reference is src/scene/bsdf.rs.

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

#ifdef DIELECTRIC
// Unpolarised Fresnel reflectance of a smooth dielectric interface. `cos_i` >= 0 is measured on
// the incident side and `eta` = n_incident / n_transmitted. Returns 1 under total internal
// reflection.
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_s * r_s + r_p * r_p);
}

struct SpecularSample {
    dir: vec3<f32>,
    // Throughput factor of this choice, already divided by its probability (without the
    // material's tint: see `reflected`).
    weight: f32,
    // Reflected (the tint's specular_reflectance applies) or refracted (its transmittance).
    reflected: bool,
}

// Samples reflection or refraction in proportion to Fresnel. `wo` points away from the surface
// (towards where the path came from); `normal` is the front (outside) normal. With `radiance`
// true the refracted weight includes (n_i/n_t)^2, the change of radiance across the interface;
// photons (importance) carry none.
fn sample_dielectric(wo: vec3<f32>, normal: vec3<f32>, int_ior: f32, ext_ior: f32, u: f32, radiance: bool) -> SpecularSample {
    let cos_o = dot(wo, normal);
    let entering = cos_o > 0.0;
    let n = select(-normal, normal, entering);
    let eta_i = select(int_ior, ext_ior, entering);
    let eta_t = select(ext_ior, int_ior, entering);
    let eta = eta_i / eta_t;
    let cos_i = abs(cos_o);
    let reflectance = fresnel_dielectric(cos_i, eta);
    if u < reflectance {
        return SpecularSample(reflect_about(wo, n), 1.0, true);
    }
    let sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    let cos_t = sqrt(max(0.0, 1.0 - sin2_t));
    let dir = normalize(-eta * wo + (eta * cos_i - cos_t) * n);
    let weight = select(1.0, eta * eta, radiance);
    return SpecularSample(dir, weight, false);
}

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
#endif
