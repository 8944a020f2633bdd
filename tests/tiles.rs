//! An image rendered in bands of rows (what a renderer does when the whole image's buffers would
//! not fit the adapter's bindings, e.g. 3840x2160 on lavapipe) against the same image rendered
//! whole. Rays and random streams follow film pixels and the bands read the photons the whole
//! image would, so the bands must give the very same image: `pt` bit for bit, the hybrid to the
//! last bits of its atomic sums. Would catch a band that keys its random streams by its own
//! pixels (a seam of repeated noise), a camera that spans each band with the whole field of view
//! (each band a squashed copy of the image), a halo too thin for the splatting pixel filter
//! (rows at the band edges missing their neighbours' samples), a band that traces its own share
//! of photons (caustic noise up by the band count), a band that reads the photons before the
//! first band traced them (or last iteration's), or rows copied to the wrong place.

mod common;

use common::*;
use hppm::graph::pass::Schedule;
use hppm::image::Image;
use hppm::render::{Budget, Renderer};
use hppm::scene::Scene;
use hppm::scene::filter::PixelFilter;
use std::sync::atomic::AtomicBool;

const SIZE: (u32, u32) = (40, 37);

/// The glass-sphere Cornell box with `filter`, whose samples splat across pixel (and band)
/// edges: Mitsuba's default Gaussian, and Lanczos, whose samples drawn for hit points (every
/// sample of the hybrid) reach twice as far (a halo of 5 rows, not 3).
fn splatting_scene(filter: PixelFilter) -> Scene {
    let mut scene = load_scene("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    scene.camera.filter = filter;
    scene
}

fn banded<'a>(
    gpu: &'a hppm::gpu::GpuContext,
    scene: &Scene,
    graph: &str,
    bands: u32,
) -> Renderer<'a> {
    Renderer::with_bands(
        gpu,
        scene,
        load_graph(graph),
        SIZE,
        3,
        Schedule::default(),
        Some(bands),
    )
    .unwrap_or_else(|e| panic!("{graph} in {bands} bands: {e}"))
}

fn max_difference(a: &Image, b: &Image) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

#[test]
fn an_image_in_bands_is_the_image_rendered_whole() {
    let gpu = gpu();
    let filters = [
        PixelFilter::MITSUBA_DEFAULT,
        PixelFilter::Lanczos { lobes: 3 },
    ];
    let cases = [("graphs/pt.ron", 4, 0.0), ("graphs/hybrid.ron", 3, 1e-5)];
    for (filter, (graph, spp, tolerance)) in filters
        .into_iter()
        .flat_map(|f| cases.into_iter().map(move |c| (f, c)))
    {
        let scene = splatting_scene(filter);
        let mut whole_renderer = banded(&gpu, &scene, graph, 1);
        let whole = render_to(&mut whole_renderer, spp);
        for bands in [2, 5] {
            let mut r = banded(&gpu, &scene, graph, bands);
            assert_eq!(r.bands(), bands as usize);
            let image = render_to(&mut r, spp);
            let difference = max_difference(&image, &whole);
            eprintln!(
                "{filter:?}, {graph}, {bands} bands: largest pixel difference {difference:e}"
            );
            assert!(
                difference <= tolerance,
                "{filter:?}, {graph} in {bands} bands differs from the whole image by {difference}"
            );
            assert_eq!(
                r.photons_per_iteration(),
                whole_renderer.photons_per_iteration()
            );
        }
    }
}

/// A banded render's checkpoint holds every band's state and resumes to the uninterrupted
/// image; its shard terms are the whole image's. Would catch bands whose state overwrote one
/// another (one name for all) or terms that kept only the first band.
#[test]
fn a_banded_render_resumes_and_shards_as_a_whole_one() {
    let gpu = gpu();
    let scene = splatting_scene(PixelFilter::MITSUBA_DEFAULT);
    let graph = "graphs/hybrid_pppm.ron";
    let run = |r: &mut Renderer<'_>, spp: u64| {
        let budget = Budget {
            spp: Some(spp),
            ..Default::default()
        };
        r.run(budget, &AtomicBool::new(false), |_, _| {})
            .unwrap_or_else(|e| panic!("render: {e}"));
    };
    let mut straight = banded(&gpu, &scene, graph, 3);
    run(&mut straight, 4);
    let mut first = banded(&gpu, &scene, graph, 3);
    run(&mut first, 2);
    let state = first.read_state().expect("state");
    assert!(state.iter().any(|(name, _)| name.starts_with("band2/")));
    let mut resumed = banded(&gpu, &scene, graph, 3);
    resumed.restore_state(2, &state).expect("restore");
    run(&mut resumed, 4);
    let difference = max_difference(
        &resumed.image().expect("image"),
        &straight.image().expect("image"),
    );
    assert!(difference <= 1e-5, "resumed differs by {difference}");

    let mut whole = banded(&gpu, &scene, graph, 1);
    run(&mut whole, 4);
    // The error estimate's halves are kept per band and put together as the image is.
    let estimate = |r: &Renderer<'_>| {
        r.error_estimate()
            .expect("estimate")
            .expect("two iterations")
            .relmse
    };
    let (banded_estimate, whole_estimate) = (estimate(&straight), estimate(&whole));
    assert!(
        (banded_estimate - whole_estimate).abs() <= 1e-3 * whole_estimate,
        "estimated relMSE {banded_estimate} in bands, {whole_estimate} whole"
    );
    let terms = straight.read_terms().expect("terms");
    let whole_terms = whole.read_terms().expect("terms");
    assert_eq!(terms.len(), whole_terms.len());
    for ((name, sums), (whole_name, whole_sums)) in terms.iter().zip(&whole_terms) {
        assert_eq!(name, whole_name);
        assert_eq!(sums.len(), (SIZE.0 * SIZE.1) as usize);
        let worst = sums
            .iter()
            .zip(whole_sums)
            .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs() / b[c].abs().max(1.0)))
            .fold(0.0f32, f32::max);
        assert!(worst <= 1e-5, "term {name} differs by {worst}");
    }
}
