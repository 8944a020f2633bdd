//! Pixel reconstruction filters (Mitsuba 3's `rfilter`: `box`, `tent`, `gaussian`, `lanczos`,
//! `mitchell`, `catmullrom`) and the CPU mirror of their sampling in
//! `shaders/common/pixel_filter.wgsl` and `shaders/common/signed_filter.wgsl`.
//!
//! Mitsuba 3 places camera samples uniformly over the film and splats each one into every pixel
//! within the filter's radius with weight f(x)f(y), then divides each pixel by its summed weight:
//! a pixel is the filter-weighted mean of the radiance around its centre, with the filter cut off
//! where the film ends (unless `sample_border`). hppm samples each pixel's camera offsets from
//! the filter itself (filter importance sampling), restricted to the film the same way, and
//! averages them: the same expected pixel value, with no splatting. The box, tent and Gaussian
//! are non-negative, so the sampled density is the normalised filter and every sample counts 1.
//!
//! Lanczos and the cubics have negative lobes, which no density can follow. Their offsets are
//! drawn from a piecewise-constant density close to |f| (a table of cumulative |f| at 2 x 63 /
//! radius nodes per pixel, [`PixelFilter::gpu_table`]), and each sample carries the weight
//! f(x) / (q(x) F_W): the filter over the sampled density, over the filter's integral F_W over
//! the window. Its mean is then the window's filtered pixel, the value splatting estimates,
//! with negative samples where the filter is negative; |weight| stays near the constant
//! ∫|f| / ∫f (over the plane: 1.85 for Lanczos 3, 1.14 for Mitchell, 1.36 for Catmull-Rom)
//! because q follows |f|. The caustic's hit points carry that weight. The camera pass splats
//! such a sample's radiance like any other, with f over the density of all pixels' draws at
//! its position ([`WeightedSampler::density`] summed over pixels), so flat regions stay flat.
//! Only with `sample_border` (nothing splatted) does a pixel take the plain mean of weighted
//! samples, noisy in flat regions (variance (c^2 - 1) L^2 a sample, 2.4 L^2 for Lanczos 3): a
//! ratio of signed sums would blow up where a few weights cancel. Window edges fall on table
//! nodes (half-integers and the radius), where F_W is exact.

/// A separable filter; its 2D weight is `eval(x) * eval(y)`, x and y in pixels from the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PixelFilter {
    /// 1 on [-0.5, 0.5): each pixel averages its own square.
    Box,
    /// max(0, 1 - |x| / radius); Mitsuba's default radius is 1.
    Tent { radius: f32 },
    /// exp(-x^2 / (2 stddev^2)) minus its value at the radius 4 stddev, clamped at 0 (Mitsuba
    /// 3's windowed Gaussian); Mitsuba's default filter, with stddev 0.5.
    Gaussian { stddev: f32 },
    /// sin(pi x) sin(pi x / lobes) / (pi^2 x^2 / lobes) for |x| < lobes, 1 at 0 (Mitsuba 3's
    /// `lanczos`, 3 lobes by default); negative on every other unit interval.
    Lanczos { lobes: u32 },
    /// The Mitchell-Netravali cubic with parameters B and C on |x| < 2 (Mitsuba 3's `mitchell`,
    /// B = C = 1/3; its `catmullrom` is B = 0, C = 1/2); negative between 1 and 2 for most B, C.
    Mitchell { b: f32, c: f32 },
}

/// Below this |x| Lanczos is 1 (Mitsuba's test against its float epsilon, 2^-24).
const LANCZOS_CENTRE: f64 = 5.960_464_5e-8;

/// The GPU codes of the filter kinds (`SceneUniform::filter_kind`).
pub const FILTER_BOX: u32 = 0;
pub const FILTER_TENT: u32 = 1;
pub const FILTER_GAUSSIAN: u32 = 2;
pub const FILTER_LANCZOS: u32 = 3;
pub const FILTER_MITCHELL: u32 = 4;

