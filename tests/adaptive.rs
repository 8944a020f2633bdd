//! Adaptive sampling (src/render/adaptive.rs): path_trace alone samples exactly the pixels a
//! sample mask lists, splatting nothing stale from the pixels it skips; a whole render that
//! stops converged pixels still converges to Mitsuba's reference, its estimate stays honest,
//! and graphs whose estimators need every pixel every iteration are refused.

mod common;

use std::sync::atomic::AtomicBool;

use common::pass_harness::PassHarness;
use common::{gpu, load_graph, load_scene, reference, relmse, renderer};
use hppm::gpu::sample_mask::{SAMPLED, SampleMask, UPDATED};
use hppm::passes::path_trace::{self, PathTrace, PathTraceParams};
use hppm::render::{Budget, Stop};
use hppm::scene::Scene;
use hppm::scene::filter::PixelFilter;

const SIZE: u32 = 24;

fn glass_sphere(filter: PixelFilter) -> Scene {
    let mut scene = load_scene("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    scene.camera.filter = filter;
    scene
}

/// path_trace's radiance accumulator (sum, weight per pixel) after two iterations, the second
/// with `mask` (`None`: every pixel), and after the first alone.
fn two_iterations(scene: &Scene, mask: Option<&[u32]>) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let gpu = gpu();
    let mut harness = PassHarness::new(&gpu, scene, (SIZE, SIZE), gpu.has_float_atomics());
    let sample_mask = SampleMask::new(&gpu, SIZE * SIZE).expect("mask");
    harness.shared.insert(sample_mask.clone());
    let mut pass = PathTrace::new(PathTraceParams {
        samples_per_iteration: 2,
        ..Default::default()
    });
    let out = harness.prepare(&path_trace::KIND, &mut pass, &[]);
    let radiance = out["radiance"].clone();
    let read = || -> Vec<[f32; 4]> {
        gpu.read_pod(&radiance.buffer, (SIZE * SIZE) as usize)
            .expect("readback")
    };
    harness.run(&mut pass, 0, 5);
    let first = read();
    sample_mask.write(&gpu, mask);
    harness.run(&mut pass, 1, 5);
    (first, read())
}

/// Pixels within `reach` (in x and y) of pixel `i`.
fn within(i: usize, reach: i32) -> impl Iterator<Item = usize> {
    let (x, y) = ((i as u32 % SIZE) as i32, (i as u32 / SIZE) as i32);
    (-reach..=reach).flat_map(move |dy| {
        (-reach..=reach).filter_map(move |dx| {
            let (qx, qy) = (x + dx, y + dy);
            let inside = (0..SIZE as i32).contains(&qx) && (0..SIZE as i32).contains(&qy);
            inside.then(|| (qy as u32 * SIZE + qx as u32) as usize)
        })
    })
}

/// The second iteration samples only the pixels the mask lists (a diagonal band and scattered
/// pixels), once with the box filter and once with Mitsuba's Gaussian, which splats each
/// sample over 5x5 pixels. A pixel whose whole reach was sampled gains exactly what it gains
/// when every pixel is; one whose whole reach was skipped gains nothing. Would catch the mask
/// ignored (skipped pixels gain), the compacted list mapped to the wrong pixels (sampled ones
/// differ from the full run), or a skipped pixel's samples of the first iteration splatted
/// again (its neighbours gain).
#[test]
fn path_trace_samples_exactly_the_pixels_the_mask_lists() {
    for (filter, reach) in [(PixelFilter::Box, 0), (PixelFilter::MITSUBA_DEFAULT, 2)] {
        let scene = glass_sphere(filter);
        let flags: Vec<u32> = (0..SIZE * SIZE)
            .map(|i| {
                let (x, y) = (i % SIZE, i / SIZE);
                let sampled = (x as i32 - y as i32).abs() < 6 || (i % 7 == 0 && x < 8);
                if sampled { SAMPLED | UPDATED } else { 0 }
            })
            .collect();
        let (first, full) = two_iterations(&scene, None);
        let (first_again, masked) = two_iterations(&scene, Some(&flags));
        assert_eq!(
            first, first_again,
            "{filter:?}: the first iteration repeats"
        );
        let (mut whole, mut none) = (0, 0);
        for i in 0..(SIZE * SIZE) as usize {
            let reach: Vec<usize> = within(i, reach).collect();
            if reach.iter().all(|&q| flags[q] & SAMPLED != 0) {
                assert_eq!(
                    masked[i], full[i],
                    "{filter:?} pixel {i}: sampled as in full"
                );
                whole += 1;
            } else if reach.iter().all(|&q| flags[q] & SAMPLED == 0) {
                assert_eq!(masked[i], first[i], "{filter:?} pixel {i}: left alone");
                none += 1;
            }
        }
        eprintln!("{filter:?}: {whole} pixels sampled whole, {none} left alone");
        assert!(whole > 50 && none > 50, "{whole} {none}");
    }
}

