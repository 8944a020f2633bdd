//! Every light kind beside area and point lights: spot, directional, constant and envmap.
//! Photons carry each light's analytic power; camera renders match closed forms or a CPU
//! quadrature of the same light (a plane under a spot and a sun, a diffuse sphere under an
//! environment map); a sun's caustic off a mirror is photon-mapped at the analytic irradiance;
//! and `sun_sky_textured` converges to Mitsuba 3's reference.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::pass_harness::PassHarness;
use common::*;
use glam::{Mat3, Vec2, Vec3};
use hppm::image::Image;
use hppm::loaders::mitsuba;
use hppm::passes::photon_trace::{self, PhotonMode, PhotonTrace, PhotonTraceParams};
use hppm::scene::Scene;
use hppm::scene::emitter::{EnvMap, Environment, SpotLight};

/// A Mitsuba scene from `body` with a 24x24 box-filtered camera at (0, 4, 4) looking at the
/// origin, and `max_depth`.
fn xml(body: &str, max_depth: i32) -> Scene {
    xml_seen_from("0, 4, 4", body, max_depth)
}

/// `max_depth` -1 is unbounded (with Mitsuba's Russian roulette from depth 5).
fn xml_seen_from(origin: &str, body: &str, max_depth: i32) -> Scene {
    let sensor = format!(
        r#"<sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="{origin}" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film>
</sensor>"#
    );
    let text = format!(
        "<scene version=\"3.0.0\">\n{sensor}\n<integrator type=\"path\"><integer name=\"max_depth\" value=\"{max_depth}\"/></integrator>\n{body}\n</scene>"
    );
    let scene = mitsuba::parse(Path::new("lights.xml"), &text).unwrap_or_else(|e| panic!("{e}"));
    scene.validate().unwrap_or_else(|e| panic!("{e}"));
    scene
}

/// A 4x4 floor at y = 0 facing up.
fn floor(bsdf: &str) -> String {
    format!(
        r#"<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="2"/></transform>{bsdf}</shape>"#
    )
}

/// A 16 x 8 map with a gradient in both directions and one bright texel, so that a wrong
/// orientation, a wrong density or a missed hot spot all show.
fn test_map(to_world: Mat3) -> EnvMap {
    let (width, height) = (16u32, 8u32);
    let mut texels = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
            texels.push(Vec3::new(0.2 + u, 0.3 + 0.5 * v, 0.1 + u * v));
        }
    }
    texels[(2 * width + 5) as usize] = Vec3::new(20.0, 15.0, 10.0);
    EnvMap {
        width,
        height,
        texels,
        to_world,
        source: "test map".into(),
    }
}

/// Quadrature of radiance x max(0, n . w) (or of radiance alone when `normal` is None) over the
/// sphere, with the CPU twin of the map: 2 pi^2 sin(theta) du dv on a fine (u, v) grid.
fn sphere_integral(env: &Environment, normal: Option<Vec3>, steps: usize) -> [f64; 3] {
    let (nu, nv) = (2 * steps, steps);
    let mut sum = [0.0f64; 3];
    for j in 0..nv {
        let theta = (j as f64 + 0.5) / nv as f64 * PI;
        for i in 0..nu {
            let phi = (i as f64 + 0.5) / nu as f64 * 2.0 * PI;
            let dir = Vec3::new(
                (phi.sin() * theta.sin()) as f32,
                theta.cos() as f32,
                (-phi.cos() * theta.sin()) as f32,
            );
            let weight = match normal {
                Some(n) => n.dot(dir).max(0.0) as f64,
                None => 1.0,
            };
            let l = env.radiance(dir);
            for c in 0..3 {
                sum[c] += l[c] as f64 * weight * theta.sin();
            }
        }
    }
    sum.map(|s| s * 2.0 * PI * PI / (nu * nv) as f64)
}

