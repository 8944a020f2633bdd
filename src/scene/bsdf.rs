//! CPU reference of every BSDF the renderer has, written from Mitsuba 3's plugins
//! (`src/bsdfs/*.cpp`, `include/mitsuba/render/microfacet.h` and `fresnel.h`, which are the
//! specification): the GPU modules in `shaders/common/` follow the same formulas, and the tests
//! check them against this code and this code against energy, reciprocity and its own sampler.
//!
//! Directions are local (z along the normal of the side the BSDF sees) and named as in
//! Mitsuba: `wi` points towards the previous vertex (the camera when tracing radiance, the light
//! when tracing photons), `wo` towards the next. [`eval`] returns f(wi, wo) |cos wo| of the
//! non-delta lobes; [`sample`] returns the weight f |cos wo| / pdf of its choice (delta lobes
//! included).

use glam::{Vec2, Vec3};

use super::{Bsdf, Distribution, Microfacet};

/// Entries of the rough plastic's external transmittance table (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`), over cos(theta) from 0 to 1.
pub const TRANSMITTANCE_RES: usize = 64;

/// What the path is carrying, which only refraction's solid-angle compression depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Camera paths: radiance is scaled by (eta_t / eta_i)^2 crossing an interface.
    Radiance,
    /// Photons (flux): no scaling.
    Importance,
}

/// A BSDF with what it precomputes (the rough plastic's tables), ready to evaluate.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    pub bsdf: Bsdf,
    /// Rough plastic: 1 - the coating's directional albedo from outside, per cos(theta).
    pub transmittance: Vec<f32>,
    /// Plastic: the coating's diffuse reflectance from inside (Mitsuba's `m_fdr_int`, or the
    /// rough coating's `m_internal_reflectance`).
    pub internal_reflectance: f32,
    /// Plastic: the probability weight of the specular lobe (Mitsuba's
    /// `m_specular_sampling_weight`).
    pub specular_weight: f32,
}

