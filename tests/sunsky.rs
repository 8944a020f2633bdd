//! Mitsuba 3's `sunsky` emitter (src/scene/sunsky): its radiance against Mitsuba 3.9.1's own
//! values (tests/refs/sunsky/values.py), the map it is baked into against the model's power
//! and irradiance, the photons it sends, a render against Mitsuba's, and every refusal at its
//! place.

mod common;

use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

use common::pass_harness::PassHarness;
use glam::{DVec3, Vec3};
use hppm::loaders::{Report, mitsuba};
use hppm::passes::photon_trace::{self, PhotonMode, PhotonTrace, PhotonTraceParams};
use hppm::scene::Scene;
use hppm::scene::emitter::{EnvMap, Environment};
use hppm::scene::sunsky::SunSkyMap;

const SENSOR: &str = r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>"#;

/// A scene with a sunsky of `body`, whose properties start on line 5 of sunsky.xml.
fn check(body: &str) -> Report {
    let text = format!(
        "<scene version=\"3.0.0\">\n{SENSOR}\n<shape type=\"sphere\"/>\n<emitter type=\"sunsky\">\n{body}\n</emitter>\n</scene>"
    );
    mitsuba::check_text(Path::new("sunsky.xml"), &text, &[])
}

fn scene_of(report: Report) -> Scene {
    let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
    report
        .scene
        .unwrap_or_else(|| panic!("refused: {}", errors.join("\n")))
}

fn sunsky(body: &str) -> SunSkyMap {
    match scene_of(check(body)).emitters.environment {
        Some(Environment::SunSky(s)) => *s,
        other => panic!("not a sunsky: {other:?}"),
    }
}

/// tests/refs/sunsky/values.csv: per configuration its XML body, Mitsuba's sun direction and
/// (direction, radiance) pairs.
struct Config {
    name: String,
    body: String,
    sun: Vec3,
    values: Vec<(Vec3, Vec3)>,
}

fn mitsuba_values() -> Vec<Config> {
    let text = std::fs::read_to_string(common::repo_path("tests/refs/sunsky/values.csv"))
        .expect("values.csv");
    let mut configs: Vec<Config> = Vec::new();
    let numbers =
        |s: &[&str]| -> Vec<f32> { s.iter().map(|v| v.parse().expect("number")).collect() };
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let fields: Vec<&str> = line.splitn(3, ',').collect();
        match fields[0] {
            "body" => configs.push(Config {
                name: fields[1].into(),
                body: fields[2].into(),
                sun: Vec3::ZERO,
                values: Vec::new(),
            }),
            "sun" => {
                let v = numbers(&fields[2].split(',').collect::<Vec<_>>());
                let c = configs
                    .iter_mut()
                    .find(|c| c.name == fields[1])
                    .expect("config");
                c.sun = Vec3::new(v[0], v[1], v[2]);
            }
            name => {
                let v = numbers(&line.split(',').skip(1).collect::<Vec<_>>());
                let c = configs.iter_mut().find(|c| c.name == name).expect("config");
                c.values
                    .push((Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5])));
            }
        }
    }
    configs
}

/// The largest relative difference over the channels (0 where both are 0).
fn relative(got: Vec3, want: Vec3) -> f32 {
    (0..3)
        .map(|c| {
            let d = (got[c] - want[c]).abs();
            if d == 0.0 {
                0.0
            } else {
                d / want[c].abs().max(1e-30)
            }
        })
        .fold(0.0, f32::max)
}

