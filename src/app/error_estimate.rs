//! A render's error without a reference (docs/error-estimate.md): the noise of the image from
//! its two halves (odd and even iterations), the bias of each photon-mapping estimator from its
//! `kernel_bias` image, likewise split in halves. Reported as `hppm compare` measures error,
//! relMSE = mean over pixels and RGB of (x - ref)^2 / (ref^2 + 0.01), with the square of the
//! image less its estimated bias in place of the ref^2 it does not have.

use crate::image::Image;

/// One running-mean image and the sums of its odd iterations' estimates, per pixel.
pub struct Halves<'a> {
    pub mean: &'a Image,
    /// xyz: sum of the odd iterations' estimates.
    pub odd_sums: &'a [[f32; 4]],
}

impl Halves<'_> {
    /// The means of the odd and the even iterations at `pixel`, channel `c`, after `n`
    /// iterations (at least 2).
    fn at(&self, n: u64, pixel: usize, c: usize) -> (f64, f64) {
        let odd = n.div_ceil(2) as f64;
        let even = (n / 2) as f64;
        let sum_odd = self.odd_sums[pixel][c] as f64;
        let total = n as f64 * self.mean.pixels[pixel][c] as f64;
        (sum_odd / odd, (total - sum_odd) / even)
    }
}

/// The estimated error of an image.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorEstimate {
    /// Estimated relMSE: `variance + bias`.
    pub relmse: f64,
    /// Its noise part: the image's variance over (x^2 + 0.01), averaged.
    pub variance: f64,
    /// Its kernel-bias part: the squared bias of the photon-mapped terms over (x^2 + 0.01),
    /// averaged (an unbiased estimate of a square: it may come out a little below 0 where the
    /// bias is small, and is reported as it is; `relmse` is kept at or above 0).
    pub bias: f64,
    /// Per pixel and channel: the estimated squared error over (x^2 + 0.01).
    pub per_pixel: Image,
}

