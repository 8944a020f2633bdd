//! The hybrid as a whole: graphs render what path tracing renders, and caustics path tracing
//! cannot, against Mitsuba references.

mod common;

use common::*;

#[test]
fn explore() {
    let gpu = gpu();
    let scene_file = "tests/refs/scenes/point_light_caustic/scene.xml";
    let scene = load_scene(scene_file);
    let reference = reference("point_light_caustic_composite");
    let mask = reference_mask();
    for graph in ["graphs/pt.ron", "graphs/hybrid.ron", "graphs/ppm_only.ron"] {
        let mut r = renderer(&gpu, &scene, load_graph(graph), 3);
        let t = std::time::Instant::now();
        for spp in [4, 16, 64, 128] {
            let img = render_to(&mut r, spp);
            let m = img.relmse_where(&reference, |i| mask[i]).unwrap();
            let caustic_err = img
                .relmse_where(&reference, |i| mask[i] && reference.pixels[i][0] > 1.0)
                .unwrap();
            eprintln!(
                "{graph} {spp}: masked {m:.5} bright {caustic_err:.5} {:.1}s",
                t.elapsed().as_secs_f64()
            );
        }
    }
}

fn reference_mask() -> Vec<bool> {
    let specular = reference("point_light_caustic_primary_specular");
    specular
        .pixels
        .iter()
        .map(|p| p.iter().all(|&c| c == 0.0))
        .collect()
}
