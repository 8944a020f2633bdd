//! Differential testing against Mitsuba on generated scenes (tests/differential/generate.py):
//! the corpus, renders of a scene over several seeds, and the bias statistic of tests/bias.rs
//! applied to every 8x8 block of the image.
//!
//! Per block, `d_k` is the block's mean (over its pixels and RGB) in seed `k`'s image minus the
//! reference's. A block is biased when
//!
//! ```text
//! |mean_k d_k| > Z * SE + Z * SE_ref
//! ```
//!
//! `SE_ref` is the reference's own standard error in the block, from the spread of the batches
//! it was rendered in (`reference_se.exr`). The seeds alone give SE with only `seeds - 1`
//! degrees of freedom, whose tails would flag some correct block among the corpus's thousands;
//! so SE is the pixels' own variance over the seeds (`64 (seeds - 1)` degrees of freedom, exact
//! where pixels are independent, as in `pt`), times the factor by which the blocks' spread over
//! the seeds exceeds it on average over the scene's blocks (photon-mapped pixels share photons),
//! never below one; and never below the noise Mitsuba's own samples have in that block, scaled
//! to our sample count (a rare path that no seed found leaves no spread to measure).

use std::path::{Path, PathBuf};

use hppm::gpu::GpuContext;
use hppm::image::Image;
use hppm::render::Renderer;
use hppm::scene::Scene;

use super::{load_graph, render_to, repo_path};

/// Standard errors allowed. With the variance pooled over 64 pixels the statistic is close to
/// normal: a correct block exceeds 4.5 with probability 7e-6, about one false alarm in a hundred
/// runs of the whole corpus (40 scenes, 17 statistics, 1 or 2 graphs each).
pub const Z: f64 = 4.5;
pub const BLOCK: u32 = 8;

pub const CORPUS: &str = "tests/differential/corpus";

/// A scene of the corpus and the graphs its line in `manifest.txt` names.
pub struct Case {
    pub name: String,
    pub dir: PathBuf,
    pub graphs: Vec<String>,
    /// Samples per pixel of the reference.
    pub reference_spp: u64,
}

impl Case {
    pub fn scene(&self) -> Scene {
        let path = self.dir.join("scene.xml");
        hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    pub fn reference(&self) -> (Image, Image) {
        let read = |name: &str| {
            let path = self.dir.join(name);
            Image::read_exr(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        };
        (read("reference.exr"), read("reference_se.exr"))
    }
}

/// The corpus at `dir` (relative to the repository, or absolute), in manifest order.
pub fn corpus(dir: &str) -> Vec<Case> {
    let dir = if Path::new(dir).is_absolute() {
        PathBuf::from(dir)
    } else {
        repo_path(dir)
    };
    let manifest = dir.join("manifest.txt");
    let text = std::fs::read_to_string(&manifest)
        .unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
    let reference_spp = text
        .lines()
        .find_map(|line| line.strip_prefix("# reference_spp "))
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or_else(|| panic!("{}: no `# reference_spp N` line", manifest.display()));
    text.lines()
        .filter(|line| !line.trim().is_empty() && !line.starts_with('#'))
        .map(|line| {
            let mut words = line.split_whitespace();
            let name = words.next().expect("scene name").to_string();
            Case {
                dir: dir.join(&name),
                name,
                graphs: words.map(str::to_string).collect(),
                reference_spp,
            }
        })
        .collect()
}

/// One render per seed at the scene's film size.
pub fn render_seeds(
    gpu: &GpuContext,
    scene: &Scene,
    graph: &str,
    seeds: std::ops::Range<u64>,
    spp: u64,
) -> Vec<Image> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    seeds
        .map(|seed| {
            let mut r = Renderer::new(gpu, scene, load_graph(graph), w, h, seed)
                .unwrap_or_else(|e| panic!("{graph}: {e}"));
            render_to(&mut r, spp)
        })
        .collect()
}

fn rgb_mean(p: &[f32; 3]) -> f64 {
    p.iter().map(|&c| c as f64).sum::<f64>() / 3.0
}

/// The bias statistic of one block (or of the whole image).
#[derive(Debug, Clone)]
pub struct BlockBias {
    pub block: (u32, u32),
    pub mean: f64,
    pub reference_mean: f64,
    pub bound: f64,
}

impl BlockBias {
    pub fn flags(&self) -> bool {
        self.mean.abs() > self.bound
    }

    pub fn ratio(&self) -> f64 {
        if self.bound > 0.0 {
            self.mean.abs() / self.bound
        } else if self.mean == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    }
}

impl std::fmt::Display for BlockBias {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "block {:?}: mean diff {:+.5} against {:.5} ({:+.1}%), bound {:.5}, |diff|/bound {:.2}",
            self.block,
            self.mean,
            self.reference_mean,
            100.0 * self.mean / self.reference_mean.max(1e-12),
            self.bound,
            self.ratio()
        )
    }
}