impl Prepared {
    pub fn new(bsdf: Bsdf) -> Self {
        let mut p = Prepared {
            bsdf,
            transmittance: Vec::new(),
            internal_reflectance: 0.0,
            specular_weight: 0.0,
        };
        match bsdf {
            Bsdf::Plastic {
                int_ior,
                ext_ior,
                diffuse,
                specular,
                ..
            } => {
                p.internal_reflectance = fresnel_diffuse_reflectance(ext_ior / int_ior);
                p.specular_weight = specular_weight(diffuse, specular);
            }
            Bsdf::RoughPlastic {
                int_ior,
                ext_ior,
                diffuse,
                specular,
                microfacet,
                ..
            } => {
                let eta = int_ior / ext_ior;
                p.transmittance = (0..TRANSMITTANCE_RES)
                    .map(|i| {
                        let mu = (i as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
                        rough_transmittance(microfacet, mu, eta)
                    })
                    .collect();
                let internal: f32 = (0..TRANSMITTANCE_RES)
                    .map(|i| {
                        let mu = (i as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
                        rough_reflectance(microfacet, mu, 1.0 / eta) * mu
                    })
                    .sum();
                p.internal_reflectance = 2.0 * internal / TRANSMITTANCE_RES as f32;
                p.specular_weight = specular_weight(diffuse, specular);
            }
            Bsdf::PolarizedPlastic {
                diffuse, specular, ..
            } => p.specular_weight = specular_weight(diffuse, specular),
            _ => {}
        }
        p
    }
}

fn mean(v: Vec3) -> f32 {
    (v.x + v.y + v.z) / 3.0
}

fn specular_weight(diffuse: Vec3, specular: Vec3) -> f32 {
    let s = mean(specular);
    s / (mean(diffuse) + s)
}

// --- Fresnel (Mitsuba's fresnel.h) ---

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

// --- Microfacet distributions (Mitsuba's microfacet.h; Walter et al. 2007, Heitz 2014) ---

impl Microfacet {
    fn alphas(&self) -> (f32, f32) {
        (self.alpha_u.max(1e-4), self.alpha_v.max(1e-4))
    }

    /// Normal distribution D(m).
    pub fn d(&self, m: Vec3) -> f32 {
        let (au, av) = self.alphas();
        let c2 = m.z * m.z;
        let r = match self.distribution {
            Distribution::Beckmann => {
                (-((m.x / au).powi(2) + (m.y / av).powi(2)) / c2).exp()
                    / (std::f32::consts::PI * au * av * c2 * c2)
            }
            Distribution::Ggx => {
                let t = (m.x / au).powi(2) + (m.y / av).powi(2) + m.z * m.z;
                1.0 / (std::f32::consts::PI * au * av * t * t)
            }
        };
        if r * m.z > 1e-20 { r } else { 0.0 }
    }

    /// Smith's masking G1(v, m), zero where v sees the back of m.
    pub fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        let (au, av) = self.alphas();
        let xy = (au * v.x).powi(2) + (av * v.y).powi(2);
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        if xy == 0.0 {
            return 1.0;
        }
        let tan2 = xy / (v.z * v.z);
        match self.distribution {
            Distribution::Beckmann => {
                let a = 1.0 / tan2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
            Distribution::Ggx => 2.0 / (1.0 + (1.0 + tan2).sqrt()),
        }
    }

    /// Density of the visible normals seen from `wi` (wi.z > 0).
    pub fn pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        self.d(m) * self.g1(wi, m) * wi.dot(m).abs() / wi.z
    }

    /// A visible normal seen from `wi` (wi.z > 0), Heitz and d'Eon 2014 as in Mitsuba.
    pub fn sample(&self, wi: Vec3, u: Vec2) -> Vec3 {
        let (au, av) = self.alphas();
        let wi_p = Vec3::new(au * wi.x, av * wi.y, wi.z).normalize();
        let sin_t = (1.0 - wi_p.z * wi_p.z).max(0.0).sqrt();
        let (sin_phi, cos_phi) = if sin_t > 0.0 {
            let inv = 1.0 / sin_t;
            (
                (wi_p.y * inv).clamp(-1.0, 1.0),
                (wi_p.x * inv).clamp(-1.0, 1.0),
            )
        } else {
            (0.0, 1.0)
        };
        let slope = self.sample_visible_11(wi_p.z, u);
        let slope = Vec2::new(
            (cos_phi * slope.x - sin_phi * slope.y) * au,
            (sin_phi * slope.x + cos_phi * slope.y) * av,
        );
        Vec3::new(-slope.x, -slope.y, 1.0).normalize()
    }

    fn sample_visible_11(&self, cos_i: f32, u: Vec2) -> Vec2 {
        match self.distribution {
            Distribution::Beckmann => {
                let tan_i = (1.0 - cos_i * cos_i).max(0.0).sqrt() / cos_i;
                let cot_i = 1.0 / tan_i;
                let maxval = erf(cot_i);
                let u = u.clamp(Vec2::splat(1e-6), Vec2::splat(1.0 - 1e-6));
                let mut x = maxval - (maxval + 1.0) * erf((-u.x.ln()).sqrt());
                let ux = u.x * (1.0 + maxval + INV_SQRT_PI * tan_i * (-cot_i * cot_i).exp());
                for _ in 0..3 {
                    let slope = erfinv(x);
                    let value = 1.0 + x + INV_SQRT_PI * tan_i * (-slope * slope).exp() - ux;
                    let derivative = 1.0 - slope * tan_i;
                    x -= value / derivative;
                }
                Vec2::new(erfinv(x), erfinv(2.0 * u.y - 1.0))
            }
            Distribution::Ggx => {
                let mut p = square_to_disk_concentric(u);
                let s = 0.5 * (1.0 + cos_i);
                let h = (1.0 - p.x * p.x).max(0.0).sqrt();
                p.y = h + (p.y - h) * s;
                let z = (1.0 - p.length_squared()).max(0.0).sqrt();
                let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
                let norm = 1.0 / (sin_i * p.y + cos_i * z);
                Vec2::new(cos_i * p.y - sin_i * z, p.x) * norm
            }
        }
    }
}

const INV_SQRT_PI: f32 = 0.564_189_6;

/// Shirley and Chiu's concentric map as Mitsuba writes it.
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let x = 2.0 * u.x - 1.0;
    let y = 2.0 * u.y - 1.0;
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, phi) = if x == 0.0 && y == 0.0 {
        (0.0, 0.0)
    } else if x * x > y * y {
        (x, quarter * (y / x))
    } else {
        (y, 2.0 * quarter - quarter * (x / y))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// erf to about 1e-7 (Abramowitz and Stegun 7.1.26 is too coarse for the Newton steps; this is
/// the series / continued-fraction split of Numerical Recipes' erfc, in f64).
pub fn erf(x: f32) -> f32 {
    let z = (x as f64).abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    let e = 1.0 - r;
    (if x >= 0.0 { e } else { -e }) as f32
}

/// Inverse error function (Giles 2010, single precision), the approximation Dr.Jit also uses.
pub fn erfinv(x: f32) -> f32 {
    let w = -((1.0 - x) * (1.0 + x)).max(1e-30).ln();
    if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_4e-8;
        p = 3.432_739_4e-7 + p * w;
        p = -3.523_387_7e-6 + p * w;
        p = -4.391_506_5e-6 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725 + p * w;
        p = -0.004_177_682 + p * w;
        p = 0.246_640_73 + p * w;
        p = 1.501_409_4 + p * w;
        p * x
    } else {
        let w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_26;
        p = 0.000_100_950_56 + p * w;
        p = 0.001_349_343_2 + p * w;
        p = -0.003_673_428_4 + p * w;
        p = 0.005_739_507_7 + p * w;
        p = -0.007_622_461 + p * w;
        p = 0.009_438_87 + p * w;
        p = 1.001_674 + p * w;
        p = 2.832_976_8 + p * w;
        p * x
    }
}