/// Nodes of a signed filter's sampling table (`SceneUniform::filter_table`, two a vec4): 0 to
/// the radius in steps of 1 / [`table_nodes_per_pixel`].
pub const FILTER_TABLE_NODES: usize = 128;

/// Table nodes per pixel for a filter of integer `radius`: an even number (so half-integers,
/// where film edges cut the window, are nodes) with at most 128 nodes over [0, radius].
pub fn table_nodes_per_pixel(radius: u32) -> u32 {
    2 * ((FILTER_TABLE_NODES as u32 - 1) / (2 * radius.max(1)))
}

/// Mitsuba 3's defaults.
pub const DEFAULT_TENT_RADIUS: f32 = 1.0;
pub const DEFAULT_GAUSSIAN_STDDEV: f32 = 0.5;
pub const DEFAULT_LANCZOS_LOBES: u32 = 3;
/// Mitchell and Netravali's recommended B = C = 1/3.
pub const DEFAULT_MITCHELL_B_C: f32 = 1.0 / 3.0;

/// Newton steps (each bracketed by bisection) that invert the Gaussian's CDF; 24 bring the
/// bracket of a 4-pixel support below f32 resolution even if every step were a bisection.
pub const GAUSSIAN_INVERSION_STEPS: u32 = 24;

impl PixelFilter {
    /// Mitsuba's default when a film names no `rfilter`.
    pub const MITSUBA_DEFAULT: PixelFilter = PixelFilter::Gaussian {
        stddev: DEFAULT_GAUSSIAN_STDDEV,
    };

    /// Mitsuba's `catmullrom`: the cubic with B = 0 and C = 1/2.
    pub const CATMULL_ROM: PixelFilter = PixelFilter::Mitchell { b: 0.0, c: 0.5 };

    /// Half the width of the support, in pixels.
    pub fn radius(&self) -> f32 {
        match *self {
            PixelFilter::Box => 0.5,
            PixelFilter::Tent { radius } => radius,
            PixelFilter::Gaussian { stddev } => 4.0 * stddev,
            PixelFilter::Lanczos { lobes } => lobes as f32,
            PixelFilter::Mitchell { .. } => 2.0,
        }
    }

    /// Whether the filter has negative lobes, so that samples drawn from the table carry a
    /// weight (see the module's doc).
    pub fn is_signed(&self) -> bool {
        matches!(
            self,
            PixelFilter::Lanczos { .. } | PixelFilter::Mitchell { .. }
        )
    }

    /// The kind code and the two parameters the GPU gets (tent radius, Gaussian stddev,
    /// Lanczos lobes, Mitchell's B and C; 0 where unused).
    pub fn gpu_code(&self) -> (u32, [f32; 2]) {
        match *self {
            PixelFilter::Box => (FILTER_BOX, [0.5, 0.0]),
            PixelFilter::Tent { radius } => (FILTER_TENT, [radius, 0.0]),
            PixelFilter::Gaussian { stddev } => (FILTER_GAUSSIAN, [stddev, 0.0]),
            PixelFilter::Lanczos { lobes } => (FILTER_LANCZOS, [lobes as f32, 0.0]),
            PixelFilter::Mitchell { b, c } => (FILTER_MITCHELL, [b, c]),
        }
    }

    /// The filter [`gpu_code`](Self::gpu_code) describes.
    pub fn from_gpu_code(kind: u32, param: [f32; 2]) -> Self {
        match kind {
            FILTER_TENT => PixelFilter::Tent { radius: param[0] },
            FILTER_GAUSSIAN => PixelFilter::Gaussian { stddev: param[0] },
            FILTER_LANCZOS => PixelFilter::Lanczos {
                lobes: param[0] as u32,
            },
            FILTER_MITCHELL => PixelFilter::Mitchell {
                b: param[0],
                c: param[1],
            },
            _ => PixelFilter::Box,
        }
    }

