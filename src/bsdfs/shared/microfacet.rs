//! Microfacet distributions as Mitsuba 3 writes them (include/mitsuba/render/microfacet.h;
//! Walter et al. 2007, Heitz 2014): Beckmann and GGX, anisotropic, sampled by visible normals.
//! `microfacet.wgsl` beside this is their GPU twin.

use glam::{Vec2, Vec3};

use crate::scene::bsdf::GpuMaterial;

/// Microfacet normal distributions (Mitsuba's `distribution`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Distribution {
    Beckmann,
    Ggx,
}

/// A rough surface's microfacet distribution: roughness `alpha_u` along the tangent (local x)
/// and `alpha_v` along the bitangent; equal for an isotropic surface. Sampled by visible
/// normals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Microfacet {
    pub distribution: Distribution,
    pub alpha_u: f32,
    pub alpha_v: f32,
}

impl Microfacet {
    /// The roughness a `glossy_threshold` is compared with: the larger alpha.
    pub fn roughness(&self) -> f32 {
        self.alpha_u.max(self.alpha_v)
    }

    /// Both alphas finite and not negative.
    pub fn is_valid(&self) -> bool {
        self.alpha_u.is_finite()
            && self.alpha_v.is_finite()
            && self.alpha_u >= 0.0
            && self.alpha_v >= 0.0
    }

    /// Its alphas (floored as evaluation floors them) and distribution into the GPU record.
    pub fn pack(&self, record: &mut GpuMaterial) {
        record.alpha_u = self.alpha_u.max(1e-4);
        record.alpha_v = self.alpha_v.max(1e-4);
        record.distribution = match self.distribution {
            Distribution::Beckmann => 0,
            Distribution::Ggx => 1,
        };
    }

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

pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let p = square_to_disk_concentric(u);
    Vec3::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt())
}