// --- The rough plastic's tables (Mitsuba's eval_transmittance / eval_reflectance) ---

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Integrates `f(visible normal)` over the visible-normal samples of the unit square.
fn integrate_visible(mf: Microfacet, wi: Vec3, eta: f32, f: impl Fn(Vec3) -> f32) -> f32 {
    let nodes = gauss_legendre(if eta > 1.0 { 32 } else { 128 });
    let mut sum = 0.0f64;
    for &(x, wx) in &nodes {
        for &(y, wy) in &nodes {
            let u = Vec2::new((0.5 * x + 0.5) as f32, (0.5 * y + 0.5) as f32);
            sum += f(mf.sample(wi, u)) as f64 * wx * wy * 0.25;
        }
    }
    sum as f32
}

/// Fraction of light from direction cos `mu` that a rough interface of relative index `eta`
/// transmits (single scattering).
pub fn rough_transmittance(mf: Microfacet, mu: f32, eta: f32) -> f32 {
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    integrate_visible(mf, wi, eta, |m| {
        let (f, cos_t, _, eta_ti) = fresnel(wi.dot(m), eta);
        let wo = refract(wi, m, cos_t, eta_ti);
        if wo.z * wi.z >= 0.0 {
            0.0
        } else {
            mf.g1(wo, m) * (1.0 - f)
        }
    })
}

/// Fraction of light from direction cos `mu` that a rough interface reflects.
pub fn rough_reflectance(mf: Microfacet, mu: f32, eta: f32) -> f32 {
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    integrate_visible(mf, wi, eta, |m| {
        let wo = reflect(wi, m);
        if wo.z <= 0.0 || wi.z <= 0.0 {
            0.0
        } else {
            mf.g1(wo, m) * fresnel(wi.dot(m), eta).0
        }
    })
}

fn lerp_table(table: &[f32], x: f32) -> f32 {
    let n = table.len();
    let x = x * (n - 1) as f32;
    let i = (x.max(0.0) as usize).min(n - 2);
    let t = x - i as f32;
    table[i] * (1.0 - t) + table[i + 1] * t
}

// --- Evaluation ---

/// f |cos wo| of a rough dielectric interface's reflection (both directions above it): the
/// coating of rough plastic and pplastic.
fn rough_reflection(microfacet: &Microfacet, eta: f32, wi: Vec3, wo: Vec3) -> f32 {
    let h = (wi + wo).normalize();
    let f = fresnel(wi.dot(h), eta).0;
    let g = microfacet.g1(wi, h) * microfacet.g1(wo, h);
    f * microfacet.d(h) * g / (4.0 * wi.z)
}