/// hppm's sky and sun radiance against Mitsuba 3.9.1's `eval` at 200 directions in each of 12
/// configurations (defaults with the sun from Tokyo's date and time, turbidity 1.5 to 10,
/// albedo 0, 1 and per channel, suns from 0.09 to 85 degrees high and one cut by the horizon,
/// both scales and a 2-degree aperture, a turned frame with the sun given in world space and
/// with the sun from Paris's date and time, the limb-darkened `complex_sun` high and low), and
/// the sun direction Mitsuba reports. Directions within 5e-5 rad of the disc's edge are left out
/// (there f32 rounding decides inside or out). Catches a sky parameter out of order, an
/// interpolation in turbidity, albedo or elevation done otherwise (per channel albedo, the
/// Bezier's variable), the sun's irradiance converted to RGB wrongly, the area ratio, a scale
/// applied to the wrong part, light below the horizon, a sun position from the wrong formula or
/// frame (mirrored, turned, its parallax), and the limb darkening's indexing.
#[test]
fn radiance_matches_mitsubas_own_values() {
    let started = Instant::now();
    let mut report = Vec::new();
    let (mut worst_sky, mut worst_disc, mut worst_complex, mut worst_sun_dir) =
        (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let mut compared = 0;
    for config in mitsuba_values() {
        let sunsky = sunsky(&config.body);
        let model = &sunsky.model;
        let sun = model.sun_direction();
        let off = (sun - config.sun).length();
        worst_sun_dir = worst_sun_dir.max(off);
        assert!(
            off < 2e-6,
            "{}: sun {sun} against Mitsuba's {}",
            config.name,
            config.sun
        );
        let half = model.half_aperture();
        let (mut sky, mut disc) = (0.0f32, 0.0f32);
        for (d, want) in &config.values {
            let gamma = d.normalize().dot(sun).clamp(-1.0, 1.0).acos();
            if (gamma - half).abs() < 5e-5 {
                continue;
            }
            let got = model.radiance(*d);
            let r = relative(got, *want);
            if gamma < half {
                disc = disc.max(r);
            } else {
                sky = sky.max(r);
            }
            compared += 1;
        }
        report.push(format!("{}: sky {sky:.1e}, disc {disc:.1e}", config.name));
        worst_sky = worst_sky.max(sky);
        if config.body.contains("complex_sun") {
            worst_complex = worst_complex.max(disc);
        } else {
            worst_disc = worst_disc.max(disc);
        }
    }
    eprintln!(
        "{}\nworst relative differences over {compared} directions: sky {worst_sky:.2e}, uniform \
         disc {worst_disc:.2e}, limb-darkened disc {worst_complex:.2e}; sun directions within \
         {worst_sun_dir:.1e} ({:.2} s)",
        report.join("\n"),
        started.elapsed().as_secs_f64()
    );
    assert!(worst_sky < 1e-4, "sky {worst_sky}");
    assert!(worst_disc < 1e-5, "uniform sun {worst_disc}");
    assert!(worst_complex < 1e-3, "complex sun {worst_complex}");
}

/// The solid angles of the texels' bilinear hats, which the bake divides the sun's integral
/// by and the map's integral weighs texels with, cover the sphere once (4 pi) at every size,
/// poles included. Catches a pole row's hat taken as a full one (or as the rows' width alone).
#[test]
fn texel_hats_cover_the_sphere() {
    for (w, h) in [(4, 2), (16, 8), (64, 33), (1024, 513), (1024, 4097)] {
        let total: f64 = (0..h)
            .map(|y| w as f64 * EnvMap::hat_solid_angle(w, h, y))
            .sum();
        assert!(
            (total / (4.0 * PI) - 1.0).abs() < 1e-12,
            "{w} x {h}: {total} against 4 pi"
        );
    }
}

/// The map's direction of texel (x, y).
fn texel_direction(map: &EnvMap, x: u32, y: u32) -> DVec3 {
    let u = (x as f64 + 0.5) / map.width as f64;
    let v = y as f64 / (map.height - 1) as f64;
    let (theta, phi) = (v * PI, u * 2.0 * PI);
    map.to_world.as_dmat3()
        * DVec3::new(
            phi.sin() * theta.sin(),
            theta.cos(),
            -phi.cos() * theta.sin(),
        )
}

/// Irradiance on a plane of `normal` from the map: each texel times its hat's solid angle
/// times the cosine at its centre (exact but for the cosine's variation across a hat, a
/// relative 1e-6 here).
fn map_irradiance(map: &EnvMap, normal: DVec3) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for y in 0..map.height {
        let solid = EnvMap::hat_solid_angle(map.width, map.height, y);
        for x in 0..map.width {
            let cos = normal.dot(texel_direction(map, x, y));
            if cos > 0.0 {
                sum += map.texels[(y * map.width + x) as usize].as_dvec3() * solid * cos;
            }
        }
    }
    sum
}

/// The model's sky irradiance on the horizontal plane (the sunsky's zenith): the midpoint rule
/// over the hemisphere, 1,500 x 3,000, of the radiance of `sky_only` (its sun off).
fn model_sky_irradiance(sky_only: &SunSkyMap) -> DVec3 {
    model_sky_quadrature(sky_only, true)
}

