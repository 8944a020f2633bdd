#define_import_path bsdfs::dielectric

// Mitsuba's smooth `dielectric`: Fresnel-weighted reflection or refraction, a delta lobe each.
// The passes sample it in world space (common::path_step), where it makes the caustic paths'
// specular vertices; the CPU reference is src/bsdfs/dielectric/mod.rs.

#import common::bsdf::reflect_about

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
