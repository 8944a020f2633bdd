//! The `minnaert` BSDF, registered from outside hppm, is read, checked and rendered like a
//! built-in one, on lavapipe (or `HPPM_TEST_ADAPTER`).

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use custom_bsdf::{Minnaert, PLUGIN, registry};
use glam::Vec3;
use hppm::gpu::GpuContext;
use hppm::image::Image;
use hppm::passes::Registry;
use hppm::render::{Budget, Renderer};
use hppm::scene::Scene;
use hppm::scene::bsdf::Bsdf;
use hppm::testing::bsdf::{Rng, chi_square, furnace, gpu_against_cpu, incident_directions};

fn here(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

fn gpu() -> GpuContext {
    let choice = std::env::var("HPPM_TEST_ADAPTER").ok();
    GpuContext::new(choice.as_deref()).unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

/// A scene of one sphere per BSDF snippet, read with `registry`'s BSDFs.
fn spheres(registry: &Registry, bsdfs: &[&str]) -> Result<Scene, hppm::scene::SceneError> {
    let shapes: String = bsdfs
        .iter()
        .enumerate()
        .map(|(i, b)| {
            format!(
                "<shape type=\"sphere\"><point name=\"center\" x=\"{i}\" y=\"0\" z=\"0\"/>\
                 <float name=\"radius\" value=\"0.4\"/>{b}</shape>"
            )
        })
        .collect();
    let xml = format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n{shapes}\n\
         <emitter type=\"constant\"/></scene>"
    );
    let path = Path::new("minnaert_test.xml");
    hppm::loaders::mitsuba::check_text_with(path, &xml, &[], registry.bsdfs()).into_result()
}

fn model(bsdf: &Bsdf) -> Minnaert {
    *bsdf.get::<Minnaert>().expect("a minnaert model")
}

/// It is read from Mitsuba XML by its plugin name, with hppm's errors at file:line:col and its
/// did-you-mean; hppm's own registry does not know it. Would catch the unit not reached by the
/// loader's dispatch, a property read wrong, or errors without their place.
#[test]
fn minnaert_is_read_from_mitsuba_xml_by_its_name() {
    let registry = registry();
    let scene = spheres(
        &registry,
        &[
            r#"<bsdf type="minnaert"><rgb name="reflectance" value="0.2, 0.4, 0.6"/><float name="k" value="2.5"/></bsdf>"#,
            r#"<bsdf type="minnaert"/>"#,
            r#"<bsdf type="minnaert"><texture name="reflectance" type="checkerboard"/></bsdf>"#,
        ],
    )
    .expect("loads");
    let m: Vec<Minnaert> = scene.materials.iter().map(|m| model(&m.bsdf)).collect();
    assert_eq!(m[0].reflectance, Vec3::new(0.2, 0.4, 0.6));
    assert_eq!(m[0].k, 2.5);
    assert_eq!((m[1].reflectance, m[1].k), (Vec3::splat(0.5), 1.0));
    assert!(scene.materials[2].textures.front.diffuse.is_some());
    assert_eq!(scene.features().bsdfs, vec!["minnaert"]);

    let error = |bsdf: &str| spheres(&registry, &[bsdf]).expect_err(bsdf).to_string();
    let low = error(r#"<bsdf type="minnaert"><float name="k" value="0.5"/></bsdf>"#);
    assert!(
        low.starts_with("minnaert_test.xml:3:") && low.contains("at least 1"),
        "{low}"
    );
    let typo = error(r#"<bsdf type="minnaert"><float name="kk" value="2"/></bsdf>"#);
    assert!(typo.contains("did you mean \"k\""), "{typo}");
    let builtin = spheres(&Registry::builtin(), &[r#"<bsdf type="minnaert"/>"#])
        .expect_err("hppm alone has no minnaert")
        .to_string();
    assert!(
        builtin.contains("bsdf type \"minnaert\" is not supported"),
        "{builtin}"
    );
}

/// hppm's source never names it: the loader's dispatch, the kind number, the WGSL constant and
/// dispatch entry all come from the registry it was added to. Would catch a special case for it
/// slipped into hppm.
#[test]
fn hppm_never_names_minnaert() {
    let mut named = Vec::new();
    for dir in ["src", "shaders"] {
        let mut pending = vec![here("../..").join(dir)];
        while let Some(path) = pending.pop() {
            if path.is_dir() {
                for entry in std::fs::read_dir(&path).expect("dir").flatten() {
                    pending.push(entry.path());
                }
            } else if let Ok(text) = std::fs::read_to_string(&path)
                && text.to_ascii_lowercase().contains("minnaert")
            {
                named.push(path.display().to_string());
            }
        }
    }
    assert!(named.is_empty(), "hppm names minnaert in {named:?}");
    let generated = registry().bsdfs().dispatch_wgsl();
    assert!(
        generated.contains("if m.kind == MATERIAL_MINNAERT"),
        "{generated}"
    );
    assert_eq!(PLUGIN.kinds[0].constant(), "MATERIAL_MINNAERT");
}

/// Its WGSL, reached through hppm's generated dispatch, gives its CPU model's eval, pdf and
/// sample on 600 random direction pairs per variant (k 1, 2.5 and 8; radiance and importance):
/// every eval within 0.2%, at most 0.5% of samples off by rounding. Would catch a slot of the
/// GPU record read wrong (k from another field), an exponent off by one, a sampler that maps
/// random numbers differently.
#[test]
fn minnaert_wgsl_matches_its_cpu_model() {
    let gpu = gpu();
    let registry = registry();
    let scene = spheres(
        &registry,
        &[
            r#"<bsdf type="minnaert"><rgb name="reflectance" value="0.9, 0.5, 0.1"/></bsdf>"#,
            r#"<bsdf type="minnaert"><rgb name="reflectance" value="0.3, 0.6, 0.9"/><float name="k" value="2.5"/></bsdf>"#,
            r#"<bsdf type="minnaert"><float name="k" value="8"/></bsdf>"#,
        ],
    )
    .expect("loads");
    let report = gpu_against_cpu(&gpu, &registry, &scene, 600, 2e-3, &mut Rng(17)).expect("kernel");
    assert_eq!(report.evals, 1800);
    assert!(
        report.eval_failures.is_empty(),
        "{} evals differ:\n{}",
        report.eval_failures.len(),
        report.eval_failures.join("\n")
    );
    assert!(report.samples_compared > report.queries / 2);
    assert!(
        report.sample_mismatches * 200 <= report.queries,
        "{} of {} samples differ",
        report.sample_mismatches,
        report.queries
    );
}

/// Its sampler draws what its pdf says (chi-square over 20 x 40 cells, 200,000 samples per
/// incident direction, z under 5) and its white furnace is the closed form: albedo cos^(k-1)
/// of the incident angle (within 4 standard errors), equal to the integral of its eval. Would
/// catch a pdf or a weight that is not eval / pdf, and energy made or lost.
#[test]
fn minnaert_samples_its_pdf_and_keeps_its_energy() {
    let mut rng = Rng(5);
    for k in [1.0f32, 2.5, 8.0] {
        let bsdf = Bsdf::new(Minnaert {
            reflectance: Vec3::ONE,
            k,
        });
        for wi in incident_directions(false) {
            let chi = chi_square(&bsdf, wi, 200_000, &mut rng);
            assert!(chi.z < 5.0, "k {k}, wi {wi}: {chi:?}");
            let f = furnace(&bsdf, wi, 100_000, &mut rng);
            let expected = (wi.z as f64).powf(k as f64 - 1.0);
            let (a, i) = (f.albedo, f.eval_integral);
            assert!(
                (a.mean - expected).abs() <= 4.0 * a.error + 1e-6,
                "k {k}, wi {wi}: albedo {a:?}, expected {expected}"
            );
            assert!(
                (i.mean - expected).abs() <= 4.0 * i.error,
                "k {k}, wi {wi}: eval integrates to {i:?}, expected {expected}"
            );
        }
    }
}

fn render(scene: &Scene, graph: &str, spp: u64, seed: u64) -> Image {
    let gpu = gpu();
    let registry = registry();
    let graph = registry.bundled_graph(graph).expect("graph");
    let mut renderer = Renderer::builder(&gpu, scene, graph)
        .registry(registry)
        .seed(seed)
        .build()
        .expect("prepare");
    let budget = Budget {
        spp: Some(spp),
        ..Budget::default()
    };
    renderer
        .run(budget, &AtomicBool::new(false), |_, _| {})
        .expect("render");
    renderer.image().expect("image")
}

fn load(relative: &str) -> Scene {
    let path = here(relative);
    hppm::loaders::load_reporting(&path, &[], registry().bsdfs(), |_| {}).expect("scene")
}

/// The furnace scene's expected image: a Minnaert sphere of radius 1 at the origin seen from 4
/// units away with a 40 degree field of view, under a sky of radiance 1. A convex body only sees
/// the sky, so a point whose normal makes cosine c with the view reflects reflectance c^(k-1);
/// each pixel is the mean of that (or 1 for the sky) over 16 x 16 points of its area (a box
/// filter), by ray-sphere intersection.
fn furnace_image(size: u32, reflectance: Vec3, k: f32) -> Vec<Vec3> {
    let half = (20f32).to_radians().tan();
    let origin = Vec3::new(0.0, 0.0, 4.0);
    let sub = 16;
    let mut pixels = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let mut sum = Vec3::ZERO;
            for j in 0..sub {
                for i in 0..sub {
                    let u = (x as f32 + (i as f32 + 0.5) / sub as f32) / size as f32;
                    let v = (y as f32 + (j as f32 + 0.5) / sub as f32) / size as f32;
                    let dir =
                        Vec3::new((2.0 * u - 1.0) * half, (1.0 - 2.0 * v) * half, -1.0).normalize();
                    let b = origin.dot(dir);
                    let disc = b * b - (origin.length_squared() - 1.0);
                    sum += if disc > 0.0 {
                        let t = -b - disc.sqrt();
                        let normal = origin + t * dir;
                        reflectance * normal.dot(-dir).max(0.0).powf(k - 1.0)
                    } else {
                        Vec3::ONE
                    };
                }
            }
            pixels.push(sum / (sub * sub) as f32);
        }
    }
    pixels
}

/// `pt` and the hybrid render the furnace scene to its closed form: in each of five rings
/// around the sphere's centre (the image is radially symmetric), the mean of two renders (256
/// spp each, two seeds) is within 4 standard errors (estimated from the two renders'
/// difference) plus 0.2% of the expected mean. Would catch the kind dispatched to the wrong
/// WGSL, k or the reflectance read from the wrong slot, a limb darkening of the wrong
/// exponent, or a graph that does not render the custom kind at all.
#[test]
fn furnace_renders_match_the_closed_form() {
    let scene = load("scenes/minnaert_furnace.xml");
    let size = scene.camera.width;
    let expected = furnace_image(size, Vec3::new(0.9, 0.6, 0.3), 3.0);
    let ring = |i: usize| {
        let (x, y) = (
            (i as u32 % size) as f32 + 0.5,
            (i as u32 / size) as f32 + 0.5,
        );
        let r = ((x - size as f32 / 2.0).powi(2) + (y - size as f32 / 2.0).powi(2)).sqrt();
        ((r / (size as f32 / 2.0)) * 5.0).min(4.0) as usize
    };
    for graph in ["pt", "hybrid"] {
        let (a, b) = (render(&scene, graph, 256, 1), render(&scene, graph, 256, 2));
        for r in 0..5 {
            let (mut sum, mut want, mut diff2, mut n) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for (i, e) in expected.iter().enumerate().filter(|(i, _)| ring(*i) == r) {
                for c in 0..3 {
                    let (pa, pb) = (a.pixels[i][c] as f64, b.pixels[i][c] as f64);
                    sum += 0.5 * (pa + pb);
                    want += e[c] as f64;
                    diff2 += (pa - pb).powi(2);
                    n += 1.0;
                }
            }
            let error = (diff2 / n / 4.0 / n).sqrt();
            let (got, want) = (sum / n, want / n);
            assert!(
                (got - want).abs() <= 4.0 * error + 2e-3 * want,
                "{graph}, ring {r}: mean {got:.5} against {want:.5} (+- {error:.2e})"
            );
        }
    }
}

/// On a scene where a glass sphere focuses light onto a diffuse wall and a Minnaert floor, the
/// hybrid (photons for the wall's caustic, path tracing for the floor's) and `pt` agree in each
/// of 16 blocks of 8 x 8 pixels: the means over three seeds of 128 spp each differ by at most 4
/// standard errors (from the seeds' spread) plus 3% (the photon kernel's blur across block
/// edges). Would catch the custom kind counted twice or dropped by the partition, or not
/// rendered by one of the graphs.
#[test]
fn hybrid_equals_pt_with_a_minnaert_floor() {
    let scene = load("scenes/minnaert_glass.xml");
    let size = scene.camera.width as usize;
    let block = |i: usize| (i % size) / 8 + 4 * ((i / size) / 8);
    let means = |graph: &str| {
        let renders: Vec<Image> = (0..3)
            .map(|seed| render(&scene, graph, 128, seed))
            .collect();
        (0..16)
            .map(|b| {
                let per_seed: Vec<f64> = renders
                    .iter()
                    .map(|img| {
                        let values = img
                            .pixels
                            .iter()
                            .enumerate()
                            .filter(|(i, _)| block(*i) == b);
                        let n = 3.0 * 64.0;
                        values
                            .map(|(_, p)| (p[0] + p[1] + p[2]) as f64)
                            .sum::<f64>()
                            / n
                    })
                    .collect();
                let mean = per_seed.iter().sum::<f64>() / 3.0;
                let var = per_seed.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 2.0;
                (mean, (var / 3.0).sqrt())
            })
            .collect::<Vec<_>>()
    };
    let (pt, hybrid) = (means("pt"), means("hybrid"));
    for (b, ((p, pe), (h, he))) in pt.iter().zip(&hybrid).enumerate() {
        assert!(
            (p - h).abs() <= 4.0 * (pe * pe + he * he).sqrt() + 0.03 * p,
            "block {b}: pt {p:.4} +- {pe:.4}, hybrid {h:.4} +- {he:.4}"
        );
    }
}
