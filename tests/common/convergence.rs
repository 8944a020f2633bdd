//! Convergence to a Mitsuba 3 reference, under the bound tests/refs/README.md gives for its
//! scenes: within 1.5x Mitsuba's own 256-spp error plus twice the reference's noise floor, on
//! pixels and on 8x8 block means (noise averages out there, a bias does not), both scaled as
//! 1/spp for other sample counts. And the paired check that a hybrid graph renders `pt`'s image.

use hppm::image::Image;

use super::*;

/// Mitsuba's own 256-spp errors on a reference scene and the reference's noise.
pub struct MitsubaFigures {
    pub scene: &'static str,
    pub reference: &'static str,
    pub pixels_256: f64,
    pub blocks_256: f64,
    pub noise: f64,
}

impl MitsubaFigures {
    /// (pixel, block) relMSE bounds at `spp`.
    pub fn bounds(&self, spp: u64) -> (f64, f64) {
        let scale = 256.0 / spp as f64;
        (
            1.5 * self.pixels_256 * scale + 2.0 * self.noise,
            1.5 * self.blocks_256 * scale + 2.0 * self.noise,
        )
    }

    /// Renders `graph` at `spp` and checks both metrics against the bounds (and that a 10%
    /// energy loss would fail the block bound); returns the metrics.
    pub fn check(&self, graph: &str, spp: u64, seed: u64) -> (f64, f64) {
        let gpu = gpu();
        let scene = load_scene(self.scene);
        let reference = reference(self.reference);
        let mut r = renderer(&gpu, &scene, load_graph(graph), seed);
        let image = render_to(&mut r, spp);
        let (pixel_bound, block_bound) = self.bounds(spp);
        let e = relmse(&image, &reference);
        let blocks = relmse(&block_means(&image, 8), &block_means(&reference, 8));
        eprintln!(
            "{} through {graph}, {spp} spp, seed {seed}: relMSE {e:.3e} (bound {pixel_bound:.3e}), \
             8x8 blocks {blocks:.3e} (bound {block_bound:.3e}), mean {:?} vs {:?}",
            self.reference,
            image.mean(),
            reference.mean()
        );
        let lossy = relmse(
            &block_means(&scaled(&image, 0.9), 8),
            &block_means(&reference, 8),
        );
        assert!(lossy > block_bound, "a 10% loss ({lossy:.2e}) would pass");
        assert!(
            e <= pixel_bound,
            "{graph}: relMSE {e:.3e} > {pixel_bound:.3e}"
        );
        assert!(
            blocks <= block_bound,
            "{graph}: block relMSE {blocks:.3e} > {block_bound:.3e}"
        );
        (e, blocks)
    }
}

/// The image averaged over `side` x `side` blocks.
pub fn block_means(image: &Image, side: u32) -> Image {
    let (w, h) = (image.width / side, image.height / side);
    let mut pixels = vec![[0.0f32; 3]; (w * h) as usize];
    for y in 0..h * side {
        for x in 0..w * side {
            let p = image.pixels[(y * image.width + x) as usize];
            let b = &mut pixels[((y / side) * w + x / side) as usize];
            for c in 0..3 {
                b[c] += p[c] / (side * side) as f32;
            }
        }
    }
    Image {
        width: w,
        height: h,
        pixels,
    }
}

pub fn scaled(image: &Image, s: f32) -> Image {
    Image {
        pixels: image.pixels.iter().map(|p| p.map(|c| c * s)).collect(),
        ..image.clone()
    }
}

/// The mean of the red channel of a renderer's `caustic` AOV (0 when its graph has none).
pub fn caustic_mean(renderer: &hppm::render::Renderer<'_>) -> f64 {
    renderer
        .aovs()
        .expect("aovs")
        .iter()
        .find(|(s, _)| *s == "caustic")
        .map_or(0.0, |(_, c)| c.mean()[0])
}

/// Per seed, the image means of `pt` and of the hybrid `graph` with the same seed (their camera
/// paths are the same: they differ only by the caustic the hybrid takes from photons), and the
/// hybrid's caustic AOV mean.
pub fn paired_means(
    graph: &str,
    scene: &hppm::scene::Scene,
    spp: u64,
    seeds: u64,
) -> Vec<([f64; 3], [f64; 3], f64)> {
    let gpu = gpu();
    (0..seeds)
        .map(|seed| {
            let mut pt = renderer(&gpu, scene, load_graph("graphs/pt.ron"), 100 + seed);
            let pt_mean = render_to(&mut pt, spp).mean();
            let mut hy = renderer(&gpu, scene, load_graph(graph), 100 + seed);
            let hy_mean = render_to(&mut hy, spp).mean();
            (pt_mean, hy_mean, caustic_mean(&hy))
        })
        .collect()
}

/// The hybrid `graph` renders `pt`'s image of `scene` (named `label` in messages): over 4 seeds
/// at 16 spp the mean of hybrid - pt must be within 4 standard errors plus 0.3% (the photon
/// kernel's blur) of zero, per channel, and the hybrid's caustic large enough (twice the
/// tolerance) that dropping it or counting it twice would fail.
pub fn hybrid_equals_pt(label: &str, graph: &str, scene: &hppm::scene::Scene) {
    let runs = paired_means(graph, scene, 16, 4);
    let n = runs.len() as f64;
    let caustic = runs.iter().map(|r| r.2).sum::<f64>() / n;
    for c in 0..3 {
        let diffs: Vec<f64> = runs.iter().map(|r| r.1[c] - r.0[c]).collect();
        let mean = diffs.iter().sum::<f64>() / n;
        let se = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let pt = runs.iter().map(|r| r.0[c]).sum::<f64>() / n;
        let tolerance = 4.0 * se + 0.003 * pt;
        eprintln!(
            "{label}, channel {c}: pt {pt:.5}, hybrid - pt {mean:+.5} +- {se:.5} (tolerance \
             {tolerance:.5}), caustic {caustic:.5} ({:.1}% of the image)",
            100.0 * caustic / pt
        );
        if c == 0 {
            assert!(
                caustic > 2.0 * tolerance,
                "the caustic ({caustic}) is too small for the test to see it dropped or doubled"
            );
        }
        assert!(
            mean.abs() <= tolerance,
            "{label}, channel {c}: hybrid - pt = {mean} (tolerance {tolerance})"
        );
    }
}
