//! Pixel reconstruction filters (Mitsuba 3's `rfilter`: `box`, `tent`, `gaussian`) and the CPU
//! mirror of their sampling in `shaders/common/pixel_filter.wgsl`.
//!
//! Mitsuba 3 places camera samples uniformly over the film and splats each one into every pixel
//! within the filter's radius with weight f(x)f(y), then divides each pixel by its summed weight:
//! a pixel is the filter-weighted mean of the radiance around its centre, with the filter cut off
//! where the film ends (unless `sample_border`). hppm samples each pixel's camera offsets from
//! the filter itself (filter importance sampling), restricted to the film the same way, and
//! averages them: the same expected pixel value, with no splatting. All three filters are
//! non-negative, so the sampled density is the normalised filter.

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
}

/// The GPU codes of the filter kinds (`SceneUniform::filter_kind`).
pub const FILTER_BOX: u32 = 0;
pub const FILTER_TENT: u32 = 1;
pub const FILTER_GAUSSIAN: u32 = 2;

/// Mitsuba 3's defaults.
pub const DEFAULT_TENT_RADIUS: f32 = 1.0;
pub const DEFAULT_GAUSSIAN_STDDEV: f32 = 0.5;

/// Newton steps (each bracketed by bisection) that invert the Gaussian's CDF; 24 bring the
/// bracket of a 4-pixel support below f32 resolution even if every step were a bisection.
pub const GAUSSIAN_INVERSION_STEPS: u32 = 24;

impl PixelFilter {
    /// Mitsuba's default when a film names no `rfilter`.
    pub const MITSUBA_DEFAULT: PixelFilter = PixelFilter::Gaussian {
        stddev: DEFAULT_GAUSSIAN_STDDEV,
    };

    /// Half the width of the support, in pixels.
    pub fn radius(&self) -> f32 {
        match *self {
            PixelFilter::Box => 0.5,
            PixelFilter::Tent { radius } => radius,
            PixelFilter::Gaussian { stddev } => 4.0 * stddev,
        }
    }

    /// The kind code and the one parameter (tent radius, Gaussian stddev) the GPU gets.
    pub fn gpu_code(&self) -> (u32, f32) {
        match *self {
            PixelFilter::Box => (FILTER_BOX, 0.5),
            PixelFilter::Tent { radius } => (FILTER_TENT, radius),
            PixelFilter::Gaussian { stddev } => (FILTER_GAUSSIAN, stddev),
        }
    }

    /// The filter [`gpu_code`](Self::gpu_code) describes.
    pub fn from_gpu_code(kind: u32, param: f32) -> Self {
        match kind {
            FILTER_TENT => PixelFilter::Tent { radius: param },
            FILTER_GAUSSIAN => PixelFilter::Gaussian { stddev: param },
            _ => PixelFilter::Box,
        }
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
        }
    }

    /// The fraction of the filter's mass below `x` within the window [lo, hi] (offsets from the
    /// pixel centre): the distribution [`sample`](Self::sample) draws from.
    pub fn cdf(&self, x: f64, lo: f64, hi: f64) -> f64 {
        let (a, b) = (self.integral(lo), self.integral(hi));
        ((self.integral(x.clamp(lo, hi)) - a) / (b - a)).clamp(0.0, 1.0)
    }

    /// An offset from the pixel centre with density proportional to the filter on [lo, hi]
    /// (the filter's support cut to the film), by inverting the CDF at `u` in [0, 1). The same
    /// arithmetic, in f32, as `filter_offset` in `shaders/common/pixel_filter.wgsl`.
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
        }
    }
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

    /// The GPU's code names its filter again (a wrong inverse would splat with another filter
    /// than the film's), and the plane integral is the closed form's square: 1 for the box, r^2
    /// for the tent, (s sqrt(2 pi) erf(r / (s sqrt 2)) - 2 r bias)^2 for the Gaussian.
    #[test]
    fn gpu_codes_name_their_filter_and_plane_integrals_are_exact() {
        for f in FILTERS {
            let (kind, param) = f.gpu_code();
            assert_eq!(PixelFilter::from_gpu_code(kind, param), f);
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
