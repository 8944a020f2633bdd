#define_import_path common::fresnel

// Fresnel terms as Mitsuba 3 writes them (include/mitsuba/render/fresnel.h); the CPU reference
// is src/bsdfs/shared/fresnel.rs.

struct Fresnel {
    // Reflectance.
    f: f32,
    // Cosine of the refracted direction, signed opposite to cos_i.
    cos_t: f32,
    // Relative indices incident/transmitted and transmitted/incident.
    eta_it: f32,
    eta_ti: f32,
}

// Unpolarised dielectric reflectance for signed `cos_i` (negative from inside) and
// `eta` = n_inside / n_outside.
fn fresnel_full(cos_i: f32, eta: f32) -> Fresnel {
    let outside = cos_i >= 0.0;
    let eta_it = select(1.0 / eta, eta, outside);
    let eta_ti = select(eta, 1.0 / eta, outside);
    let cos_t_sqr = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
    let ci = abs(cos_i);
    let ct = sqrt(max(cos_t_sqr, 0.0));
    let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
    let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
    var r = 0.5 * (a_s * a_s + a_p * a_p);
    if eta == 1.0 {
        r = 0.0;
    } else if ci == 0.0 {
        r = 1.0;
    }
    return Fresnel(r, select(ct, -ct, cos_i >= 0.0), eta_it, eta_ti);
}

// Conductor reflectance for the complex index eta + i k, per channel.
fn fresnel_conductor(cos_i: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let c2 = cos_i * cos_i;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - vec3<f32>(s2);
    let a2b2 = sqrt(max(t1 * t1 + 4.0 * k * k * eta * eta, vec3<f32>(0.0)));
    let a = sqrt(max(0.5 * (a2b2 + t1), vec3<f32>(0.0)));
    let term1 = a2b2 + vec3<f32>(c2);
    let term2 = 2.0 * cos_i * a;
    let r_s = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * c2 + vec3<f32>(s4);
    let term4 = term2 * s2;
    let r_p = r_s * (term3 - term4) / (term3 + term4);
    return 0.5 * (r_s + r_p);
}