/// f(wi, wo) |cos wo| of the non-delta lobes.
pub fn eval(p: &Prepared, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
    let (ci, co) = (wi.z, wo.z);
    match p.bsdf {
        Bsdf::Diffuse { reflectance } => {
            if ci > 0.0 && co > 0.0 {
                reflectance * co * std::f32::consts::FRAC_1_PI
            } else {
                Vec3::ZERO
            }
        }
        Bsdf::Dielectric { .. } | Bsdf::Mirror | Bsdf::Conductor { .. } => Vec3::ZERO,
        Bsdf::ThinDielectric { .. } | Bsdf::Null => Vec3::ZERO,
        // Never evaluated: a child is chosen first (see `Bsdf::Blend`).
        Bsdf::Blend { .. } => Vec3::ZERO,
        Bsdf::Principled(ref pr) => super::principled::eval(pr, wi, wo, mode),
        Bsdf::PrincipledThin(ref pr) => super::principled_thin::eval(pr, wi, wo),
        Bsdf::RoughConductor {
            eta,
            k,
            specular,
            microfacet,
        } => {
            if ci <= 0.0 || co <= 0.0 {
                return Vec3::ZERO;
            }
            let h = (wi + wo).normalize();
            let d = microfacet.d(h);
            let g = microfacet.g1(wi, h) * microfacet.g1(wo, h);
            fresnel_conductor(wi.dot(h), eta, k) * specular * (d * g / (4.0 * ci))
        }
        Bsdf::Plastic {
            int_ior,
            ext_ior,
            diffuse,
            nonlinear,
            ..
        } => {
            if ci <= 0.0 || co <= 0.0 {
                return Vec3::ZERO;
            }
            let eta = int_ior / ext_ior;
            let fi = fresnel(ci, eta).0;
            let fo = fresnel(co, eta).0;
            diffuse_under_coating(diffuse, nonlinear, p.internal_reflectance)
                * (co * std::f32::consts::FRAC_1_PI / (eta * eta) * (1.0 - fi) * (1.0 - fo))
        }
        Bsdf::RoughPlastic {
            int_ior,
            ext_ior,
            diffuse,
            specular,
            nonlinear,
            microfacet,
        } => {
            if ci <= 0.0 || co <= 0.0 {
                return Vec3::ZERO;
            }
            let eta = int_ior / ext_ior;
            let spec = specular * rough_reflection(&microfacet, eta, wi, wo);
            let ti = lerp_table(&p.transmittance, ci);
            let to = lerp_table(&p.transmittance, co);
            spec + diffuse_under_coating(diffuse, nonlinear, p.internal_reflectance)
                * (std::f32::consts::FRAC_1_PI / (eta * eta) * co * ti * to)
        }
        Bsdf::PolarizedPlastic {
            int_ior,
            ext_ior,
            diffuse,
            specular,
            microfacet,
        } => {
            if ci <= 0.0 || co <= 0.0 {
                return Vec3::ZERO;
            }
            let eta = int_ior / ext_ior;
            let spec = specular * rough_reflection(&microfacet, eta, wi, wo);
            let (fi, fo) = (fresnel(ci, eta).0, fresnel(co, eta).0);
            spec + diffuse * ((1.0 - fi) * (1.0 - fo) * co * std::f32::consts::FRAC_1_PI)
        }
        Bsdf::RoughDielectric {
            int_ior,
            ext_ior,
            microfacet,
            tint,
        } => {
            // Reflection when both directions are on one side.
            tint.factor(wi.z * wo.z > 0.0)
                * rough_dielectric_eval(int_ior / ext_ior, microfacet, wi, wo, mode)
        }
    }
}

fn diffuse_under_coating(diffuse: Vec3, nonlinear: bool, internal: f32) -> Vec3 {
    if nonlinear {
        diffuse / (Vec3::ONE - diffuse * internal)
    } else {
        diffuse / (1.0 - internal)
    }
}

/// The half vector of a rough dielectric's (wi, wo) pair, facing +z, and the relative index
/// across it seen from wi.
fn dielectric_half(m_eta: f32, wi: Vec3, wo: Vec3) -> (Vec3, f32, bool) {
    let reflect = wi.z * wo.z > 0.0;
    let eta = if wi.z > 0.0 { m_eta } else { 1.0 / m_eta };
    let m = (wi + wo * if reflect { 1.0 } else { eta }).normalize();
    let m = if m.z < 0.0 { -m } else { m };
    (m, eta, reflect)
}

fn rough_dielectric_eval(m_eta: f32, mf: Microfacet, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
    let ci = wi.z;
    if ci == 0.0 {
        return Vec3::ZERO;
    }
    let (m, eta, reflect) = dielectric_half(m_eta, wi, wo);
    let d = mf.d(m);
    let f = fresnel(wi.dot(m), m_eta).0;
    let g = mf.g1(wi, m) * mf.g1(wo, m);
    let v = if reflect {
        f * d * g / (4.0 * ci.abs())
    } else {
        let scale = match mode {
            Mode::Radiance => 1.0 / (eta * eta),
            Mode::Importance => 1.0,
        };
        let denom = wi.dot(m) + eta * wo.dot(m);
        (scale * (1.0 - f) * d * g * eta * eta * wi.dot(m) * wo.dot(m) / (ci * denom * denom)).abs()
    };
    if v.is_finite() {
        Vec3::splat(v)
    } else {
        Vec3::ZERO
    }
}