    /// The signed filters' sampling table for the GPU: node j at x = j / [`table_nodes_per_pixel`]
    /// holds (∫_0^x |f|, ∫_0^x f), two nodes a vec4; zeros for the non-negative filters, which
    /// are sampled in closed form.
    pub fn gpu_table(&self) -> [[f32; 4]; FILTER_TABLE_NODES / 2] {
        let mut table = [[0.0f32; 4]; FILTER_TABLE_NODES / 2];
        if !self.is_signed() {
            return table;
        }
        let per_pixel = table_nodes_per_pixel(self.radius() as u32) as f64;
        let nodes = (per_pixel * self.radius() as f64) as usize + 1;
        // Every bin gets at least this share of |f|'s mass, so that consecutive f32 nodes differ
        // (a draw never lands in a bin of density 0) and q > 0 wherever f is not: the
        // weights f / q stay exact, q only departs from |f| in the tails.
        let floor =
            TABLE_BIN_FLOOR * gauss_legendre_sum(|x| self.eval(x).abs(), 0.0, self.radius() as f64);
        let (mut abs_sum, mut sum) = (0.0f64, 0.0f64);
        for j in 0..nodes.min(FILTER_TABLE_NODES) {
            if j > 0 {
                let (a, b) = ((j - 1) as f64 / per_pixel, j as f64 / per_pixel);
                abs_sum += gauss_legendre(|x| self.eval(x).abs(), a, b).max(floor);
                sum += gauss_legendre(|x| self.eval(x), a, b);
            }
            table[j / 2][2 * (j % 2)] = abs_sum as f32;
            table[j / 2][2 * (j % 2) + 1] = sum as f32;
        }
        table
    }

    /// The integral of the separable 2D filter over the plane, in pixels: the weight a sample
    /// splatted uniformly within a pixel brings an interior pixel on average.
    pub fn plane_integral(&self) -> f64 {
        let r = self.radius() as f64;
        let line = self.integral(r) - self.integral(-r);
        line * line
    }

    /// The 1D filter at `x` pixels from the centre (unnormalised, as Mitsuba defines it).
    pub fn eval(&self, x: f64) -> f64 {
        match *self {
            PixelFilter::Box => {
                if (-0.5..0.5).contains(&x) {
                    1.0
                } else {
                    0.0
                }
            }
            PixelFilter::Tent { radius } => (1.0 - (x / radius as f64).abs()).max(0.0),
            PixelFilter::Gaussian { stddev } => {
                let s = stddev as f64;
                let r = 4.0 * s;
                let g = |t: f64| (-t * t / (2.0 * s * s)).exp();
                (g(x) - g(r)).max(0.0)
            }
            PixelFilter::Lanczos { lobes } => {
                let (x, r) = (x.abs(), lobes as f64);
                if x < LANCZOS_CENTRE {
                    1.0
                } else if x > r {
                    0.0
                } else {
                    let a = std::f64::consts::PI * x;
                    (a.sin() * (a / r).sin()) / (a * a / r)
                }
            }
            PixelFilter::Mitchell { b, c } => {
                let (x, b, c) = (x.abs(), b as f64, c as f64);
                let value = if x < 1.0 {
                    (12.0 - 9.0 * b - 6.0 * c) * x * x * x
                        + (-18.0 + 12.0 * b + 6.0 * c) * x * x
                        + (6.0 - 2.0 * b)
                } else {
                    (-b - 6.0 * c) * x * x * x
                        + (6.0 * b + 30.0 * c) * x * x
                        + (-12.0 * b - 48.0 * c) * x
                        + (8.0 * b + 24.0 * c)
                };
                if x < 2.0 { value / 6.0 } else { 0.0 }
            }
        }
    }

