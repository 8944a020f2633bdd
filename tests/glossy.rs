//! Glossy caustics (issue 14): a microfacet lobe smoother than a graph's `glossy_threshold` is a
//! specular vertex of the light-transport partition (docs/design.md section 1). After a photon-mapped
//! vertex the camera leaves the light through it to photons, and caustic photons continue
//! through it; whatever the threshold, `hybrid` must render `pt`'s image.
//!
//! Each scene (tests/data/scenes/glossy_*.xml; box-filtered, so that `pt` and the hybrid, whose
//! hit-point samples keep filter-distributed positions, trace the same camera paths) holds one BSDF with a GGX lobe of alpha 0.05 over
//! a white floor, lit from low on one side: a rough aluminium sphere (roughconductor), a rough
//! glass sphere (roughdielectric) and a rough plastic panel of index 2.4 (roughplastic: only its
//! coating is glossy, its base is path traced). Each is rendered through `pt` and through
//! `hybrid` with `glossy_threshold` 0 (the default: only delta lobes), 0.03 (below the lobe's
//! alpha: nothing changes) and 0.08 (above it: the glossy caustic is photon-mapped), with the
//! same seeds, so that the camera paths of both graphs are the same and their difference is the
//! photon-mapped light minus the path-traced light it replaces. Over the seeds, the mean of
//! hybrid - pt must be within 4 standard errors plus the photon kernel's blur of zero, on the
//! whole image (blur 0.3%, as tests/materials.rs) and on the glossy caustic itself (the pixels
//! where the above-threshold render's caustic is at least a fifth of its peak; blur 4%).
//!
//! What it catches: the photon-mapped glossy caustic is required to be at least twice the image
//! tolerance (measured 0.0206 / 0.0176 / 0.0088 of image means 0.47 / 0.44 / 0.45 for
//! conductor / dielectric / plastic, 4.3 / 4.1 / 3.8 times the tolerance; hybrid - pt itself
//! -0.0003 +- 0.0008, -0.0004 +- 0.0008, +0.0005 +- 0.0002; about 45 s on lavapipe), so a light path
//! that the two passes split differently fails. Checked by breaking the shaders through
//! `HPPM_SHADER_DIR` (64 spp, 8 seeds): photons stopping at glossy lobes while the camera drops
//! them gives image hybrid - pt = -0.0224 / -0.0180 / -0.0089 against tolerances 0.0047 /
//! 0.0043 / 0.0024; the camera path tracing them while photons add them, +0.0220 / +0.0177 /
//! +0.0094 (tolerances 0.0016 / 0.0015 / 0.0015); the camera dropping rough plastic's base with
//! its coating (photons carrying the coating's share only), -0.0133 against 0.0025 on the plastic
//! (the caustic region: -0.14 of its pt mean against 0.086). A threshold read differently by the
//! two passes is one of the first two. Below the lobe's alpha the hybrid's image must be `pt`'s
//! bit for bit (the same camera paths, no photon deposits), with the glossy code compiled in
//! (0.03) or out (0).

mod common;

use common::pass_harness::PassHarness;
use common::*;
use glam::Vec3;
use hppm::graph::{ValidGraph, parse_graph};
use hppm::image::Image;
use hppm::passes::hit_points::{GpuPhotonHit, PhotonHitsHeader};
use hppm::passes::photon_trace::{self, PhotonMode, PhotonTrace, PhotonTraceParams};

const SCENES: [&str; 3] = [
    "tests/data/scenes/glossy_conductor.xml",
    "tests/data/scenes/glossy_dielectric.xml",
    "tests/data/scenes/glossy_plastic.xml",
];
/// Each scene's lobe has alpha 0.05: none, below it, above it.
const THRESHOLDS: [f32; 3] = [0.0, 0.03, 0.08];
const SEEDS: u64 = 8;
const SPP: u64 = 64;
/// Photons per iteration: 8 per pixel, so that the caustic's own noise stays small at 32x32.
const PHOTONS: u32 = 8192;

