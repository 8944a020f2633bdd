//! Participating media: the phase functions against their closed forms (CPU), light through an
//! absorbing medium against Beer-Lambert's law (GPU, `pt`), the shader defs that leave medium
//! code out of scenes without media, and photon mapping alone refused on a scene with media.
//! The renders against Mitsuba's `volpath` references are tests/media_refs.rs.

mod common;

use std::path::Path;

use common::*;
use glam::{Vec2, Vec3};
use hppm::scene::medium::Phase;

const PHASES: [Phase; 5] = [
    Phase::Isotropic,
    Phase::HenyeyGreenstein { g: 0.9 },
    Phase::HenyeyGreenstein { g: -0.4 },
    Phase::HenyeyGreenstein { g: 0.0 },
    Phase::Rayleigh,
];

/// Each phase function integrates to 1 over the sphere (midpoint rule in cos theta, which is all
/// they depend on), and HG's mean cosine is its g: a missing 1/(4 pi), a squared term off or
/// the asymmetry's sign turned fails.
#[test]
fn phase_functions_are_normalised_with_their_mean_cosine() {
    let d_in = Vec3::new(0.3, -0.5, 0.8).normalize();
    let (b1, _) = d_in.any_orthonormal_pair();
    let steps = 200_000;
    for phase in PHASES {
        let (mut total, mut mean_cos) = (0.0f64, 0.0f64);
        for i in 0..steps {
            let cos = -1.0 + 2.0 * (i as f32 + 0.5) / steps as f32;
            let wo = d_in * cos + b1 * (1.0 - cos * cos).max(0.0).sqrt();
            // The ring of directions at this cosine has solid angle 2 pi d(cos).
            let p = phase.eval(d_in, wo) as f64 * 2.0 * std::f64::consts::PI * 2.0 / steps as f64;
            total += p;
            mean_cos += p * cos as f64;
        }
        assert!(
            (total - 1.0).abs() < 1e-4,
            "{phase:?} integrates to {total}"
        );
        let expected = match phase {
            Phase::HenyeyGreenstein { g } => g as f64,
            _ => 0.0,
        };
        assert!(
            (mean_cos - expected).abs() < 2e-3,
            "{phase:?}: mean cosine {mean_cos}, expected {expected}"
        );
    }
}

