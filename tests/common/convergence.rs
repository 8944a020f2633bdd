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

/// One seed's renders of a scene by `pt` and by a hybrid graph with the same seed (their camera
/// paths are the same: they differ only by the caustic the hybrid takes from photons), and the
/// hybrid's caustic AOV (black when its graph has none).
pub struct PairedRun {
    pub pt: Image,
    pub hybrid: Image,
    pub caustic: Image,
}

pub fn paired_runs(
    graph: &str,
    scene: &hppm::scene::Scene,
    spp: u64,
    seeds: u64,
) -> Vec<PairedRun> {
    let gpu = gpu();
    (0..seeds)
        .map(|seed| {
            let mut pt = renderer(&gpu, scene, load_graph("graphs/pt.ron"), 100 + seed);
            let pt = render_to(&mut pt, spp);
            let mut hy = renderer(&gpu, scene, load_graph(graph), 100 + seed);
            let hybrid = render_to(&mut hy, spp);
            let caustic = hy
                .aovs()
                .expect("aovs")
                .into_iter()
                .find(|(s, _)| *s == "caustic")
                .map_or_else(|| scaled(&hybrid, 0.0), |(_, c)| c);
            PairedRun {
                pt,
                hybrid,
                caustic,
            }
        })
        .collect()
}

/// Per seed, the image means of `pt` and of the hybrid `graph` and the hybrid's caustic AOV mean
/// (red).
pub fn paired_means(
    graph: &str,
    scene: &hppm::scene::Scene,
    spp: u64,
    seeds: u64,
) -> Vec<([f64; 3], [f64; 3], f64)> {
    paired_runs(graph, scene, spp, seeds)
        .iter()
        .map(|r| (r.pt.mean(), r.hybrid.mean(), r.caustic.mean()[0]))
        .collect()
}

/// The side of the blocks [`hybrid_equals_pt`] compares.
const BLOCK: u32 = 8;

/// Two-sided 1e-3 point of Student's t with 7 degrees of freedom (8 seeds): with the 16-64
/// blocks of a test image, a correct hybrid fails a block by chance about once in 30 runs at
/// most.
const T_7: f64 = 5.41;

/// The hybrid `graph` renders `pt`'s image of `scene` (named `label` in messages), over 8 seeds
/// at 16 spp, paired by seed:
/// - on the whole image, the mean of hybrid - pt within 4 standard errors plus 0.3% (the
///   photon kernel's blur) of zero, per channel, with the hybrid's caustic large enough (twice
///   that tolerance) that dropping it or counting it twice fails;
/// - on every 8x8 block, the mean over seeds of the block's hybrid - pt within Student's t
///   (7 degrees of freedom, 1e-3) standard errors, plus 0.3% of the block and 10% of the
///   block's own caustic (the kernel's blur carries a little of a caustic across a block's
///   edge); so a caustic in the wrong place, or one block's caustic lost, fails where the
///   whole image's mean would not see it. The block with the most caustic must hold more than
///   twice its tolerance, so that losing it there fails, and the same runs with the caustic
///   moved one block sideways must fail.
pub fn hybrid_equals_pt(label: &str, graph: &str, scene: &hppm::scene::Scene) {
    let runs = paired_runs(graph, scene, 16, 8);
    let n = runs.len() as f64;
    let means: Vec<([f64; 3], [f64; 3], f64)> = runs
        .iter()
        .map(|r| (r.pt.mean(), r.hybrid.mean(), r.caustic.mean()[0]))
        .collect();
    let caustic = means.iter().map(|r| r.2).sum::<f64>() / n;
    for c in 0..3 {
        let diffs: Vec<f64> = means.iter().map(|r| r.1[c] - r.0[c]).collect();
        let (mean, se) = mean_and_se(&diffs);
        let pt = means.iter().map(|r| r.0[c]).sum::<f64>() / n;
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
    if let Err(why) = blocks_agree(label, &runs) {
        panic!("{why}");
    }
    // The same hybrid with its caustic moved one block sideways (the image's mean unchanged):
    // the block check must refuse it.
    let moved: Vec<PairedRun> = runs.iter().map(caustic_moved).collect();
    assert!(
        blocks_agree(label, &moved).is_err(),
        "{label}: a caustic moved by {BLOCK} pixels would pass the block check"
    );
}

/// `run` with the hybrid's caustic moved `BLOCK` pixels along x (wrapping round), as a
/// hybrid that put its caustic in the wrong place would render it.
fn caustic_moved(run: &PairedRun) -> PairedRun {
    let (w, h) = (run.hybrid.width, run.hybrid.height);
    let mut hybrid = run.hybrid.clone();
    for y in 0..h {
        for x in 0..w {
            let here = (y * w + x) as usize;
            let from = (y * w + (x + w - BLOCK % w) % w) as usize;
            for c in 0..3 {
                hybrid.pixels[here][c] += run.caustic.pixels[from][c] - run.caustic.pixels[here][c];
            }
        }
    }
    PairedRun {
        pt: run.pt.clone(),
        hybrid,
        caustic: run.caustic.clone(),
    }
}

/// The per-block half of [`hybrid_equals_pt`], on the mean of the three channels: what it
/// measured, or the first block that disagrees.
fn blocks_agree(label: &str, runs: &[PairedRun]) -> Result<(), String> {
    let grey = |i: &Image| -> Vec<f64> {
        block_means(i, BLOCK)
            .pixels
            .iter()
            .map(|p| p.iter().map(|&v| v as f64).sum::<f64>() / 3.0)
            .collect()
    };
    let per_run: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = runs
        .iter()
        .map(|r| (grey(&r.pt), grey(&r.hybrid), grey(&r.caustic)))
        .collect();
    let blocks = per_run[0].0.len();
    let n = per_run.len() as f64;
    let mut worst = (0.0f64, 0usize);
    let mut strongest = (0.0f64, 0.0f64, 0usize);
    for b in 0..blocks {
        let diffs: Vec<f64> = per_run.iter().map(|r| r.1[b] - r.0[b]).collect();
        let (mean, se) = mean_and_se(&diffs);
        let pt = per_run.iter().map(|r| r.0[b]).sum::<f64>() / n;
        let caustic = per_run.iter().map(|r| r.2[b]).sum::<f64>() / n;
        let tolerance = T_7 * se + 0.003 * pt + 0.1 * caustic;
        if mean.abs() / tolerance > worst.0 {
            worst = (mean.abs() / tolerance, b);
        }
        if caustic > strongest.0 {
            strongest = (caustic, tolerance, b);
        }
        if mean.abs() > tolerance {
            return Err(format!(
                "{label}, block {b} ({BLOCK}x{BLOCK}): hybrid - pt = {mean:+.5} +- {se:.5} \
                 (tolerance {tolerance:.5}; pt {pt:.5}, caustic {caustic:.5})"
            ));
        }
    }
    eprintln!(
        "{label}: {blocks} blocks of {BLOCK}x{BLOCK}, the largest |hybrid - pt| / tolerance \
         {:.2} (block {}); the most caustic block {} holds {:.5} against a tolerance of {:.5}",
        worst.0, worst.1, strongest.2, strongest.0, strongest.1
    );
    if strongest.0 <= 2.0 * strongest.1 {
        return Err(format!(
            "{label}: no block's caustic ({:.5}) exceeds twice its tolerance ({:.5}): losing \
             it would pass",
            strongest.0, strongest.1
        ));
    }
    Ok(())
}

/// The mean of `xs` and its standard error.
fn mean_and_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}
