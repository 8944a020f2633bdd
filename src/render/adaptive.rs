//! Adaptive sampling (docs/error-estimate.md): once a render's per-pixel error estimate is
//! trustworthy, pixels whose estimate is below the target error stop receiving camera samples,
//! as Cycles' adaptive sampling stops converged pixels. A pixel's estimate is averaged over its
//! 3x3 neighbourhood first: one pixel's noise estimate has three degrees of freedom (one per
//! channel) and would stop pixels on a lucky draw.
//!
//! With a splatting pixel filter a pixel's value comes from its neighbours' samples too, so a
//! pixel that has not converged keeps every neighbour within the filter's reach sampled (its
//! value then stays the filtered mean over a uniformly sampled neighbourhood), and the pixels
//! within reach of a sampled one are the ones whose image changes.

use crate::gpu::sample_mask::{SAMPLED, UPDATED};
use crate::image::Image;

/// Per pixel, [`SAMPLED`] and [`UPDATED`] flags for the next iterations: sampled where any
/// pixel within `reach` (pixels, in x and y) has a windowed estimate at or above `target`,
/// updated within `reach` of a sampled pixel. `per_pixel` is the estimated relative squared
/// error per pixel and channel.
pub fn sample_flags(per_pixel: &Image, target: f64, reach: u32) -> Vec<u32> {
    let (width, height) = (per_pixel.width as usize, per_pixel.height as usize);
    let pixel_error: Vec<f64> = per_pixel
        .pixels
        .iter()
        .map(|p| p.iter().map(|&c| c as f64).sum::<f64>() / 3.0)
        .collect();
    let windowed = box_mean(&pixel_error, width, height, 1);
    // An unknown (NaN) estimate keeps its pixels sampled.
    let unconverged: Vec<bool> = windowed
        .iter()
        .map(|&e| e >= target || e.is_nan())
        .collect();
    let sampled = dilate(&unconverged, width, height, reach as usize);
    let updated = dilate(&sampled, width, height, reach as usize);
    sampled
        .iter()
        .zip(&updated)
        .map(|(&s, &u)| (s as u32 * SAMPLED) | (u as u32 * UPDATED))
        .collect()
}

/// The mean of `values` over each pixel's (2r+1)^2 neighbourhood, cut at the image's edges.
fn box_mean(values: &[f64], width: usize, height: usize, r: usize) -> Vec<f64> {
    let mut out = vec![0.0; values.len()];
    for y in 0..height {
        for x in 0..width {
            let (mut sum, mut count) = (0.0, 0usize);
            for qy in y.saturating_sub(r)..(y + r + 1).min(height) {
                for qx in x.saturating_sub(r)..(x + r + 1).min(width) {
                    sum += values[qy * width + qx];
                    count += 1;
                }
            }
            out[y * width + x] = sum / count.max(1) as f64;
        }
    }
    out
}

/// Pixels within `r` (in x and y) of a set pixel.
fn dilate(set: &[bool], width: usize, height: usize, r: usize) -> Vec<bool> {
    if r == 0 {
        return set.to_vec();
    }
    // Separable: rows, then columns.
    let mut rows = vec![false; set.len()];
    for y in 0..height {
        for x in 0..width {
            rows[y * width + x] =
                (x.saturating_sub(r)..(x + r + 1).min(width)).any(|qx| set[y * width + qx]);
        }
    }
    let mut out = vec![false; set.len()];
    for y in 0..height {
        for x in 0..width {
            out[y * width + x] =
                (y.saturating_sub(r)..(y + r + 1).min(height)).any(|qy| rows[qy * width + x]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, error: impl Fn(u32, u32) -> f32) -> Image {
        Image {
            width,
            height,
            pixels: (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .map(|(x, y)| [error(x, y); 3])
                .collect(),
        }
    }

    // Catches a window that is not applied (a lone noisy pixel would keep only itself sampled,
    // and a lone pixel just above the target would not be diluted) or a dilation off by one.
    #[test]
    fn one_noisy_pixel_keeps_its_window_and_the_filter_reach_sampled() {
        // Pixel (5, 5) alone at 9: every window that holds it averages 1, the others 0.
        let errors = image(11, 11, |x, y| if (x, y) == (5, 5) { 9.0 } else { 0.0 });
        let distance = |i: usize| {
            let (x, y) = ((i % 11) as i32, (i / 11) as i32);
            (x - 5).abs().max((y - 5).abs())
        };
        let flags = sample_flags(&errors, 0.5, 0);
        for (i, f) in flags.iter().enumerate() {
            assert_eq!(f & SAMPLED != 0, distance(i) <= 1, "pixel {i}");
        }
        // A lone pixel at 0.9 averages 0.1 over its window: below a target of 0.5.
        let lone = image(11, 11, |x, y| if (x, y) == (5, 5) { 0.9 } else { 0.0 });
        assert!(sample_flags(&lone, 0.5, 0).iter().all(|&f| f == 0));
        // Reach 2: sampled within 1 + 2 of the centre, updated within 1 + 4.
        let flags = sample_flags(&errors, 0.5, 2);
        for (i, f) in flags.iter().enumerate() {
            assert_eq!(f & SAMPLED != 0, distance(i) <= 3, "sampled, pixel {i}");
            assert_eq!(f & UPDATED != 0, distance(i) <= 5, "updated, pixel {i}");
        }
    }

    // Catches a comparison that stops pixels exactly at the target or keeps NaN estimates out.
    #[test]
    fn at_the_target_and_unknown_estimates_keep_sampling() {
        let flags = sample_flags(&image(4, 4, |_, _| 0.25), 0.25, 0);
        assert!(flags.iter().all(|&f| f == SAMPLED | UPDATED));
        let flags = sample_flags(&image(4, 4, |_, _| f32::NAN), 0.25, 0);
        assert!(flags.iter().all(|&f| f == SAMPLED | UPDATED));
        let flags = sample_flags(&image(4, 4, |_, _| 0.1), 0.25, 1);
        assert!(flags.iter().all(|&f| f == 0));
    }
}