/// Sampling draws the density eval gives: a chi-square test of the sampled cosines in 40 bins
/// against eval's integral over each (2 pi times it in cos), 200,000 samples each, and the
/// samples' azimuth uniform about the travel direction. An inverted CDF off by a term, or a
/// sample about the wrong axis, fails by hundreds of standard deviations.
#[test]
fn phase_sampling_draws_the_phase_functions_density() {
    let d_in = Vec3::new(-0.2, 0.9, 0.1).normalize();
    let (b1, b2) = d_in.any_orthonormal_pair();
    let mut rng = common::rng::Rng(0x9e37_79b9_7f4a_7c15);
    let (bins, n) = (40usize, 200_000usize);
    for phase in PHASES {
        let mut counts = vec![0usize; bins];
        let mut quadrants = [0usize; 4];
        for _ in 0..n {
            let wo = phase.sample(d_in, Vec2::new(rng.unit(), rng.unit()));
            assert!((wo.length() - 1.0).abs() < 1e-4);
            let cos = d_in.dot(wo).clamp(-1.0, 1.0);
            counts[(((cos + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1)] += 1;
            let (x, y) = (wo.dot(b1), wo.dot(b2));
            quadrants[(x >= 0.0) as usize * 2 + (y >= 0.0) as usize] += 1;
        }
        let mut chi2 = 0.0f64;
        for (b, &count) in counts.iter().enumerate() {
            let fine = 200;
            let mut p = 0.0f64;
            for k in 0..fine {
                let cos = -1.0 + 2.0 * (b as f32 + (k as f32 + 0.5) / fine as f32) / bins as f32;
                let wo = d_in * cos + b1 * (1.0 - cos * cos).max(0.0).sqrt();
                p += phase.eval(d_in, wo) as f64 * 2.0 * std::f64::consts::PI * 2.0
                    / (bins * fine) as f64;
            }
            let expected = p * n as f64;
            if expected > 0.0 {
                chi2 += (count as f64 - expected).powi(2) / expected;
            }
        }
        // 39 degrees of freedom: mean 39, standard deviation 8.8; 5 standard deviations.
        assert!(chi2 < 39.0 + 5.0 * 8.8, "{phase:?}: chi-square {chi2:.1}");
        for q in quadrants {
            let share = q as f64 / n as f64;
            assert!(
                (share - 0.25).abs() < 0.006,
                "{phase:?}: azimuth quadrants {quadrants:?}"
            );
        }
    }
}

/// A scene for the Beer-Lambert checks: a camera with a 2 degree view looking down -z at an
/// emitting rectangle (radiance 1) at z = -3, behind `between` (shapes, media).
fn beer_lambert_scene(sensor_medium: &str, between: &str) -> hppm::scene::Scene {
    let text = format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
    <sensor type="perspective"><float name="fov" value="2"/>
        <transform name="to_world"><lookat origin="0, 0, 10" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/><rfilter type="box"/></film>
        {sensor_medium}
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5"/><translate z="-3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
    {between}
</scene>"#
    );
    hppm::loaders::mitsuba::parse(Path::new("beer_lambert.xml"), &text)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The image's mean per channel against `expected`, within 4.5 standard errors of the mean
/// (from the pixels' spread: each pixel is an independent estimate) plus 0.1%, and that bound
/// tighter than a 5% error.
fn assert_mean_is(label: &str, image: &hppm::image::Image, expected: Vec3) {
    let n = image.pixels.len() as f64;
    let mean = image.mean();
    for c in 0..3 {
        let var = image
            .pixels
            .iter()
            .map(|p| (p[c] as f64 - mean[c]).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        let se = (var / n).sqrt();
        let tolerance = 4.5 * se + 1e-3 * expected[c] as f64;
        eprintln!(
            "{label}, channel {c}: {:.5} expected {:.5} (tolerance {tolerance:.5})",
            mean[c], expected[c]
        );
        assert!(
            tolerance < 0.05 * expected[c] as f64,
            "{label}: too noisy to judge"
        );
        assert!(
            (mean[c] - expected[c] as f64).abs() <= tolerance,
            "{label}, channel {c}: {} against Beer-Lambert's {}",
            mean[c],
            expected[c]
        );
    }
}

/// Light crossing a purely absorbing medium (albedo 0) arrives dimmed by exp(-sigma_t d), per
/// colour: through a null-bounded cube 2 units deep (sigma_t 0.25, 0.5, 1: extinction that
/// differs per channel, which the free-flight sampler's MIS over channels must weigh right),
/// and with the camera inside an unbounded medium 13 units from the light. The view is 2
/// degrees wide, so the path lengths differ from the axis' by under 0.02%. A missing
/// transmittance, one channel's extinction used for all, a medium entered on the wrong side of
/// its boundary, or the sensor's medium ignored fails.
#[test]
fn light_through_an_absorbing_medium_obeys_beer_lambert() {
    let gpu = gpu();
    let sigma = Vec3::new(0.25, 0.5, 1.0);
    let absorber = r#"<medium type="homogeneous" id="ink"><rgb name="albedo" value="0"/><rgb name="sigma_t" value="0.25, 0.5, 1"/></medium>"#;
    let cube = format!(
        r#"{absorber}<shape type="cube"><bsdf type="null"/><ref name="interior" id="ink"/></shape>"#
    );
    let slab = beer_lambert_scene("", &cube);
    let mut r = renderer(&gpu, &slab, load_graph("graphs/pt.ron"), 1);
    assert_mean_is("cube", &render_to(&mut r, 256), (-sigma * 2.0).exp());

    let around = beer_lambert_scene(
        r#"<medium type="homogeneous"><rgb name="albedo" value="0"/><rgb name="sigma_t" value="0.025, 0.05, 0.1"/></medium>"#,
        "",
    );
    let mut r = renderer(&gpu, &around, load_graph("graphs/pt.ron"), 2);
    assert_mean_is(
        "sensor medium",
        &render_to(&mut r, 256),
        (-sigma * 0.1 * 13.0).exp(),
    );
}

/// Medium code is compiled only into scenes that have media: the MEDIA def is set exactly
/// when some shape or the sensor has a medium.
#[test]
fn only_scenes_with_media_compile_medium_code() {
    let bsdfs = hppm::bsdfs::BsdfRegistry::builtin();
    let defs = |scene: &hppm::scene::Scene| hppm::passes::scene_defs(&scene.features(), &bsdfs);
    let plain = load_scene("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    assert!(!defs(&plain).contains_key("MEDIA"));
    let foggy = load_scene("tests/refs/media/scenes/absorbing_glass/scene.xml");
    assert!(defs(&foggy).contains_key("MEDIA"));
    let camera = beer_lambert_scene(r#"<medium type="homogeneous"/>"#, "");
    assert!(defs(&camera).contains_key("MEDIA"));
}

/// Photon mapping alone (photons deposited at every diffuse vertex) would miss the light that
/// scatters in media; it refuses such a scene rather than render it dark.
#[test]
fn photon_mapping_alone_refuses_media() {
    let gpu = gpu();
    let scene = load_scene("tests/refs/media/scenes/absorbing_glass/scene.xml");
    let graph = load_graph("graphs/ppm_only.ron");
    let error = match hppm::render::Renderer::new(&gpu, &scene, graph, 16, 16, 0) {
        Ok(_) => panic!("photon mapping alone rendered a scene with media"),
        Err(e) => e.to_string(),
    };
    assert!(error.contains("participating media"), "{error}");
}

/// Where the fog scenes' camera stands: its max_depth, height above the origin (it looks down
/// -z with a half-degree view) and film width.
struct FogView {
    max_depth: u32,
    eye_height: f64,
    width: u32,
}

/// A homogeneous HG medium around the camera, lit by a point light, with `more` (shapes) in it.
fn fog_around_the_camera(
    name: &str,
    view: FogView,
    (sigma_t, albedo, g): ([f64; 3], f64, f64),
    (light, intensity): ([f64; 3], f64),
    more: &str,
) -> hppm::scene::Scene {
    let FogView {
        max_depth,
        eye_height: y,
        width,
    } = view;
    let [s0, s1, s2] = sigma_t;
    let [lx, ly, lz] = light;
    let text = format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="{max_depth}"/></integrator>
    <sensor type="perspective"><float name="fov" value="0.5"/>
        <transform name="to_world"><lookat origin="0, {y}, 0" target="0, {y}, -1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{width}"/><rfilter type="box"/></film>
        <medium type="homogeneous"><rgb name="sigma_t" value="{s0}, {s1}, {s2}"/><float name="albedo" value="{albedo}"/>
            <phase type="hg"><float name="g" value="{g}"/></phase></medium>
    </sensor>
    <emitter type="point"><point name="position" x="{lx}" y="{ly}" z="{lz}"/><rgb name="intensity" value="{intensity}"/></emitter>
    {more}
</scene>"#
    );
    hppm::loaders::mitsuba::parse(Path::new(name), &text).unwrap_or_else(|e| panic!("{e}"))
}

/// Single scattering from a point light in a medium all around the camera (max_depth 2:
/// one scattering vertex), against the line integral along the view axis, computed here:
/// L = integral over t of sigma_s p(cos) I Tr(t) Tr(d) / d^2, d the distance from the point at
/// t to the light, p Henyey-Greenstein with g 0.5 (forward scattering: the light behind the
/// scattering point, towards the camera, dominates). The view is half a degree wide, so
/// across it the integral changes only to second order. A phase function turned around
/// (g taken as -g), a transmittance left out on either leg, sigma_s taken as sigma_t or the
/// light's falloff lost fails by far more than the tolerance.
#[test]
fn single_scattering_from_a_point_light_matches_its_line_integral() {
    let sigma_t = [0.2f64, 0.4, 0.6];
    let albedo = 0.8f64;
    let g = 0.5f64;
    let intensity = 5.0f64;
    let light = [0.0f64, 1.0, -2.0];
    let scene = fog_around_the_camera(
        "single_scattering.xml",
        FogView {
            max_depth: 2,
            eye_height: 0.0,
            width: 8,
        },
        (sigma_t, albedo, g),
        (light, intensity),
        "",
    );
    let mut expected = Vec3::ZERO;
    for c in 0..3 {
        expected[c] = line_integral(0.0, light, sigma_t[c], albedo, g, intensity, None) as f32;
    }
    let gpu = gpu();
    let mut r = renderer(&gpu, &scene, load_graph("graphs/pt.ron"), 3);
    assert_mean_is("single scattering", &render_to(&mut r, 1024), expected);
}

/// The volumetric caustic only photons can render: a point light over a mirror in fog, seen by
/// a camera whose paths never meet the mirror (max_depth 3). Light scattered once after the
/// mirror (L S M E) is the single scattering of the light's mirror image, whose line integral
/// is computed here as above (the mirror's 20 x 20 extent bounding where it reflects); path
/// tracing cannot reach a point light through a mirror, so the hybrid's image minus `pt`'s with
/// the same seeds (the same camera paths) is exactly the photons' share. Over 12 seeds it must
/// equal the integral within 4 standard errors plus 3% (the photon grid's kernel): photons
/// stored at the wrong density, with the phase function turned around, not gathered at medium
/// vertices (0) or counted twice (2x) fail.
#[test]
fn photons_render_the_volumetric_caustic_of_a_point_light_over_a_mirror() {
    let sigma_t = [0.2f64, 0.3, 0.4];
    let (albedo, g, intensity) = (0.8f64, 0.3f64, 5.0f64);
    let mirror = r#"<shape type="rectangle">
        <transform name="to_world"><scale value="10"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="conductor"><string name="material" value="none"/></bsdf>
    </shape>"#;
    let scene = fog_around_the_camera(
        "mirror_in_fog.xml",
        FogView {
            max_depth: 3,
            eye_height: 0.5,
            width: 32,
        },
        (sigma_t, albedo, g),
        ([0.0, 1.0, -3.0], intensity),
        mirror,
    );
    // The light's mirror image below the plane y = 0, seen through the 20 x 20 mirror.
    let image = [0.0f64, -1.0, -3.0];
    let expected =
        sigma_t.map(|sigma| line_integral(0.5, image, sigma, albedo, g, intensity, Some(10.0)));
    let runs = common::convergence::paired_means("graphs/hybrid.ron", &scene, 512, 12);
    let n = runs.len() as f64;
    for (c, &integral) in expected.iter().enumerate() {
        let shares: Vec<f64> = runs.iter().map(|r| (r.1[c] - r.0[c]) / integral).collect();
        let mean = shares.iter().sum::<f64>() / n;
        let se = (shares.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let tolerance = 4.0 * se + 0.03;
        eprintln!(
            "channel {c}: hybrid - pt over the integral {mean:.4} +- {se:.4} (expected {:.5}, \
             tolerance {tolerance:.4}), per seed {shares:.3?}",
            integral
        );
        assert!(
            tolerance < 0.25,
            "too noisy to tell a missing or doubled caustic"
        );
        assert!(
            (mean - 1.0).abs() <= tolerance,
            "channel {c}: the photons' volumetric caustic is {mean:.3} of its integral"
        );
    }
}

/// A grid medium's scene: the emitter of `beer_lambert_scene`'s kind behind a null cube
/// [-1, 1]^3 holding a heterogeneous medium whose extinction is `file` (a .vol grid stretched
/// over the cube) times `scale`, seen from z = 50 by a `width` x 4 film spanning x in
/// [-0.9, 0.9] at z = 0.
fn grid_scene(file: &str, scale: f32, albedo: f32, width: u32) -> hppm::scene::Scene {
    let fov = 2.0 * (0.9f32 / 50.0).atan().to_degrees();
    let text = format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
    <sensor type="perspective"><float name="fov" value="{fov}"/>
        <transform name="to_world"><lookat origin="0, 0, 50" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="4"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5"/><translate z="-3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
    <medium type="heterogeneous" id="smoke">
        <volume type="gridvolume" name="sigma_t"><string name="filename" value="{file}"/>
            <transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform></volume>
        <float name="scale" value="{scale}"/><float name="albedo" value="{albedo}"/>
    </medium>
    <shape type="cube"><bsdf type="null"/><ref name="interior" id="smoke"/></shape>
</scene>"#
    );
    hppm::loaders::mitsuba::parse(&repo_path("grid_medium.xml"), &text)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Light through an absorbing grid medium (albedo 0) is dimmed by exp(-integral of sigma_t)
/// along each ray: the grid (tests/data/volumes/ramp.vol, 0.5 in its left cells and 1.5 in its
/// right ones, so trilinear lookups ramp between the cell centres and are flat past them) varies
/// along x only, so each column of the film sees exp(-2 sigma(x)), averaged here over the
/// column's span with the CPU grid's lookup (tests/vol_grid.rs holds that to Mitsuba's). Per
/// block of 8 columns within 4.5 standard errors plus 0.5%: a GPU lookup off by half a cell,
/// the grid's placement mirrored or unscaled, or tracking that is biased (a majorant below the
/// grid's values, a null collision weighted wrong) fails.
#[test]
fn light_through_an_absorbing_grid_obeys_beer_lambert_per_column() {
    let width = 64u32;
    let scene = grid_scene("tests/data/volumes/ramp.vol", 1.0, 0.0, width);
    let grid = hppm::loaders::vol::read_vol(&repo_path("tests/data/volumes/ramp.vol"))
        .unwrap_or_else(|e| panic!("{e}"));
    let gpu = gpu();
    let mut r = renderer(&gpu, &scene, load_graph("graphs/pt.ron"), 5);
    let image = render_to(&mut r, 1024);
    let columns_per_block = 8u32;
    for block in 0..width / columns_per_block {
        let values: Vec<f64> = (0..image.height)
            .flat_map(|y| {
                (block * columns_per_block..(block + 1) * columns_per_block).map(move |x| (x, y))
            })
            .map(|(x, y)| image.pixels[(y * width + x) as usize][0] as f64)
            .collect();
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let se = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let (lo, hi) = (
            -0.9 + 1.8 * (block * columns_per_block) as f64 / width as f64,
            -0.9 + 1.8 * ((block + 1) * columns_per_block) as f64 / width as f64,
        );
        let steps = 1000;
        let expected = (0..steps)
            .map(|i| {
                let x = lo + (hi - lo) * (i as f64 + 0.5) / steps as f64;
                let sigma = grid
                    .eval(glam::Vec3::new(((x + 1.0) / 2.0) as f32, 0.5, 0.5))
                    .x;
                (-2.0 * sigma as f64).exp()
            })
            .sum::<f64>()
            / steps as f64;
        let tolerance = 4.5 * se + 0.005 * expected;
        eprintln!(
            "x in [{lo:.3}, {hi:.3}]: {mean:.5} expected {expected:.5} (tolerance {tolerance:.5})"
        );
        assert!(
            (mean - expected).abs() <= tolerance,
            "x in [{lo}, {hi}]: {mean} through the grid, Beer-Lambert {expected}"
        );
    }
}

/// A grid of constant values is the homogeneous medium of that extinction: the same scene with
/// a scattering (albedo 0.8) grid medium of 2x2x2 cells of 1 (tests/data/volumes, written here)
/// times 1.5, and with a homogeneous sigma_t 1.5, have the same image mean within 4.5 standard
/// errors of their difference. Real and null collisions weighted wrong, or the grid's
/// scattering left out, fail; it checks the heterogeneous path against the homogeneous one,
/// which the other tests hold to closed forms.
#[test]
fn a_constant_grid_renders_as_the_homogeneous_medium() {
    let dir = std::env::temp_dir().join(format!("hppm_const_grid_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("ones.vol");
    let ones = hppm::scene::grid::Grid::new([2, 2, 2], 1, vec![1.0; 8]);
    hppm::loaders::vol::write_vol(&file, &ones).expect("write ones.vol");
    let gpu = gpu();
    let mut means = Vec::new();
    let grid = grid_scene(&file.to_string_lossy(), 1.5, 0.8, 32);
    let mut homogeneous = grid.clone();
    for m in &mut homogeneous.media.list {
        m.density = None;
    }
    for (label, scene) in [("grid", &grid), ("homogeneous", &homogeneous)] {
        let mut r = renderer(&gpu, scene, load_graph("graphs/pt.ron"), 9);
        let image = render_to(&mut r, 512);
        let n = image.pixels.len() as f64;
        let mean = image.mean()[1];
        let var = image
            .pixels
            .iter()
            .map(|p| (p[1] as f64 - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        eprintln!("{label}: mean {mean:.5} +- {:.5}", (var / n).sqrt());
        means.push((mean, var / n));
    }
    let diff = means[0].0 - means[1].0;
    let se = (means[0].1 + means[1].1).sqrt();
    assert!(4.5 * se < 0.05 * means[1].0, "too noisy to tell");
    assert!(
        diff.abs() <= 4.5 * se,
        "grid {} against homogeneous {}",
        means[0].0,
        means[1].0
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Light a point source of `intensity` at `light` scatters once towards the camera along the ray
/// from (0, `camera_y`, 0) down -z, in a medium of extinction `sigma` and `albedo` with
/// Henyey-Greenstein's `g`: the integral over t of sigma_s p(cos) I Tr(t + d) / d^2, d the
/// distance from the point at t to the light (midpoint rule to 100 units). With `mirror`, the
/// light is a mirror image below the plane y = 0 and only points whose line to it crosses the
/// plane within `mirror` of the origin (in x and z) see it.
fn line_integral(
    camera_y: f64,
    light: [f64; 3],
    sigma: f64,
    albedo: f64,
    g: f64,
    intensity: f64,
    mirror: Option<f64>,
) -> f64 {
    let (steps, far) = (200_000, 100.0f64);
    let mut sum = 0.0;
    for i in 0..steps {
        let t = (i as f64 + 0.5) * far / steps as f64;
        let v = [-light[0], camera_y - light[1], -t - light[2]];
        let d = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if let Some(half) = mirror {
            let a = -light[1] / v[1];
            if (light[0] + a * v[0]).abs() > half || (light[2] + a * v[2]).abs() > half {
                continue;
            }
        }
        // The light travels along v / d and leaves towards the camera (+z).
        let cos = v[2] / d;
        let hg =
            (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * cos).powf(1.5));
        sum += albedo * sigma * hg * intensity * (-sigma * (t + d)).exp() / (d * d);
    }
    sum * far / steps as f64
}
