//! Fresnel terms as Mitsuba 3 writes them (include/mitsuba/render/fresnel.h), shared by the
//! dielectrics, conductors and plastics; `fresnel.wgsl` beside this is their GPU twin.

use glam::Vec3;

/// Unpolarised dielectric Fresnel reflectance for `cos_i` (signed: negative from inside) and
/// `eta` = n_inside / n_outside. Returns (F, cos_t signed opposite to cos_i, eta_it, eta_ti).
pub fn fresnel(cos_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let outside = cos_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_t_sqr = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
    let ci = cos_i.abs();
    let ct = cos_t_sqr.max(0.0).sqrt();
    let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
    let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
    let mut r = 0.5 * (a_s * a_s + a_p * a_p);
    if eta == 1.0 {
        r = 0.0;
    } else if ci == 0.0 {
        r = 1.0;
    }
    let cos_t = if cos_i >= 0.0 { -ct } else { ct };
    (r, cos_t, eta_it, eta_ti)
}

/// Conductor Fresnel reflectance for complex index eta + i k, per channel.
pub fn fresnel_conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let c2 = cos_i * cos_i;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let one = |eta: f32, k: f32| {
        let t1 = eta * eta - k * k - s2;
        let a2b2 = (t1 * t1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
        let a = (0.5 * (a2b2 + t1)).max(0.0).sqrt();
        let term1 = a2b2 + c2;
        let term2 = 2.0 * cos_i * a;
        let r_s = (term1 - term2) / (term1 + term2);
        let term3 = a2b2 * c2 + s4;
        let term4 = term2 * s2;
        let r_p = r_s * (term3 - term4) / (term3 + term4);
        0.5 * (r_s + r_p)
    };
    Vec3::new(one(eta.x, k.x), one(eta.y, k.y), one(eta.z, k.z))
}

/// Mitsuba's fit of the hemispherical average of Fresnel reflectance (Egan and Hilgeman 1973
/// below eta 1, d'Eon and Irving 2011 above).
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        0.0636 / eta + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let x = 1.0 / eta;
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0f32, |acc, &ci| acc * x + ci)
    }
}

pub fn reflect(wi: Vec3, m: Vec3) -> Vec3 {
    2.0 * wi.dot(m) * m - wi
}

pub fn refract(wi: Vec3, m: Vec3, cos_t: f32, eta_ti: f32) -> Vec3 {
    m * (wi.dot(m) * eta_ti + cos_t) - wi * eta_ti
}