/// `graphs/hybrid.ron` with `glossy_threshold` (its default 0.2) set to `threshold` on both its
/// camera and photon nodes.
fn hybrid_with_threshold(threshold: f32) -> ValidGraph {
    let path = repo_path("graphs/hybrid.ron");
    let text = std::fs::read_to_string(&path).expect("graphs/hybrid.ron");
    let edits = [
        (
            "params: (merge_depth: 1, glossy_threshold: 0.2)",
            format!("params: (merge_depth: 1, glossy_threshold: {threshold:?})"),
        ),
        (
            "params: (mode: Caustic, glossy_threshold: 0.2)",
            format!(
                "params: (mode: Caustic, glossy_threshold: {threshold:?}, \
                 photons_per_iteration: {PHOTONS})"
            ),
        ),
    ];
    let mut text = text;
    for (from, to) in edits {
        assert!(text.contains(from), "graphs/hybrid.ron has no {from:?}");
        text = text.replacen(from, &to, 1);
    }
    parse_graph(&path, &text, hppm::passes::builtin_kinds()).unwrap_or_else(|e| panic!("{e}"))
}

/// Mean of `image` over the pixels in `mask` (all three channels).
fn region_mean(image: &Image, mask: &[bool]) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for (p, &inside) in image.pixels.iter().zip(mask) {
        if inside {
            sum += p.iter().map(|&v| v as f64).sum::<f64>() / 3.0;
            n += 1.0;
        }
    }
    sum / n
}

fn image_mean(image: &Image) -> f64 {
    image.mean().iter().sum::<f64>() / 3.0
}

/// Mean and standard error of `values`.
fn mean_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

struct Run {
    image: Image,
    caustic: Option<Image>,
}

fn render(
    gpu: &hppm::gpu::GpuContext,
    scene: &hppm::scene::Scene,
    graph: ValidGraph,
    seed: u64,
) -> Run {
    let mut r = renderer(gpu, scene, graph, 500 + seed);
    let image = render_to(&mut r, SPP);
    let caustic = r
        .aovs()
        .expect("aovs")
        .into_iter()
        .find(|(slot, _)| *slot == "caustic")
        .map(|(_, c)| c);
    Run { image, caustic }
}