/// Estimates the error of `image` after `iterations` iterations (`None` before 2, when there
/// are no two halves), from its halves and those of each estimator's kernel bias.
pub fn estimate(
    iterations: u64,
    image: &Halves<'_>,
    biases: &[Halves<'_>],
) -> Option<ErrorEstimate> {
    if iterations < 2 {
        return None;
    }
    let n = iterations as f64;
    let odd = iterations.div_ceil(2) as f64;
    let even = (iterations / 2) as f64;
    // Var(A - B) = sigma^2 (1/odd + 1/even) for per-iteration variance sigma^2; the mean of
    // all n iterations has variance sigma^2 / n.
    let variance_scale = 1.0 / ((1.0 / odd + 1.0 / even) * n);
    let (width, height) = (image.mean.width, image.mean.height);
    let mut per_pixel = Image {
        width,
        height,
        pixels: vec![[0.0; 3]; image.mean.pixels.len()],
    };
    // Per pixel and channel: the image's variance, its squared bias, and the image less its
    // bias (estimating the reference) with that difference's variance.
    let pixels = image.mean.pixels.len();
    let mut parts = vec![[PixelParts::default(); 3]; pixels];
    for (pixel, out) in parts.iter_mut().enumerate() {
        for (c, part) in out.iter_mut().enumerate() {
            let (a, b) = image.at(iterations, pixel, c);
            let (bias_a, bias_b) = biases
                .iter()
                .map(|h| h.at(iterations, pixel, c))
                .fold((0.0, 0.0), |(sa, sb), (a, b)| (sa + a, sb + b));
            let (debiased_a, debiased_b) = (a - bias_a, b - bias_b);
            *part = PixelParts {
                variance: (a - b).powi(2) * variance_scale,
                // E[A_bias B_bias] is the squared bias when the halves are independent.
                bias_squared: (bias_a * bias_b).max(0.0),
                debiased: (odd * debiased_a + even * debiased_b) / n,
                debiased_variance: (debiased_a - debiased_b).powi(2) * variance_scale,
            };
        }
    }
    let (mut variance_sum, mut bias_sum) = (0.0, 0.0);
    for (pixel, out) in per_pixel.pixels.iter_mut().enumerate() {
        for c in 0..3 {
            let part = parts[pixel][c];
            let scale = 1.0 / (reference_squared(&parts, width, height, pixel, c) + 0.01);
            variance_sum += part.variance * scale;
            bias_sum += part.bias_squared * scale;
            out[c] = ((part.variance + part.bias_squared) * scale) as f32;
        }
    }
    let count = (per_pixel.pixels.len() * 3).max(1) as f64;
    let (variance, bias) = (variance_sum / count, bias_sum / count);
    Some(ErrorEstimate {
        relmse: (variance + bias).max(0.0),
        variance,
        bias,
        per_pixel,
    })
}

#[derive(Debug, Clone, Copy, Default)]
struct PixelParts {
    variance: f64,
    bias_squared: f64,
    debiased: f64,
    debiased_variance: f64,
}

/// The reference's square at `pixel`, which relMSE divides by. The image less its bias
/// estimates the reference, and E[y^2] - Var(y) its square: x^2 alone would hide a firefly's
/// error behind the firefly, and a blurred caustic's behind the blur. One pixel's variance
/// estimate has one degree of freedom, and where it comes out large the square drops to 0 and
/// the pixel's error is inflated 1/0.01-fold; averaged over the 3x3 neighbourhood it has
/// nine (measured: 3x too high on the hybrid at 15 iterations with one pixel, 1.1x with nine).
fn reference_squared(
    parts: &[[PixelParts; 3]],
    width: u32,
    height: u32,
    pixel: usize,
    c: usize,
) -> f64 {
    let (w, h) = (width as i64, height as i64);
    let (x, y) = (pixel as i64 % w, pixel as i64 / w);
    let (mut mean, mut variance, mut count) = (0.0, 0.0, 0.0);
    for ny in (y - 1).max(0)..=(y + 1).min(h - 1) {
        for nx in (x - 1).max(0)..=(x + 1).min(w - 1) {
            let part = parts[(ny * w + nx) as usize][c];
            mean += part.debiased;
            variance += part.debiased_variance;
            count += 1.0;
        }
    }
    // Radiance is not negative: where the bias estimate overshoots the image (a sharp caustic
    // just inside the kernel), the reference is near 0.
    let mean = (mean / count).max(0.0);
    (mean * mean - variance / (count * count)).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(values: &[f32]) -> Image {
        Image {
            width: values.len() as u32,
            height: 1,
            pixels: values.iter().map(|&v| [v; 3]).collect(),
        }
    }

    /// Per-iteration estimates x_i of one pixel: the halves' difference gives the mean's
    /// variance; a constant image has none.
    #[test]
    fn variance_from_halves() {
        // Four iterations: 1, 3 (odd) and 2, 4 (even): mean 2.5, A = 2, B = 3.
        let mean = image(&[2.5, 7.0]);
        let odd = [[4.0; 4], [14.0; 4]];
        let e = estimate(
            4,
            &Halves {
                mean: &mean,
                odd_sums: &odd,
            },
            &[],
        )
        .expect("two halves");
        // (A - B)^2 / 4 = 0.25, over 2.5^2 + 0.01; the constant pixel adds 0.
        let expected = 0.25 / (2.5f64 * 2.5 + 0.01) / 2.0;
        assert!((e.variance - expected).abs() < 1e-9, "{e:?}");
        assert_eq!(e.bias, 0.0);
        assert_eq!(e.per_pixel.pixels[1], [0.0; 3]);
    }

    /// Halves of unequal size (an odd iteration count) weigh as their counts say: three
    /// iterations 0, 3, 0 have sample variance 3, so the mean's variance is 1.
    #[test]
    fn unequal_halves() {
        let mean = image(&[1.0]);
        let odd = [[0.0; 4]];
        let e = estimate(
            3,
            &Halves {
                mean: &mean,
                odd_sums: &odd,
            },
            &[],
        )
        .expect("two halves");
        // A = 0 (iterations 1, 3), B = 3: (A-B)^2 / ((1/2 + 1) 3) = 9 / 4.5 = 2: the
        // two-group estimate of sigma^2 / n (sigma^2 = 6 from two groups, n = 3).
        assert!((e.variance - 2.0 / 1.01).abs() < 1e-9, "{e:?}");
    }

    /// The bias part multiplies the halves' bias estimates: equal halves give their square,
    /// halves of opposite sign (noise around no bias) a negative term.
    #[test]
    fn bias_from_halves() {
        let mean = image(&[1.0, 1.0]);
        let odd = [[2.0; 4], [2.0; 4]];
        let bias = image(&[0.5, 0.0]);
        let bias_odd = [[1.0; 4], [2.0; 4]];
        let e = estimate(
            4,
            &Halves {
                mean: &mean,
                odd_sums: &odd,
            },
            &[Halves {
                mean: &bias,
                odd_sums: &bias_odd,
            }],
        )
        .expect("two halves");
        // Pixel 0: both halves 0.5 -> 0.25; pixel 1: +1 and -1 -> -1.
        let expected = (0.25 - 1.0) / 1.01 / 2.0;
        assert!((e.bias - expected).abs() < 1e-9, "{e:?}");
        assert_eq!(e.relmse, 0.0);
    }

    #[test]
    fn needs_two_iterations() {
        let mean = image(&[1.0]);
        assert!(
            estimate(
                1,
                &Halves {
                    mean: &mean,
                    odd_sums: &[[1.0; 4]]
                },
                &[]
            )
            .is_none()
        );
    }
}
