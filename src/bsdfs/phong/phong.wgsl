#define_import_path bsdfs::phong

// Mitsuba 0.6's phong (src/bsdfs/phong.cpp of mitsuba-renderer/mitsuba): the modified Phong
// model, f = kd / pi + ks (n + 2) / (2 pi) cos^n(alpha) about wi's mirror direction, its lobe
// sampled as cos^n about that direction in 0.6's frame (`coordinateSystem`), the diffuse lobe
// cosine-weighted, picked by the specular sampling weight. The record holds kd in `albedo`, ks
// in `specular` (textures may replace either), 0.6's energy-conservation scale in `int_ior`,
// the weight in `specular_weight`, n in `eta.x` (a field texture may replace it) and the
// Beckmann-equivalent roughness sqrt(2 / (n + 2)) in `alpha_u`/`alpha_v` for the glossy
// partition. The CPU reference is src/bsdfs/phong/mod.rs.

#import common::sampling::{PI, INV_PI, square_to_cosine_hemisphere}
#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample, mirror_local}

// f |cos wo| of the Phong lobe, both directions above the surface.
fn phong_lobe(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let cos_alpha = dot(wo, mirror_local(wi));
    if cos_alpha <= 0.0 {
        return vec3<f32>(0.0);
    }
    let n = m.eta.x;
    return m.specular * (m.int_ior * (n + 2.0) * (0.5 * INV_PI) * pow(cos_alpha, n) * wo.z);
}

fn phong_pdf(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let cos_alpha = dot(wo, mirror_local(wi));
    let n = m.eta.x;
    var specular = 0.0;
    if cos_alpha > 0.0 {
        specular = pow(cos_alpha, n) * (n + 1.0) * (0.5 * INV_PI);
    }
    let w = m.specular_weight;
    return w * specular + (1.0 - w) * wo.z * INV_PI;
}

fn phong_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let value = phong_lobe(m, wi, wo) + m.albedo * (m.int_ior * INV_PI * wo.z);
    return BsdfEval(value, phong_pdf(m, wi, wo));
}

fn phong_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    if wi.z <= 0.0 {
        return no_sample();
    }
    var wo: vec3<f32>;
    if u1 < m.specular_weight {
        let n = m.eta.x;
        let cos_alpha = pow(u2.y, 1.0 / (n + 1.0));
        let sin_alpha = sqrt(max(1.0 - pow(u2.y, 2.0 / (n + 1.0)), 0.0));
        let phi = 2.0 * PI * u2.x;
        let r = mirror_local(wi);
        // 0.6's coordinateSystem(r): t first, then s = t x r.
        var t: vec3<f32>;
        if abs(r.x) > abs(r.y) {
            t = vec3<f32>(r.z, 0.0, -r.x) * (1.0 / sqrt(r.x * r.x + r.z * r.z));
        } else {
            t = vec3<f32>(0.0, r.z, -r.y) * (1.0 / sqrt(r.y * r.y + r.z * r.z));
        }
        let s = cross(t, r);
        wo = s * (sin_alpha * cos(phi)) + t * (sin_alpha * sin(phi)) + r * cos_alpha;
        if wo.z <= 0.0 {
            return no_sample();
        }
    } else {
        wo = square_to_cosine_hemisphere(u2);
    }
    let e = phong_eval(m, wi, wo, radiance);
    if !(e.pdf > 0.0) {
        return no_sample();
    }
    return BsdfSample(wo, e.value / e.pdf, e.pdf, false, true);
}

// The glossy-caustic partition's view: the Phong lobe's f |cos wo|, and its share of the whole
// per channel (0 where the BSDF is 0).
fn phong_specular(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return vec3<f32>(0.0);
    }
    return phong_lobe(m, wi, wo);
}

fn phong_specular_share(m: Material, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let total = phong_eval(m, wi, wo, true).value;
    return select(vec3<f32>(0.0), phong_specular(m, wi, wo) / total, total > vec3<f32>(0.0));
}