#[test]
fn hybrid_equals_pt_at_every_glossy_threshold() {
    let gpu = gpu();
    for scene_path in SCENES {
        let scene = load_scene(scene_path);
        let pt: Vec<Run> = (0..SEEDS)
            .map(|seed| render(&gpu, &scene, load_graph("graphs/pt.ron"), seed))
            .collect();
        let runs: Vec<(f32, Vec<Run>)> = THRESHOLDS
            .iter()
            .map(|&t| {
                let runs = (0..SEEDS)
                    .map(|seed| render(&gpu, &scene, hybrid_with_threshold(t), seed))
                    .collect();
                (t, runs)
            })
            .collect();
        // The glossy caustic: where the above-threshold hybrid's photon-mapped image is at least
        // a fifth of its whole image and a tenth of its peak (sums over the seeds).
        let above = &runs.last().expect("thresholds").1;
        let pixels = scene.camera.width as usize * scene.camera.height as usize;
        let (mut caustic, mut whole) = (vec![0.0f64; pixels], vec![0.0f64; pixels]);
        for run in above {
            let c = run.caustic.as_ref().expect("a caustic above the threshold");
            for (i, (p, q)) in c.pixels.iter().zip(&run.image.pixels).enumerate() {
                caustic[i] += p.iter().map(|&v| v as f64).sum::<f64>();
                whole[i] += q.iter().map(|&v| v as f64).sum::<f64>();
            }
        }
        let peak = caustic.iter().cloned().fold(0.0, f64::max);
        let mask: Vec<bool> = caustic
            .iter()
            .zip(&whole)
            .map(|(&c, &w)| c >= w / 5.0 && c >= 0.1 * peak)
            .collect();
        assert!(
            mask.iter().filter(|&&m| m).count() >= 8,
            "{scene_path}: the glossy caustic covers fewer than 8 pixels"
        );
        let region_pt = mean_se(
            &pt.iter()
                .map(|r| region_mean(&r.image, &mask))
                .collect::<Vec<_>>(),
        )
        .0;
        let image_pt = mean_se(&pt.iter().map(|r| image_mean(&r.image)).collect::<Vec<_>>()).0;
        for (t, hybrid) in &runs {
            let diffs = |f: &dyn Fn(&Image) -> f64| -> Vec<f64> {
                hybrid
                    .iter()
                    .zip(&pt)
                    .map(|(h, p)| f(&h.image) - f(&p.image))
                    .collect()
            };
            let (image_diff, image_se) = mean_se(&diffs(&image_mean));
            let (region_diff, region_se) = mean_se(&diffs(&|i| region_mean(i, &mask)));
            let image_tol = 4.0 * image_se + 0.003 * image_pt;
            let region_tol = 4.0 * region_se + 0.04 * region_pt;
            let caustic_mean = |f: &dyn Fn(&Image) -> f64| -> f64 {
                hybrid
                    .iter()
                    .map(|r| r.caustic.as_ref().map_or(0.0, f))
                    .sum::<f64>()
                    / SEEDS as f64
            };
            let image_share = caustic_mean(&image_mean);
            let region_share = caustic_mean(&|c| region_mean(c, &mask));
            eprintln!(
                "{scene_path}, glossy_threshold {t}: image pt {image_pt:.4}, hybrid - pt \
                 {image_diff:+.5} +- {image_se:.5} (tol {image_tol:.5}), photon-mapped \
                 {image_share:.5}; caustic region ({} px) pt {region_pt:.4}, relative to it \
                 hybrid - pt {:+.4} +- {:.4} (tol {:.4}), photon-mapped {:.3}",
                mask.iter().filter(|&&m| m).count(),
                region_diff / region_pt,
                region_se / region_pt,
                region_tol / region_pt,
                region_share / region_pt,
            );
            if *t > 0.05 {
                assert!(
                    image_share > 2.0 * image_tol && region_share > region_tol,
                    "{scene_path}: the photon-mapped glossy caustic ({image_share} of the image, \
                     {region_share} of its region) is too small for the test to see it dropped \
                     or doubled (tolerances {image_tol}, {region_tol})"
                );
            } else {
                assert!(
                    image_share == 0.0,
                    "{scene_path}, threshold {t}: photons deposited {image_share}"
                );
                // No lobe is specular: the glossy code (compiled in above 0) changes nothing.
                for (seed, (h, p)) in hybrid.iter().zip(&pt).enumerate() {
                    assert!(
                        h.image.pixels == p.image.pixels,
                        "{scene_path}, threshold {t}, seed {seed}: the image differs from pt's"
                    );
                }
            }
            assert!(
                image_diff.abs() <= image_tol,
                "{scene_path}, glossy_threshold {t}: image hybrid - pt = {image_diff} (tolerance {image_tol})"
            );
            assert!(
                region_diff.abs() <= region_tol,
                "{scene_path}, glossy_threshold {t}: caustic region hybrid - pt = {region_diff} \
                 (tolerance {region_tol})"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// photon_trace alone.

/// Total flux (RGB) of the caustic photon hits of `iterations` iterations of `photons` photons,
/// averaged over the iterations, and how many hits there were.
fn caustic_flux(
    gpu: &hppm::gpu::GpuContext,
    scene: &hppm::scene::Scene,
    params: PhotonTraceParams,
    iterations: u64,
) -> ([f64; 3], u64) {
    let h = PassHarness::new(gpu, scene, (16, 16), gpu.has_float_atomics());
    let mut pass = PhotonTrace::new(params);
    let photon_hits = h.prepare(&photon_trace::KIND, &mut pass, &[])["photon_hits"].clone();
    let (mut flux, mut count) = ([0.0f64; 3], 0u64);
    for iteration in 0..iterations {
        h.run(&mut pass, iteration, 11);
        let header: PhotonHitsHeader = photon_hits.read_header(gpu).expect("readback");
        assert_eq!(header.dropped, 0, "the photon hits buffer overflowed");
        let hits: Vec<GpuPhotonHit> = photon_hits.read(gpu).expect("readback");
        for hit in &hits[..header.count as usize] {
            for (f, &c) in flux.iter_mut().zip(&hit.flux) {
                *f += c as f64 / iterations as f64;
            }
        }
        count += header.count as u64;
    }
    (flux, count)
}

/// The directional albedo of `bsdf` seen from `cos` off the normal (isotropic): the integral of
/// the CPU reference's f |cos wo| (its unit's model under src/bsdfs/, checked against Mitsuba's in
/// tests/bsdf.rs) over outgoing directions, by the midpoint rule over half vectors (dwo = 4
/// |wo.m| dm; 800 x 200 cells over the half-vector hemisphere's mirror-symmetric half).
fn directional_albedo(bsdf: &hppm::scene::Bsdf, cos: f32) -> [f64; 3] {
    use hppm::scene::bsdf::Mode;
    let wi = Vec3::new((1.0 - cos * cos).max(0.0).sqrt(), 0.0, cos);
    let (n_theta, n_phi) = (800, 200);
    let (d_theta, d_phi) = (
        std::f64::consts::FRAC_PI_2 / n_theta as f64,
        std::f64::consts::PI / n_phi as f64,
    );
    let mut albedo = [0.0f64; 3];
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * d_theta;
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * d_phi;
            let m = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
            );
            let wi_m = wi.dot(m);
            if wi_m <= 0.0 {
                continue;
            }
            let wo = 2.0 * wi_m * m - wi;
            // Both halves of the circle of azimuths: twice the measure.
            let measure = 2.0 * 4.0 * wi_m as f64 * theta.sin() * d_theta * d_phi;
            let f = bsdf.eval(wi, wo, Mode::Importance);
            for c in 0..3 {
                albedo[c] += f[c] as f64 * measure;
            }
        }
    }
    albedo
}

/// What a point light of intensity `intensity` at `light` sends off the rough mirror of
/// tests/data/scenes/rough_mirror_over_floor.xml (all of which lands on its vast floor): I times
/// the integral over the mirror of its directional albedo times the solid angle, by the midpoint
/// rule on 64 x 64 cells, the albedo interpolated linearly between 17 cosines spanning theirs.
fn rough_mirror_flux(bsdf: &hppm::scene::Bsdf, light: Vec3, intensity: [f64; 3]) -> [f64; 3] {
    let cells = 64;
    let normal = Vec3::new(0.0, -1.0, 0.0);
    let mut patches = Vec::new();
    for i in 0..cells {
        for j in 0..cells {
            let x = 0.5 + (i as f32 + 0.5) / cells as f32;
            let z = -0.5 + (j as f32 + 0.5) / cells as f32;
            let to_light = light - Vec3::new(x, 1.5, z);
            let cos = to_light.normalize().dot(normal);
            let solid_angle = (cos / to_light.length_squared()) as f64 / (cells * cells) as f64;
            patches.push((cos, solid_angle));
        }
    }
    let lo = patches.iter().map(|p| p.0).fold(1.0, f32::min);
    let hi = patches.iter().map(|p| p.0).fold(0.0, f32::max);
    let knots = 17;
    let table: Vec<[f64; 3]> = (0..knots)
        .map(|k| directional_albedo(bsdf, lo + (hi - lo) * k as f32 / (knots - 1) as f32))
        .collect();
    let mut flux = [0.0f64; 3];
    for (cos, solid_angle) in patches {
        let t = ((cos - lo) / (hi - lo) * (knots - 1) as f32).clamp(0.0, (knots - 1) as f32);
        let k = (t as usize).min(knots - 2);
        let w = (t - k as f32) as f64;
        for c in 0..3 {
            let albedo = table[k][c] * (1.0 - w) + table[k + 1][c] * w;
            flux[c] += intensity[c] * albedo * solid_angle;
        }
    }
    flux
}

/// `photon_trace` alone on a point light under a rough perfect mirror (GGX alpha 0.1, Fresnel 1)
/// over a vast floor: with `glossy_threshold` 0.15 every photon that reaches the mirror is a
/// caustic photon, and the flux they deposit on the floor must be the light's intensity times
/// the mirror's albedo integrated over the solid angle it subtends, computed on the CPU, within
/// 0.5% (measured -0.01% unaimed, 2^22 photons, and -0.07% aimed, 2^20; the albedo is about
/// 0.98). With the threshold at 0 or below the mirror's alpha (0.05) no photon is deposited.
/// Catches photons that stop at glossy lobes (no flux), that continue with the wrong weight (the
/// shadowing of the outgoing direction left out: +1.8%; a Fresnel or lobe-share factor applied
/// twice or not at all moves it more),
/// that go past a lobe rougher than the threshold, and aiming that misses glossy surfaces (the
/// sphere of the specular ones is empty here: aimed photons would find nothing).
#[test]
fn caustic_photons_continue_through_a_glossy_mirror_with_its_albedo() {
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/rough_mirror_over_floor.xml");
    let mirror = scene
        .materials
        .iter()
        .find(|m| m.bsdf.kind() == "roughconductor")
        .expect("the rough mirror");
    let light = &scene.point_lights[0];
    let intensity = light.intensity.to_array().map(|c| c as f64);
    let expected = rough_mirror_flux(&mirror.bsdf, light.position, intensity);
    let params = |glossy_threshold: f32, aim: bool| PhotonTraceParams {
        mode: PhotonMode::Caustic,
        photons_per_iteration: Some(1 << 18),
        aim,
        glossy_threshold,
        ..Default::default()
    };
    for aim in [false, true] {
        let (flux, count) = caustic_flux(&gpu, &scene, params(0.15, aim), if aim { 4 } else { 16 });
        eprintln!("aim {aim}: {count} caustic photon hits, flux {flux:?}, CPU {expected:?}");
        for c in 0..3 {
            let rel = flux[c] / expected[c] - 1.0;
            assert!(
                rel.abs() < 0.005,
                "aim {aim}, channel {c}: deposited {} against {} ({rel:+.4})",
                flux[c],
                expected[c]
            );
        }
        for threshold in [0.0, 0.05] {
            let (flux, count) = caustic_flux(&gpu, &scene, params(threshold, aim), 1);
            assert_eq!(
                count, 0,
                "aim {aim}, glossy_threshold {threshold}: {count} photons deposited ({flux:?})"
            );
        }
    }
}

/// The roughness an anisotropic lobe is judged by is the larger of its two alphas: a rough
/// mirror with alpha_u 0.05 and alpha_v 0.3 (the same scene) is no specular vertex at
/// `glossy_threshold` 0.2, whatever the photon's direction, and is one at 0.35.
#[test]
fn an_anisotropic_lobe_is_as_specular_as_its_larger_alpha() {
    let gpu = gpu();
    let defines = [("alpha_u", "0.05"), ("alpha_v", "0.3")].map(|(k, v)| (k.into(), v.into()));
    let path = repo_path("tests/data/scenes/rough_mirror_over_floor.xml");
    let scene = hppm::loaders::load_with(&path, &defines).unwrap_or_else(|e| panic!("{e}"));
    let params = |glossy_threshold: f32| PhotonTraceParams {
        mode: PhotonMode::Caustic,
        photons_per_iteration: Some(1 << 16),
        glossy_threshold,
        ..Default::default()
    };
    let (_, below) = caustic_flux(&gpu, &scene, params(0.2), 1);
    let (flux, above) = caustic_flux(&gpu, &scene, params(0.35), 1);
    eprintln!("threshold 0.2: {below} caustic photon hits; 0.35: {above} (flux {flux:?})");
    assert_eq!(
        below, 0,
        "a lobe with alpha_v 0.3 counted as specular below 0.3"
    );
    assert!(
        above > 1000,
        "only {above} caustic photons above both alphas"
    );
}
