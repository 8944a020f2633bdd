//! A render's error without a reference (docs/error-estimate.md): the noise of the image from
//! its two halves (odd and even iterations), the bias of each photon-mapping estimator from its
//! `kernel_bias` image, likewise split in halves. Reported as `hppm compare` measures error,
//! relMSE = mean over pixels and RGB of (x - ref)^2 / (ref^2 + 0.01), with the square of the
//! image less its estimated bias in place of the ref^2 it does not have.

use crate::image::Image;

/// One running-mean image and, per pixel, the sum of its odd updates' estimates and its count
/// of updates (every iteration, unless adaptive sampling left the pixel alone).
pub struct Halves<'a> {
    pub mean: &'a Image,
    /// xyz: sum of the odd updates' estimates; w: the pixel's updates.
    pub odd_sums: &'a [[f32; 4]],
}

/// One pixel channel's two halves: the means of its odd and of its even updates, and how many
/// of each.
#[derive(Debug, Clone, Copy)]
struct HalfMeans {
    odd: f64,
    even: f64,
    odd_count: f64,
    even_count: f64,
}

impl HalfMeans {
    fn count(&self) -> f64 {
        self.odd_count + self.even_count
    }

    /// The variance of the whole mean: Var(A - B) = sigma^2 (1/odd + 1/even) for a per-update
    /// variance sigma^2, and the mean of all n updates has sigma^2 / n.
    fn variance_of_mean(&self, difference: f64) -> f64 {
        difference.powi(2) / ((1.0 / self.odd_count + 1.0 / self.even_count) * self.count())
    }
}

impl Halves<'_> {
    /// The halves at `pixel`, channel `c`; `None` before the pixel's second update.
    fn at(&self, pixel: usize, c: usize) -> Option<HalfMeans> {
        let [.., updates] = self.odd_sums[pixel];
        let updates = updates.max(0.0).round() as u64;
        if updates < 2 {
            return None;
        }
        let (odd_count, even_count) = (updates.div_ceil(2) as f64, (updates / 2) as f64);
        let sum_odd = self.odd_sums[pixel][c] as f64;
        let total = updates as f64 * self.mean.pixels[pixel][c] as f64;
        Some(HalfMeans {
            odd: sum_odd / odd_count,
            even: (total - sum_odd) / even_count,
            odd_count,
            even_count,
        })
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
    /// averaged.
    pub bias: f64,
    /// Per pixel and channel: the estimated squared error over (x^2 + 0.01).
    pub per_pixel: Image,
    /// Per pixel, the parts of `per_pixel` summed over RGB: (noise, kernel bias).
    parts: Vec<(f64, f64)>,
}

impl ErrorEstimate {
    /// The estimate over the pixels `keep` selects (as `hppm compare --mask` measures):
    /// (relMSE, noise part, kernel-bias part).
    pub fn over(&self, keep: impl Fn(usize) -> bool) -> (f64, f64, f64) {
        let (mut variance, mut bias, mut count) = (0.0, 0.0, 0usize);
        for (i, (v, b)) in self.parts.iter().enumerate() {
            if keep(i) {
                variance += v;
                bias += b;
                count += 3;
            }
        }
        let count = count.max(1) as f64;
        let (variance, bias) = (variance / count, bias / count);
        ((variance + bias).max(0.0), variance, bias)
    }
}