fn emitted_power(scene: &Scene, photons: u32) -> [f32; 3] {
    let gpu = gpu();
    let h = PassHarness::new(&gpu, scene, (8, 8), gpu.has_float_atomics());
    let mut pass = PhotonTrace::new(PhotonTraceParams {
        mode: PhotonMode::All,
        photons_per_iteration: Some(photons),
        ..Default::default()
    });
    h.prepare(&photon_trace::KIND, &mut pass, &[]);
    h.run(&mut pass, 0, 3);
    pass.emitted_flux(&gpu).expect("readback")
}

fn assert_close(what: &str, got: [f32; 3], expected: [f64; 3], tolerance: f64) {
    for c in 0..3 {
        let rel = (got[c] as f64 - expected[c]).abs() / expected[c];
        assert!(
            rel < tolerance,
            "{what}, channel {c}: {} against {} ({:.3}% off, allowed {:.1}%)",
            got[c],
            expected[c],
            rel * 100.0,
            tolerance * 100.0
        );
    }
}

/// The scene's bounding sphere's cross-section: the disc distant lights emit through.
fn disc_area(scene: &Scene) -> f64 {
    let (lo, hi) = scene.bounds();
    PI * (0.5 * (hi - lo).length() as f64).powi(2)
}

/// Photons carry each light's power: the spot's integral of intensity x falloff (by quadrature
/// here, not the closed form the renderer picks lights by), and the power distant lights send
/// through the scene's bounding disc (directional E A, constant 4 pi L A, map A times the
/// integral of its radiance). Catches a wrong spot cone or falloff, a disc of the wrong size, an
/// environment density that does not match its sampling (a wrong Jacobian, a half-texel shift)
/// or a lost photon class.
#[test]
fn photons_carry_each_lights_power() {
    let black = floor(r#"<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>"#);
    let spot_xml = format!(
        r#"{black}<emitter type="spot"><rgb name="intensity" value="3, 2, 1"/><float name="cutoff_angle" value="35"/><float name="beam_width" value="15"/>
           <transform name="to_world"><lookat origin="0, 2, 0" target="1, 0, 0.5" up="0, 0, 1"/></transform></emitter>"#
    );
    let spot_scene = xml(&spot_xml, 4);
    let spot: SpotLight = spot_scene.emitters.spots[0];
    // The falloff integrated over the sphere, 200,000 steps in theta.
    let n = 200_000;
    let solid: f64 = (0..n)
        .map(|i| {
            let theta = (i as f64 + 0.5) / n as f64 * PI;
            2.0 * PI * theta.sin() * spot.falloff(theta.cos() as f32) as f64 * PI / n as f64
        })
        .sum();
    let expected = [3.0 * solid, 2.0 * solid, solid];
    assert_close("spot", emitted_power(&spot_scene, 1 << 18), expected, 0.01);

    let sun = xml(
        &format!(
            r#"{black}<emitter type="directional"><vector name="direction" x="0.3" y="-1" z="0.2"/><rgb name="irradiance" value="2, 1, 0.5"/></emitter>"#
        ),
        4,
    );
    let a = disc_area(&sun);
    // Every photon carries the same flux: exact up to rounding.
    assert_close(
        "directional",
        emitted_power(&sun, 1 << 16),
        [2.0 * a, a, 0.5 * a],
        1e-4,
    );

    let sky = xml(
        &format!(
            r#"{black}<emitter type="constant"><rgb name="radiance" value="0.5, 1, 2"/></emitter>"#
        ),
        4,
    );
    let a = disc_area(&sky);
    let expected = [0.5, 1.0, 2.0].map(|l| 4.0 * PI * l * a);
    assert_close("constant", emitted_power(&sky, 1 << 16), expected, 1e-4);

    let mut map_scene = xml(&black, 4);
    let turn = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(0.3);
    let env = Environment::Map(test_map(turn));
    let a = disc_area(&map_scene);
    let expected = sphere_integral(&env, None, 512).map(|i| i * a);
    map_scene.emitters.environment = Some(env);
    // Flux per photon is L / pdf: it varies within a cell (bilinear radiance against a
    // constant density), about 1% noise at 2^18 photons.
    assert_close("envmap", emitted_power(&map_scene, 1 << 18), expected, 0.03);
}

/// Primary-ray direction through film position `film` (pixels) as shaders/common/camera.wgsl
/// computes it.
fn camera_ray(scene: &Scene, film: Vec2) -> (Vec3, Vec3) {
    let cam = &scene.camera;
    let forward = (cam.target - cam.origin).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let tan_x = (cam.fov_x_deg.to_radians() * 0.5).tan();
    let tan_y = tan_x * cam.height as f32 / cam.width as f32;
    let x = (2.0 * film.x / cam.width as f32 - 1.0) * tan_x;
    let y = (1.0 - 2.0 * film.y / cam.height as f32) * tan_y;
    (cam.origin, (forward + x * right + y * up).normalize())
}

/// Per-pixel means of `f` over a `k` x `k` grid of film positions in each pixel.
fn supersampled(scene: &Scene, k: u32, f: impl Fn(Vec3, Vec3) -> Vec3) -> Image {
    supersampled_with_spread(scene, k, f).0
}

/// [`supersampled`] and each pixel's standard deviation of `f` within it.
fn supersampled_with_spread(
    scene: &Scene,
    k: u32,
    f: impl Fn(Vec3, Vec3) -> Vec3,
) -> (Image, Image) {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (mut means, mut spreads) = (Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let (mut sum, mut sum2) = (Vec3::ZERO, Vec3::ZERO);
            for j in 0..k {
                for i in 0..k {
                    let film = Vec2::new(
                        x as f32 + (i as f32 + 0.5) / k as f32,
                        y as f32 + (j as f32 + 0.5) / k as f32,
                    );
                    let (o, d) = camera_ray(scene, film);
                    let v = f(o, d);
                    sum += v;
                    sum2 += v * v;
                }
            }
            let mean = sum / (k * k) as f32;
            let spread = (sum2 / (k * k) as f32 - mean * mean).max(Vec3::ZERO);
            means.push(mean.to_array());
            spreads.push(spread.to_array().map(f32::sqrt));
        }
    }
    let image = |pixels| Image {
        width: w,
        height: h,
        pixels,
    };
    (image(means), image(spreads))
}

