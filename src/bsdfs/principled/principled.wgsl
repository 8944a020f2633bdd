#define_import_path bsdfs::principled

// Mitsuba 3's principled BSDF, lobe for lobe as src/bsdfs/principled/mod.rs (the CPU reference,
// which says where each formula comes from). The parameters live in the fields of the other
// kinds (src/gpu_scene/layout.rs): base colour in albedo, roughness and metallic in alpha_u
// and alpha_v (textures replace those three), (anisotropic, spec_trans, spec_tint) in
// specular, (sheen, sheen_tint, flatness) in eta, (clearcoat, clearcoat_gloss, eta) in k, the
// sampling rates in int_ior, ext_ior and specular_weight, Mitsuba's m_has_* bits in nonlinear.

#import common::scene::Material
#import common::bsdf::{BsdfEval, BsdfSample, no_sample, reflect_about}
#import common::fresnel::fresnel_full
#import common::microfacet::{Microfacet, microfacet_d, microfacet_g1, microfacet_pdf, microfacet_sample}
#import common::sampling::{PI, INV_PI, square_to_cosine_hemisphere, luminance}

const HAS_ANISOTROPIC: u32 = 1u;
const HAS_SPEC_TRANS: u32 = 2u;
const HAS_SHEEN: u32 = 4u;
const HAS_SHEEN_TINT: u32 = 8u;
const HAS_FLATNESS: u32 = 16u;
const HAS_SPEC_TINT: u32 = 32u;
const HAS_METALLIC: u32 = 64u;
const HAS_CLEARCOAT: u32 = 128u;

struct Principled {
    base_color: vec3<f32>,
    roughness: f32,
    anisotropic: f32,
    metallic: f32,
    spec_trans: f32,
    spec_tint: f32,
    sheen: f32,
    sheen_tint: f32,
    flatness: f32,
    clearcoat: f32,
    clearcoat_gloss: f32,
    eta: f32,
    spec_srate: f32,
    clearcoat_srate: f32,
    diffuse_srate: f32,
    has: u32,
}

fn unpack(m: Material) -> Principled {
    return Principled(m.albedo, m.alpha_u, m.specular.x, m.alpha_v, m.specular.y, m.specular.z, m.eta.x, m.eta.y, m.eta.z, m.k.x, m.k.y, m.k.z, m.int_ior, m.ext_ior, m.specular_weight, m.nonlinear);
}

fn has(p: Principled, bit: u32) -> bool {
    return (p.has & bit) != 0u;
}

// The GGX distribution of a roughness and anisotropy (0: isotropic).
fn ggx(anisotropic: f32, roughness: f32) -> Microfacet {
    let r2 = roughness * roughness;
    let aspect = sqrt(1.0 - 0.9 * anisotropic);
    return Microfacet(max(0.001, r2 / aspect), max(0.001, r2 * aspect), true);
}

fn specular_distribution(p: Principled) -> Microfacet {
    return ggx(select(0.0, p.anisotropic, has(p, HAS_ANISOTROPIC)), p.roughness);
}

fn clearcoat_alpha(p: Principled) -> f32 {
    return mix(0.1, 0.001, p.clearcoat_gloss);
}

// (brdf, bsdf): the diffuse and transmissive major lobes' weights.
fn major_weights(p: Principled) -> vec2<f32> {
    return vec2<f32>((1.0 - p.metallic) * (1.0 - p.spec_trans), (1.0 - p.metallic) * p.spec_trans);
}

// (diffuse, clearcoat, transmission, reflection) probabilities for dielectric Fresnel `f`.
fn lobe_probabilities(p: Principled, front: bool, f: f32) -> vec4<f32> {
    let w = major_weights(p);
    let reflect = select(f, p.spec_srate * (1.0 - w.y * (1.0 - f)), front);
    var trans = 0.0;
    if has(p, HAS_SPEC_TRANS) {
        trans = select(1.0 - f, p.spec_srate * w.y * (1.0 - f), front);
    }
    var clearcoat = 0.0;
    if has(p, HAS_CLEARCOAT) && front {
        clearcoat = 0.25 * p.clearcoat * p.clearcoat_srate;
    }
    let diffuse = select(0.0, w.x * p.diffuse_srate, front);
    return vec4<f32>(diffuse, clearcoat, trans, reflect) / (reflect + trans + clearcoat + diffuse);
}

