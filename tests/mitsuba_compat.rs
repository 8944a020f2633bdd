//! Scenes as people ship them: what Mitsuba 3 accepts, hppm accepts and reads the same way (the
//! figures marked "Mitsuba" were printed by Mitsuba 3.9.1 `scalar_rgb` for the same XML); what
//! hppm cannot render is reported, every problem at once, each at its file:line:col. CPU only.

use std::path::Path;

use glam::Vec3;
use hppm::bsdfs::blendbsdf::Blend;
use hppm::bsdfs::dielectric::Dielectric;
use hppm::bsdfs::diffuse::Diffuse;
use hppm::bsdfs::null::Null;
use hppm::loaders::{Report, mitsuba};
use hppm::scene::filter::PixelFilter;
use hppm::scene::{Bsdf, Scene};

fn check(body: &str) -> Report {
    check_version("3.0.0", body)
}

fn check_version(version: &str, body: &str) -> Report {
    let text = format!("<scene version=\"{version}\">\n{body}\n</scene>");
    mitsuba::check_text(Path::new("shipped.xml"), &text, &[])
}

/// The scene, which must load without errors.
fn scene_of(report: Report) -> Scene {
    let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
    report
        .scene
        .unwrap_or_else(|| panic!("refused: {}", errors.join("\n")))
}

/// `body` (after a sensor on line 2) must be refused with an error at `line` saying `expected`.
fn assert_error_at(body: &str, line: usize, expected: &str) {
    let report = check(&format!("{}\n{body}", sensor("", 8, 8)));
    let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
    let place = format!("shipped.xml:{line}:");
    assert!(
        errors
            .iter()
            .any(|e| e.contains(expected) && e.contains(&place)),
        "{body}: expected \"{expected}\" at line {line} in {errors:?}"
    );
}

/// The scene is refused, and its first error is at `place` and names `field`.
fn assert_refused_first(report: &Report, place: &str, field: &str, what: &dyn std::fmt::Debug) {
    let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
    assert!(
        report.scene.is_none()
            && errors
                .first()
                .is_some_and(|e| e.contains(place) && e.contains(field)),
        "{what:?}: {errors:#?}"
    );
}

/// The report's errors are exactly `expected`, in order: each at its line of shipped.xml and
/// containing its words.
fn assert_errors_in_order(report: &Report, expected: &[(usize, &str)]) {
    let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(errors.len(), expected.len(), "{errors:#?}");
    for (error, (line, words)) in errors.iter().zip(expected) {
        assert!(
            error.contains(&format!("shipped.xml:{line}:")) && error.contains(words),
            "expected line {line} and {words:?} in: {error}"
        );
    }
}

fn warnings(report: &Report) -> Vec<String> {
    report.warnings.iter().map(|w| w.to_string()).collect()
}

const LIGHT: &str = r#"<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#;

fn sensor(inner: &str, width: u32, height: u32) -> String {
    format!(
        r#"<sensor type="perspective">{inner}<film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/></film></sensor>"#
    )
}

/// The horizontal field of view hppm derives from a sensor, against Mitsuba's `x_fov` for the
/// same sensor: the 50 mm default lens (a diagonal fov, so it depends on the film's shape),
/// `focal_length`, and `fov` along each `fov_axis`. A default read as a horizontal 39.3 degrees
/// (hppm's rule before) is 1.1 degrees off at 768x576 and 23.7 at 100x300, and fails.
#[test]
fn the_field_of_view_is_mitsubas_for_every_way_of_giving_it() {
    let cases: &[(&str, u32, u32, f32)] = &[
        ("", 768, 576, 38.184_84),
        ("", 100, 300, 15.581_79),
        ("", 512, 512, 34.022_06),
        (
            r#"<float name="fov" value="40"/><string name="fov_axis" value="diagonal"/>"#,
            640,
            480,
            32.468_6,
        ),
        (
            r#"<string name="focal_length" value="35mm"/>"#,
            640,
            480,
            52.622_54,
        ),
        (
            r#"<float name="fov" value="30"/><string name="fov_axis" value="y"/>"#,
            200,
            100,
            56.373_57,
        ),
    ];
    for &(inner, w, h, mitsuba_x_fov) in cases {
        let scene = scene_of(check(&format!("{}{LIGHT}", sensor(inner, w, h))));
        let fov = scene.camera.fov_x_deg;
        assert!(
            (fov - mitsuba_x_fov).abs() < 1e-3,
            "{inner} at {w}x{h}: {fov} degrees, Mitsuba {mitsuba_x_fov}"
        );
    }
    let both = check(&format!(
        "{}{LIGHT}",
        sensor(
            r#"<float name="fov" value="30"/><string name="focal_length" value="35mm"/>"#,
            64,
            64
        )
    ));
    assert!(both.scene.is_none(), "fov and focal_length together");
}

/// What Mitsuba's perspective sensor reads and a pinhole render does not need (the focal
/// distance of the tutorials' Cornell box, clip planes, shutter times) loads; an off-centre
/// principal point, which would shift the image, is refused rather than ignored.
#[test]
fn the_perspective_sensor_takes_every_property_mitsuba_reads() {
    let inner = r#"<float name="focus_distance" value="1000"/><float name="near_clip" value="0.1"/><float name="far_clip" value="100"/><float name="shutter_open" value="0"/><float name="shutter_close" value="1"/><float name="principal_point_offset_x" value="0"/>"#;
    scene_of(check(&format!("{}{LIGHT}", sensor(inner, 32, 32))));
    let shifted = check(&format!(
        "{}{LIGHT}",
        sensor(
            r#"<float name="principal_point_offset_y" value="0.1"/>"#,
            32,
            32
        )
    ));
    let error = shifted.errors[0].to_string();
    assert!(
        error.contains("shipped.xml:2:") && error.contains("principal point"),
        "{error}"
    );
}

/// A perspective sensor whose 96x64 film holds `props` (hdrfilm's crop window), one a line from
/// line 4 on, so errors can be placed.
fn cropped(props: &[&str]) -> Report {
    let props: String = props.iter().map(|p| format!("\n{p}")).collect();
    check(&format!(
        "<sensor type=\"perspective\">\n<film type=\"hdrfilm\">\n<integer name=\"width\" value=\"96\"/><integer name=\"height\" value=\"64\"/>{props}\n</film></sensor>{LIGHT}"
    ))
}