/// Per block: seed-mean difference to the reference and its bound (see the module's comment).
/// `samples_ratio`: the reference's samples per pixel over those of all `images` together.
pub fn block_biases(
    images: &[Image],
    reference: &Image,
    reference_se: &Image,
    samples_ratio: f64,
) -> Vec<BlockBias> {
    let k = images.len();
    assert!(k >= 3, "need three seeds for a spread");
    let (w, h) = (reference.width, reference.height);
    for image in images {
        assert_eq!((image.width, image.height), (w, h), "image size");
    }
    let blocks: Vec<(u32, u32)> = (0..h.div_ceil(BLOCK))
        .flat_map(|by| (0..w.div_ceil(BLOCK)).map(move |bx| (bx, by)))
        .collect();
    let pixels_of = |(bx, by): (u32, u32)| {
        (by * BLOCK..((by + 1) * BLOCK).min(h)).flat_map(move |y| {
            (bx * BLOCK..((bx + 1) * BLOCK).min(w)).map(move |x| (y * w + x) as usize)
        })
    };
    struct Raw {
        block: (u32, u32),
        mean: f64,
        reference_mean: f64,
        seed_variance: f64,
        pooled_variance: f64,
        reference_variance: f64,
    }
    let raw: Vec<Raw> = blocks
        .iter()
        .map(|&block| {
            let pixels: Vec<usize> = pixels_of(block).collect();
            let n = pixels.len() as f64;
            let reference_mean = pixels
                .iter()
                .map(|&i| rgb_mean(&reference.pixels[i]))
                .sum::<f64>()
                / n;
            let d: Vec<f64> = images
                .iter()
                .map(|img| {
                    pixels
                        .iter()
                        .map(|&i| rgb_mean(&img.pixels[i]))
                        .sum::<f64>()
                        / n
                        - reference_mean
                })
                .collect();
            let mean = d.iter().sum::<f64>() / k as f64;
            let seed_variance =
                d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (k - 1) as f64 / k as f64;
            let pooled_variance = pixels
                .iter()
                .map(|&i| {
                    let v: Vec<f64> = images.iter().map(|img| rgb_mean(&img.pixels[i])).collect();
                    let m = v.iter().sum::<f64>() / k as f64;
                    v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (k - 1) as f64
                })
                .sum::<f64>()
                / (n * n)
                / k as f64;
            // The channels' errors are taken as fully correlated (their mean's error is then the
            // mean of theirs): the larger of the two readings.
            let reference_variance = pixels
                .iter()
                .map(|&i| rgb_mean(&reference_se.pixels[i]).powi(2))
                .sum::<f64>()
                / (n * n);
            Raw {
                block,
                mean,
                reference_mean,
                seed_variance,
                pooled_variance,
                reference_variance,
            }
        })
        .collect();
    let ratios: Vec<f64> = raw
        .iter()
        .filter(|r| r.pooled_variance > 0.0)
        .map(|r| r.seed_variance / r.pooled_variance)
        .collect();
    let inflation = if ratios.is_empty() {
        1.0
    } else {
        (ratios.iter().sum::<f64>() / ratios.len() as f64).max(1.0)
    };
    raw.into_iter()
        .map(|r| {
            // Light that reaches a pixel rarely (a caustic seen through a path tracer) may not
            // show in any of a few seeds: the seeds' spread is then zero and says nothing. The
            // reference's spread, scaled to our sample count, is the noise Mitsuba's path
            // tracer has with as many samples; the larger of the two is taken.
            let predicted = r.reference_variance * samples_ratio;
            let variance = (inflation * r.pooled_variance).max(predicted);
            // Float sums of identical samples (a constant background) differ in the last bits.
            let rounding = 1e-4 * r.reference_mean.abs();
            BlockBias {
                block: r.block,
                mean: r.mean,
                reference_mean: r.reference_mean,
                bound: Z * variance.sqrt() + Z * r.reference_variance.sqrt() + rounding,
            }
        })
        .collect()
}

/// The flagged blocks of `images` (`spp` samples per pixel each) against the case's reference,
/// worst first, and the worst block's statistic.
pub fn flagged(case: &Case, images: &[Image], spp: u64) -> (Vec<BlockBias>, BlockBias) {
    let (reference, reference_se) = case.reference();
    let ratio = case.reference_spp as f64 / (spp * images.len() as u64) as f64;
    let mut biases = block_biases(images, &reference, &reference_se, ratio);
    biases.sort_by(|a, b| b.ratio().total_cmp(&a.ratio()));
    let worst = biases[0].clone();
    (biases.into_iter().filter(BlockBias::flags).collect(), worst)
}
