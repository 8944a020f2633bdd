//! Broken scene inputs: every one gives an error naming the file and the offending line (and
//! saying what is wrong); nothing panics, whatever the input. CPU only.

use std::path::{Path, PathBuf};

use hppm::loaders::{mitsuba, obj, ron_format};
use hppm::scene::SceneError;

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

fn error_of(file: &str) -> String {
    let path = repo(&format!("tests/data/scene_errors/{file}"));
    match hppm::loaders::load(&path) {
        Ok(_) => panic!("{file} loaded, but it is broken"),
        Err(e) => e.to_string(),
    }
}

/// (file, the file the error must name, line, words the message must contain)
const CASES: &[(&str, &str, usize, &[&str])] = &[
    ("syntax.xml", "syntax.xml", 4, &["XML"]),
    ("unknown_tag.xml", "unknown_tag.xml", 4, &["<teapot>"]),
    (
        "unknown_property.xml",
        "unknown_property.xml",
        5,
        &["radiuss"],
    ),
    (
        "unknown_attribute.xml",
        "unknown_attribute.xml",
        3,
        &["unit"],
    ),
    ("unknown_shape.xml", "unknown_shape.xml", 4, &["teapot"]),
    (
        "duplicate_property.xml",
        "duplicate_property.xml",
        4,
        &["fov", "twice"],
    ),
    ("bad_number.xml", "bad_number.xml", 3, &["fov", "forty"]),
    ("nan.xml", "nan.xml", 4, &["center", "nan"]),
    ("inf.xml", "inf.xml", 5, &["intensity", "inf"]),
    (
        "negative_radius.xml",
        "negative_radius.xml",
        7,
        &["radius", "-0.5"],
    ),
    ("zero_film.xml", "zero_film.xml", 4, &["width", "0"]),
    (
        "twosided.xml",
        "twosided.xml",
        5,
        &["twosided", "transmission"],
    ),
    (
        "unknown_rfilter.xml",
        "unknown_rfilter.xml",
        4,
        &[
            "blackman",
            "box, tent, gaussian, lanczos, mitchell, catmullrom",
        ],
    ),
    (
        "bad_rfilter_lobes.xml",
        "bad_rfilter_lobes.xml",
        5,
        &["lobes", "0", "1 to 16"],
    ),
    (
        "bad_rfilter_stddev.xml",
        "bad_rfilter_stddev.xml",
        5,
        &["stddev", "-0.5"],
    ),
    (
        "rfilter_unknown_property.xml",
        "rfilter_unknown_property.xml",
        5,
        &["radius", "gaussian"],
    ),
    ("bad_matrix.xml", "bad_matrix.xml", 5, &["16 numbers"]),
    ("missing_default.xml", "missing_default.xml", 4, &["$spp"]),
    (
        "missing_property.xml",
        "missing_property.xml",
        3,
        &["filename"],
    ),
    ("missing_obj.xml", "missing_obj.xml", 3, &["missing.obj"]),
    ("missing_ref.xml", "missing_ref.xml", 4, &["nowhere"]),
    (
        "broken_obj.xml",
        "broken.obj",
        5,
        &["9", "broken_obj.xml:3"],
    ),
    ("broken.obj", "broken.obj", 5, &["index 9"]),
    ("bad_vertex.obj", "bad_vertex.obj", 4, &["1.0.0"]),
    ("syntax.ron", "syntax.ron", 5, &[]),
    ("unknown_field.ron", "unknown_field.ron", 5, &["colour"]),
    (
        "unknown_material.ron",
        "unknown_material.ron",
        5,
        &["whyte", "white"],
    ),
    ("nan.ron", "nan.ron", 3, &["NaN"]),
    ("overflow.ron", "overflow.ron", 4, &["1e39"]),
    (
        "negative_radius.ron",
        "negative_radius.ron",
        7,
        &["radius", "-1"],
    ),
    ("missing_obj.ron", "missing_obj.ron", 6, &["nowhere.obj"]),
    (
        "duplicate_material.ron",
        "duplicate_material.ron",
        5,
        &["\"white\"", "twice"],
    ),
    (
        "bad_camera.ron",
        "bad_camera.ron",
        4,
        &["origin equals target"],
    ),
    (
        "stretched_sphere.ron",
        "stretched_sphere.ron",
        7,
        &["sphere", "uniformly"],
    ),
    (
        "beyond_extent.ron",
        "beyond_extent.ron",
        6,
        &["this shape", "1.0e20", "1e15", "f32"],
    ),
    (
        "below_extent.ron",
        "below_extent.ron",
        1,
        &["extent", "5.0e-20", "1e-15 to 1e15"],
    ),
    (
        "beyond_extent.xml",
        "beyond_extent.xml",
        6,
        &["this shape", "1.0e20", "1e15"],
    ),
];