    /// The integral of [`eval`](Self::eval) from 0 to `x` (negative for negative `x`), in f64:
    /// the reference the samplers are tested against and the analytic filtered edge.
    pub fn integral(&self, x: f64) -> f64 {
        let r = self.radius() as f64;
        let x = x.clamp(-r, r);
        match *self {
            PixelFilter::Box => x,
            PixelFilter::Tent { radius } => x - x * x.abs() / (2.0 * radius as f64),
            PixelFilter::Gaussian { stddev } => {
                let s = stddev as f64;
                let bias = (-r * r / (2.0 * s * s)).exp();
                s * (std::f64::consts::PI / 2.0).sqrt() * erf(x / (s * std::f64::consts::SQRT_2))
                    - bias * x
            }
            PixelFilter::Lanczos { .. } | PixelFilter::Mitchell { .. } => {
                // Split at whole pixels (the cubic's pieces meet at 1) and in eighths of a
                // pixel, where 8 Gauss nodes integrate either filter to f64 precision.
                let end = x.abs();
                let mut total = 0.0;
                let mut start = 0.0f64;
                while start < end {
                    let stop = (start.floor() + 1.0).min(end);
                    let steps = ((stop - start) * 8.0).ceil().max(1.0) as usize;
                    let h = (stop - start) / steps as f64;
                    for i in 0..steps {
                        let a = start + i as f64 * h;
                        total += gauss_legendre(|t| self.eval(t), a, a + h);
                    }
                    start = stop;
                }
                total.copysign(x)
            }
        }
    }

    /// The fraction of the filter's mass below `x` within the window [lo, hi] (offsets from the
    /// pixel centre): the distribution [`sample`](Self::sample) draws from for a non-negative
    /// filter, and for any filter the filtered value of a step that is 1 below `x`. (A signed
    /// filter's fraction leaves [0, 1] next to its negative lobes.)
    pub fn cdf(&self, x: f64, lo: f64, hi: f64) -> f64 {
        let (a, b) = (self.integral(lo), self.integral(hi));
        let fraction = (self.integral(x.clamp(lo, hi)) - a) / (b - a);
        if self.is_signed() {
            fraction
        } else {
            fraction.clamp(0.0, 1.0)
        }
    }

    /// The sampler of offsets and their weights (see the module's doc); build it once and draw
    /// many samples, as the GPU reads its table from the scene uniform.
    pub fn weighted_sampler(&self) -> WeightedSampler {
        let r = self.radius();
        let per_pixel = if self.is_signed() {
            table_nodes_per_pixel(r as u32)
        } else {
            0
        };
        WeightedSampler {
            filter: *self,
            table: self.gpu_table(),
            per_pixel,
            bins: per_pixel * r as u32,
        }
    }

    /// An offset from the pixel centre with density proportional to the filter on [lo, hi]
    /// (the filter's support cut to the film), by inverting the CDF at `u` in [0, 1). The same
    /// arithmetic, in f32, as `filter_offset` in `shaders/common/pixel_filter.wgsl`. A signed
    /// filter's offsets follow its table's |f| instead ([`WeightedSampler`]).
    pub fn sample(&self, u: f32, lo: f32, hi: f32) -> f32 {
        let r = self.radius();
        let (lo, hi) = (lo.max(-r), hi.min(r));
        match *self {
            PixelFilter::Box => lo + u * (hi - lo),
            PixelFilter::Tent { radius } => {
                let c = |x: f32| x - x * x.abs() / (2.0 * radius);
                let t = c(lo) + u * (c(hi) - c(lo));
                // c(x) = t solved for x of the sign of t: |x| = r (1 - sqrt(1 - 2|t|/r)).
                let a = radius * (1.0 - (1.0 - 2.0 * t.abs() / radius).max(0.0).sqrt());
                a.copysign(t).clamp(lo, hi)
            }
            PixelFilter::Gaussian { stddev } => gaussian_sample(stddev, u, lo, hi),
            PixelFilter::Lanczos { .. } | PixelFilter::Mitchell { .. } => {
                self.weighted_sampler().sample(u, lo, hi).0
            }
        }
    }
}