/// hdrfilm's crop window: the image is the window's size and the fov stays the whole film's
/// (Mitsuba 3.9.1's x_fov for the default 50 mm lens on this 96x64 film cropped to 32x32 is
/// 39.59775 degrees, as uncropped; taken on the square window's shape it would be 34.02). No crop, or a window equal to
/// the film, leaves the camera as it was. A loader that ignored the crop (a 96x64 image) or
/// kept the window's offset nowhere fails.
#[test]
fn a_crop_window_sets_the_image_size_and_keeps_the_films_view() {
    let window = [
        r#"<integer name="crop_offset_x" value="40"/>"#,
        r#"<integer name="crop_offset_y" value="18"/>"#,
        r#"<integer name="crop_width" value="32"/>"#,
        r#"<integer name="crop_height" value="32"/>"#,
    ];
    let scene = scene_of(cropped(&window));
    let camera = &scene.camera;
    assert_eq!((camera.width, camera.height), (32, 32));
    assert_eq!(
        camera.crop,
        Some(hppm::scene::Crop {
            film_width: 96,
            film_height: 64,
            x: 40,
            y: 18
        })
    );
    assert!(
        (camera.fov_x_deg - 39.597_75).abs() < 1e-3,
        "{}",
        camera.fov_x_deg
    );
    let whole = scene_of(cropped(&[
        r#"<integer name="crop_offset_x" value="0"/>"#,
        r#"<integer name="crop_width" value="96"/>"#,
    ]));
    let plain = scene_of(cropped(&[]));
    assert_eq!(whole.camera, plain.camera);
    assert_eq!(plain.camera.crop, None);
    assert_eq!((plain.camera.width, plain.camera.height), (96, 64));
    // Only the width cropped: the height stays the film's.
    let strip = scene_of(cropped(&[r#"<integer name="crop_width" value="10"/>"#]));
    assert_eq!((strip.camera.width, strip.camera.height), (10, 64));
}

/// The window's rays are the film's: the camera plane through pixel (x, y) of the cropped image
/// is the one through pixel (x + 40, y + 18) of the whole film, at the scene's size and at a
/// `--size` of twice it (film and window scaled together). Rendering the film's top-left corner
/// (no offset), the window stretched over the whole view (the window's own projection) or an
/// offset left unscaled under `--size` fails.
#[test]
fn a_crop_window_sees_what_the_film_sees_there() {
    use hppm::gpu_scene::layout::GpuScene;
    let window = [
        r#"<integer name="crop_offset_x" value="40"/>"#,
        r#"<integer name="crop_offset_y" value="18"/>"#,
        r#"<integer name="crop_width" value="32"/>"#,
        r#"<integer name="crop_height" value="24"/>"#,
    ];
    let crop = scene_of(cropped(&window));
    let film = scene_of(cropped(&[]));
    for scale in [1, 2] {
        let c = GpuScene::new(&crop, 32 * scale, 24 * scale)
            .expect("layout")
            .uniform;
        let f = GpuScene::new(&film, 96 * scale, 64 * scale)
            .expect("layout")
            .uniform;
        let plane = |u: &hppm::gpu_scene::layout::GpuSceneUniform, x: f32, y: f32| {
            (
                u.plane_origin[0] + x * u.plane_step_x,
                u.plane_origin[1] + y * u.plane_step_y,
            )
        };
        let s = scale as f32;
        for (x, y) in [
            (0.0, 0.0),
            (0.5, 0.5),
            (31.0, 23.0),
            (32.0, 24.0),
            (-1.5, 25.0),
        ] {
            let (x, y) = (x * s, y * s);
            let seen = plane(&c, x, y);
            let expected = plane(&f, x + 40.0 * s, y + 18.0 * s);
            assert!(
                (seen.0 - expected.0).abs() < 1e-5 && (seen.1 - expected.1).abs() < 1e-5,
                "at {scale}x, image ({x}, {y}): {seen:?}, the film there {expected:?}"
            );
        }
    }
}

/// A crop window that leaves the film is an error at the property that takes it past the edge
/// (the size if given, else the offset: Mitsuba's default size is the whole film), naming the
/// field, as Mitsuba refuses it. A window of no pixels too. Accepting any of them (or placing
/// the error on the film or sensor) fails.
#[test]
fn a_crop_window_off_the_film_is_refused_where_it_is_given() {
    let cases: &[(&[&str], &str, &str)] = &[
        (
            &[
                r#"<integer name="crop_offset_x" value="40"/>"#,
                r#"<integer name="crop_width" value="64"/>"#,
            ],
            "shipped.xml:6:",
            "crop_width 64",
        ),
        (
            &[r#"<integer name="crop_offset_y" value="1"/>"#],
            "shipped.xml:5:",
            "crop_offset_y 1",
        ),
        (
            &[r#"<integer name="crop_height" value="65"/>"#],
            "shipped.xml:5:",
            "crop_height 65",
        ),
        (
            &[r#"<integer name="crop_width" value="0"/>"#],
            "shipped.xml:5:",
            "crop_width 0",
        ),
    ];
    for (props, place, field) in cases {
        assert_refused_first(&cropped(props), place, field, &props);
    }
}

/// Mitsuba's thinlens: aperture and focus distance read (focus defaulting to far_clip, itself
/// 10^4 by default), the fov read as the perspective sensor reads it, a zero aperture a
/// pinhole with a warning, no aperture an error at the sensor (Mitsuba has no default), a
/// principal point shift unknown (thinlens reads none), a negative aperture or focus and clip
/// planes out of order refused. A loader that dropped the lens, took another default focus
/// or let the principal point through fails.
/// The filters with negative lobes read as Mitsuba reads them: Lanczos's `lobes` (default 3),
/// Mitchell's `B` and `C` (default 1/3 each, not swapped), `catmullrom` as B = 0, C = 1/2.
#[test]
fn signed_pixel_filters_read_mitsubas_properties() {
    let film = |rfilter: &str| {
        let body = format!(
            r#"<sensor type="perspective"><film type="hdrfilm">{rfilter}</film></sensor>
               <emitter type="constant"/>"#
        );
        scene_of(check(&body)).camera.filter
    };
    assert_eq!(
        film(r#"<rfilter type="lanczos"/>"#),
        PixelFilter::Lanczos { lobes: 3 }
    );
    assert_eq!(
        film(r#"<rfilter type="lanczos"><integer name="lobes" value="5"/></rfilter>"#),
        PixelFilter::Lanczos { lobes: 5 }
    );
    assert_eq!(
        film(r#"<rfilter type="mitchell"/>"#),
        PixelFilter::Mitchell {
            b: 1.0 / 3.0,
            c: 1.0 / 3.0
        }
    );
    assert_eq!(
        film(
            r#"<rfilter type="mitchell"><float name="B" value="0.2"/><float name="C" value="0.6"/></rfilter>"#
        ),
        PixelFilter::Mitchell { b: 0.2, c: 0.6 }
    );
    assert_eq!(
        film(r#"<rfilter type="catmullrom"/>"#),
        PixelFilter::CATMULL_ROM
    );
}

#[test]
fn the_thinlens_sensor_reads_what_mitsubas_reads() {
    use hppm::scene::Lens;
    let lens = |inner: &str| {
        check(&format!(
            "<sensor type=\"thinlens\">\n{inner}\n<film type=\"hdrfilm\"><integer name=\"width\" value=\"200\"/><integer name=\"height\" value=\"100\"/></film></sensor>{LIGHT}"
        ))
    };
    let scene = scene_of(lens(
        r#"<float name="aperture_radius" value="0.2"/><float name="focus_distance" value="3"/><float name="fov" value="30"/><string name="fov_axis" value="y"/>"#,
    ));
    assert_eq!(
        scene.camera.lens,
        Some(Lens {
            aperture_radius: 0.2,
            focus_distance: 3.0
        })
    );
    assert!((scene.camera.fov_x_deg - 56.373_57).abs() < 1e-3);
    let far = scene_of(lens(
        r#"<float name="aperture_radius" value="0.2"/><float name="far_clip" value="50"/>"#,
    ));
    assert_eq!(far.camera.lens.map(|l| l.focus_distance), Some(50.0));
    let default = scene_of(lens(r#"<float name="aperture_radius" value="0.2"/>"#));
    assert_eq!(default.camera.lens.map(|l| l.focus_distance), Some(1e4));
    let pinhole = lens(r#"<float name="aperture_radius" value="0"/>"#);
    assert!(
        warnings(&pinhole)
            .iter()
            .any(|w| w.contains("aperture_radius 0")),
        "{:?}",
        warnings(&pinhole)
    );
    assert_eq!(scene_of(pinhole).camera.lens, None);
    let refused: &[(&str, &str, &str)] = &[
        ("", "shipped.xml:2:", "aperture_radius"),
        (
            r#"<float name="aperture_radius" value="0.1"/><float name="principal_point_offset_x" value="0.1"/>"#,
            "shipped.xml:3:",
            "principal_point_offset_x",
        ),
        (
            r#"<float name="aperture_radius" value="-0.1"/>"#,
            "shipped.xml:3:",
            "aperture_radius -0.1",
        ),
        (
            r#"<float name="aperture_radius" value="0.1"/><float name="focus_distance" value="0"/>"#,
            "shipped.xml:3:",
            "focus_distance 0",
        ),
        (
            r#"<float name="aperture_radius" value="0.1"/><float name="near_clip" value="5"/><float name="far_clip" value="2"/>"#,
            "shipped.xml:3:",
            "near_clip 5",
        ),
    ];
    for (inner, place, field) in refused {
        assert_refused_first(&lens(inner), place, field, &inner);
    }
}

/// A `<lookat>` without `up` (Mitsuba picks one orthogonal to the view): the camera's up
/// direction equals the second column of Mitsuba's to_world for the same lookat. Any other
/// choice of perpendicular (or an error) fails.
#[test]
fn a_lookat_without_up_turns_the_camera_as_mitsuba_does() {
    let cases = [
        (
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.960_356_8, -0.079_286_5, -0.267_261_2),
        ),
        (Vec3::new(0.0, 5.0, 0.0), Vec3::new(1.0, 0.0, 0.0)),
        (
            Vec3::new(-2.0, 0.5, -4.0),
            Vec3::new(0.895_424_8, 0.026_143_8, -0.444_444_4),
        ),
    ];
    for (origin, mitsuba_up) in cases {
        let lookat = format!(
            r#"<transform name="to_world"><lookat origin="{}, {}, {}" target="0, 0, 0"/></transform>"#,
            origin.x, origin.y, origin.z
        );
        let camera = scene_of(check(&format!("{}{LIGHT}", sensor(&lookat, 8, 8)))).camera;
        let view = (camera.target - camera.origin).normalize();
        let up = (camera.up - view * camera.up.dot(view)).normalize();
        assert!(
            up.distance(mitsuba_up) < 1e-5,
            "origin {origin}: up {up}, Mitsuba {mitsuba_up}"
        );
    }
}

/// Any integrator is advice: its path depths are taken (`direct` means two segments; a wrapper
/// such as `aov` gives its nested integrator's), and one warning names it and what is left
/// out. A sampler gives its sample count the same way. An integer given as a float is still an
/// error, as in Mitsuba.
#[test]
fn integrators_and_samplers_are_advice() {
    let cases: &[(&str, Option<u32>, &str)] = &[
        (
            r#"<integrator type="bdpt"><integer name="max_depth" value="6"/><boolean name="light_image" value="false"/></integrator>"#,
            Some(6),
            "light_image",
        ),
        (
            r#"<integrator type="path_guiding_integrator"><integer name="max_depth" value="-1"/></integrator>"#,
            None,
            "path_guiding_integrator",
        ),
        (r#"<integrator type="direct"/>"#, Some(2), "direct"),
        (
            r#"<integrator type="aov"><string name="aovs" value="nn:sh_normal"/><integrator type="path"><integer name="max_depth" value="3"/></integrator></integrator>"#,
            Some(3),
            "aov",
        ),
    ];
    for &(integrator, depth, named) in cases {
        let report = check(&format!("{integrator}{}{LIGHT}", sensor("", 8, 8)));
        let said = warnings(&report);
        let scene = scene_of(report);
        assert_eq!(scene.integrator.max_depth, depth, "{integrator}");
        assert!(
            said.len() == 1 && said[0].contains(named) && said[0].contains("shipped.xml:2:"),
            "{integrator}: {said:?}"
        );
    }
    let sampled = check(&format!(
        "{}{LIGHT}",
        sensor(
            r#"<sampler type="ldsampler"><integer name="sample_count" value="64"/></sampler>"#,
            8,
            8
        )
    ));
    let said = warnings(&sampled);
    assert_eq!(scene_of(sampled).spp_hint, Some(64));
    assert!(said.len() == 1 && said[0].contains("ldsampler"), "{said:?}");
    let typed = check(&format!(
        r#"<integrator type="volpath"><float name="max_depth" value="3"/></integrator>{}{LIGHT}"#,
        sensor("", 8, 8)
    ));
    assert!(typed.scene.is_none(), "a float max_depth was accepted");
    // The volumetric path tracers are what hppm renders media as: no warning.
    for kind in ["volpath", "volpathmis"] {
        let report = check(&format!(
            r#"<integrator type="{kind}"><integer name="max_depth" value="5"/><integer name="rr_depth" value="3"/></integrator>{}{LIGHT}"#,
            sensor("", 8, 8)
        ));
        assert!(
            warnings(&report).is_empty(),
            "{kind}: {:?}",
            warnings(&report)
        );
        let integrator = scene_of(report).integrator;
        assert_eq!(
            (integrator.max_depth, integrator.rr_depth),
            (Some(5), Some(3))
        );
    }
}

/// A file written for Mitsuba 0.5 loads as Mitsuba 3 upgrades it: camelCase property names
/// become snake_case (`maxDepth`, `fovAxis`, `toWorld`, `sampleCount`), a diffuse BSDF's
/// `diffuseReflectance` becomes `reflectance`, and properties only 0.x read are warnings. In a
/// version 3 file the same camelCase name is an unknown property with a did-you-mean.
#[test]
fn old_scenes_are_upgraded_as_mitsuba_upgrades_them() {
    let body = r#"<integrator type="path"><integer name="maxDepth" value="6"/><boolean name="strictNormals" value="true"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/><string name="fovAxis" value="y"/>
<transform name="toWorld"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
<sampler type="independent"><integer name="sampleCount" value="16"/></sampler>
<film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="16"/><boolean name="highQualityEdges" value="true"/></film></sensor>
<shape type="sphere"><bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.25"/></bsdf></shape>
<shape type="rectangle"><transform name="toWorld"><translate z="3"/></transform><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#;
    let report = check_version("0.5.0", body);
    let said = warnings(&report);
    let scene = scene_of(report);
    assert_eq!(scene.integrator.max_depth, Some(6));
    assert_eq!(scene.spp_hint, Some(16));
    assert_eq!(scene.camera.origin, Vec3::new(0.0, 0.0, 4.0));
    // fov 40 along y of a 2:1 film.
    let x_fov = 2.0 * (20f32.to_radians().tan() * 2.0).atan().to_degrees();
    assert!((scene.camera.fov_x_deg - x_fov).abs() < 1e-3);
    assert!(scene.materials.iter().any(|m| {
        m.bsdf
            .get::<Diffuse>()
            .is_some_and(|d| d.reflectance == Vec3::splat(0.25))
    }));
    assert_eq!(said.len(), 2, "{said:?}");
    assert!(said[0].contains("strict_normals") && said[1].contains("high_quality_edges"));

    let current = check_version("3.0.0", body);
    let first = current.errors[0].to_string();
    assert!(
        first.contains("shipped.xml:2:") && first.contains("did you mean \"max_depth\"?"),
        "{first}"
    );
}

/// Every problem at once: four broken objects and a typo in a fifth are five errors in file
/// order, each at its own line (a loader stopping at the first would report one); a reference
/// to a BSDF that failed says so instead of calling it undeclared; warnings come apart from
/// errors; a property Mitsuba never read is still an error with a did-you-mean.
#[test]
fn every_problem_is_reported_at_once() {
    let body = r#"<bsdf type="diffuse" id="a"><rgb name="reflectanse" value="0.5"/></bsdf>
<bsdf type="bumpmap" id="b"><bsdf type="diffuse"/></bsdf>
<shape type="sphere"><ref id="a"/></shape>
<shape type="sphere"><float name="radius" value="one"/></shape>
<integrator type="bdpt"/>
<shape type="cube"><bsdf type="plastic"><float name="int_ior" value="1.5"/><float name="intior" value="1.5"/></bsdf></shape>
<emitter type="timed_sunsky"/>"#;
    let report = check(&format!("{body}{}{LIGHT}", sensor("", 8, 8)));
    let expected: &[(usize, &str)] = &[
        (2, "did you mean \"reflectance\"?"),
        (3, "bumpmap needs a <texture"),
        (4, "the <bsdf id=\"a\"> at line 2 could not be read"),
        (5, "expected a number"),
        (7, "did you mean \"int_ior\"?"),
        (8, "timed_sunsky"),
    ];
    assert_errors_in_order(&report, expected);
    assert_eq!(warnings(&report).len(), 1, "bdpt's warning");
    assert!(report.scene.is_none());
}

/// A sensor's sampler, film and filter each report their problems and the sensor is read on:
/// an unknown sampler property, an unsupported filter, an unknown film property, the film's
/// `compensate` warning and an unknown sensor property, all at once (a failed filter used to
/// hide the rest of its sensor).
#[test]
fn a_sensors_problems_are_all_reported() {
    let body = r#"<sensor type="perspective">
<sampler type="independent"><integer name="sample_cont" value="4"/></sampler>
<film type="hdrfilm"><rfilter type="blackman"/>
<boolean name="compensate" value="true"/><integer name="heigth" value="3"/></film>
<float name="fvo" value="30"/></sensor>"#;
    let report = check(&format!("{body}{LIGHT}"));
    let expected: &[(usize, &str)] = &[
        (3, "did you mean \"sample_count\"?"),
        (4, "rfilter \"blackman\" is not supported"),
        (5, "unknown property \"heigth\""),
        (6, "unknown property \"fvo\""),
    ];
    assert_errors_in_order(&report, expected);
    assert_eq!(warnings(&report).len(), 1, "compensate's warning");
    assert!(report.scene.is_none());
}

/// `<shape type="serialized">` picks the file's shape by `shape_index` (the reader itself is
/// checked against Mitsuba's in src/loaders/serialized.rs): the v4 file's cube (12 triangles,
/// its normals kept, so it shades smoothly unless `face_normals`) and tetrahedron (4); an index
/// past the file's shapes is an error at the shape's line that says how many there are.
#[test]
fn serialized_shapes_load_by_index() {
    let shape = |index: i32, extra: &str| {
        format!(
            r#"<shape type="serialized"><string name="filename" value="tests/data/serialized/two_shapes_v4.serialized"/><integer name="shape_index" value="{index}"/>{extra}</shape>"#
        )
    };
    let scene = scene_of(check(&format!(
        "{}{}{}{LIGHT}",
        shape(0, ""),
        shape(1, r#"<boolean name="face_normals" value="true"/>"#),
        sensor("", 8, 8)
    )));
    // 12 + 4 triangles, then the light's 2.
    assert_eq!(scene.triangles.len(), 18);
    let missing = check(&format!("{}{}{LIGHT}", shape(2, ""), sensor("", 8, 8)));
    let error = missing.errors[0].to_string();
    assert!(
        error.contains("2 shapes") && error.contains("shipped.xml:2:"),
        "{error}"
    );
}

/// A scene split over files as Mitsuba allows: `<include>` of a file holding a `<scene>` (its
/// elements read in place, in a Mitsuba 0.5 file upgraded on its own) and of a file holding one
/// `<bsdf>`; `<path>` adding a folder where a mesh is found; `<alias>` giving a BSDF a second
/// id. A missing include is an error at the `<include>`'s line, with the rest still checked.
#[test]
fn includes_paths_and_aliases_load() {
    let dir = std::env::temp_dir().join(format!("hppm_includes_{}", std::process::id()));
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    write(
        "materials.xml",
        r#"<scene version="0.5.0"><bsdf type="diffuse" id="grey"><rgb name="diffuseReflectance" value="0.3"/></bsdf></scene>"#,
    );
    write(
        "glass.xml",
        r#"<bsdf type="dielectric" id="glass"><string name="int_ior" value="acrylic glass"/></bsdf>"#,
    );
    std::fs::write(
        meshes.join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let scene_text = format!(
        r#"<scene version="3.0.0">
<include filename="materials.xml"/>
<include filename="glass.xml"/>
<path value="meshes"/>
<alias id="grey" as="floor_material"/>
{}
<shape type="obj"><string name="filename" value="tri.obj"/><ref id="floor_material"/></shape>
<shape type="sphere"><ref id="glass"/></shape>
{LIGHT}
</scene>"#,
        sensor("", 8, 8)
    );
    write("scene.xml", &scene_text);
    let scene = scene_of(mitsuba::check_with(&dir.join("scene.xml"), &[]));
    assert!(scene.materials.iter().any(|m| {
        m.bsdf
            .get::<Diffuse>()
            .is_some_and(|d| d.reflectance == Vec3::splat(0.3))
    }));
    assert!(scene.materials.iter().any(|m| {
        m.bsdf
            .get::<Dielectric>()
            .is_some_and(|d| d.int_ior == 1.49)
    }));
    assert_eq!(
        scene.triangles.len(),
        1 + 2,
        "the OBJ's triangle and the light's two"
    );

    write(
        "broken.xml",
        &scene_text
            .replace("glass.xml", "missing.xml")
            .replace("tri.obj", "none.obj"),
    );
    let report = mitsuba::check_with(&dir.join("broken.xml"), &[]);
    let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        errors.len() == 3
            && errors[0].contains("broken.xml:3:")
            && errors[0].contains("missing.xml")
            && errors[1].contains("none.obj")
            && !errors[2].contains("could not be read")
            && errors[2].contains("broken.xml:8:"),
        "{errors:#?}"
    );
}

/// A texture is decoded by what its bytes are: a progressive JPEG saved under a .png name (as
/// downloaded scenes have) reads as the same picture as the lossless PNG it was made from, to
/// within JPEG's loss (its halved chroma: under 6% per channel; swapped channels or a wrong
/// decode are off by up to 100%). Decoding by the name's format refuses it.
#[test]
fn textures_are_decoded_by_their_content() {
    let read = |name: &str| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/textures")
            .join(name);
        hppm::scene::texture::read_image(&path, true).unwrap_or_else(|e| panic!("{e}"))
    };
    let (w, h, jpeg) = read("gradient_progressive_named.png");
    let (pw, ph, png) = read("gradient.png");
    assert_eq!((w, h), (pw, ph));
    let worst = jpeg
        .iter()
        .zip(&png)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(worst < 0.06, "worst channel difference {worst}");
}

/// Shapegroups and instances: each instance adds the group's shapes placed by its own
/// transform (rendered against Mitsuba in tests/differential/plugins/instances); an emitter in
/// a group (Mitsuba refuses one too), an instance of an undeclared group and an instance of a
/// group that failed are errors at their lines.
#[test]
fn instances_place_shapegroups() {
    let group = r#"<shape type="shapegroup" id="g"><shape type="cube"/><shape type="sphere"><point name="center" value="3, 0, 0"/></shape></shape>"#;
    let instance = |x: f32| {
        format!(
            r#"<shape type="instance"><ref id="g"/><transform name="to_world"><translate x="{x}"/></transform></shape>"#
        )
    };
    let scene = scene_of(check(&format!(
        "{group}{}{}{}{LIGHT}",
        instance(0.0),
        instance(10.0),
        sensor("", 8, 8)
    )));
    assert_eq!(scene.triangles.len(), 2 * 12 + 2, "two cubes and the light");
    let centres: Vec<f32> = scene.spheres.iter().map(|s| s.center.x).collect();
    assert_eq!(centres, [3.0, 13.0]);

    let broken = check(&format!(
        r#"<shape type="shapegroup" id="lit"><shape type="cube"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></shape>
<shape type="instance"><ref id="lit"/></shape>
<shape type="instance"><ref id="nothing"/></shape>
{}{LIGHT}"#,
        sensor("", 8, 8)
    ));
    let errors: Vec<String> = broken.errors.iter().map(|e| e.to_string()).collect();
    assert!(
        errors.len() == 3
            && errors[0].contains("cannot emit")
            && errors[1].contains("shipped.xml:3:")
            && errors[1].contains("could not be read")
            && errors[2].contains("shipped.xml:4:"),
        "{errors:#?}"
    );
}

/// A scene holding one object of `object` type `kind`, with `property` (XML) inside it and
/// whatever else that plugin needs to load.
fn host(object: &str, kind: &str, property: &str) -> String {
    let film = r#"<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>"#;
    let plain = format!(r#"<sensor type="perspective">{film}</sensor>"#);
    let on_cube = |inner: String| format!(r#"<shape type="cube">{inner}</shape>{plain}{LIGHT}"#);
    match object {
        "integrator" => {
            format!(r#"<integrator type="{kind}">{property}</integrator>{plain}{LIGHT}"#)
        }
        "sensor" => {
            // Mitsuba's thinlens has no default aperture.
            let needs = match kind {
                "thinlens" => r#"<float name="aperture_radius" value="0.1"/>"#,
                _ => "",
            };
            format!(r#"<sensor type="{kind}">{needs}{property}{film}</sensor>{LIGHT}"#)
        }
        "sampler" => format!(
            r#"<sensor type="perspective"><sampler type="{kind}">{property}</sampler>{film}</sensor>{LIGHT}"#
        ),
        "film" => format!(
            r#"<sensor type="perspective"><film type="{kind}">{property}</film></sensor>{LIGHT}"#
        ),
        "rfilter" => format!(
            r#"<sensor type="perspective"><film type="hdrfilm"><rfilter type="{kind}">{property}</rfilter></film></sensor>{LIGHT}"#
        ),
        "shape" => {
            let file = |path: &str| format!(r#"<string name="filename" value="{path}"/>"#);
            let shape = match kind {
                "shapegroup" => {
                    format!(
                        r#"<shape type="shapegroup" id="g">{property}<shape type="cube"/></shape>"#
                    )
                }
                "instance" => format!(
                    r#"<shape type="shapegroup" id="g"><shape type="cube"/></shape><shape type="instance"><ref id="g"/>{property}</shape>"#
                ),
                _ => {
                    let needs = match kind {
                        "obj" => file("tests/differential/plugins/instances/ring0.obj"),
                        "ply" => file("tests/data/mitsuba/smooth_sphere.ply"),
                        "serialized" => file("tests/data/serialized/two_shapes_v4.serialized"),
                        _ => String::new(),
                    };
                    format!(r#"<shape type="{kind}">{needs}{property}</shape>"#)
                }
            };
            format!("{shape}{plain}{LIGHT}")
        }
        "bsdf" if kind == "twosided" => on_cube(format!(
            r#"<bsdf type="twosided">{property}<bsdf type="diffuse"/></bsdf>"#
        )),
        "bsdf" if kind == "normalmap" || kind == "bumpmap" => {
            let name = if kind == "normalmap" {
                "normalmap"
            } else {
                "height"
            };
            on_cube(format!(
                r#"<bsdf type="{kind}"><texture name="{name}" type="bitmap"><string name="filename" value="tests/data/textures/grid4.png"/><boolean name="raw" value="true"/></texture>{property}<bsdf type="diffuse"/></bsdf>"#
            ))
        }
        "bsdf" if kind == "blendbsdf" => {
            // The weight it needs, unless the property under test is that weight.
            let weight = if property.is_empty() {
                r#"<float name="weight" value="0.5"/>"#
            } else {
                ""
            };
            on_cube(format!(
                r#"<bsdf type="blendbsdf">{weight}{property}<bsdf type="diffuse"/><bsdf type="roughconductor"/></bsdf>"#
            ))
        }
        "bsdf" if kind == "mixturebsdf" => {
            // The weights it needs, unless the property under test is those weights.
            let weights = if property.is_empty() {
                r#"<string name="weights" value="0.5, 0.5"/>"#
            } else {
                ""
            };
            on_cube(format!(
                r#"<bsdf type="mixturebsdf">{weights}{property}<bsdf type="diffuse"/><bsdf type="roughconductor"/></bsdf>"#
            ))
        }
        "bsdf" if kind == "coating" || kind == "roughcoating" => on_cube(format!(
            r#"<bsdf type="{kind}">{property}<bsdf type="diffuse"/></bsdf>"#
        )),
        "bsdf" if kind == "mask" => on_cube(format!(
            r#"<bsdf type="mask">{property}<bsdf type="diffuse"/></bsdf>"#
        )),
        "bsdf" => on_cube(format!(r#"<bsdf type="{kind}">{property}</bsdf>"#)),
        "texture" => {
            let needs = match kind {
                "bitmap" => r#"<string name="filename" value="tests/data/textures/grid4.png"/>"#,
                _ => "",
            };
            on_cube(format!(
                r#"<bsdf type="diffuse"><texture name="reflectance" type="{kind}">{needs}{property}</texture></bsdf>"#
            ))
        }
        "emitter" if kind == "area" => format!(
            r#"<shape type="cube"><emitter type="area">{property}</emitter></shape>{plain}"#
        ),
        "emitter" => {
            let needs = match kind {
                "envmap" => r#"<string name="filename" value="tests/data/textures/grid4.png"/>"#,
                _ => "",
            };
            format!(
                r#"<emitter type="{kind}">{needs}{property}</emitter><shape type="cube"/>{plain}"#
            )
        }
        "spectrum" => {
            let needs = match kind {
                "blackbody" => r#"<float name="temperature" value="3000"/>"#,
                "regular" => r#"<string name="values" value="0.2, 0.4"/>"#,
                "irregular" => {
                    r#"<string name="wavelengths" value="400, 700"/><string name="values" value="0.2, 0.4"/>"#
                }
                "srgb" => r#"<rgb name="color" value="0.5"/>"#,
                _ => "",
            };
            on_cube(format!(
                r#"<bsdf type="diffuse"><spectrum name="reflectance" type="{kind}">{needs}{property}</spectrum></bsdf>"#
            ))
        }
        "medium" | "phase" | "volume" => {
            let medium = match object {
                "medium" => format!(r#"<medium type="{kind}" id="m">{property}</medium>"#),
                "phase" => format!(
                    r#"<medium type="homogeneous" id="m"><phase type="{kind}">{property}</phase></medium>"#
                ),
                _ if kind == "gridvolume" => format!(
                    r#"<medium type="heterogeneous" id="m"><volume type="{kind}" name="sigma_t"><string name="filename" value="tests/data/volumes/ramp.vol"/>{property}</volume></medium>"#
                ),
                _ => format!(
                    r#"<medium type="homogeneous" id="m"><volume type="{kind}" name="sigma_t">{property}</volume></medium>"#
                ),
            };
            format!(
                r#"{medium}<shape type="sphere"><ref name="interior" id="m"/><bsdf type="null"/></shape>{plain}{LIGHT}"#
            )
        }
        other => panic!("no host for {other}"),
    }
}

/// The plugin table (src/loaders/plugins.rs, which docs/scenes.md's table and the loader's messages
/// come from) and the loader agree both ways: each listed plugin loads with what it needs; a
/// listed property is read (given a value of the wrong type, the loader says so rather than
/// calling it unknown); and every property the loader looks for is listed. A property added to
/// the loader but not to the table, or listed but never read, fails here.
#[test]
fn the_plugin_table_is_what_the_loader_reads() {
    let mut failures = Vec::new();
    for plugin in hppm::loaders::plugins::all(&hppm::bsdfs::BsdfRegistry::builtin()) {
        for kind in plugin.kinds {
            let kind = if *kind == "any other" {
                "made_up"
            } else {
                kind
            };
            // Mitsuba 0.6's plugins that Mitsuba 3 dropped (roughdiffuse, phong, ward, difftrans,
            // mixturebsdf, hk, coating, roughcoating) are refused in version 3 files, saying so;
            // they are checked in a 0.6.0 file.
            let mut version = "3.0.0";
            let base = check(&host(plugin.object, kind, ""));
            let base = if base
                .errors
                .iter()
                .any(|e| e.to_string().contains("is a Mitsuba 0.6 plugin"))
            {
                version = "0.6.0";
                check_version(version, &host(plugin.object, kind, ""))
            } else {
                base
            };
            if !base.errors.is_empty() {
                failures.push(format!(
                    "{} {kind} does not load: {:?}",
                    plugin.object,
                    base.errors
                        .iter()
                        .map(|e| e.to_string())
                        .collect::<Vec<_>>()
                ));
                continue;
            }
            let key = format!("{} {kind}", plugin.object);
            for read in base.properties_read.get(&key).into_iter().flatten() {
                if !plugin.properties.iter().any(|p| p.name == read) {
                    failures.push(format!(
                        "{key} reads \"{read}\", which the table leaves out"
                    ));
                }
            }
            for property in plugin.properties {
                let given = format!(r#"<boolean name="{}" value="true"/>"#, property.name);
                let report = check_version(version, &host(plugin.object, kind, &given));
                let unknown = report
                    .errors
                    .iter()
                    .map(|e| e.to_string())
                    .find(|e| e.contains("unknown property"));
                if let Some(e) = unknown {
                    failures.push(format!(
                        "{key}: listed \"{}\" is not read: {e}",
                        property.name
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The plugin table of docs/scenes.md is the code's (`hppm plugins`): edit
/// src/loaders/plugins.rs, then paste `hppm plugins` between docs/scenes.md's `plugins:begin` and
/// `plugins:end` markers.
#[test]
fn the_plugin_table_of_docs_is_generated_from_the_code() {
    let doc = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("docs")
            .join("scenes.md"),
    )
    .expect("docs/scenes.md");
    let begin = "<!-- plugins:begin -->\n";
    let start = doc.find(begin).expect("plugins:begin marker") + begin.len();
    let end = doc
        .find("<!-- plugins:end -->")
        .expect("plugins:end marker");
    assert!(
        doc[start..end] == hppm::loaders::plugins::markdown(&hppm::bsdfs::BsdfRegistry::builtin()),
        "docs/scenes.md's plugin table differs from `hppm plugins`: regenerate it"
    );
}

/// The materials a shape's blend chooses among, as (weight, first, second) and the children.
fn blend_of(scene: &Scene, material: u32) -> (f32, Bsdf, Bsdf) {
    let m = &scene.materials[material as usize];
    let Some(&Blend {
        weight,
        children: [first, second],
    }) = m.bsdf.get::<Blend>()
    else {
        panic!("not a blend: {:?}", m.bsdf);
    };
    assert!(first < material && second < material, "children come first");
    (
        weight,
        scene.materials[first as usize].bsdf.clone(),
        scene.materials[second as usize].bsdf.clone(),
    )
}

/// `blendbsdf`, `mask` and `null` load as Mitsuba reads them: the weight is the second child's
/// share; a mask is a blend of `null` and its BSDF by opacity (0.5 by default); children may be
/// `<ref>`s and blends themselves; a texture weight is kept; a `bumpmap` around a blend perturbs
/// both children (copies, so the referenced BSDF elsewhere keeps its plain frame). Would catch
/// children swapped, the default opacity, a lost texture or frame.
#[test]
fn blends_and_masks_load_as_mitsuba_reads_them() {
    let body = format!(
        r#"<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
        <shape type="cube"><bsdf type="blendbsdf"><float name="weight" value="0.25"/><ref id="red"/><bsdf type="roughconductor"/></bsdf></shape>
        <shape type="cube"><bsdf type="mask"><ref id="red"/></bsdf></shape>
        <shape type="cube"><bsdf type="null"/></shape>
        <shape type="cube"><bsdf type="blendbsdf"><texture name="weight" type="checkerboard"/><bsdf type="blendbsdf"><float name="weight" value="0.5"/><ref id="red"/><bsdf type="null"/></bsdf><ref id="red"/></bsdf></shape>
        <shape type="cube"><bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="tests/data/textures/grid4.png"/></texture><bsdf type="mask"><float name="opacity" value="0.7"/><ref id="red"/></bsdf></bsdf></shape>
        <shape type="cube"><ref id="red"/></shape>
        {}{LIGHT}"#,
        sensor("", 8, 8)
    );
    let scene = scene_of(check(&body));
    let shape = |i: usize| scene.triangles[12 * i].material;
    let red = hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::new(0.8, 0.1, 0.1));
    let (w, first, second) = blend_of(&scene, shape(0));
    assert_eq!((w, &first), (0.25, &red));
    assert!(second.kind() == "roughconductor");
    assert_eq!(blend_of(&scene, shape(1)), (0.5, Null::bsdf(), red.clone()));
    assert_eq!(scene.materials[shape(2) as usize].bsdf, Null::bsdf());
    let textured = &scene.materials[shape(3) as usize];
    assert!(textured.textures.front.blend_weight.is_some());
    let (_, inner, outer_second) = blend_of(&scene, shape(3));
    assert!(inner.kind() == "blend");
    assert_eq!(outer_second, red);
    let Some(&Blend {
        children: [first, second],
        ..
    }) = scene.materials[shape(4) as usize].bsdf.get::<Blend>()
    else {
        panic!("bumpmap > mask is a blend");
    };
    assert_eq!(blend_of(&scene, shape(4)).0, 0.7);
    let frame = |i: u32| scene.materials[i as usize].textures.front.frame;
    assert!(frame(first).is_some() && frame(second).is_some());
    assert!(
        frame(shape(5)).is_none(),
        "the referenced BSDF keeps its own frame"
    );
    assert!(scene.features().has_bsdf("blend"));
}

/// What Mitsuba refuses, hppm refuses at the element, every problem at once: a blendbsdf
/// without its weight, with one child or three; a mask inside twosided (its pass-through
/// transmits); a blend inside twosided with a dielectric child.
#[test]
fn broken_blends_are_errors_at_their_line() {
    let cases = [
        (
            r#"<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            "needs a weight",
        ),
        (
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/></bsdf>"#,
            "needs two nested",
        ),
        (
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            "at most 2",
        ),
        (
            r#"<bsdf type="twosided"><bsdf type="mask"><bsdf type="diffuse"/></bsdf></bsdf>"#,
            "without transmission",
        ),
        (
            r#"<bsdf type="twosided"><bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/><bsdf type="dielectric"/></bsdf></bsdf>"#,
            "without transmission",
        ),
        (
            r#"<bsdf type="mask"><float name="opacty" value="0.5"/><bsdf type="diffuse"/></bsdf>"#,
            "opacity",
        ),
    ];
    for (bsdf, expected) in cases {
        assert_error_at(
            &format!("<shape type=\"cube\">{bsdf}</shape>{LIGHT}"),
            3,
            expected,
        );
    }
}

/// `principled` reads what Mitsuba's reads: `specular` 0.5 is eta 1.5 (Mitsuba's
/// 2 / (1 - sqrt(0.08 s)) - 1), `eta` and `specular` together are refused, a parameter counts
/// as given (Mitsuba's m_has_*) when it is a texture or a float other than 0, every parameter
/// Mitsuba reads as a texture takes one (kept in its slot) and `eta` and `specular`, which it
/// reads as numbers, refuse one by name. Would catch a lobe switched on by a zero, the
/// specular-to-eta mapping, a texture silently dropped or kept in another parameter's slot.
#[test]
fn principled_reads_what_mitsuba_reads() {
    use hppm::bsdfs::principled::{
        HAS_CLEARCOAT, HAS_METALLIC, HAS_SHEEN, HAS_SPEC_TRANS, Principled,
    };
    let shape = |bsdf: &str| {
        format!(
            "{}\n<shape type=\"cube\"><bsdf type=\"principled\">{bsdf}</bsdf></shape>{LIGHT}",
            sensor("", 8, 8)
        )
    };
    let scene = scene_of(check(&shape(
        r#"<float name="sheen" value="0"/><float name="clearcoat" value="0.5"/><texture name="metallic" type="checkerboard"/><texture name="roughness" type="checkerboard"/><texture name="spec_trans" type="checkerboard"/>"#,
    )));
    let m = &scene.materials[scene.triangles[0].material as usize];
    let Some(p) = m.bsdf.get::<Principled>() else {
        panic!("not principled: {:?}", m.bsdf);
    };
    assert!(
        (p.eta - 1.5).abs() < 1e-6,
        "specular 0.5 is eta 1.5: {}",
        p.eta
    );
    assert_eq!(p.has & HAS_SHEEN, 0, "a zero or absent lobe is off");
    assert_eq!(
        p.has & (HAS_CLEARCOAT | HAS_METALLIC | HAS_SPEC_TRANS),
        HAS_CLEARCOAT | HAS_METALLIC | HAS_SPEC_TRANS
    );
    assert!(m.textures.front.alpha_u.is_some() && m.textures.front.alpha_v.is_some());
    let spec_trans = hppm::bsdfs::principled::TEXTURED
        .iter()
        .position(|&n| n == "spec_trans");
    for (i, slot) in m.textures.front.fields.iter().enumerate() {
        assert_eq!(slot.is_some(), Some(i) == spec_trans, "principled slot {i}");
    }
    for (bsdf, expected) in [
        (
            r#"<float name="eta" value="1.3"/><float name="specular" value="0.3"/>"#,
            "not both",
        ),
        (
            r#"<texture name="eta" type="checkerboard"/>"#,
            "takes no texture",
        ),
        (
            r#"<texture name="specular" type="checkerboard"/>"#,
            "takes no texture",
        ),
    ] {
        assert_error_at(
            &format!("<shape type=\"cube\"><bsdf type=\"principled\">{bsdf}</bsdf></shape>{LIGHT}"),
            3,
            expected,
        );
    }
}

/// Media as Mitsuba 3 reads them: a top-level `homogeneous` medium with an id (albedo, sigma_t
/// times `scale`, a nested `hg`), referenced as a shape's interior; a nested exterior with a
/// `constvolume` coefficient and `rayleigh`; the sensor's medium by `<ref>`; Mitsuba's defaults
/// (albedo 0.75, sigma_t 1, isotropic, hg g 0.8). A medium put on the wrong side, a scale not
/// applied or a default that is not Mitsuba's fails.
#[test]
fn media_are_read_as_mitsuba_defines_them() {
    use hppm::scene::medium::{Medium, Phase};
    let scene = scene_of(check(&format!(
        r#"<medium type="homogeneous" id="fog">
    <rgb name="albedo" value="0.9, 0.8, 0.7"/><float name="sigma_t" value="0.5"/><float name="scale" value="2"/>
    <phase type="hg"><float name="g" value="0.3"/></phase>
</medium>
<medium type="homogeneous" id="plain"/>
<medium type="homogeneous" id="default_hg"><phase type="hg"/></medium>
{}
<shape type="sphere"><ref name="interior" id="fog"/><bsdf type="dielectric"/></shape>
<shape type="cube"><bsdf type="null"/>
    <medium type="homogeneous" name="exterior"><volume type="constvolume" name="sigma_t"><rgb name="value" value="1, 2, 3"/></volume><phase type="rayleigh"/></medium>
</shape>{LIGHT}"#,
        sensor(r#"<ref id="plain" name="medium"/>"#, 8, 8)
    )));
    let media = &scene.media.list;
    let fog = Medium {
        sigma_t: Vec3::splat(1.0),
        albedo: Vec3::new(0.9, 0.8, 0.7),
        phase: Phase::HenyeyGreenstein { g: 0.3 },
        sample_emitters: true,
        density: None,
    };
    let plain = Medium {
        sigma_t: Vec3::ONE,
        albedo: Vec3::splat(0.75),
        phase: Phase::Isotropic,
        sample_emitters: true,
        density: None,
    };
    let default_hg = Medium {
        phase: Phase::HenyeyGreenstein { g: 0.8 },
        ..plain.clone()
    };
    let nested = Medium {
        sigma_t: Vec3::new(1.0, 2.0, 3.0),
        phase: Phase::Rayleigh,
        ..plain.clone()
    };
    assert_eq!(media, &vec![fog, plain, default_hg, nested]);
    assert_eq!(scene.media.camera, Some(1));
    let sphere = &scene.materials[scene.spheres[0].material as usize];
    assert_eq!(
        (sphere.media.interior, sphere.media.exterior),
        (Some(0), None)
    );
    let cube = &scene.materials[scene.triangles[0].material as usize];
    assert_eq!((cube.media.interior, cube.media.exterior), (None, Some(3)));
    assert!(scene.features().media);
}

/// Every way a medium can be wrong is an error at its line, saying what is wrong: an unknown
/// property (with its did-you-mean), negative and non-finite coefficients, an asymmetry outside
/// (-1, 1), phase functions and media hppm does not render yet, a grid volume, a `<ref>` to no
/// medium, a shape's medium without its side, two phase functions.
#[test]
fn broken_media_are_refused_where_they_are_written() {
    for (medium, expected) in [
        (
            r#"<float name="sigma_tt" value="1"/>"#,
            "did you mean \"sigma_t\"",
        ),
        (
            r#"<rgb name="sigma_t" value="1, -2, 1"/>"#,
            "expected finite numbers of 0 or more",
        ),
        (r#"<float name="albedo" value="inf"/>"#, "albedo"),
        (
            r#"<phase type="hg"><float name="g" value="1"/></phase>"#,
            "between -1 and 1",
        ),
        (r#"<phase type="sggx"/>"#, "\"sggx\" is not supported"),
        (
            r#"<phase type="isotropic"/><phase type="isotropic"/>"#,
            "a second <phase>",
        ),
        (
            r#"<volume type="gridvolume" name="albedo"><string name="filename" value="a.vol"/></volume>"#,
            "grids of albedo",
        ),
        (r#"<float name="scale" value="-1"/>"#, "scale -1"),
    ] {
        assert_error_at(
            &format!(r#"<medium type="homogeneous" id="m">{medium}</medium>{LIGHT}"#),
            3,
            expected,
        );
    }
    assert_error_at(
        &format!(r#"<medium type="inhomogeneous" id="m"/>{LIGHT}"#),
        3,
        "medium type \"inhomogeneous\" is not supported",
    );
    for (volume, expected) in [
        (
            r#"<string name="filename" value="nowhere.vol"/>"#,
            "nowhere.vol",
        ),
        (r#""#, "needs a \"filename\""),
        (
            r#"<string name="filename" value="tests/data/volumes/ramp.vol"/><string name="filter_type" value="cubic"/>"#,
            "filter_type \"cubic\"",
        ),
        (
            r#"<string name="filename" value="tests/data/volumes/ramp.vol"/><float name="sigma" value="1"/>"#,
            "unknown property \"sigma\"",
        ),
    ] {
        assert_error_at(
            &format!(
                r#"<medium type="heterogeneous" id="m"><volume type="gridvolume" name="sigma_t">{volume}</volume></medium>{LIGHT}"#
            ),
            3,
            expected,
        );
    }
    assert_error_at(
        &format!(r#"<shape type="sphere"><ref name="interior" id="nowhere"/></shape>{LIGHT}"#),
        3,
        "no <medium id=\"nowhere\"> is declared before this",
    );
    assert_error_at(
        &format!(r#"<shape type="sphere"><medium type="homogeneous"/></shape>{LIGHT}"#),
        3,
        "needs name=\"interior\" or name=\"exterior\"",
    );
}

/// The light a textured spot or a projector sends to a point, as hppm's loaded light gives it
/// (intensity towards the point over distance squared, what NEE uses), against Mitsuba 3.9.1
/// `scalar_rgb`'s `sample_direction` for the same XML at the same points (the figures marked
/// Mitsuba). A nearest-texel lookup of quadrants_wide.png makes every uv error a different
/// texel: u or v mirrored, the projector's image upside down, the spot's frame turned, the
/// 1/cos^3 or pi left out, or the texture's aspect ignored all fail.
#[test]
fn textured_spots_and_projectors_light_points_as_mitsuba_does() {
    let texture = r#"<texture name="NAME" type="bitmap"><string name="filename" value="tests/differential/plugins/projector/quadrants_wide.png"/><string name="filter_type" value="nearest"/></texture>"#;
    let scene = scene_of(check(&format!(
        r#"<emitter type="projector"><float name="fov" value="60"/><float name="scale" value="2"/>{}
            <transform name="to_world"><lookat origin="1, 2, 3" target="1, 0, 3" up="0, 0, 1"/></transform></emitter>
        <emitter type="spot"><float name="cutoff_angle" value="30"/><float name="beam_width" value="20"/><rgb name="intensity" value="2"/>{}
            <transform name="to_world"><lookat origin="1, 2, 3" target="1, 0, 3" up="1, 0, 1"/></transform></emitter>
        <shape type="cube"/>{}"#,
        texture.replace("NAME", "irradiance"),
        texture.replace("NAME", "texture"),
        sensor("", 8, 8)
    )));
    assert!(scene.features().textures, "a light's texture is uploaded");
    let projector = scene.emitters.projectors[0];
    let spot = scene.emitters.spots[0];
    assert!((projector.aspect - 4.0 / 3.0).abs() < 1e-6);
    let tex = |t: Option<u32>| &scene.textures[t.expect("textured") as usize];
    let close = |got: Vec3, want: [f32; 3], what: &str| {
        let want = Vec3::from(want);
        assert!(
            (got - want).abs().max_element() <= 1e-4 * want.max_element().max(1e-3),
            "{what}: hppm {got}, Mitsuba {want}"
        );
    };
    // A point and Mitsuba's figure for the projector there.
    let points = [
        ([1.3, 0.0, 3.4], [0.0374885, 0.00491453, 0.00294872]),
        ([0.5, -1.0, 2.6], [0.713857, 0.713857, 0.713857]),
        ([1.0, 0.0, 3.0], [0.0363692, 0.0363692, 0.0363692]),
    ];
    // (0.5, -1, 2.6) is outside the spot's cone: the spot's second point is its own.
    let spot_points = [[1.3, 0.0, 3.4], [0.5, 0.0, 2.6], [1.0, 0.0, 3.0]];
    let spot_mitsuba = [
        [0.00114269, 0.00224797, 0.0108957],
        [0.453515, 0.0204926, 0.00962314],
        [0.0115767, 0.0115767, 0.0115767],
    ];
    for (p, projector_want) in points {
        let to = Vec3::from(p) - projector.position;
        let (dist2, dir) = (to.length_squared(), to.normalize());
        let cos = dir.dot(projector.frame[2]);
        let uv = projector.uv(dir).expect("inside the frustum");
        let got = projector.irradiance * tex(projector.texture).eval(uv) * std::f32::consts::PI
            / (cos * cos * cos * dist2);
        close(got, projector_want, &format!("projector at {p:?}"));
    }
    for (p, want) in spot_points.into_iter().zip(spot_mitsuba) {
        let to = Vec3::from(p) - spot.position;
        let (dist2, dir) = (to.length_squared(), to.normalize());
        let got = spot.intensity
            * spot.falloff(dir.dot(spot.axis))
            * tex(spot.texture).eval(spot.uv(dir))
            / dist2;
        close(got, want, &format!("spot at {p:?}"));
    }
}

/// Defaults as Mitsuba's: a projector without properties is lit by irradiance 1 through the
/// 50 mm lens's fov (34.02 degrees on its 1 x 1 image); `fov_axis` y on a 4:3 image widens x.
/// Its power is pi x the image's area at z = 1 x the mean irradiance, and a spot's texture
/// scales its power by the texture's mean over the cone (a uniform checkerboard of 0.5 halves
/// it): a power without the texture, or the area without pi, fails.
#[test]
fn projector_defaults_and_light_powers() {
    let scene = scene_of(check(&format!(
        r#"<emitter type="projector"/>
        <emitter type="projector"><float name="fov" value="40"/><string name="fov_axis" value="y"/>
            <texture name="irradiance" type="bitmap"><string name="filename" value="tests/differential/plugins/projector/quadrants_wide.png"/></texture></emitter>
        <emitter type="spot"><texture name="texture" type="checkerboard"><rgb name="color0" value="0.5"/><rgb name="color1" value="0.5"/></texture></emitter>
        <shape type="cube"/>{}"#,
        sensor("", 8, 8)
    )));
    let plain = scene.emitters.projectors[0];
    assert_eq!(plain.irradiance, Vec3::ONE);
    assert_eq!(plain.texture, None);
    assert!((plain.tan_half_fov.atan().to_degrees() * 2.0 - 34.02206).abs() < 1e-3);
    let area = 4.0 * plain.tan_half_fov * plain.tan_half_fov;
    let power = plain.power_with(&scene.textures);
    assert!((power.x - std::f32::consts::PI * area).abs() < 1e-4 * power.x);
    let wide = scene.emitters.projectors[1];
    let fov_x = (2.0 * ((20f32).to_radians().tan() * 4.0 / 3.0).atan()).to_degrees();
    assert!((wide.tan_half_fov.atan().to_degrees() * 2.0 - fov_x).abs() < 1e-3);
    let spot = scene.emitters.spots[0];
    let ratio = spot.power_with(&scene.textures) / spot.power();
    assert!(
        (ratio - Vec3::splat(0.5)).abs().max_element() < 2e-3,
        "{ratio}"
    );
}

/// What Mitsuba refuses (or hppm cannot render) on these lights is an error at its line: a
/// spot `texture` that is a colour ("must be spatially varying"), a projector with both `fov`
/// and `focal_length`, a scaled projector, an unknown `fov_axis`, a negative `scale`.
#[test]
fn broken_light_textures_and_projectors_are_errors_at_their_line() {
    let cases = [
        (
            r#"<emitter type="spot"><rgb name="texture" value="0.5"/></emitter>"#,
            "must be a <texture>",
        ),
        (
            r#"<emitter type="projector"><float name="fov" value="40"/><string name="focal_length" value="35mm"/></emitter>"#,
            "not both",
        ),
        (
            r#"<emitter type="projector"><transform name="to_world"><scale value="2"/></transform></emitter>"#,
            "rotation and translation",
        ),
        (
            r#"<emitter type="projector"><float name="fov" value="40"/><string name="fov_axis" value="z"/></emitter>"#,
            "fov_axis",
        ),
        (
            r#"<emitter type="projector"><float name="scale" value="-1"/></emitter>"#,
            "negative",
        ),
    ];
    for (emitter, expected) in cases {
        assert_error_at(
            &format!("{emitter}<shape type=\"cube\"/>{LIGHT}"),
            3,
            expected,
        );
    }
}

/// An `id` on an object nested inside another declares it for every later `<ref>`, as Mitsuba
/// registers every id it reads: a BSDF inside a `twosided` (then used alone), a texture given
/// to a BSDF (then given to another), a medium given as a shape's interior (then another
/// shape's), and a shapegroup whose nested BSDF has an id, instanced twice (its shapes are read
/// again per instance: the same declaration, not a second). Would catch nested ids dropped
/// (the refs then fail as undeclared) or the wrong object stored under the id.
#[test]
fn ids_on_nested_objects_are_declared_for_later_refs() {
    let body = format!(
        r#"<shape type="cube"><bsdf type="twosided"><bsdf type="diffuse" id="inner"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf></bsdf></shape>
        <shape type="cube"><ref id="inner"/></shape>
        <shape type="cube"><bsdf type="diffuse"><texture name="reflectance" type="checkerboard" id="checks"/></bsdf></shape>
        <shape type="cube"><bsdf type="roughplastic"><ref name="diffuse_reflectance" id="checks"/></bsdf></shape>
        <shape type="cube"><bsdf type="null"/><medium type="homogeneous" name="interior" id="fog"><float name="sigma_t" value="0.5"/></medium></shape>
        <shape type="sphere"><bsdf type="null"/><ref name="interior" id="fog"/></shape>
        <shape type="shapegroup" id="group"><shape type="cube"><bsdf type="diffuse" id="grouped"/></shape></shape>
        <shape type="instance"><ref id="group"/></shape>
        <shape type="instance"><ref id="group"/><transform name="to_world"><translate x="3"/></transform></shape>
        <shape type="cube"><ref id="grouped"/></shape>
        {}{LIGHT}"#,
        sensor("", 8, 8)
    );
    let scene = scene_of(check(&body));
    let material = |i: usize| &scene.materials[scene.triangles[12 * i].material as usize];
    let inner = Diffuse::bsdf(Vec3::new(0.2, 0.4, 0.6));
    assert_eq!(material(0).bsdf, inner);
    assert_eq!(material(0).back.as_ref(), Some(&inner), "twosided");
    assert_eq!(material(1).bsdf, inner);
    assert_eq!(
        material(1).back,
        None,
        "the nested BSDF alone, not its twosided"
    );
    let checks = material(2)
        .textures
        .front
        .all()
        .flatten()
        .collect::<Vec<_>>();
    assert_eq!(checks.len(), 1, "{:?}", material(2).textures);
    let plastic = material(3)
        .textures
        .front
        .all()
        .flatten()
        .collect::<Vec<_>>();
    assert_eq!(plastic, checks, "the same texture, added to the scene once");
    let fog = material(4).media.interior.expect("the nested medium");
    let sphere = &scene.materials[scene.spheres[0].material as usize];
    assert_eq!(sphere.media.interior, Some(fog));
    assert_eq!(scene.media.list.len(), 1);
    // The two instances (shapes 5 and 6) and the cube that refers to the grouped BSDF.
    assert_eq!(material(7).bsdf, Diffuse::bsdf(Vec3::splat(0.5)));
}

/// An id declared twice, whether at top level or nested, on objects of any type, is refused at
/// the second with the place of the first (Mitsuba refuses duplicate ids too). Would catch a
/// nested declaration silently replacing the first, which every `<ref>` after it would then
/// see, and two shapes or two kinds of object sharing an id unnoticed.
#[test]
fn a_second_declaration_of_an_id_names_the_first() {
    assert_error_at(
        r#"<bsdf type="diffuse" id="white"/>
<shape type="cube"><bsdf type="twosided"><bsdf type="conductor" id="white"/></bsdf></shape>"#,
        4,
        "a second <bsdf id=\"white\"> (the first is at shipped.xml:3:1)",
    );
    assert_error_at(
        r#"<shape type="cube"><bsdf type="diffuse"><texture name="reflectance" type="checkerboard" id="t"/></bsdf></shape>
<texture type="checkerboard" id="t"/>"#,
        4,
        "a second <texture id=\"t\"> (the first is at shipped.xml:3:",
    );
    assert_error_at(
        r#"<medium type="homogeneous" id="m"/>
<shape type="cube"><bsdf type="null"/><medium type="homogeneous" name="interior" id="m"/></shape>"#,
        4,
        "a second <medium id=\"m\"> (the first is at shipped.xml:3:1)",
    );
    // One table of ids for every object, as in Mitsuba: two shapes, or a BSDF and a texture.
    assert_error_at(
        &format!("{LIGHT}\n<shape type=\"cube\" id=\"box\"/>\n<shape type=\"sphere\" id=\"box\"/>"),
        5,
        "id \"box\" is declared already, by the <shape type=\"cube\"> at shipped.xml:4",
    );
    assert_error_at(
        r#"<bsdf type="diffuse" id="red"/>
<texture type="checkerboard" id="red"/>"#,
        4,
        "id \"red\" is declared already, by the <bsdf type=\"diffuse\"> at shipped.xml:3",
    );
}
