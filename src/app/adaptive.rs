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

    // Catches a window that is not applied (an isolated noisy pixel would keep only itself
    // sampled) or a dilation that is off by one.
    #[test]
    fn one_noisy_pixel_keeps_its_window_and_the_filter_reach_sampled() {
        // Pixel (5, 5) alone: its 3x3 mean is 9/9 = 1 there and 1/9 at its neighbours.
        let errors = image(11, 11, |x, y| if (x, y) == (5, 5) { 9.0 } else { 0.0 });
        let flags = sample_flags(&errors, 0.5, 0);
        let sampled: Vec<usize> = (0..flags.len())
            .filter(|&i| flags[i] & SAMPLED != 0)
            .collect();
        assert_eq!(sampled, vec![5 * 11 + 5]);
        let flags = sample_flags(&errors, 0.1, 0);
        let count = flags.iter().filter(|&&f| f & SAMPLED != 0).count();
        assert_eq!(count, 9, "target below 1/9: the whole window");
        // Reach 2: sampled within 2 of the centre, updated within 4.
        let flags = sample_flags(&errors, 0.5, 2);
        for y in 0..11i32 {
            for x in 0..11i32 {
                let d = (x - 5).abs().max((y - 5).abs());
                let f = flags[(y * 11 + x) as usize];
                assert_eq!(f & SAMPLED != 0, d <= 2, "sampled at ({x}, {y})");
                assert_eq!(f & UPDATED != 0, d <= 4, "updated at ({x}, {y})");
            }
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