fn render(scene: &Scene, graph: &str, spp: u64, seed: u64) -> Image {
    let gpu = gpu();
    let mut r = renderer(&gpu, scene, load_graph(graph), seed);
    render_to(&mut r, spp)
}

const SPOT: &str = r#"<emitter type="spot"><rgb name="intensity" value="4, 3, 2"/><float name="cutoff_angle" value="30"/>
    <transform name="to_world"><lookat origin="0.5, 1.5, -0.5" target="0, 0, 0.3" up="0, 0, 1"/></transform></emitter>"#;
const SUN: &str = r#"<emitter type="directional"><vector name="direction" x="-0.5" y="-1" z="0.3"/><rgb name="irradiance" value="0.5, 0.6, 0.7"/></emitter>"#;

/// The floor under `lights`, seen directly (max_depth 2: nothing bounces), and the closed form
/// of its image: albedo / pi times the sun's E cos plus the spot's I falloff cos / d^2,
/// supersampled over each pixel.
fn lit_floor(lights: &str) -> (Scene, Image, Image) {
    let scene = xml(
        &format!(
            "{}{lights}",
            floor(r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf>"#)
        ),
        2,
    );
    let albedo = Vec3::new(0.6, 0.5, 0.4);
    let (expected, spread) = supersampled_with_spread(&scene, 8, |o, d| {
        if d.y >= 0.0 {
            return Vec3::ZERO;
        }
        let p = o + d * (-o.y / d.y);
        if p.x.abs() > 2.0 || p.z.abs() > 2.0 {
            return Vec3::ZERO;
        }
        let mut irradiance = Vec3::ZERO;
        for spot in &scene.emitters.spots {
            let to_spot = spot.position - p;
            let dist2 = to_spot.length_squared();
            let l = to_spot / dist2.sqrt();
            irradiance += spot.falloff(-l.dot(spot.axis)) * spot.intensity * l.y / dist2;
        }
        for sun in &scene.emitters.directionals {
            irradiance += sun.irradiance * (-sun.direction.y).max(0.0);
        }
        albedo / std::f32::consts::PI * irradiance
    });
    (scene, expected, spread)
}

/// A diffuse floor lit by one delta light at a time is deterministic per film position, so the
/// render must match the CPU's supersampled closed form to the spread within a pixel; with both
/// lights (one picked per sample) the image mean must. Catches a spot aimed wrong, a falloff in
/// the wrong units or direction (cos against angle), a sun whose direction is reversed, a
/// shadow ray to a distant light that hits the scene, and a light-selection probability that is
/// not divided out. (Mitsuba 3.9.1 renders these two lights, each alone, to within 0.05% of
/// this renderer's image mean.)
#[test]
fn a_floor_under_a_spot_and_a_sun_has_the_analytic_radiance() {
    for (name, lights) in [("spot", SPOT), ("sun", SUN)] {
        let (scene, expected, spread) = lit_floor(lights);
        let image = render(&scene, "graphs/pt.ron", 64, 1);
        // Where the image varies within a pixel (the spot's cone edge spans about two pixels
        // here, the floor's edge) 64 jittered samples and the 8x8 grid disagree by a part of
        // that spread; elsewhere only rounding separates them. A wrong falloff, a factor of pi
        // or a reversed direction moves whole regions far past this.
        let w = image.width as i64;
        // An edge that only clips a pixel's border can slip between the grid's points: take
        // the largest spread of the pixel and its neighbours, and allow a sliver (6%) of the
        // step to any neighbour.
        let near_spread = |i: usize, c: usize| {
            let (x, y) = (i as i64 % w, i as i64 / w);
            let mut most = 0.0f32;
            for (dx, dy) in (-1..=1).flat_map(|dx| (-1..=1).map(move |dy| (dx, dy))) {
                let (nx, ny) = (x + dx, y + dy);
                if nx >= 0 && ny >= 0 && nx < w && ny < image.height as i64 {
                    let n = (ny * w + nx) as usize;
                    let step = (expected.pixels[n][c] - expected.pixels[i][c]).abs();
                    most = most.max(spread.pixels[n][c]).max(0.12 * step);
                }
            }
            most
        };
        for (i, (g, e)) in image.pixels.iter().zip(&expected.pixels).enumerate() {
            for c in 0..3 {
                let allowed = 0.02 * e[c] + 0.5 * near_spread(i, c) + 1e-4;
                assert!(
                    (g[c] - e[c]).abs() <= allowed,
                    "{name}: pixel {i}, channel {c}: {} against {} (allowed {allowed})",
                    g[c],
                    e[c]
                );
            }
        }
    }
    let (scene, expected, _) = lit_floor(&format!("{SPOT}{SUN}"));
    let image = render(&scene, "graphs/pt.ron", 256, 1);
    let (got, want) = (image.mean(), expected.mean());
    for c in 0..3 {
        let rel = (got[c] - want[c]).abs() / want[c];
        // Light selection noise over 576 pixels x 256 samples: about 0.3%.
        assert!(
            rel < 0.015,
            "both lights, channel {c}: mean {} against {}",
            got[c],
            want[c]
        );
    }
}

/// A diffuse sphere (convex: it never sees itself) under a turned, non-uniform environment
/// map, direct light only: each pixel is albedo / pi times the map's cosine-weighted integral
/// around the normal, and the background is the map itself, both from the CPU twin by
/// quadrature. Catches a GPU lookup that differs from the CPU's (orientation, wrap, bilinear
/// weights), a turn applied the wrong way, a light-sampling density that disagrees with the
/// map (MIS then misweights the hot texel), and a background not drawn.
#[test]
fn a_sphere_under_an_environment_map_has_the_quadrature_radiance() {
    let mut scene = xml_seen_from(
        "0, 0.5, 3.5",
        r#"<shape type="sphere"><float name="radius" value="1"/><bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></shape>"#,
        2,
    );
    let env = Environment::Map(test_map(Mat3::from_rotation_y(1.1)));
    scene.emitters.environment = Some(env.clone());
    let expected = supersampled(&scene, 4, |o, d| {
        // Ray against the unit sphere at the origin.
        let b = o.dot(d);
        let disc = b * b - (o.length_squared() - 1.0);
        if disc < 0.0 {
            return env.radiance(d);
        }
        let p = o + d * (-b - disc.sqrt());
        let e = sphere_integral(&env, Some(p.normalize()), 64);
        Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32) * (0.8 / std::f32::consts::PI)
    });
    let image = render(&scene, "graphs/pt.ron", 256, 2);
    // Compare 4x4 block means: noise averages there, a bias (a wrong density, a turned map)
    // does not. The sphere's silhouette mixes background and sphere within a pixel: the 2x2
    // CPU grid and the renderer's jitter split those pixels differently, so its blocks are
    // allowed more.
    let blocks = |img: &Image| -> Vec<Vec3> {
        (0..36)
            .map(|b| {
                let (bx, by) = (b % 6 * 4, b / 6 * 4);
                let mut s = Vec3::ZERO;
                for y in by..by + 4 {
                    for x in bx..bx + 4 {
                        s += Vec3::from_array(img.pixels[(y * 24 + x) as usize]);
                    }
                }
                s / 16.0
            })
            .collect()
    };
    let (got, want) = (blocks(&image), blocks(&expected));
    let mut worst = (0.0f32, 0);
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        let off = ((*g - *w).abs() / (*w + 0.02)).max_element();
        if off > worst.0 {
            worst = (off, i);
        }
    }
    eprintln!(
        "worst block: {worst:?}: {:?} against {:?}",
        got[worst.1], want[worst.1]
    );
    let worst = worst.0;
    assert!(worst < 0.05, "worst 4x4 block {:.3} off", worst);
}