/// Offsets from the pixel centre with the weight each sample counts: the filter's own
/// distribution and weight 1 for the non-negative filters; for the signed ones a draw from the
/// piecewise-constant density q of the table's |f| and the weight f(x) / (q(x) F_W), F_W the
/// filter's integral over the window.
#[derive(Debug, Clone)]
pub struct WeightedSampler {
    filter: PixelFilter,
    table: [[f32; 4]; FILTER_TABLE_NODES / 2],
    per_pixel: u32,
    bins: u32,
}

impl WeightedSampler {
    /// Node `j`'s (∫_0^x |f|, ∫_0^x f).
    fn node(&self, j: u32) -> [f32; 2] {
        let v = self.table[(j / 2) as usize];
        if j % 2 == 1 {
            [v[2], v[3]]
        } else {
            [v[0], v[1]]
        }
    }

    /// The cumulative |f| (`k` 0) or f (`k` 1) from 0 to `x`, odd, linear between nodes.
    fn cumulative(&self, x: f32, k: usize) -> f32 {
        let r = self.filter.radius();
        let a = x.abs().min(r) * self.per_pixel as f32;
        let j = (a as u32).min(self.bins - 1);
        let t = a - j as f32;
        let (here, next) = (self.node(j)[k], self.node(j + 1)[k]);
        (here + t * (next - here)).copysign(x)
    }

    /// The density [`sample`](Self::sample) draws a signed filter's offsets with at `offset`
    /// in the window [lo, hi] (0 outside it): the table's |f| per bin, normalised on the
    /// window. The same arithmetic as `table_density` in `shaders/common/signed_filter.wgsl`.
    pub fn density(&self, offset: f32, lo: f32, hi: f32) -> f32 {
        let r = self.filter.radius();
        let (lo, hi) = (lo.max(-r), hi.min(r));
        if offset < lo || offset > hi {
            return 0.0;
        }
        let j = ((offset.abs() * self.per_pixel as f32) as u32).min(self.bins - 1);
        let mass = self.node(j + 1)[0] - self.node(j)[0];
        mass * self.per_pixel as f32 / (self.cumulative(hi, 0) - self.cumulative(lo, 0))
    }

    /// The offset for `u` in [0, 1) in the window [lo, hi], and its weight. The same
    /// arithmetic, in f32, as `table_offset` in `shaders/common/signed_filter.wgsl`.
    pub fn sample(&self, u: f32, lo: f32, hi: f32) -> (f32, f32) {
        if !self.filter.is_signed() {
            return (self.filter.sample(u, lo, hi), 1.0);
        }
        let r = self.filter.radius();
        let (lo, hi) = (lo.max(-r), hi.min(r));
        let (c_lo, c_hi) = (self.cumulative(lo, 0), self.cumulative(hi, 0));
        let target = c_lo + u * (c_hi - c_lo);
        let s = target.abs();
        let (mut first, mut last) = (0u32, self.bins);
        while last - first > 1 {
            let mid = (first + last) / 2;
            if self.node(mid)[0] <= s {
                first = mid;
            } else {
                last = mid;
            }
        }
        let mass = (self.node(first + 1)[0] - self.node(first)[0]).max(f32::MIN_POSITIVE);
        let a = (first as f32 + (s - self.node(first)[0]) / mass) / self.per_pixel as f32;
        let x = a.copysign(target).clamp(lo, hi);
        let density = mass * self.per_pixel as f32 / (c_hi - c_lo);
        let window = self.cumulative(hi, 1) - self.cumulative(lo, 1);
        (x, self.filter.eval(x as f64) as f32 / (density * window))
    }
}

/// A signed filter's table bins hold at least this share of its |f| mass (see `gpu_table`):
/// 1e-4 of a total near 1 is a thousand f32 steps.
const TABLE_BIN_FLOOR: f64 = 1e-4;