/// Estimates the error of `image` after `iterations` iterations of the render (`None` before
/// 2, when there are no two halves), from its halves and those of each estimator's kernel bias.
pub fn estimate(
    iterations: u64,
    image: &Halves<'_>,
    biases: &[Halves<'_>],
) -> Option<ErrorEstimate> {
    if iterations < 2 {
        return None;
    }
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
            let Some(halves) = image.at(pixel, c) else {
                // Not two updates yet: no noise known, the image as the reference.
                part.debiased = image.mean.pixels[pixel][c] as f64;
                continue;
            };
            let (bias_a, bias_b) = biases
                .iter()
                .filter_map(|h| h.at(pixel, c))
                .fold((0.0, 0.0), |(sa, sb), h| (sa + h.odd, sb + h.even));
            let (debiased_a, debiased_b) = (halves.odd - bias_a, halves.even - bias_b);
            *part = PixelParts {
                variance: halves.variance_of_mean(halves.odd - halves.even),
                // E[A_bias B_bias] is the squared bias when the halves are independent; not
                // below 0, where a firefly in one half would cancel its own variance.
                bias_squared: (bias_a * bias_b).max(0.0),
                debiased: (halves.odd_count * debiased_a + halves.even_count * debiased_b)
                    / halves.count(),
                debiased_variance: halves.variance_of_mean(debiased_a - debiased_b),
            };
        }
    }
    let mut pixel_parts = vec![(0.0, 0.0); pixels];
    for (pixel, out) in per_pixel.pixels.iter_mut().enumerate() {
        for c in 0..3 {
            let part = parts[pixel][c];
            let scale = 1.0 / (reference_squared(&parts, width, height, pixel, c) + 0.01);
            pixel_parts[pixel].0 += part.variance * scale;
            pixel_parts[pixel].1 += part.bias_squared * scale;
            out[c] = ((part.variance + part.bias_squared) * scale) as f32;
        }
    }
    let variance_sum: f64 = pixel_parts.iter().map(|p| p.0).sum();
    let bias_sum: f64 = pixel_parts.iter().map(|p| p.1).sum();
    let count = (per_pixel.pixels.len() * 3).max(1) as f64;
    let (variance, bias) = (variance_sum / count, bias_sum / count);
    Some(ErrorEstimate {
        relmse: (variance + bias).max(0.0),
        variance,
        bias,
        per_pixel,
        parts: pixel_parts,
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
/// the pixel's error is inflated 1/0.01-fold; averaged over the 3x3 neighbourhood it has nine
/// (measured: 3x too high on the hybrid at 15 iterations with one pixel, 1.1x with nine).
/// Beside a caustic's sharp edge that average carries the bright side into a dark pixel's
/// reference and hides the kernel's blur there, so a pixel that is darker than its
/// neighbourhood by more than its own noise (three standard deviations) is its own reference.
/// (The neighbourhood's median instead over-read noise 2-6x: BENCHMARKS.md.)
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
    let mean = mean / count;
    let own = parts[pixel][c];
    if own.debiased + 3.0 * own.debiased_variance.sqrt() < mean {
        let own_value = own.debiased.max(0.0);
        return (own_value * own_value - own.debiased_variance).max(0.0);
    }
    // Radiance is not negative: where the bias estimate overshoots the image (a sharp caustic
    // just inside the kernel), the reference is near 0.
    let mean = mean.max(0.0);
    (mean * mean - variance / (count * count)).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform random number in [0, 1) from a 64-bit LCG (Knuth's MMIX constants).
    fn uniform(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A running mean over `n` iterations of per-pixel estimates drawn by `draw`, as the GPU
    /// keeps it: the mean image and its odd iterations' sums.
    fn simulate(size: u32, n: u64, mut draw: impl FnMut(usize) -> f64) -> (Image, Vec<[f32; 4]>) {
        let pixels = (size * size) as usize;
        let mut sum = vec![0.0f64; pixels];
        let mut odd = vec![[0.0f32; 4]; pixels];
        for i in 1..=n {
            for p in 0..pixels {
                let x = draw(p);
                sum[p] += x;
                if i % 2 == 1 {
                    odd[p] = [odd[p][0] + x as f32; 4];
                }
                odd[p][3] = i as f32;
            }
        }
        let mean = Image {
            width: size,
            height: size,
            pixels: sum.iter().map(|s| [(s / n as f64) as f32; 3]).collect(),
        };
        (mean, odd)
    }

    /// The estimate of an image and one kernel-bias image, each (mean, odd sums).
    fn with_bias(
        n: u64,
        (mean, odd_sums): (&Image, &[[f32; 4]]),
        (bias, bias_odd): (&Image, &[[f32; 4]]),
    ) -> ErrorEstimate {
        let bias = Halves {
            mean: bias,
            odd_sums: bias_odd,
        };
        estimate(n, &Halves { mean, odd_sums }, &[bias]).expect("halves")
    }

    /// Estimates of mean 0.5 and standard deviation 0.4 per iteration (a uniform variable),
    /// 64 iterations: the image's relMSE is 0.16 / 64 / (0.25 + 0.01) = 9.6e-3, and the
    /// estimate finds it within 5% over 64x64 pixels. Would catch the variance of one
    /// iteration reported for the mean (64x), or halves of different sizes weighed wrongly.
    #[test]
    fn noise_alone_is_estimated_as_the_variance_of_the_mean() {
        let mut rng = 7u64;
        let half_width = 0.4 * 3f64.sqrt();
        for n in [64, 63] {
            let (mean, odd) = simulate(64, n, |_| {
                0.5 + half_width * (2.0 * uniform(&mut rng) - 1.0)
            });
            let e = estimate(
                n,
                &Halves {
                    mean: &mean,
                    odd_sums: &odd,
                },
                &[],
            )
            .expect("halves");
            let expected = 0.16 / n as f64 / 0.26;
            assert!(
                (e.relmse / expected - 1.0).abs() < 0.05,
                "{n} iterations: estimated {} vs {expected}",
                e.relmse
            );
            assert_eq!(e.bias, 0.0);
        }
    }

    /// A firefly: one pixel in 50 gets 100 in one iteration of 32, over a black image. Its
    /// error is (100/32)^2 / 0.01 where it lands: the estimate finds the mean within 30%.
    /// With the image's own square as the denominator it would find 1/0.98 of a firefly's
    /// worth per pixel instead: 1000x too low.
    #[test]
    fn a_firefly_is_measured_against_the_dark_it_lands_in() {
        let mut rng = 3u64;
        let n = 32;
        let (mean, odd) = simulate(64, n, |_| {
            if uniform(&mut rng) < 1.0 / (50.0 * 32.0) {
                100.0
            } else {
                0.0
            }
        });
        let e = estimate(
            n,
            &Halves {
                mean: &mean,
                odd_sums: &odd,
            },
            &[],
        )
        .expect("halves");
        // E[(x - 0)^2] = p (100/32)^2 with p = 1/50 per pixel over 32 iterations... per
        // iteration p_i = 1/1600: Var(mean) = 32 p_i (100/32)^2 (1 - p_i).
        let p = 1.0 / 1600.0;
        let expected = n as f64 * p * (100.0f64 / n as f64).powi(2) / 0.01;
        assert!(
            (e.relmse / expected - 1.0).abs() < 0.3,
            "estimated {} vs {expected}",
            e.relmse
        );
    }

    /// A constant kernel bias of 0.2 under a mean of 0.7 (reference 0.5) with noise in both:
    /// the bias part is 0.04 / (0.25 + 0.01) within 10%, and the image less its bias stands in
    /// for the reference. Would catch the bias left out, squared from one half only (its
    /// noise added), or the biased image as the denominator (0.04 / 0.5 instead).
    #[test]
    fn kernel_bias_is_squared_from_independent_halves() {
        let mut rng = 11u64;
        let n = 40;
        let (mean, odd) = simulate(48, n, |_| 0.7 + 0.2 * (2.0 * uniform(&mut rng) - 1.0));
        let (bias, bias_odd) = simulate(48, n, |_| 0.2 + 0.3 * (2.0 * uniform(&mut rng) - 1.0));
        let e = with_bias(n, (&mean, &odd), (&bias, &bias_odd));
        let expected = 0.04 / 0.26;
        assert!(
            (e.bias / expected - 1.0).abs() < 0.1,
            "bias part {} vs {expected}",
            e.bias
        );
        // Over half the pixels, the same.
        let (_, _, half) = e.over(|i| i % 2 == 0);
        assert!((half / e.bias - 1.0).abs() < 0.1, "{half} vs {}", e.bias);
    }

    /// A caustic's sharp edge blurred by the kernel: columns 0-7 are bright (10), column 8 is
    /// dark (0.5) but reads 2.5 with a kernel bias of 2, columns 9-15 are dark. The error is
    /// at column 8, 4 / (0.25 + 0.01) per pixel, 0.96 over the image; the estimate finds it
    /// within 10%. With the neighbourhood's mean as the reference (10 + 0.5 + 0.5) / 3, the
    /// bright side hides the blur: 0.02, 50x too low.
    #[test]
    fn a_blurred_sharp_edge_is_measured_against_its_dark_side() {
        let mut rng = 5u64;
        let n = 32;
        let size = 16;
        let column = |p: usize| p % size as usize;
        let (mean, odd) = simulate(size, n, |p| {
            let x = match column(p) {
                0..=7 => 10.0,
                8 => 2.5,
                _ => 0.5,
            };
            x * (1.0 + 0.01 * (2.0 * uniform(&mut rng) - 1.0))
        });
        let (bias, bias_odd) = simulate(size, n, |p| if column(p) == 8 { 2.0 } else { 0.0 });
        let e = with_bias(n, (&mean, &odd), (&bias, &bias_odd));
        let expected = 4.0 / 0.26 / 16.0;
        assert!(
            (e.relmse / expected - 1.0).abs() < 0.1,
            "estimated {} vs {expected}",
            e.relmse
        );
    }

    #[test]
    fn needs_two_iterations() {
        let mean = Image {
            width: 1,
            height: 1,
            pixels: vec![[1.0; 3]],
        };
        let odd = [[1.0, 1.0, 1.0, 1.0]];
        assert!(
            estimate(
                1,
                &Halves {
                    mean: &mean,
                    odd_sums: &odd
                },
                &[]
            )
            .is_none()
        );
    }
}