/// `sun_sky_textured` (tests/refs: an HDR sky `envmap`, a `directional` sun, a checkerboard
/// floor, rough plastic, Mitsuba's default Gaussian filter), from tests/refs/README.md.
const SUN_SKY: common::convergence::MitsubaFigures = common::convergence::MitsubaFigures {
    scene: "tests/refs/scenes/sun_sky_textured/scene.xml",
    reference: "sun_sky_textured",
    pixels_256: 0.00031,
    blocks_256: 1.7e-5,
    noise: 6.3e-7,
};

/// `hybrid` (which has nothing to photon-map here: no specular surface) at 32 spp within the
/// bound scaled to 32 spp. Catches a sky turned or mirrored against Mitsuba's convention, a
/// sun of the wrong strength or direction, a lost or doubled light, and a filter that is not
/// Mitsuba's (a 10% energy loss fails the block metric several times over). Measured on
/// lavapipe: 0.0029 and 1.3e-4 against bounds 0.0037 and 2.1e-4.
#[test]
fn sun_sky_textured_matches_mitsuba_at_32_spp() {
    SUN_SKY.check("graphs/hybrid.ron", 32, 1);
}

/// The issue's acceptance figure: `pt` and `hybrid` at 256 spp within 1.5x Mitsuba's own
/// 256-spp error plus twice the reference's noise, pixels and 8x8 blocks (8 s in a release
/// build on 2 cores with lavapipe).
#[test]
fn sun_sky_textured_converges_to_mitsuba_at_256_spp() {
    for graph in ["graphs/pt.ron", "graphs/hybrid.ron"] {
        SUN_SKY.check(graph, 256, 0);
    }
}