fn mulsign(a: vec3<f32>, b: f32) -> vec3<f32> {
    return select(a, -a, b < 0.0);
}

fn tint_of(c: vec3<f32>) -> vec3<f32> {
    let lum = luminance(c);
    return select(vec3<f32>(1.0), c / lum, lum > 0.0);
}

fn schlick_weight(cos: f32) -> f32 {
    let m = clamp(1.0 - cos, 0.0, 1.0);
    return m * m * m * m * m;
}

fn calc_schlick(r0: vec3<f32>, cos_i: f32, eta: f32) -> vec3<f32> {
    let outside = cos_i >= 0.0;
    let eta_it = select(1.0 / eta, eta, outside);
    let eta_ti = select(eta, 1.0 / eta, outside);
    let cos_t = sqrt(max(1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti, 0.0));
    let w = select(schlick_weight(cos_t), schlick_weight(abs(cos_i)), eta_it > 1.0);
    return vec3<f32>(w) * (vec3<f32>(1.0) - r0) + r0;
}

// Schlick's reflectance at normal incidence for the relative index `eta`.
fn schlick_r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    return r * r;
}

fn compatible(m: vec3<f32>, wi: vec3<f32>, wo: vec3<f32>, cos_i: f32, reflection: bool) -> bool {
    let m_i = mulsign(m, cos_i);
    let m_o = select(-m_i, m_i, reflection);
    return dot(wi, m_i) > 0.0 && dot(wo, m_o) > 0.0;
}

fn principled_fresnel(p: Principled, f_dielectric: f32, cos_i: f32, front: bool) -> vec3<f32> {
    if !front {
        return vec3<f32>(major_weights(p).y * f_dielectric);
    }
    let eta_it = select(1.0 / p.eta, p.eta, cos_i >= 0.0);
    var schlick = vec3<f32>(0.0);
    if has(p, HAS_METALLIC) {
        schlick += p.metallic * calc_schlick(p.base_color, cos_i, p.eta);
    }
    if has(p, HAS_SPEC_TINT) {
        schlick += (1.0 - p.metallic) * p.spec_tint * calc_schlick(tint_of(p.base_color) * schlick_r0(eta_it), cos_i, p.eta);
    }
    return vec3<f32>((1.0 - p.metallic) * (1.0 - p.spec_tint) * f_dielectric) + schlick;
}

fn gtr1_d(alpha: f32, m: vec3<f32>) -> f32 {
    let a2 = alpha * alpha;
    let r = (a2 - 1.0) / (PI * log(a2) * (1.0 + (a2 - 1.0) * m.z * m.z));
    return select(0.0, r, r * m.z > 1e-20);
}

fn gtr1_pdf(alpha: f32, m: vec3<f32>) -> f32 {
    return select(m.z * gtr1_d(alpha, m), 0.0, m.z < 0.0);
}

fn gtr1_sample(alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let phi = 2.0 * PI * u.x;
    let a2 = alpha * alpha;
    let cos2 = (1.0 - pow(a2, 1.0 - u.y)) / (1.0 - a2);
    let s = sqrt(max(1.0 - cos2, 0.0));
    return vec3<f32>(cos(phi) * s, sin(phi) * s, sqrt(max(cos2, 0.0)));
}

fn smith_ggx1(v: vec3<f32>, m: vec3<f32>, alpha: f32) -> f32 {
    if dot(v, m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    return 2.0 / (1.0 + sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2));
}

// Burley's diffuse with retro-reflection, towards the fake subsurface term by `flatness`.
fn diffuse_lobe(roughness: f32, flatness: f32, cos_i: f32, cos_o: f32, cos_d: f32) -> f32 {
    let fo = schlick_weight(cos_o);
    let fi = schlick_weight(cos_i);
    let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * roughness * cos_d * cos_d;
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    if flatness == 0.0 {
        return f_diff + f_retro;
    }
    let fss90 = rr / 2.0;
    let fss = mix(1.0, fss90, fo) * mix(1.0, fss90, fi);
    let f_ss = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
    return mix(f_diff + f_retro, f_ss, flatness);
}