#[test]
fn every_broken_input_names_its_file_line_and_problem() {
    let mut failures = Vec::new();
    for &(file, named, line, words) in CASES {
        let err = error_of(file);
        if !err.contains(&format!("{named}:{line}:")) {
            failures.push(format!("{file}: expected {named}:{line}: in: {err}"));
        }
        for word in words {
            if !err.contains(word) {
                failures.push(format!("{file}: expected \"{word}\" in: {err}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_broken_file_in_the_data_folder_is_covered() {
    let dir = repo("tests/data/scene_errors");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(
            CASES.iter().any(|c| c.0 == name),
            "{name} has no expected line"
        );
    }
}

#[test]
fn the_xml_error_points_at_the_column_of_the_bad_attribute() {
    let err = error_of("bad_number.xml");
    // `    <float name="fov" value="forty"/>`: the value attribute starts at column 23.
    assert!(err.contains("bad_number.xml:3:23:"), "{err}");
    assert!(
        err.contains("<float name=\"fov\">: expected a number, got \"forty\""),
        "{err}"
    );
}

fn xml_error(body: &str) -> String {
    let text =
        format!("<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n{body}\n</scene>");
    match mitsuba::parse(Path::new("inline.xml"), &text) {
        Ok(_) => panic!("accepted: {body}"),
        Err(e) => e.to_string(),
    }
}

/// Things the renderer cannot honour are refused (at the line of the third line of the file,
/// where each body starts) rather than silently rendered differently.
#[test]
fn unsupported_mitsuba_features_are_refused_with_a_location() {
    let cases = [
        (r#"<shape type="ply"/>"#, "ply"),
        (
            r#"<shape type="sphere"><bsdf type="blendbsdf"/></shape>"#,
            "blendbsdf",
        ),
        (
            r#"<shape type="sphere"><bsdf type="conductor"><string name="material" value="Gold"/></bsdf></shape>"#,
            "Gold",
        ),
        (
            r#"<shape type="sphere"><bsdf type="conductor"><string name="material" value="Au"/><rgb name="eta" value="1"/></bsdf></shape>"#,
            "not both",
        ),
        (
            r#"<shape type="sphere"><bsdf type="diffuse"/><bsdf type="diffuse"/></shape>"#,
            "at most one",
        ),
        (
            r#"<shape type="sphere"><emitter type="point"/></shape>"#,
            "only \"area\"",
        ),
        (r#"<emitter type="timed_sunsky"/>"#, "timed_sunsky"),
        (r#"<emitter type="envmap"/>"#, "filename"),
        (
            r#"<emitter type="envmap"><string name="filename" value="missing.exr"/></emitter>"#,
            "missing.exr",
        ),
        (
            r#"<emitter type="constant"/><emitter type="constant"/>"#,
            "second environment",
        ),
        (r#"<emitter type="area"/>"#, "inside the <shape>"),
        (
            r#"<emitter type="spot"><float name="cutoff_angle" value="10"/><float name="beam_width" value="20"/></emitter>"#,
            "beam_width",
        ),
        (
            r#"<emitter type="spot"><float name="cutoff_angle" value="200"/></emitter>"#,
            "0 to 180",
        ),
        (
            r#"<emitter type="spot"><transform name="to_world"><scale x="2"/></transform></emitter>"#,
            "round",
        ),
        (
            r#"<emitter type="directional"><vector name="direction" x="0" y="0" z="0"/></emitter>"#,
            "zero",
        ),
        (
            r#"<emitter type="constant"><rgb name="radiance" value="-1"/></emitter>"#,
            "negative",
        ),
        (
            r#"<shape type="sphere"><transform name="to_world"><scale x="2"/></transform></shape>"#,
            "uniformly",
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1"/></transform></shape>"#,
            "projective",
        ),
        (
            r#"<shape type="cube"><float name="to_world" value="1"/></shape>"#,
            "<transform>",
        ),
        (
            r#"<shape type="cube"><integer name="flip_normals" value="1"/></shape>"#,
            "<boolean>",
        ),
        (
            r#"<integrator type="volpath"><float name="max_depth" value="3"/></integrator>"#,
            "<integer>",
        ),
        (
            r#"<integrator type="path"><integer name="max_depth" value="0"/></integrator>"#,
            "max_depth",
        ),
        (
            r#"<integrator type="path"><float name="max_depth" value="3"/></integrator>"#,
            "<integer>",
        ),
        (r#"<sensor type="perspective"/>"#, "second <sensor>"),
        (r#"<shape type="sphere"><ref id="x"/></shape>"#, "x"),
        (
            r#"<bsdf type="diffuse" id="a"/><bsdf type="diffuse" id="a"/>"#,
            "unique",
        ),
        (
            r#"<shape type="sphere"><rgb name="radius" value="1, 2"/></shape>"#,
            "<float>",
        ),
        (
            r#"<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.2"/></bsdf></shape>"#,
            "1 or 3 numbers",
        ),
        (
            r#"<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="-0.1"/></bsdf></shape>"#,
            "negative",
        ),
        (
            r#"<shape type="rectangle"><bsdf type="dielectric"><float name="int_ior" value="0"/></bsdf></shape>"#,
            "positive",
        ),
        (
            r#"<shape type="sphere"><texture name="reflectance" type="bitmap"/></shape>"#,
            "<texture name=\"reflectance\">",
        ),
    ];
    for (body, word) in cases {
        let err = xml_error(body);
        assert!(err.contains("inline.xml:3:"), "{body}: {err}");
        assert!(err.contains(word), "{body}: expected \"{word}\" in {err}");
    }
}

#[test]
fn a_sensor_that_mirrors_or_looks_nowhere_is_refused() {
    let mirror = r#"<scene version="3.0.0">
<sensor type="perspective">
<transform name="to_world"><scale x="-1"/><lookat origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/></transform>
</sensor></scene>"#;
    let err = mitsuba::parse(Path::new("m.xml"), mirror)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("m.xml:3:") && err.contains("mirroring"),
        "{err}"
    );
    let nowhere = r#"<scene version="3.0.0">
<sensor type="perspective">
<transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 1" up="0, 1, 0"/></transform>
</sensor></scene>"#;
    let err = mitsuba::parse(Path::new("n.xml"), nowhere)
        .unwrap_err()
        .to_string();
    assert!(err.contains("n.xml:3:") && err.contains("lookat"), "{err}");
    // Found by tests/fuzz.rs: so far from 0 that origin + view direction rounds to the origin.
    let far = r#"<scene version="3.0.0">
<sensor type="perspective">
<transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/><translate z="3e38"/></transform>
</sensor></scene>"#;
    let err = mitsuba::parse(Path::new("f.xml"), far)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("f.xml:3:") && err.contains("no view direction"),
        "{err}"
    );
    let no_sensor = "<scene version=\"3.0.0\">\n</scene>";
    let err = mitsuba::parse(Path::new("s.xml"), no_sensor)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("s.xml:1:") && err.contains("no <sensor>"),
        "{err}"
    );
}

fn ron_error(shapes: &str) -> String {
    let text = format!(
        "(\n camera: (origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8),\n \
         materials: {{ \"m\": Diffuse(reflectance: (0.5, 0.5, 0.5)) }},\n shapes: [\n{shapes}\n ],\n)"
    );
    match ron_format::parse(Path::new("inline.ron"), &text) {
        Ok(_) => panic!("accepted: {shapes}"),
        Err(e) => e.to_string(),
    }
}

/// Each `shapes` body starts at line 5; the broken entry is always the last line of the body.
#[test]
fn ron_semantic_errors_point_at_the_offending_entry() {
    let cases = [
        (
            "(shape: Cube, material: \"m\", emission: Some((1, -1, 1)))",
            5,
            "negative",
        ),
        (
            "(shape: Cube, material: \"m\"),\n(shape: Cube, material: \"m\", to_world: [Rotate(axis: (0, 0, 0), degrees: 3)])",
            6,
            "axis",
        ),
        (
            "(shape: Cube, material: \"m\"),\n(shape: Cube, material: \"m\",\n to_world: [Matrix((1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  1, 0, 0, 1))])",
            7,
            "projective",
        ),
        ("(shape: Cube, material: \"m\", emission: inf)", 5, "finite"),
        (
            "(shape: Cube, material: \"m\", emission: Some((1, -NaN, 1)))",
            5,
            "finite",
        ),
        (
            "(shape: Cube, material: \"m\"),\n(shape: Cube, material: \"n\")",
            6,
            "\"n\"",
        ),
    ];
    for (shapes, line, word) in cases {
        let err = ron_error(shapes);
        assert!(
            err.contains(&format!("inline.ron:{line}:")),
            "{shapes}: expected line {line} in {err}"
        );
        assert!(err.contains(word), "{shapes}: expected \"{word}\" in {err}");
    }
}

#[test]
fn ron_camera_integrator_material_and_light_checks() {
    let scene = |camera: &str, rest: &str| {
        format!(
            "(\n camera: {camera},\n materials: {{ \"m\": Diffuse(reflectance: (0.5, 0.5, 0.5)) }},\n shapes: [],\n{rest}\n)"
        )
    };
    let good_camera = "(origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8)";
    let cases = [
        (
            scene(
                "(origin: (0, 0, 5), target: (0, 0, 0), fov_x: 180, width: 8, height: 8)",
                "",
            ),
            2,
            "fov_x",
        ),
        (
            scene(
                "(origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 0, height: 8)",
                "",
            ),
            2,
            "width",
        ),
        (
            scene(
                "(origin: (0, 0, 5), target: (0, 0, 0), up: (0, 0, 1), fov_x: 40, width: 8, height: 8)",
                "",
            ),
            2,
            "parallel",
        ),
        (
            scene(good_camera, " integrator: (max_depth: 0),"),
            5,
            "depth",
        ),
        (scene(good_camera, " spp: 0,"), 5, "spp"),
        (
            scene(
                good_camera,
                " point_lights: [\n (position: (0, 1, 0), intensity: (1, 1, 1)),\n (position: (0, 1, 0), intensity: (1, -1, 1))],",
            ),
            7,
            "intensity",
        ),
    ];
    for (text, line, word) in cases {
        let err = ron_format::parse(Path::new("c.ron"), &text)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("c.ron:{line}:")),
            "expected line {line} in {err}\n{text}"
        );
        assert!(err.contains(word), "expected \"{word}\" in {err}");
    }
    let bad_material = "(\n camera: (origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8),\n materials: {\n  \"a\": Mirror,\n  \"glass\": Dielectric(int_ior: -1.5),\n },\n shapes: [],\n)";
    let err = ron_format::parse(Path::new("d.ron"), bad_material)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(err.contains("d.ron:5:3:") && err.contains("glass"), "{err}");
}

#[test]
fn obj_errors_carry_the_line() {
    let cases = [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", 4, "3 corners"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", 4, "-4"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            5,
            "texture coordinate index 2",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n",
            4,
            "normal index 1",
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n", 3, "nan"),
        ("v 0 0\n", 1, "3 numbers"),
        ("v 0 0 0\nf 1 1 x\n", 2, "\"x\""),
    ];
    for (text, line, word) in cases {
        let err = obj::parse_triangles(Path::new("m.obj"), text)
            .unwrap_err()
            .to_string();
        assert!(err.contains(&format!("m.obj:{line}:")), "{text}: {err}");
        assert!(err.contains(word), "{text}: expected \"{word}\" in {err}");
    }
    let err = obj::parse_triangles(Path::new("e.obj"), "# nothing\n").unwrap_err();
    assert!(matches!(err, SceneError::File { .. }), "{err}");
    let err = obj::load_mesh(
        &repo("tests/data/scene_errors/none.obj"),
        glam::Mat4::IDENTITY,
        0,
        false,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("none.obj"), "{err}");
}

/// A deterministic pseudo-random stream (no extra dependency).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) as usize
    }
}

/// Cuts and single-byte edits of every bundled and reference scene: errors are fine, panics
/// are not (the test harness would report one).
#[test]
fn mangled_scenes_never_panic() {
    let xml = [
        "tests/refs/scenes/cornell_diffuse/scene.xml",
        "tests/refs/scenes/cornell_diffuse_obj/scene.xml",
        "tests/refs/scenes/cornell_glass_sphere/scene.xml",
        "tests/refs/scenes/point_light_caustic/scene.xml",
    ];
    let ron = [
        "scenes/cornell_box.ron",
        "scenes/cornell_diffuse.ron",
        "scenes/furnace.ron",
    ];
    let junk = b"0(),:\"x9e-<>/=$ \n.nNaf";
    let mut rng = Lcg(2024);
    let mut mangle = |text: &str, n: usize, parse: &dyn Fn(&str)| {
        for i in 0..n {
            parse(&text[..text.floor_char_boundary(rng.next() % text.len())]);
            let mut bytes = text.as_bytes().to_vec();
            for _ in 0..1 + i % 3 {
                let at = rng.next() % bytes.len();
                bytes[at] = junk[rng.next() % junk.len()];
            }
            if let Ok(s) = String::from_utf8(bytes) {
                parse(&s);
            }
        }
    };
    for file in xml {
        let path = repo(file);
        let text = std::fs::read_to_string(&path).unwrap();
        mangle(&text, 120, &|s| drop(mitsuba::parse(&path, s)));
    }
    for file in ron {
        let path = repo(file);
        let text = std::fs::read_to_string(&path).unwrap();
        mangle(&text, 120, &|s| drop(ron_format::parse(&path, s)));
    }
    let path = repo("tests/refs/scenes/cornell_diffuse_obj/unit_cube.obj");
    let text = std::fs::read_to_string(&path).unwrap();
    mangle(&text, 200, &|s| drop(obj::parse_triangles(&path, s)));
}