/// The mean of `image` over pixels whose primary ray (through the pixel centre) meets the
/// floor y = 0 at x within `x_range`.
fn floor_band_mean(scene: &Scene, image: &Image, x_range: (f32, f32)) -> Vec3 {
    let (mut sum, mut n) = (Vec3::ZERO, 0);
    for y in 0..image.height {
        for x in 0..image.width {
            let (o, d) = camera_ray(scene, Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let p = o + d * (-o.y / d.y);
            if p.x > x_range.0 && p.x < x_range.1 && p.z.abs() < 1.5 {
                sum += Vec3::from_array(image.pixels[(y * image.width + x) as usize]);
                n += 1;
            }
        }
    }
    assert!(n > 20, "only {n} pixels in the band {x_range:?}");
    sum / n as f32
}

/// A sun at 45 degrees on a floor beside a vertical mirror (x = 1, one unit high, facing the
/// sun), max_depth 3 so that the floor gets exactly its direct light and the mirror's caustic:
/// the band x in (0, 1) has E cos 45 twice (the camera's NEE once, photons from the sun through
/// the mirror once), the mirror's shadow (1, 2) nothing, the rest E cos 45, all times albedo /
/// pi. Only photons can render the caustic of a delta light through a mirror. Catches distant
/// photons that miss the specular surfaces (a disc in the wrong place or of the wrong size),
/// flux per photon off by the disc's area, the caustic counted twice or not at all.
#[test]
fn a_suns_caustic_off_a_mirror_has_the_analytic_irradiance() {
    let scene = xml_seen_from(
        "0, 6, 0.01",
        &format!(
            r#"{}
            <shape type="rectangle">
                <transform name="to_world"><rotate y="1" angle="-90"/><scale x="1" y="0.5" z="2"/><translate x="1" y="0.5"/></transform>
                <bsdf type="conductor"><string name="material" value="none"/></bsdf>
            </shape>
            <emitter type="directional"><vector name="direction" x="1" y="-1" z="0"/><rgb name="irradiance" value="1, 0.8, 0.6"/></emitter>"#,
            floor(r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>"#)
        ),
        3,
    );
    let direct =
        Vec3::new(1.0, 0.8, 0.6) * (0.5 * std::f32::consts::FRAC_1_SQRT_2 / std::f32::consts::PI);
    let image = render(&scene, "graphs/hybrid.ron", 512, 4);
    // Bands a little inside their edges: the photon map's radius blurs the caustic's.
    let bands = [
        ((-1.7, -0.3), direct),
        ((0.25, 0.75), 2.0 * direct),
        ((1.3, 1.7), Vec3::ZERO),
    ];
    for (range, expected) in bands {
        let got = floor_band_mean(&scene, &image, range);
        eprintln!("band {range:?}: {got:?} against {expected:?}");
        let off = ((got - expected).abs() / (expected + Vec3::splat(0.01))).max_element();
        assert!(off < 0.02, "band {range:?}: {got:?} against {expected:?}");
    }
}

/// A furnace under the sky: a white diffuse sphere (albedo 1) beside a glass sphere under a
/// constant environment of radiance 1 is radiance 1 everywhere (nothing absorbs, every path
/// ends in the sky), through every graph. The glass throws the sky's caustic onto the white
/// sphere, which photons from the environment render in the photon-mapping graphs: a caustic
/// counted twice or not at all, environment photons of the wrong flux, or escaping rays
/// weighted wrongly against light sampling move the mean by more than the tolerance (the
/// caustic is printed; the test requires it to be at least 2% of the image, four times the
/// tolerance).
#[test]
fn spheres_under_a_constant_sky_are_a_furnace_through_every_graph() {
    let scene = xml_seen_from(
        "0, 0.5, 1.9",
        r#"<shape type="sphere"><point name="center" x="-0.45" y="0" z="0"/><float name="radius" value="0.5"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></shape>
        <shape type="sphere"><point name="center" x="0.55" y="0" z="0.1"/><float name="radius" value="0.45"/>
            <bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf></shape>
        <emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#,
        -1,
    );
    let gpu = gpu();
    for graph in [
        "graphs/pt.ron",
        "graphs/hybrid.ron",
        "graphs/hybrid_ppm.ron",
        "graphs/hybrid_first_vertex.ron",
        "graphs/ppm_only.ron",
    ] {
        let mut r = renderer(&gpu, &scene, load_graph(graph), 6);
        let image = render_to(&mut r, 128);
        let caustic = common::convergence::caustic_mean(&r);
        let mean = image.mean();
        eprintln!("{graph}: mean {mean:?}, caustic {caustic:.4}");
        for c in mean {
            assert!(
                (c - 1.0).abs() < 0.005,
                "{graph}: image mean {mean:?}, not 1"
            );
        }
        if graph.contains("hybrid") {
            assert!(caustic > 0.02, "{graph}: the caustic is only {caustic}");
        }
    }
}