/// [`gauss_legendre`] over [a, b] in eighths of a pixel.
fn gauss_legendre_sum(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let steps = ((b - a) * 8.0).ceil().max(1.0) as usize;
    let h = (b - a) / steps as f64;
    (0..steps)
        .map(|i| gauss_legendre(&f, a + i as f64 * h, a + (i + 1) as f64 * h))
        .sum()
}

/// 8-point Gauss-Legendre quadrature of `f` over [a, b] (exact for polynomials of degree 15).
fn gauss_legendre(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    const NODES: [(f64, f64); 4] = [
        (0.183_434_642_495_649_8, 0.362_683_783_378_362),
        (0.525_532_409_916_329, 0.313_706_645_877_887_3),
        (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
        (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    ];
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    NODES
        .iter()
        .map(|&(t, w)| w * (f(mid - half * t) + f(mid + half * t)))
        .sum::<f64>()
        * half
}

/// The windowed Gaussian's integral from 0 to x in f32, with [`erf_f32`].
fn gaussian_integral_f32(s: f32, bias: f32, x: f32) -> f32 {
    s * (std::f32::consts::PI / 2.0).sqrt() * erf_f32(x / (s * std::f32::consts::SQRT_2)) - bias * x
}

fn gaussian_sample(s: f32, u: f32, lo: f32, hi: f32) -> f32 {
    let r = 4.0 * s;
    let bias = (-r * r / (2.0 * s * s)).exp();
    let c = |x: f32| gaussian_integral_f32(s, bias, x);
    let t = c(lo) + u * (c(hi) - c(lo));
    let (mut a, mut b) = (lo, hi);
    let mut x = 0.0f32.clamp(lo, hi);
    for _ in 0..GAUSSIAN_INVERSION_STEPS {
        let err = c(x) - t;
        if err > 0.0 {
            b = x;
        } else {
            a = x;
        }
        let density = (-x * x / (2.0 * s * s)).exp() - bias;
        let next = x - err / density;
        // A Newton step that leaves the bracket (or divides by a vanishing density in the
        // window's tail) becomes a bisection.
        x = if next > a && next < b {
            next
        } else {
            0.5 * (a + b)
        };
    }
    x
}

/// erf by Abramowitz & Stegun 7.1.26 (absolute error below 1.5e-7), odd-extended; the formula
/// the WGSL uses.
pub fn erf_f32(z: f32) -> f32 {
    let a = z.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * a);
    let poly = t
        * (0.254_829_6
            + t * (-0.284_496_74 + t * (1.421_413_7 + t * (-1.453_152_1 + t * 1.061_405_4))));
    (1.0 - poly * (-a * a).exp()).copysign(z)
}

/// erf in f64: the Maclaurin series near 0 and the continued fraction of erfc in the tail,
/// both to about 1e-15.
pub fn erf(x: f64) -> f64 {
    let a = x.abs();
    let value = if a < 2.5 {
        // Maclaurin series: erf(a) = 2/sqrt(pi) sum (-1)^n a^(2n+1) / (n! (2n+1)).
        let mut term = a;
        let mut sum = a;
        let mut n = 0.0;
        while term.abs() > 1e-17 * sum.abs() {
            n += 1.0;
            term *= -a * a / n;
            sum += term / (2.0 * n + 1.0);
        }
        sum * 2.0 / std::f64::consts::PI.sqrt()
    } else {
        // erfc(a) = exp(-a^2)/sqrt(pi) * 1/(a + 1/2/(a + 1/(a + 3/2/(a + ...)))).
        let mut fraction = a;
        for k in (1..60).rev() {
            fraction = a + (k as f64 * 0.5) / fraction;
        }
        1.0 - (-a * a).exp() / (std::f64::consts::PI.sqrt() * fraction)
    };
    value.copysign(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILTERS: [PixelFilter; 5] = [
        PixelFilter::Box,
        PixelFilter::Tent { radius: 1.0 },
        PixelFilter::Tent { radius: 1.7 },
        PixelFilter::Gaussian { stddev: 0.5 },
        PixelFilter::Gaussian { stddev: 0.3 },
    ];

    /// The closed-form integrals against a midpoint sum of `eval`: a wrong constant in the
    /// Gaussian's CDF or the tent's would shift every filtered edge.
    #[test]
    fn integrals_match_numerical_integration() {
        for f in FILTERS {
            let r = f.radius() as f64;
            let n = 200_000;
            let step = 2.0 * r / n as f64;
            let mut sum = 0.0;
            for i in 0..n {
                let x = -r + (i as f64 + 0.5) * step;
                sum += f.eval(x) * step;
                let upper = x + 0.5 * step;
                if i % 20_000 == 0 {
                    let exact = f.integral(upper) - f.integral(-r);
                    assert!(
                        (sum - exact).abs() < 1e-6 * (1.0 + exact),
                        "{f:?} at {upper}: sum {sum}, closed form {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn erf_matches_known_values() {
        for (x, v) in [
            (0.5, 0.520_499_877_813_046_5),
            (1.0, 0.842_700_792_949_714_9),
            (2.0, 0.995_322_265_018_952_7),
            (3.0, 0.999_977_909_503_001_4),
        ] {
            assert!((erf(x) - v).abs() < 1e-13, "erf({x}) = {}", erf(x));
            assert!((erf(-x) + v).abs() < 1e-13);
            assert!((erf_f32(x as f32) as f64 - v).abs() < 1e-6);
        }
    }

    /// Pearson's chi-square of `n` offsets drawn by `sample` in `bins` equal-width bins of the
    /// window, against the probabilities of the f64 CDF. Returns (statistic, degrees of freedom).
    fn chi_square(f: PixelFilter, lo: f32, hi: f32, n: usize, bins: usize) -> (f64, usize) {
        let (wlo, whi) = (lo.max(-f.radius()) as f64, hi.min(f.radius()) as f64);
        let mut counts = vec![0usize; bins];
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..n {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            let u = ((state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32) / 16_777_216.0;
            let x = f.sample(u, lo, hi) as f64;
            assert!(
                x >= wlo - 1e-5 && x <= whi + 1e-5,
                "{f:?}: {x} outside [{wlo}, {whi}]"
            );
            let bin = (((x - wlo) / (whi - wlo)) * bins as f64) as usize;
            counts[bin.min(bins - 1)] += 1;
        }
        let mut stat = 0.0;
        let mut dof = 0usize;
        for (i, &count) in counts.iter().enumerate() {
            let a = wlo + (whi - wlo) * i as f64 / bins as f64;
            let b = wlo + (whi - wlo) * (i + 1) as f64 / bins as f64;
            let p = f.cdf(b, wlo, whi) - f.cdf(a, wlo, whi);
            let expected = p * n as f64;
            if expected < 5.0 {
                continue;
            }
            stat += (count as f64 - expected).powi(2) / expected;
            dof += 1;
        }
        (stat, dof.saturating_sub(1))
    }

    /// The sampled offsets follow the filter's shape, over its whole support and cut to a film
    /// edge on either side (the first and last pixel of a row): a sampler inverting the wrong
    /// CDF, ignoring the window or losing the Gaussian's bias term fails. The bound, the mean
    /// plus 4.5 standard deviations of chi-square, is beyond its 99.99th percentile.
    #[test]
    fn sampled_offsets_follow_the_filter() {
        let windows: [(f32, f32); 4] = [(-10.0, 10.0), (-0.5, 10.0), (-10.0, 0.5), (-1.3, 0.2)];
        for f in FILTERS {
            for (lo, hi) in windows {
                if hi.min(f.radius()) - lo.max(-f.radius()) <= 0.0 {
                    continue;
                }
                let (stat, dof) = chi_square(f, lo, hi, 400_000, 64);
                let bound = dof as f64 + 4.5 * (2.0 * dof as f64).sqrt();
                assert!(
                    stat < bound,
                    "{f:?} in [{lo}, {hi}]: chi-square {stat:.1} with {dof} dof (bound {bound:.1})"
                );
            }
        }
    }

    const SIGNED: [PixelFilter; 4] = [
        PixelFilter::Lanczos { lobes: 3 },
        PixelFilter::Lanczos { lobes: 2 },
        PixelFilter::Mitchell {
            b: DEFAULT_MITCHELL_B_C,
            c: DEFAULT_MITCHELL_B_C,
        },
        PixelFilter::CATMULL_ROM,
    ];

    /// The signed filters' weighted samples estimate the filtered step in every window: the
    /// mean of weight x [x < t] over evenly spaced uniforms is cdf(t) (the signed fraction of
    /// the filter's mass below t in the window) within 2e-3, and the mean weight is 1. Also
    /// checks that the weights' magnitude is near the constant ∫|f| / ∫f (the density follows
    /// |f|). A dropped sign, a window integral over the wrong range or a density that is not
    /// the sampled one fails.
    #[test]
    fn signed_weights_estimate_the_filtered_step() {
        let windows: [(f32, f32); 5] = [
            (-10.0, 10.0),
            (-0.5, 10.0),
            (-10.0, 0.5),
            (-1.5, 0.5),
            (-0.5, 2.5),
        ];
        let n = 200_000;
        for f in SIGNED {
            let sampler = f.weighted_sampler();
            for (lo, hi) in windows {
                let (wlo, whi) = (lo.max(-f.radius()) as f64, hi.min(f.radius()) as f64);
                let draws: Vec<(f32, f32)> = (0..n)
                    .map(|i| sampler.sample((i as f32 + 0.5) / n as f32, lo, hi))
                    .collect();
                let mean_weight = draws.iter().map(|d| d.1 as f64).sum::<f64>() / n as f64;
                assert!(
                    (mean_weight - 1.0).abs() < 2e-3,
                    "{f:?} [{lo}, {hi}]: mean weight {mean_weight}"
                );
                for k in 1..8 {
                    let t = wlo + (whi - wlo) * k as f64 / 8.0;
                    let estimate = draws
                        .iter()
                        .filter(|d| (d.0 as f64) < t)
                        .map(|d| d.1 as f64)
                        .sum::<f64>()
                        / n as f64;
                    let exact = f.cdf(t, wlo, whi);
                    assert!(
                        (estimate - exact).abs() < 2e-3,
                        "{f:?} [{lo}, {hi}] below {t}: {estimate} against {exact}"
                    );
                }
            }
        }
    }

    /// The GPU's code names its filter again (a wrong inverse would splat with another filter
    /// than the film's), and the plane integral is the closed form's square: 1 for the box, r^2
    /// for the tent, (s sqrt(2 pi) erf(r / (s sqrt 2)) - 2 r bias)^2 for the Gaussian.
    #[test]
    fn gpu_codes_name_their_filter_and_plane_integrals_are_exact() {
        for f in FILTERS.iter().chain(&SIGNED) {
            let (kind, param) = f.gpu_code();
            assert_eq!(PixelFilter::from_gpu_code(kind, param), *f);
        }
        assert!((PixelFilter::Box.plane_integral() - 1.0).abs() < 1e-12);
        let tent = PixelFilter::Tent { radius: 1.5 };
        assert!((tent.plane_integral() - 2.25).abs() < 1e-9);
        let (s, r) = (0.5f64, 2.0f64);
        let bias = (-r * r / (2.0 * s * s)).exp();
        let line =
            s * (2.0 * std::f64::consts::PI).sqrt() * erf(r / (s * std::f64::consts::SQRT_2))
                - 2.0 * r * bias;
        let gaussian = PixelFilter::Gaussian { stddev: 0.5 };
        assert!((gaussian.plane_integral() - line * line).abs() < 1e-9);
    }
}