/// Density of [`sample`] choosing `wo` (non-delta lobes; delta choices have none).
pub fn pdf(p: &Prepared, wi: Vec3, wo: Vec3) -> f32 {
    let (ci, co) = (wi.z, wo.z);
    let cosine = co.max(0.0) * std::f32::consts::FRAC_1_PI;
    match p.bsdf {
        Bsdf::Diffuse { .. } => {
            if ci > 0.0 {
                cosine
            } else {
                0.0
            }
        }
        Bsdf::Dielectric { .. }
        | Bsdf::Mirror
        | Bsdf::Conductor { .. }
        | Bsdf::ThinDielectric { .. }
        | Bsdf::Null
        | Bsdf::Blend { .. } => 0.0,
        Bsdf::Principled(ref pr) => super::principled::pdf(pr, wi, wo),
        Bsdf::PrincipledThin(ref pr) => super::principled_thin::pdf(pr, wi, wo),
        Bsdf::RoughConductor { microfacet, .. } => {
            if ci <= 0.0 || co <= 0.0 {
                return 0.0;
            }
            let h = (wi + wo).normalize();
            microfacet.d(h) * microfacet.g1(wi, h) / (4.0 * ci)
        }
        Bsdf::Plastic {
            int_ior, ext_ior, ..
        } => {
            if ci <= 0.0 || co <= 0.0 {
                return 0.0;
            }
            let fi = fresnel(ci, int_ior / ext_ior).0;
            cosine * plastic_diffuse_prob(fi, p.specular_weight)
        }
        Bsdf::RoughPlastic { microfacet, .. } => {
            if ci <= 0.0 || co <= 0.0 {
                return 0.0;
            }
            let ti = lerp_table(&p.transmittance, ci);
            let prob_diffuse = plastic_diffuse_prob(1.0 - ti, p.specular_weight);
            let h = (wi + wo).normalize();
            let spec = microfacet.d(h) * microfacet.g1(wi, h) / (4.0 * ci);
            (1.0 - prob_diffuse) * spec + prob_diffuse * cosine
        }
        Bsdf::PolarizedPlastic { microfacet, .. } => {
            if ci <= 0.0 || co <= 0.0 {
                return 0.0;
            }
            // Mitsuba's fixed lobe probabilities (no Fresnel term in them).
            let h = (wi + wo).normalize();
            let spec = microfacet.d(h) * microfacet.g1(wi, h) / (4.0 * ci);
            p.specular_weight * spec + (1.0 - p.specular_weight) * cosine
        }
        Bsdf::RoughDielectric {
            int_ior,
            ext_ior,
            microfacet,
            ..
        } => {
            if ci == 0.0 {
                return 0.0;
            }
            let m_eta = int_ior / ext_ior;
            let (m, eta, reflect) = dielectric_half(m_eta, wi, wo);
            if wi.dot(m) * ci <= 0.0 || wo.dot(m) * co <= 0.0 {
                return 0.0;
            }
            let dwh_dwo = if reflect {
                1.0 / (4.0 * wo.dot(m))
            } else {
                let denom = wi.dot(m) + eta * wo.dot(m);
                eta * eta * wo.dot(m) / (denom * denom)
            };
            let wi_up = if ci < 0.0 { -wi } else { wi };
            let f = fresnel(wi.dot(m), m_eta).0;
            let prob = microfacet.pdf(wi_up, m) * if reflect { f } else { 1.0 - f };
            let v = prob * dwh_dwo.abs();
            if v.is_finite() { v } else { 0.0 }
        }
    }
}

/// Probability of the plastic's diffuse lobe given the coating's reflectance `f` at wi.
fn plastic_diffuse_prob(f: f32, specular_weight: f32) -> f32 {
    let ps = f * specular_weight;
    let pd = (1.0 - f) * (1.0 - specular_weight);
    pd / (ps + pd)
}

/// One sampled direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub wo: Vec3,
    /// f |cos wo| / pdf (delta lobes: their weight over their choice probability).
    pub weight: Vec3,
    /// Solid-angle density for non-delta choices; the choice probability for delta ones.
    pub pdf: f32,
    pub delta: bool,
}