// The sheen lobe's f, white tinted towards the base colour's hue by `sheen_tint`.
fn sheen_lobe(sheen: f32, sheen_tint: f32, base_color: vec3<f32>, cos_d: f32) -> vec3<f32> {
    var tint = vec3<f32>(1.0);
    if sheen_tint != 0.0 {
        tint = mix(vec3<f32>(1.0), tint_of(base_color), sheen_tint);
    }
    return sheen * schlick_weight(abs(cos_d)) * tint;
}

// The half vector of (wi, wo), facing +z.
fn half_vector(p: Principled, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let eta_path = select(1.0 / p.eta, p.eta, wi.z > 0.0);
    let h = normalize(wi + wo * select(eta_path, 1.0, wi.z * wo.z > 0.0));
    return mulsign(h, h.z);
}

fn principled_value(p: Principled, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> vec3<f32> {
    let ci = wi.z;
    let co = wo.z;
    let w = major_weights(p);
    let front = ci > 0.0;
    let reflect_pair = ci * co > 0.0;
    let refract_pair = ci * co < 0.0;
    let eta_path = select(1.0 / p.eta, p.eta, front);
    let h = half_vector(p, wi, wo);
    let mf = specular_distribution(p);
    let f = fresnel_full(dot(wi, h), p.eta).f;
    let reflection_ok = compatible(h, wi, wo, ci, true);
    let d = microfacet_d(mf, h);
    let g = microfacet_g1(mf, wi, h) * microfacet_g1(mf, wo, h);
    var value = vec3<f32>(0.0);
    if reflect_pair && reflection_ok && f > 0.0 {
        value += principled_fresnel(p, f, dot(wi, h), front) * d * g / (4.0 * abs(ci));
    }
    if has(p, HAS_SPEC_TRANS) && w.y > 0.0 && refract_pair && compatible(h, wi, wo, ci, false) && f < 1.0 {
        let scale = select(1.0, 1.0 / (eta_path * eta_path), radiance);
        let denom = dot(wi, h) + eta_path * dot(wo, h);
        let t = abs(scale * (1.0 - f) * d * g * eta_path * eta_path * dot(wi, h) * dot(wo, h) / (ci * denom * denom));
        value += sqrt(max(p.base_color, vec3<f32>(0.0))) * w.y * t;
    }
    if has(p, HAS_CLEARCOAT) && p.clearcoat > 0.0 && reflect_pair && reflection_ok && front {
        let fcc = calc_schlick(vec3<f32>(0.04), dot(wi, h), p.eta).x;
        let gcc = smith_ggx1(wi, h, 0.25) * smith_ggx1(wo, h, 0.25);
        value += vec3<f32>(p.clearcoat * 0.25 * fcc * gtr1_d(clearcoat_alpha(p), h) * gcc * abs(co));
    }
    if w.x > 0.0 && reflect_pair && front {
        let flatness = select(0.0, p.flatness, has(p, HAS_FLATNESS));
        let lobe = diffuse_lobe(p.roughness, flatness, abs(ci), abs(co), dot(h, wo));
        value += w.x * abs(co) * p.base_color * INV_PI * lobe;
    }
    if has(p, HAS_SHEEN) && p.sheen > 0.0 && reflect_pair && 1.0 - p.metallic > 0.0 && front {
        let sheen_tint = select(0.0, p.sheen_tint, has(p, HAS_SHEEN_TINT));
        value += (1.0 - p.metallic) * sheen_lobe(p.sheen, sheen_tint, p.base_color, dot(h, wo)) * abs(co);
    }
    return value;
}

fn principled_pdf(p: Principled, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let ci = wi.z;
    let front = ci > 0.0;
    let reflect_pair = ci * wo.z > 0.0;
    let refract_pair = ci * wo.z < 0.0;
    let eta_path = select(1.0 / p.eta, p.eta, front);
    let h = half_vector(p, wi, wo);
    let mf = specular_distribution(p);
    let f = fresnel_full(dot(wi, h), p.eta).f;
    let probs = lobe_probabilities(p, front, f);
    let dot_i = dot(wi, h);
    let dot_o = dot(wo, h);
    var dwh_dwo = 1.0 / (4.0 * dot_o);
    if has(p, HAS_SPEC_TRANS) && !reflect_pair {
        let denom = dot_i + eta_path * dot_o;
        dwh_dwo = eta_path * eta_path * dot_o / (denom * denom);
    }
    dwh_dwo = abs(dwh_dwo);
    let visible = microfacet_pdf(mf, mulsign(wi, ci), h);
    let reflection_ok = compatible(h, wi, wo, ci, true) && reflect_pair;
    var pdf = 0.0;
    if reflection_ok {
        pdf += probs.w * visible * dwh_dwo;
    }
    if reflect_pair {
        pdf += probs.x * wo.z * INV_PI;
    }
    if has(p, HAS_SPEC_TRANS) && compatible(h, wi, wo, ci, false) && refract_pair {
        pdf += probs.z * visible * dwh_dwo;
    }
    if has(p, HAS_CLEARCOAT) && reflection_ok {
        pdf += probs.y * gtr1_pdf(clearcoat_alpha(p), h) * dwh_dwo;
    }
    return pdf;
}

fn principled_eval(m: Material, wi: vec3<f32>, wo: vec3<f32>, radiance: bool) -> BsdfEval {
    if wi.z == 0.0 {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    let p = unpack(m);
    let value = principled_value(p, wi, wo, radiance);
    let pdf = principled_pdf(p, wi, wo);
    if !all(value < vec3<f32>(3.0e38)) || !(pdf < 3.0e38) {
        return BsdfEval(vec3<f32>(0.0), 0.0);
    }
    return BsdfEval(value, select(0.0, pdf, pdf >= 0.0));
}

// As Mitsuba: the specular normal first, the lobe by `u1` with probabilities that use its
// Fresnel, then the lobe's direction from `u2` again.
fn principled_sample(m: Material, wi: vec3<f32>, u1: f32, u2: vec2<f32>, radiance: bool) -> BsdfSample {
    let ci = wi.z;
    if ci == 0.0 {
        return no_sample();
    }
    let p = unpack(m);
    let front = ci > 0.0;
    var bsdf = 0.0;
    if has(p, HAS_SPEC_TRANS) {
        bsdf = major_weights(p).y;
    }
    if !front && !(bsdf > 0.0) {
        return no_sample();
    }
    let mf = specular_distribution(p);
    let h = microfacet_sample(mf, mulsign(wi, ci), u2);
    let fr = fresnel_full(dot(wi, h), p.eta);
    let probs = lobe_probabilities(p, front, fr.f);
    var wo: vec3<f32>;
    var ok: bool;
    if u1 < probs.x {
        wo = square_to_cosine_hemisphere(u2);
        ok = ci * wo.z > 0.0;
    } else if has(p, HAS_CLEARCOAT) && u1 < probs.x + probs.y {
        let mc = gtr1_sample(clearcoat_alpha(p), u2);
        wo = reflect_about(wi, mc);
        ok = compatible(mc, wi, wo, ci, true) && ci * wo.z > 0.0;
    } else if has(p, HAS_SPEC_TRANS) && u1 < probs.x + probs.y + probs.z {
        wo = h * (dot(wi, h) * fr.eta_ti + fr.cos_t) - wi * fr.eta_ti;
        ok = compatible(h, wi, wo, ci, false) && ci * wo.z < 0.0;
    } else {
        wo = reflect_about(wi, h);
        ok = compatible(h, wi, wo, ci, true) && ci * wo.z > 0.0;
    }
    if !ok {
        return no_sample();
    }
    let pdf = principled_pdf(p, wi, wo);
    if !(pdf > 0.0) || !(pdf < 3.0e38) {
        return no_sample();
    }
    let weight = principled_value(p, wi, wo, radiance) / pdf;
    if !all(weight < vec3<f32>(3.0e38)) {
        return no_sample();
    }
    return BsdfSample(wo, weight, pdf, false, true);
}