/// The same quadrature of radiance alone (with `cosine` false): the sky's integral over the
/// sphere (nothing comes from below the horizon).
fn model_sky_quadrature(sky_only: &SunSkyMap, cosine: bool) -> DVec3 {
    let model = &sky_only.model;
    let zenith = model.zenith().as_dvec3();
    let helper = if zenith.x.abs() < 0.9 {
        DVec3::X
    } else {
        DVec3::Z
    };
    let (a, b) = {
        let a = helper.cross(zenith).normalize();
        (a, zenith.cross(a))
    };
    let (nt, np) = (1500usize, 3000usize);
    let mut sum = DVec3::ZERO;
    for i in 0..nt {
        let theta = (i as f64 + 0.5) / nt as f64 * 0.5 * PI;
        let (s, c) = theta.sin_cos();
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
            let d = zenith * c + (a * phi.cos() + b * phi.sin()) * s;
            sum += model.radiance(d.as_vec3()).as_dvec3() * if cosine { c * s } else { s };
        }
    }
    sum * (0.5 * PI / nt as f64) * (2.0 * PI / np as f64)
}

/// The bake keeps the model's power. With the sky off, the map's integral over the sphere is
/// the sun's (its radiance integrated over its disc: L 2 pi (1 - cos a) for the uniform disc)
/// to rounding, whether the disc is uniform, limb-darkened, 2 degrees wide or cut by the
/// horizon; with the sun off, the map's irradiance on the horizontal plane is the model's sky
/// irradiance (a fine quadrature of the model); and the whole map's is the sum of both.
/// Catches a sun point-sampled into its texels (its power then follows where texel centres
/// fall: 14% too much at the default aperture), a hat's solid angle wrong at the pole the sun sits on, a
/// horizon that clips or leaks the sky, a map turned against the model. Prints the bake's
/// time.
#[test]
fn the_bake_keeps_the_models_power() {
    let cases = [
        ("default", ""),
        (
            "complex",
            r#"<vector name="sun_direction" x="0.3" y="0.3" z="0.6"/><boolean name="complex_sun" value="true"/>"#,
        ),
        (
            "wide",
            r#"<vector name="sun_direction" x="0.5" y="0.5" z="0.5"/><float name="sun_aperture" value="2"/>"#,
        ),
        (
            "on the horizon",
            r#"<vector name="sun_direction" x="-1" y="0" z="0.0015"/>"#,
        ),
        (
            "turned",
            r#"<vector name="sun_direction" x="0.4" y="0.6" z="-0.3"/><transform name="to_world"><rotate x="1" angle="-90"/><rotate y="1" angle="30"/></transform>"#,
        ),
    ];
    for (name, body) in cases {
        let started = Instant::now();
        let sun_only = sunsky(&format!(r#"{body}<float name="sky_scale" value="0"/>"#));
        let elapsed = started.elapsed().as_secs_f64();
        let model = &sun_only.model;
        let expected = model.sun_irradiance_normal().as_dvec3();
        let got = sun_only.map.radiance_integral().as_dvec3();
        let off = ((got - expected).abs() / expected).max_element();
        eprintln!(
            "{name}: the sun's integral over the map {got:.5?} against {expected:.5?} ({off:.1e} \
             off); sun-only load and bake {elapsed:.2} s"
        );
        // The uniform disc wholly above the horizon: L 2 pi (1 - cos a) in closed form.
        if !body.contains("complex") && name != "on the horizon" {
            let a = model.half_aperture() as f64;
            let l = model.radiance(model.sun_direction()).as_dvec3();
            let closed = l * 2.0 * PI * 2.0 * (0.5 * a).sin().powi(2);
            let off = ((expected - closed).abs() / closed).max_element();
            assert!(off < 1e-6, "{name}: quadrature {expected} against {closed}");
        }
        let tolerance = match name {
            "on the horizon" => 2e-3,
            "complex" => 1e-4,
            _ => 1e-5,
        };
        assert!(off < tolerance, "{name}: {off}");

        let sky_only = sunsky(&format!(r#"{body}<float name="sun_scale" value="0"/>"#));
        let zenith = sky_only.model.zenith().as_dvec3();
        let want_sky = model_sky_irradiance(&sky_only);
        let got_sky = map_irradiance(&sky_only.map, zenith);
        let off_sky = ((got_sky - want_sky).abs() / want_sky).max_element();
        let full = sunsky(body);
        let got_full = map_irradiance(&full.map, zenith);
        // The uniform disc's cosine-weighted integral: the cap's centroid is the sun's
        // direction times (1 + cos a) / 2.
        let sun_dir = model.sun_direction().as_dvec3();
        let a = model.half_aperture() as f64;
        let want_full = want_sky + expected * sun_dir.dot(zenith) * 0.5 * (1.0 + a.cos());
        let off_full = ((got_full - want_full).abs() / want_full).max_element();
        eprintln!(
            "{name}: horizontal irradiance, sky {got_sky:.5?} against {want_sky:.5?} \
             ({off_sky:.1e}), sun and sky {got_full:.5?} against {want_full:.5?} ({off_full:.1e})"
        );
        assert!(off_sky < 5e-4, "{name}: sky irradiance {off_sky}");
        if name != "on the horizon" && !body.contains("complex") {
            assert!(off_full < 5e-4, "{name}: irradiance {off_full}");
        }
    }
}

/// The baked map looks like the model: away from the sun's disc and the horizon its bilinear
/// radiance is the model's within 1% (the sky's curvature over a texel), and at the sun's
/// centre it holds the sun's radiance. Catches a map mirrored, turned or flipped against the
/// model, and a sun smeared beyond its texels.
#[test]
fn the_baked_map_looks_like_the_model() {
    for body in [
        "",
        r#"<vector name="sun_direction" x="0.4" y="0.6" z="-0.3"/><transform name="to_world"><rotate x="1" angle="-90"/><rotate y="1" angle="30"/></transform><float name="turbidity" value="6"/>"#,
        r#"<vector name="sun_direction" x="0.4" y="0.6" z="0.2"/><float name="sun_scale" value="0"/>"#,
    ] {
        let sunsky = sunsky(body);
        let (model, map) = (&sunsky.model, &sunsky.map);
        let zenith = model.zenith();
        let sun = model.sun_direction();
        let mut rng = common::rng::Rng(0x9e37_79b9_7f4a_7c15);
        let mut worst = 0.0f32;
        let mut n = 0;
        while n < 2000 {
            let d = rng.direction();
            if d.dot(zenith).abs() < 0.02 || d.dot(sun) > 0.9995 {
                continue;
            }
            n += 1;
            worst = worst.max(relative(map.eval(d), model.radiance(d)).min(1e3));
        }
        let centre =
            ((map.eval(sun) - model.radiance(sun)).abs() / model.radiance(sun)).max_element();
        eprintln!(
            "{body:?}: {}x{} map, worst sky texel {worst:.2e}, sun centre {centre:.1e}",
            map.width, map.height
        );
        assert!(worst < 0.01, "sky: {worst}");
        assert!(centre < 1e-3, "sun centre: {centre}");
    }
}

/// Every refusal of a sunsky names its file, line and column and says why: Mitsuba's own
/// checks (turbidity, albedo range and texture, negative scales, the aperture, sun_direction
/// with a place or time) and hppm's where Mitsuba would compute on with nonsense (a zero
/// direction, an impossible date or place, a to_world that is not a rotation), unknown
/// properties with a did-you-mean, a second environment. Catches a check lost or reported at
/// the emitter instead of its property.
#[test]
fn bad_sunsky_inputs_are_refused_at_their_place() {
    let cases: &[(&str, usize, &str)] = &[
        (
            r#"<float name="turbidity" value="0.5"/>"#,
            5,
            "from 1 to 10",
        ),
        (
            r#"<float name="turbidity" value="10.5"/>"#,
            5,
            "from 1 to 10",
        ),
        (
            r#"<float name="turbidity" value="nan"/>"#,
            5,
            "not a finite number",
        ),
        (r#"<rgb name="albedo" value="0.2, 1.1, 0.3"/>"#, 5, "[0, 1]"),
        (r#"<float name="albedo" value="-0.1"/>"#, 5, "[0, 1]"),
        (
            r#"<texture type="checkerboard" name="albedo"/>"#,
            5,
            "not a texture",
        ),
        (
            r#"<float name="sun_scale" value="-1"/>"#,
            5,
            "must not be negative",
        ),
        (
            r#"<float name="sky_scale" value="-0.5"/>"#,
            5,
            "must not be negative",
        ),
        (r#"<float name="sun_aperture" value="0"/>"#, 5, "(0, 180)"),
        (r#"<float name="sun_aperture" value="180"/>"#, 5, "(0, 180)"),
        (r#"<string name="complex_sun" value="yes"/>"#, 5, "boolean"),
        (
            "<float name=\"hour\" value=\"9\"/>\n<vector name=\"sun_direction\" x=\"0\" y=\"0\" z=\"1\"/>",
            6,
            "not both (hour at line 5)",
        ),
        (
            r#"<vector name="sun_direction" x="0" y="0" z="0"/>"#,
            5,
            "sun_direction is zero",
        ),
        (r#"<float name="latitude" value="91"/>"#, 5, "[-90, 90]"),
        (
            r#"<float name="longitude" value="-200"/>"#,
            5,
            "[-180, 180]",
        ),
        (r#"<float name="timezone" value="15"/>"#, 5, "[-12, 14]"),
        (r#"<integer name="month" value="13"/>"#, 5, "[1, 12]"),
        (
            "<integer name=\"month\" value=\"6\"/>\n<integer name=\"day\" value=\"31\"/>",
            6,
            "[1, 30]",
        ),
        (
            "<integer name=\"year\" value=\"2023\"/>\n<integer name=\"month\" value=\"2\"/>\n<integer name=\"day\" value=\"29\"/>",
            7,
            "[1, 28]",
        ),
        (r#"<float name="year" value="2010"/>"#, 5, "<integer>"),
        (r#"<float name="hour" value="25"/>"#, 5, "[0, 24]"),
        (r#"<float name="minute" value="-1"/>"#, 5, "[0, 60]"),
        (
            r#"<transform name="to_world"><scale value="2"/></transform>"#,
            5,
            "must be a rotation",
        ),
        (
            r#"<transform name="to_world"><scale x="-1"/></transform>"#,
            5,
            "must be a rotation",
        ),
        (
            r#"<float name="turbity" value="3"/>"#,
            5,
            "did you mean \"turbidity\"?",
        ),
        (
            r#"<float name="sun_size" value="3"/>"#,
            5,
            "unknown property",
        ),
    ];
    let mut failures = Vec::new();
    for (body, line, words) in cases {
        let report = check(body);
        let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
        let place = format!("sunsky.xml:{line}:");
        if report.scene.is_some()
            || !errors
                .iter()
                .any(|e| e.contains(&place) && e.contains(words))
        {
            failures.push(format!(
                "{body}: expected {place} and {words:?}, got {errors:#?}"
            ));
        }
    }
    // A second environment is refused at the second.
    let text = format!(
        "<scene version=\"3.0.0\">\n{SENSOR}\n<emitter type=\"constant\"/>\n<emitter type=\"sunsky\"/>\n</scene>"
    );
    let report = mitsuba::check_text(Path::new("sunsky.xml"), &text, &[]);
    if !report
        .errors
        .iter()
        .any(|e| e.to_string().contains("sunsky.xml:4:") && e.to_string().contains("second"))
    {
        failures.push(format!("a second environment: {:?}", report.errors));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A sun below the horizon (Tokyo at 3 in the morning) loads with a warning at the emitter, and
/// its environment is black everywhere, sky included, as Mitsuba renders it. Catches a sky
/// drawn without its sun, or a night refused.
#[test]
fn a_sun_below_the_horizon_renders_black_with_a_warning() {
    let report = check(r#"<float name="hour" value="3"/>"#);
    let warnings: Vec<String> = report.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("sunsky.xml:4:") && w.contains("below the horizon")),
        "{warnings:#?}"
    );
    let scene = scene_of(report);
    let env = scene.emitters.environment.as_ref().expect("environment");
    assert_eq!(env.radiance_integral(), Vec3::ZERO);
    let Environment::SunSky(s) = env else {
        panic!("not a sunsky")
    };
    assert!(!s.model.sun_is_up());
    assert_eq!(s.model.radiance(Vec3::Z), Vec3::ZERO);
}

/// The photons hppm's photon pass sends from a sunsky carry its power: what crosses the scene's
/// bounding disc, its area times the model's radiance integrated over the sphere (the sky's by
/// quadrature of the model, the sun's over its disc), through the GPU's table of the baked map
/// (its 84 MB, its density at the pole the sun sits on). Catches a table the GPU reads
/// otherwise than the CPU wrote it, a density that disagrees with the map near the pole (a
/// photon's flux is radiance over density), a sun lost or doubled.
#[test]
fn photons_carry_the_sunskys_power() {
    let floor = r#"<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="2"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></shape>"#;
    let body = r#"<vector name="sun_direction" x="0.3" y="0.8" z="-0.4"/><transform name="to_world"><rotate x="1" angle="-90"/></transform>"#;
    let text = format!(
        "<scene version=\"3.0.0\">\n{SENSOR}\n{floor}\n<emitter type=\"sunsky\">{body}</emitter>\n</scene>"
    );
    let scene = scene_of(mitsuba::check_text(Path::new("photons.xml"), &text, &[]));
    let Some(Environment::SunSky(sunsky_map)) = &scene.emitters.environment else {
        panic!("no sunsky")
    };
    let sky_only = sunsky(&format!(r#"{body}<float name="sun_scale" value="0"/>"#));
    let integral = model_sky_quadrature(&sky_only, false)
        + sunsky_map.model.sun_irradiance_normal().as_dvec3();
    let (lo, hi) = scene.bounds();
    let disc = PI * (0.5 * (hi - lo).length() as f64).powi(2);
    let expected = integral * disc;

    let gpu = common::gpu();
    let h = PassHarness::new(&gpu, &scene, (8, 8), gpu.has_float_atomics());
    let mut pass = PhotonTrace::new(PhotonTraceParams {
        mode: PhotonMode::All,
        photons_per_iteration: Some(1 << 18),
        ..Default::default()
    });
    h.prepare(&photon_trace::KIND, &mut pass, &[]);
    h.run(&mut pass, 0, 3);
    let got = pass.emitted_flux(&gpu).expect("readback");
    let off: Vec<f64> = (0..3)
        .map(|c| (got[c] as f64 - expected[c]).abs() / expected[c])
        .collect();
    eprintln!("emitted {got:?} against {expected:.4?}: relative {off:?}");
    // As for an envmap (tests/lights.rs): a photon's flux varies within a cell (bilinear
    // radiance against a constant density), about 1% noise at 2^18 photons.
    assert!(off.iter().all(|o| *o < 0.03), "{off:?}");
}

/// Mitsuba 3.9.1's figures for tests/refs/sunsky/scene.xml (render.py, figures.json): its
/// relMSE at 256 spp against the reference (median over the passes, against the mean of the
/// others, 256 passes) on pixels and on 8x8 block means, and the reference's own block noise.
const PIXELS_256: f64 = 4.986e-4;
const BLOCKS_256: f64 = 8.228e-6;
const NOISE_BLOCKS: f64 = 3.274e-8;

/// A diffuse ground, a box and a sphere under a sunsky (turned Y-up by `to_world`, the sun given
/// in world space, the sky seen above the horizon), hppm's `pt` at 256 spp against Mitsuba
/// 3.9.1's render (tests/refs/sunsky): 8x8 block means within 2x Mitsuba's own 256-spp block
/// relMSE plus twice the reference's block noise, a bound a 10% loss fails. Catches the bake
/// seen through the renderer otherwise than Mitsuba's model (a sun of the wrong power or
/// place, shadows cast the wrong way, a sky of the wrong colour or orientation, light below the
/// horizon).
#[test]
fn a_ground_box_and_sphere_under_a_sunsky_match_mitsuba() {
    let scene = common::load_scene("tests/refs/sunsky/scene.xml");
    let reference =
        hppm::image::Image::read_exr(&common::repo_path("tests/refs/sunsky/images/sunsky.exr"))
            .expect("reference");
    let gpu = common::gpu();
    let started = Instant::now();
    let image = common::render_to(
        &mut common::renderer(&gpu, &scene, common::load_graph("graphs/pt.ron"), 0),
        256,
    );
    let elapsed = started.elapsed().as_secs_f64();
    let blocks = |i: &hppm::image::Image| common::convergence::block_means(i, 8);
    let e_blocks = common::relmse(&blocks(&image), &blocks(&reference));
    let e_pixels = common::relmse(&image, &reference);
    let lossy = common::relmse(
        &blocks(&common::convergence::scaled(&image, 0.9)),
        &blocks(&reference),
    );
    let bound = 2.0 * BLOCKS_256 + 2.0 * NOISE_BLOCKS;
    eprintln!(
        "pt 256 spp ({elapsed:.1} s): 8x8 blocks relMSE {e_blocks:.3e} (bound {bound:.3e}; \
         Mitsuba's own {BLOCKS_256:.3e}; 10% darker {lossy:.3e}), pixels {e_pixels:.3e} \
         (Mitsuba's own {PIXELS_256:.3e}), mean {:?} vs {:?}",
        image.mean(),
        reference.mean()
    );
    assert!(lossy > bound, "a 10% loss would pass");
    assert!(e_blocks <= bound, "{e_blocks:.3e} > {bound:.3e}");
}