/// Samples `wo` given `wi`, with `u1` choosing a lobe and `u2` the direction within it.
pub fn sample(p: &Prepared, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
    let ci = wi.z;
    let mirror = Vec3::new(-wi.x, -wi.y, wi.z);
    let from_eval = |wo: Vec3| {
        let pdf = pdf(p, wi, wo);
        (pdf > 0.0).then(|| Sample {
            wo,
            weight: eval(p, wi, wo, mode) / pdf,
            pdf,
            delta: false,
        })
    };
    match p.bsdf {
        Bsdf::Diffuse { .. } => {
            if ci <= 0.0 {
                return None;
            }
            from_eval(square_to_cosine_hemisphere(u2))
        }
        Bsdf::Mirror | Bsdf::Conductor { .. } => {
            if ci <= 0.0 {
                return None;
            }
            let weight = match p.bsdf {
                Bsdf::Conductor { eta, k, specular } => specular * fresnel_conductor(ci, eta, k),
                _ => Vec3::ONE,
            };
            Some(Sample {
                wo: mirror,
                weight,
                pdf: 1.0,
                delta: true,
            })
        }
        Bsdf::Dielectric {
            int_ior,
            ext_ior,
            tint,
        } => {
            if ci == 0.0 {
                return None;
            }
            let (f, cos_t, _, eta_ti) = fresnel(ci, int_ior / ext_ior);
            if u1 <= f {
                return Some(Sample {
                    wo: mirror,
                    weight: tint.reflectance,
                    pdf: f,
                    delta: true,
                });
            }
            let scale = match mode {
                Mode::Radiance => eta_ti * eta_ti,
                Mode::Importance => 1.0,
            };
            Some(Sample {
                wo: Vec3::new(-eta_ti * wi.x, -eta_ti * wi.y, cos_t),
                weight: tint.transmittance * scale,
                pdf: 1.0 - f,
                delta: true,
            })
        }
        Bsdf::Null => Some(Sample {
            wo: -wi,
            weight: Vec3::ONE,
            pdf: 1.0,
            delta: true,
        }),
        Bsdf::Blend { .. } => None,
        Bsdf::Principled(ref pr) => {
            super::principled::sample(pr, wi, u1, u2, mode).map(|(wo, weight, pdf)| Sample {
                wo,
                weight,
                pdf,
                delta: false,
            })
        }
        Bsdf::PrincipledThin(ref pr) => {
            super::principled_thin::sample(pr, wi, u1, u2).map(|(wo, weight, pdf)| Sample {
                wo,
                weight,
                pdf,
                delta: false,
            })
        }
        Bsdf::ThinDielectric {
            int_ior,
            ext_ior,
            tint,
        } => {
            let mut r = fresnel(ci.abs(), int_ior / ext_ior).0;
            r *= 2.0 / (1.0 + r);
            let reflected = u1 <= r;
            Some(Sample {
                wo: if reflected { mirror } else { -wi },
                weight: tint.factor(reflected),
                pdf: if reflected { r } else { 1.0 - r },
                delta: true,
            })
        }
        Bsdf::RoughConductor {
            eta,
            k,
            specular,
            microfacet,
        } => {
            if ci <= 0.0 {
                return None;
            }
            let m = microfacet.sample(wi, u2);
            let wo = reflect(wi, m);
            let pdf = microfacet.pdf(wi, m) / (4.0 * wo.dot(m));
            if pdf.is_nan() || pdf <= 0.0 || wo.z <= 0.0 {
                return None;
            }
            let weight = fresnel_conductor(wi.dot(m), eta, k) * specular * microfacet.g1(wo, m);
            Some(Sample {
                wo,
                weight,
                pdf,
                delta: false,
            })
        }
        Bsdf::Plastic {
            int_ior,
            ext_ior,
            specular,
            ..
        } => {
            if ci <= 0.0 {
                return None;
            }
            let fi = fresnel(ci, int_ior / ext_ior).0;
            let prob_diffuse = plastic_diffuse_prob(fi, p.specular_weight);
            if u1 < 1.0 - prob_diffuse {
                let prob = 1.0 - prob_diffuse;
                return Some(Sample {
                    wo: mirror,
                    weight: specular * (fi / prob),
                    pdf: prob,
                    delta: true,
                });
            }
            from_eval(square_to_cosine_hemisphere(u2))
        }
        Bsdf::RoughPlastic { microfacet, .. } => {
            if ci <= 0.0 {
                return None;
            }
            let ti = lerp_table(&p.transmittance, ci);
            let prob_diffuse = plastic_diffuse_prob(1.0 - ti, p.specular_weight);
            let wo = if u1 < 1.0 - prob_diffuse {
                reflect(wi, microfacet.sample(wi, u2))
            } else {
                square_to_cosine_hemisphere(u2)
            };
            from_eval(wo)
        }
        Bsdf::PolarizedPlastic { microfacet, .. } => {
            if ci <= 0.0 {
                return None;
            }
            let wo = if u1 < p.specular_weight {
                reflect(wi, microfacet.sample(wi, u2))
            } else {
                square_to_cosine_hemisphere(u2)
            };
            from_eval(wo)
        }
        Bsdf::RoughDielectric {
            int_ior,
            ext_ior,
            microfacet,
            tint,
        } => {
            if ci == 0.0 {
                return None;
            }
            let m_eta = int_ior / ext_ior;
            let wi_up = if ci < 0.0 { -wi } else { wi };
            let m = microfacet.sample(wi_up, u2);
            let mut pdf = microfacet.pdf(wi_up, m);
            if pdf.is_nan() || pdf <= 0.0 {
                return None;
            }
            let (f, cos_t, eta_it, eta_ti) = fresnel(wi.dot(m), m_eta);
            let reflected = u1 <= f;
            let (wo, mut weight, dwh_dwo) = if reflected {
                pdf *= f;
                let wo = reflect(wi, m);
                (wo, 1.0, 1.0 / (4.0 * wo.dot(m)))
            } else {
                pdf *= 1.0 - f;
                let wo = refract(wi, m, cos_t, eta_ti);
                let scale = match mode {
                    Mode::Radiance => eta_ti * eta_ti,
                    Mode::Importance => 1.0,
                };
                let denom = wi.dot(m) + eta_it * wo.dot(m);
                (wo, scale, eta_it * eta_it * wo.dot(m) / (denom * denom))
            };
            weight *= microfacet.g1(wo, m);
            pdf *= dwh_dwo.abs();
            (pdf > 0.0 && pdf.is_finite() && weight > 0.0).then_some(Sample {
                wo,
                weight: tint.factor(reflected) * weight,
                pdf,
                delta: false,
            })
        }
    }
}

pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let p = square_to_disk_concentric(u);
    Vec3::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt())
}

/// Named conductors at RGB, as Mitsuba 3's RGB variants use them: `complex_ior_from_file`
/// (include/mitsuba/render/ior.h) reads `data/ior/<name>.eta.spd` and `.k.spd` from the
/// mitsuba-data repository and converts each spectrum with `spectrum_list_to_srgb`
/// (src/core/spectrum.cpp: 1000 steps over 360-830 nm against the CIE 1931 tables, XYZ to
/// linear sRGB, negatives clamped). The figures below are that computation, redone from those
/// files (mitsuba-data commit 02e8c49) and Mitsuba's CIE table by
/// tests/data/bsdf/named_conductors.py: (name, eta RGB, k RGB).
#[rustfmt::skip]
pub const NAMED_CONDUCTORS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("Ag", [0.155276, 0.116728, 0.138388], [4.82835, 3.12222, 2.1469]),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    ("AlAs", [3.6053, 3.23294, 2.21632], [0.000679437, 0.0, 0.00751271]),
    ("AlAs_palik", [3.6053, 3.23294, 2.21632], [0.000679437, 0.0, 0.00751271]),
    ("AlSb", [0.0, 4.13937, 4.66925], [0.0, 0.0940091, 1.30057]),
    ("AlSb_palik", [0.0, 4.13937, 4.66925], [0.0, 0.0940091, 1.30057]),
    ("Au", [0.143036, 0.375307, 1.44205], [3.983, 2.38556, 1.60336]),
    ("Be", [4.18501, 3.18503, 2.78406], [3.83547, 3.01012, 2.86899]),
    ("Be_palik", [4.18501, 3.18503, 2.78406], [3.83547, 3.01012, 2.86899]),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    ("CsI", [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
    ("CsI_palik", [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
    ("Cu", [0.201006, 0.923749, 1.10222], [3.91326, 2.45305, 2.14209]),
    ("Cu2O", [3.55177, 2.94987, 2.75188], [0.114207, 0.193897, 0.606134]),
    ("Cu2O_palik", [3.55177, 2.94987, 2.75188], [0.114207, 0.193897, 0.606134]),
    ("CuO", [3.24754, 2.44781, 2.21022], [0.52109, 0.570031, 0.722179]),
    ("CuO_palik", [3.24754, 2.44781, 2.21022], [0.52109, 0.570031, 0.722179]),
    ("Cu_palik", [0.213229, 0.919715, 1.10241], [3.92187, 2.45733, 2.13658]),
    ("Hg", [2.39894, 1.44003, 0.90957], [6.32759, 4.37192, 3.42176]),
    ("HgTe", [4.77904, 3.2312, 2.6599], [1.63161, 1.58081, 1.72929]),
    ("HgTe_palik", [4.77904, 3.2312, 2.6599], [1.63161, 1.58081, 1.72929]),
    ("Hg_palik", [2.39894, 1.44003, 0.90957], [6.32759, 4.37192, 3.42176]),
    ("Ir", [3.0863, 2.08219, 1.61791], [5.59215, 4.06709, 3.26731]),
    ("Ir_palik", [3.0863, 2.08219, 1.61791], [5.59215, 4.06709, 3.26731]),
    ("K", [0.0640432, 0.0464098, 0.0381849], [2.1042, 1.34894, 0.913126]),
    ("K_palik", [0.0640432, 0.0464098, 0.0381849], [2.1042, 1.34894, 0.913126]),
    ("Li", [0.265791, 0.195618, 0.220949], [3.54016, 2.31112, 1.66861]),
    ("Li_palik", [0.265791, 0.195618, 0.220949], [3.54016, 2.31112, 1.66861]),
    ("MgO", [2.08958, 1.65072, 1.59488], [4.3327e-12, 0.0, 2.49865e-11]),
    ("MgO_palik", [2.08958, 1.65072, 1.59488], [4.3327e-12, 0.0, 2.49865e-11]),
    ("Mo", [4.48397, 3.52513, 2.77631], [4.11144, 3.42083, 3.15061]),
    ("Mo_palik", [4.48397, 3.52513, 2.77631], [4.11144, 3.42083, 3.15061]),
    ("Na_palik", [0.0602694, 0.0561409, 0.0619884], [3.17927, 2.11249, 1.57904]),
    ("Nb", [3.42007, 2.79009, 2.39563], [3.44139, 2.73767, 2.57975]),
    ("Nb_palik", [3.42007, 2.79009, 2.39563], [3.44139, 2.73767, 2.57975]),
    ("Ni_palik", [2.3673, 1.66337, 1.46708], [4.49881, 3.05015, 2.34544]),
    ("Rh", [2.58579, 1.86022, 1.55426], [6.78226, 4.70299, 3.97607]),
    ("Rh_palik", [2.58579, 1.86022, 1.55426], [6.78226, 4.70299, 3.97607]),
    ("Se", [4.05831, 2.84293, 2.82085], [0.75405, 0.638444, 0.521807]),
    ("Se-e", [5.72285, 4.16574, 4.08134], [0.871136, 1.10516, 1.56532]),
    ("Se-e_palik", [5.72285, 4.16574, 4.08134], [0.871136, 1.10516, 1.56532]),
    ("Se_palik", [4.05831, 2.84293, 2.82085], [0.75405, 0.638444, 0.521807]),
    ("SiC", [3.17234, 2.52597, 2.47937], [7.53766e-07, 0.0, 1.01925e-05]),
    ("SiC_palik", [3.17234, 2.52597, 2.47937], [7.53766e-07, 0.0, 1.01925e-05]),
    ("SnTe", [4.52425, 1.98164, 1.28159], [0.0, 0.0, 0.0]),
    ("SnTe_palik", [4.52425, 1.98164, 1.28159], [0.0, 0.0, 0.0]),
    ("Ta", [2.06272, 2.39294, 2.62793], [2.40836, 1.74149, 1.94703]),
    ("Ta_palik", [2.06272, 2.39294, 2.62793], [2.40836, 1.74149, 1.94703]),
    ("Te", [7.39023, 4.4821, 2.63711], [3.25602, 3.52706, 3.29205]),
    ("Te-e", [7.50891, 4.29643, 2.36999], [5.58393, 4.9472, 3.99759]),
    ("Te-e_palik", [7.50891, 4.29643, 2.36999], [5.58393, 4.9472, 3.99759]),
    ("Te_palik", [7.39023, 4.4821, 2.63711], [3.25602, 3.52706, 3.29205]),
    ("ThF4", [1.83071, 1.44223, 1.38765], [0.0, 0.0, 0.0]),
    ("ThF4_palik", [1.83071, 1.44223, 1.38765], [0.0, 0.0, 0.0]),
    ("TiC", [3.70053, 2.83742, 2.58229], [3.26564, 2.35159, 2.17279]),
    ("TiC_palik", [3.70053, 2.83742, 2.58229], [3.26564, 2.35159, 2.17279]),
    ("TiN", [1.64845, 1.15052, 1.37982], [3.36833, 1.9435, 1.10207]),
    ("TiN_palik", [1.64845, 1.15052, 1.37982], [3.36833, 1.9435, 1.10207]),
    ("TiO2", [3.45661, 2.80174, 2.90517], [0.000105265, 0.0, 0.000652886]),
    ("TiO2-e", [3.10656, 2.51317, 2.58244], [2.97516e-05, 0.0, 0.000182698]),
    ("TiO2-e_palik", [3.10656, 2.51317, 2.58244], [2.97516e-05, 0.0, 0.000182698]),
    ("TiO2_palik", [3.45661, 2.80174, 2.90517], [0.000105265, 0.0, 0.000652886]),
    ("VC", [3.65757, 2.75274, 2.53267], [3.0683, 2.19869, 1.96319]),
    ("VC_palik", [3.65757, 2.75274, 2.53267], [3.0683, 2.19869, 1.96319]),
    ("VN", [2.8656, 2.11919, 1.94009], [3.03224, 2.05612, 1.61631]),
    ("VN_palik", [2.8656, 2.11919, 1.94009], [3.03224, 2.05612, 1.61631]),
    ("V_palik", [4.27758, 3.51295, 2.76107], [3.4913, 2.88945, 3.11152]),
    ("W", [4.37082, 3.30025, 2.99841], [3.50064, 2.60487, 2.27323]),
    ("a-C", [2.94405, 2.22714, 1.96816], [0.887465, 0.799298, 0.81529]),
    ("d-C", [2.70872, 2.31883, 2.2289], [0.0, 0.0, 0.0]),
    ("d-C_palik", [2.70872, 2.31883, 2.2289], [0.0, 0.0, 0.0]),
];

/// eta and k of a named conductor, or `None` for a name Mitsuba does not have.
pub fn named_conductor(name: &str) -> Option<(Vec3, Vec3)> {
    NAMED_CONDUCTORS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, e, k)| (Vec3::from_array(*e), Vec3::from_array(*k)))
}