/// An adaptive render of the glass sphere (pt, Gaussian filter, target 2e-3, at most 128 spp)
/// stops sampling converged pixels and still converges: its error against Mitsuba's reference
/// stays within 1.5x of a uniform render of the same 128 spp while taking fewer samples, and
/// its own estimate stays within 2x of that error. Would catch pixels that stop while their
/// neighbours splat stale or one-sided samples into them (a bias the uniform render does not
/// have), or halves counted as if every pixel were sampled (the estimate falls as skipped
/// pixels repeat their last estimate).
#[test]
fn an_adaptive_render_converges_and_estimates_its_error() {
    let gpu = gpu();
    let scene = load_scene("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    let reference = reference("cornell_glass_sphere");
    let never = AtomicBool::new(false);
    let render = |adaptive: bool| {
        let mut r = renderer(&gpu, &scene, load_graph("graphs/pt.ron"), 1);
        let summary = r
            .run(
                Budget {
                    spp: Some(128),
                    target_error: Some(2e-3),
                    adaptive,
                    ..Default::default()
                },
                &never,
                |_, _| {},
            )
            .expect("render");
        let image = r.image().expect("image");
        let estimate = r.error_estimate().expect("estimate").expect("halves");
        (
            summary,
            relmse(&image, &reference),
            estimate.relmse,
            r.mean_samples_per_pixel(),
        )
    };
    let (uniform, uniform_error, _, uniform_spp) = render(false);
    let (adaptive, adaptive_error, estimated, mean_spp) = render(true);
    eprintln!(
        "uniform: {uniform_spp} spp, relMSE {uniform_error:.3e} ({:?}); adaptive: {mean_spp:.1} \
         spp on average, relMSE {adaptive_error:.3e}, estimated {estimated:.3e} ({:?})",
        uniform.stop, adaptive.stop
    );
    assert_eq!(uniform_spp, 128.0);
    assert!(
        mean_spp < 0.9 * 128.0,
        "adaptive sampling stopped no pixels"
    );
    assert!(adaptive_error < 1.5 * uniform_error);
    assert!(
        (0.5..2.0).contains(&(estimated / adaptive_error)),
        "estimate {estimated:.3e} vs measured {adaptive_error:.3e}"
    );
    assert_ne!(adaptive.stop, Stop::Cancelled);
}

/// The hybrid's estimators count every pixel's photons each iteration: --adaptive is refused
/// with the node named, before any iteration runs; and it needs a target.
#[test]
fn adaptive_sampling_is_refused_where_it_would_be_wrong() {
    let gpu = gpu();
    let scene = load_scene("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    let never = AtomicBool::new(false);
    let mut r = renderer(&gpu, &scene, load_graph("graphs/hybrid.ron"), 1);
    let budget = Budget {
        spp: Some(16),
        target_error: Some(1e-3),
        adaptive: true,
        ..Default::default()
    };
    let error = r.run(budget, &never, |_, _| {}).expect_err("refused");
    let text = error.to_string();
    assert!(
        text.contains("adaptive sampling") && text.contains("camera"),
        "{text}"
    );
    assert_eq!(r.iterations(), 0);
    let no_target = Budget {
        spp: Some(16),
        adaptive: true,
        ..Default::default()
    };
    let text = no_target.check().expect_err("refused").to_string();
    assert!(text.contains("adaptive needs target_error"), "{text}");
}
