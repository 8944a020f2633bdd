//! The `hppm` binary as a user runs it.

use std::process::{Command, Output};

fn hppm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hppm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run hppm")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn no_adapter_is_a_clear_error_with_exit_code_2() {
    // wgpu finds no Metal adapter on Linux or Windows: the same as a machine without drivers.
    if cfg!(target_os = "macos") {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_hppm"))
        .arg("info")
        .env("WGPU_BACKEND", "metal")
        .output()
        .expect("run hppm");
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("apt-get install -y mesa-vulkan-drivers"),
        "{}",
        stderr(&out)
    );
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
}

#[test]
fn render_writes_png_and_exr_with_the_adapter_recorded() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
    for ext in ["png", "exr"] {
        let path = dir.join(format!("out.{ext}"));
        let path_text = path.to_string_lossy().into_owned();
        let out = hppm(&[
            "render", scene, "--spp", "4", "--size", "40x24", "--seed", "3", "--out", &path_text,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("40x24, 4 spp"), "{stdout}");
        let bytes = std::fs::read(&path).expect("output written");
        // The adapter's name is stored in the file (PNG tEXt chunk / EXR text attribute).
        let needle = b"hppm_adapter";
        assert!(
            bytes.windows(needle.len()).any(|w| w == needle),
            "{ext}: no adapter recorded"
        );
        if ext == "exr" {
            let image = hppm::image::Image::read_exr(&path).expect("readable EXR");
            assert_eq!((image.width, image.height), (40, 24));
            assert!(image.mean()[0] > 0.0, "a lit Cornell box is not black");
        }
    }
    // No temporary files are left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .expect("list")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_output_format_and_bad_size_are_errors() {
    let out = hppm(&["render", "--spp", "1", "--out", "render.bmp"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("render.bmp"), "{}", stderr(&out));
    let out = hppm(&["render", "--size", "12by5"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("WxH"), "{}", stderr(&out));
}

#[test]
fn graph_command_prints_the_schedule_and_dot() {
    let out = hppm(&["graph", "graphs/pt.ron"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("path_trace"));
    let out = hppm(&["graph", "graphs/pt.ron", "--dot"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("digraph"));
}

#[test]
fn a_broken_scene_names_file_and_line_without_panicking() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("broken.xml");
    std::fs::write(&path, "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n    <float name=\"radius\" value=\"abc\"/>\n  </shape>\n</scene>\n").expect("write");
    let out = hppm(&["render", &path.to_string_lossy(), "--spp", "1"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("broken.xml:3:"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A buffer that no band of rows can shrink (this iteration's photon hits, asked for in the
/// graph) is named with its size, after the render tried splitting the image into bands.
#[test]
fn a_buffer_larger_than_the_adapter_allows_is_named_with_its_size() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-huge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let graph = dir.join("many_photons.ron");
    let hybrid = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs/hybrid.ron");
    let text = std::fs::read_to_string(hybrid).expect("hybrid.ron");
    let text = text.replace(
        "(mode: Caustic",
        "(photons_per_iteration: 300000000, mode: Caustic",
    );
    std::fs::write(&graph, text).expect("write graph");
    let out = hppm(&[
        "render",
        "--graph",
        &graph.to_string_lossy(),
        "--size",
        "32x32",
        "--spp",
        "1",
        "--out",
        &dir.join("huge.exr").to_string_lossy(),
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    // The graph allocates it, and names it by node and slot (48 bytes a hit after a 16-byte
    // header), at the node's line.
    assert!(err.contains("photons.photon_hits"), "{err}");
    assert!(err.contains("14400000016 bytes"), "{err}");
    assert!(err.contains("bands of as few as 1 rows"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// An image whose bands together need more memory than the machine has free (lavapipe keeps
/// its buffers in the machine's memory) is refused before they are allocated, with what it
/// needs and what would fit, instead of swapping the machine to a halt. The largest size the
/// command takes, 16384x16384, needs about 96 GiB with the default graph (256 bands, each with
/// its own photon hits): more than a test machine has free.
#[test]
fn an_image_larger_than_memory_is_refused_with_what_would_fit() {
    let out = hppm(&[
        "render",
        "--size",
        "16384x16384",
        "--spp",
        "1",
        "--out",
        "huge.exr",
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("a 16384x16384 image"), "{err}");
    assert!(err.contains("GiB of memory is free"), "{err}");
    assert!(err.contains("would fit"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// Ctrl-C (SIGINT) stops a render and still writes what it has.
#[cfg(unix)]
#[test]
fn interrupt_writes_the_image_so_far() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-int-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("partial.exr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_hppm"))
        .args(["render", "--time", "120", "--size", "32x32", "--out"])
        .arg(&path)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn hppm");
    // The handler is installed once the device is open and the pipelines are compiled, which
    // takes a machine-dependent time: wait for the line that says so, not for a fixed time.
    let mut err = String::new();
    let mut reader = std::io::BufReader::new(child.stderr.take().expect("stderr"));
    loop {
        let mut line = String::new();
        let read = std::io::BufRead::read_line(&mut reader, &mut line).expect("read stderr");
        assert!(read > 0, "hppm ended before rendering: {err}");
        err.push_str(&line);
        if line.starts_with("rendering ") {
            break;
        }
    }
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    assert!(killed.is_ok_and(|s| s.success()));
    std::io::Read::read_to_string(&mut reader, &mut err).expect("read stderr");
    let out = child.wait_with_output().expect("wait");
    assert!(out.status.success(), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    let image = hppm::image::Image::read_exr(&path).expect("partial image written");
    assert_eq!((image.width, image.height), (32, 32));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn time_budget_stops_the_render() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-time-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("timed.exr");
    let start = std::time::Instant::now();
    let out = hppm(&[
        "render",
        "--time",
        "1.5",
        "--size",
        "24x24",
        "--out",
        &path.to_string_lossy(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    // Device start-up and pipeline compilation come on top of the 1.5 s budget.
    assert!(start.elapsed().as_secs_f64() < 30.0);
    assert!(path.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hybrid_render_stops_at_a_photon_budget_and_writes_its_aovs() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-aovs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out_path = dir.join("glass.exr");
    let out_text = out_path.to_string_lossy().into_owned();
    // 24x16 pixels = 384 photons per iteration in Caustic mode: 1000 photons take 3 iterations.
    let out = hppm(&[
        "render",
        "tests/refs/scenes/cornell_glass_sphere/scene.xml",
        "--graph",
        "graphs/hybrid.ron",
        "--size",
        "24x16",
        "--photons",
        "1000",
        "--aovs",
        "--out",
        &out_text,
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("3 spp and 1152 photons"), "{stdout}");
    let read = |name: &str| {
        hppm::image::Image::read_exr(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let (combined, pt, caustic, radius) = (
        read("glass.exr"),
        read("glass.pt.exr"),
        read("glass.caustic.exr"),
        read("glass.radius.exr"),
    );
    // combined = pt + caustic, pixel by pixel.
    for i in 0..combined.pixels.len() {
        for c in 0..3 {
            let sum = pt.pixels[i][c] + caustic.pixels[i][c];
            assert!((combined.pixels[i][c] - sum).abs() <= 1e-5 * sum.abs().max(1.0));
        }
    }
    assert!(radius.mean()[0] > 0.0, "hit points have radii");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Budgets that would render nothing or never end are refused before any work, with exit 1
/// and a message naming the option.
#[test]
fn impossible_budgets_are_refused() {
    let cases: &[(&[&str], &str)] = &[
        (&["--spp", "0"], "--spp must be at least 1"),
        (&["--time", "nan"], "--time must be a positive"),
        (&["--time=-1"], "--time must be a positive"),
        (&["--time", "inf"], "--time must be a positive"),
        (&["--photons", "0"], "--photons must be at least 1"),
        // pt.ron emits no photons: a photon budget alone would never be met.
        (
            &["--photons", "1000", "--graph", "graphs/pt.ron"],
            "emits no photons",
        ),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["render", "--size", "8x8", "--out", "/tmp/hppm-budget.exr"];
        args.extend_from_slice(extra);
        let started = std::time::Instant::now();
        let out = hppm(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {err}");
        assert!(
            err.contains(needle),
            "{extra:?}: expected {needle:?} in {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            started.elapsed().as_secs() < 60,
            "{extra:?} was not refused at once"
        );
    }
}

/// An output in a folder that does not exist is refused before the render, not after it.
#[test]
fn an_unwritable_output_is_found_before_rendering() {
    let out = hppm(&[
        "render",
        "--spp",
        "100000",
        "--out",
        "/nonexistent-hppm-folder/out.exr",
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("/nonexistent-hppm-folder/out.exr"), "{err}");
    assert!(!err.contains("rendering "), "it rendered first: {err}");
}

/// A render on a headless machine prints no "XDG_RUNTIME_DIR" line (Mesa's Wayland probe), and
/// a PNG whose provenance holds non-Latin-1 text (a scene path in Cyrillic) is written, with
/// the text in an iTXt chunk.
#[test]
fn a_headless_render_is_quiet_and_png_text_may_be_any_unicode() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-утф-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = dir.join("сцена.ron");
    std::fs::copy(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box.ron"),
        &scene,
    )
    .expect("copy scene");
    let png = dir.join("кадр.png");
    let out = Command::new(env!("CARGO_BIN_EXE_hppm"))
        .arg("render")
        .arg(&scene)
        .args(["--spp", "1", "--size", "8x8", "--out"])
        .arg(&png)
        .env_remove("XDG_RUNTIME_DIR")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run hppm");
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    let bytes = std::fs::read(&png).expect("png written");
    let has_itxt = bytes.windows(4).any(|w| w == b"iTXt");
    assert!(has_itxt, "the Cyrillic scene path goes into an iTXt chunk");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A small Mitsuba scene whose film and sample count are `<default>` parameters, in its own
/// temporary folder.
fn parameterised_scene(tag: &str) -> (std::path::PathBuf, String) {
    let dir = std::env::temp_dir().join(format!("hppm-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("scene.xml");
    std::fs::write(
        &path,
        r#"<scene version="3.0.0">
    <default name="spp" value="2"/>
    <default name="resx" value="20"/>
    <default name="resy" value="12"/>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="$resx"/>
            <integer name="height" value="$resy"/>
        </film>
    </sensor>
    <shape type="rectangle">
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
</scene>"#,
    )
    .expect("scene written");
    let text = path.to_string_lossy().into_owned();
    (dir, text)
}

/// `-D name=value` replaces the scene's `<default>` as `mitsuba -D` does: the film size and the
/// sample count follow it (a loader that ignored -D renders 20x12 at 2 spp), and it is recorded
/// in the output file.
#[test]
fn defines_override_scene_defaults() {
    let (dir, scene) = parameterised_scene("defines");
    let out_path = dir.join("out.exr").to_string_lossy().into_owned();
    let plain = hppm(&[
        "render",
        &scene,
        "--graph",
        "graphs/pt.ron",
        "--out",
        &out_path,
    ]);
    assert!(plain.status.success(), "{}", stderr(&plain));
    let stdout = String::from_utf8_lossy(&plain.stdout);
    assert!(stdout.contains("20x12, 2 spp"), "{stdout}");
    let set = hppm(&[
        "render",
        &scene,
        "--graph",
        "graphs/pt.ron",
        "-D",
        "spp=3",
        "--define",
        "resx=24",
        "--out",
        &out_path,
    ]);
    assert!(set.status.success(), "{}", stderr(&set));
    let stdout = String::from_utf8_lossy(&set.stdout);
    assert!(stdout.contains("24x12, 3 spp"), "{stdout}");
    let bytes = std::fs::read(&out_path).expect("output written");
    let needle = b"spp=3 resx=24";
    assert!(
        bytes.windows(needle.len()).any(|w| w == needle),
        "the defines are not recorded in the EXR"
    );
    // `graph --scene` loads the scene with them too.
    let graph = hppm(&[
        "graph",
        "graphs/hybrid.ron",
        "--scene",
        &scene,
        "-D",
        "resy=8",
    ]);
    assert!(graph.status.success(), "{}", stderr(&graph));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `-D` no attribute uses is refused, as Mitsuba 3 refuses unused parameters (a typo must not
/// render the scene unchanged), naming it and the scene's parameters; a malformed one, or one
/// for a scene format without parameters, is refused before any work. Nothing panics.
#[test]
fn unused_or_malformed_defines_are_errors() {
    let (dir, scene) = parameterised_scene("bad-defines");
    let out_path = dir.join("out.exr").to_string_lossy().into_owned();
    let typo = hppm(&["render", &scene, "-D", "sp=16", "--out", &out_path]);
    assert!(!typo.status.success());
    let err = stderr(&typo);
    for words in ["scene.xml", "-D sp=16", "$sp", "resx, resy, spp"] {
        assert!(err.contains(words), "expected {words:?} in: {err}");
    }
    let malformed = hppm(&["render", &scene, "-D", "spp", "--out", &out_path]);
    assert!(!malformed.status.success());
    assert!(
        stderr(&malformed).contains("NAME=VALUE"),
        "{}",
        stderr(&malformed)
    );
    let ron = hppm(&[
        "render",
        "scenes/cornell_box.ron",
        "-D",
        "spp=2",
        "--out",
        &out_path,
    ]);
    assert!(!ron.status.success());
    assert!(
        stderr(&ron).contains("Mitsuba XML scenes only"),
        "{}",
        stderr(&ron)
    );
    let compare = hppm(&[
        "compare",
        &scene,
        "--reference",
        "none.exr",
        "--graph",
        "graphs/pt.ron",
        "--time",
        "1",
        "--out",
        &out_path,
        "-D",
        "nothing=1",
    ]);
    assert!(!compare.status.success());
    assert!(
        stderr(&compare).contains("$nothing"),
        "{}",
        stderr(&compare)
    );
    for out in [&typo, &malformed, &ron, &compare] {
        assert!(!stderr(out).contains("panicked"), "{}", stderr(out));
    }
    assert!(
        !std::path::Path::new(&out_path).exists(),
        "an image was written"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `hppm check` says which rules a Mitsuba 0.x file is read with and how many upgrades that
/// took; `--verbose` names each at its line, and says Mitsuba 3's rules for a version 3 file.
/// Catches: a user left guessing why a 0.6 file reads differently from Mitsuba 3.
#[test]
fn check_names_the_rule_set_and_verbose_lists_the_upgrades() {
    let dir = std::env::temp_dir().join(format!("hppm_rules_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let old = dir.join("old.xml");
    std::fs::write(
        &old,
        "<scene version=\"0.5.0\">\n<sensor type=\"perspective\"><transform name=\"toWorld\"><lookAt origin=\"0, 0, 3\" target=\"0, 0, 0\"/></transform>\n<film type=\"ldrfilm\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor>\n<emitter type=\"constant\"/></scene>",
    )
    .expect("write");
    let out = hppm(&["check", old.to_str().expect("path")]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{text}{}", stderr(&out));
    assert!(
        text.contains("old.xml: Mitsuba 0.5/0.6 rules (version 0.5.0)")
            && text.contains("upgrades applied to read Mitsuba 0.6 files (--verbose lists them)"),
        "{text}"
    );
    let out = hppm(&["check", "--verbose", old.to_str().expect("path")]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    for expected in [
        "upgrade: ",
        "old.xml:2:",
        "property \"toWorld\" read as \"to_world\"",
        "<lookAt> read as <lookat>",
        "old.xml:3:",
        "film \"ldrfilm\": read as hdrfilm",
    ] {
        assert!(text.contains(expected), "{expected:?} missing in:\n{text}");
    }
    let current = dir.join("current.xml");
    std::fs::write(
        &current,
        "<scene version=\"3.0.0\"><sensor type=\"perspective\"/><emitter type=\"constant\"/></scene>",
    )
    .expect("write");
    let out = hppm(&["check", "-v", current.to_str().expect("path")]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        text.contains("current.xml: Mitsuba 3 rules (version 3.0.0)"),
        "{text}"
    );
    assert!(!text.contains("upgrade"), "{text}");
}

/// `hppm check` lists every problem of a scene at once, errors and warnings apart, each with
/// file:line:col, and exits 0 only when the scene renders; `render` prints the warnings of a
/// scene it renders (an integrator taken as advice) before rendering.
#[test]
fn check_lists_every_problem_and_render_prints_warnings() {
    let dir = std::env::temp_dir().join(format!("hppm_check_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let sensor = r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>"#;
    let light = r#"<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#;
    let good = dir.join("good.xml");
    std::fs::write(
        &good,
        format!(r#"<scene version="3.0.0"><integrator type="ptracer"/>{sensor}{light}</scene>"#),
    )
    .expect("write");
    let bad = dir.join("bad.xml");
    std::fs::write(
        &bad,
        format!(
            "<scene version=\"3.0.0\">\n<integrator type=\"bdpt\"/>\n{sensor}\n<shape type=\"sphere\"><float name=\"radios\" value=\"1\"/></shape>\n<shape type=\"teapot\"/>\n{light}\n</scene>"
        ),
    )
    .expect("write");

    let out = hppm(&["check", good.to_str().expect("path")]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{text}{}", stderr(&out));
    assert!(text.contains("warning:") && text.contains("ptracer") && text.contains("renders"));

    let out = hppm(&["check", bad.to_str().expect("path")]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(!out.status.success(), "{text}");
    for expected in [
        "bad.xml:2:",
        "bad.xml:4:",
        "did you mean \"radius\"",
        "bad.xml:5:",
        "teapot",
    ] {
        assert!(text.contains(expected), "{expected:?} missing in:\n{text}");
    }
    assert_eq!(text.matches("error:").count(), 2, "{text}");

    let png = dir.join("good.png");
    let out = hppm(&[
        "render",
        good.to_str().expect("path"),
        "--graph",
        "graphs/pt.ron",
        "--spp",
        "1",
        "--out",
        png.to_str().expect("path"),
    ]);
    let printed = stderr(&out);
    std::fs::remove_dir_all(&dir).ok();
    assert!(out.status.success(), "{printed}");
    assert!(
        printed.contains("warning:") && printed.contains("ptracer"),
        "{printed}"
    );
}

/// A point light behind glass with `pt`: the caustic cannot be path traced, and the render says
/// so before it starts and calls its error estimate a lower bound at the end; the hybrid (which traces photons) and an area-lit glass scene do not
/// warn. Would catch the warning lost, or raised for every glass scene.
#[test]
fn pt_warns_of_a_point_lights_caustic_it_cannot_sample() {
    let dir = std::env::temp_dir().join(format!("hppm-cli-delta-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out_path = dir.join("out.exr").to_string_lossy().into_owned();
    let render = |scene: &str, graph: &str| {
        let out = hppm(&[
            "render", scene, "--graph", graph, "--spp", "2", "--size", "16x16", "--out", &out_path,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let warned = stderr(&out).contains("cannot be path traced");
        assert_eq!(
            stderr(&out).contains("a lower bound"),
            warned,
            "{}",
            stderr(&out)
        );
        warned
    };
    let point = "tests/refs/scenes/point_light_caustic/scene.xml";
    let area = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
    assert!(render(point, "graphs/pt.ron"));
    assert!(!render(point, "graphs/hybrid.ron"));
    assert!(!render(area, "graphs/pt.ron"));
}

/// `auto` (the default graph) with a count budget: each candidate pilots the scene, the chosen
/// one goes on from its pilot. On the Veach scene of glossy plates (no caustic) the path tracer
/// is predicted 6-10x ahead of either hybrid, so the choice does not hang on timing noise. The
/// image must be the one `--graph pt` renders with the same seed and samples: it would catch the
/// pilot's iterations lost (fewer samples, a different image) or counted twice (more samples
/// than asked for), and another graph chosen.
#[test]
fn auto_chooses_pt_on_glossy_plates_and_continues_its_pilot() {
    let dir = std::env::temp_dir().join(format!("hppm-auto-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = "tests/data/mitsuba06/lajolla/veach_mi/mi.xml";
    let (auto_out, pt_out) = (dir.join("auto.exr"), dir.join("pt.exr"));
    let common = ["--spp", "64", "--size", "32x18", "--seed", "5"];
    let path = |p: &std::path::Path| p.to_string_lossy().into_owned();
    let auto_path = path(&auto_out);
    let mut args = vec!["render", scene, "--out", &auto_path];
    args.extend(common);
    let out = hppm(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let log = stderr(&out);
    assert!(log.contains("auto: chose pt by"), "{log}");
    for candidate in ["pt: ", "hybrid: ", "hybrid_pppm: "] {
        assert!(log.contains(candidate), "{candidate} missing: {log}");
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("32x18, 64 spp"), "{stdout}");
    let pt_path = path(&pt_out);
    let mut args = vec!["render", scene, "--graph", "pt", "--out", &pt_path];
    args.extend(common);
    let out = hppm(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let read = |p: &std::path::Path| hppm::image::Image::read_exr(p).expect("EXR");
    let (auto_image, pt_image) = (read(&auto_out), read(&pt_out));
    let worst = auto_image
        .pixels
        .iter()
        .zip(&pt_image.pixels)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs() / (b[c].abs() + 1e-3)))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "auto's image differs from pt's by {worst}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A path tracer never samples a point light's caustic, and its error estimate cannot see the
/// caustic missing: `auto` must leave it out rather than choose it because its noise is low.
/// Would catch the unsampled-light check dropped from the choice.
#[test]
fn auto_leaves_out_pt_where_caustics_come_from_a_point_light() {
    let out_path = std::env::temp_dir().join(format!("hppm-auto-point-{}.exr", std::process::id()));
    let out_text = out_path.to_string_lossy().into_owned();
    let out = hppm(&[
        "render",
        "tests/refs/scenes/point_light_caustic/scene.xml",
        "--spp",
        "64",
        "--size",
        "24x24",
        "--out",
        &out_text,
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let log = stderr(&out);
    assert!(
        log.contains("pt: left out (the scene has caustics from point"),
        "{log}"
    );
    assert!(!log.contains("auto: chose pt"), "{log}");
    assert!(log.contains("auto: chose hybrid"), "{log}");
    let _ = std::fs::remove_file(&out_path);
}

/// A budget too short to pilot three graphs renders the hybrid, and says why. Would catch
/// pilots that cost more than the render they choose for (three renders of 16 samples).
#[test]
fn auto_does_not_pilot_a_short_count_budget() {
    let out = hppm(&[
        "render",
        "--spp",
        "16",
        "--size",
        "16x16",
        "--out",
        "/tmp/hppm-auto-short.exr",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let log = stderr(&out);
    assert!(
        log.contains("auto: chose hybrid without pilots: 16 samples per pixel are too few"),
        "{log}"
    );
    assert!(!log.contains("piloting"), "{log}");
}

/// Every shard renders the same graph: `auto`, whose choice depends on each machine's timing,
/// is refused for one before anything is loaded; without --graph a shard renders the hybrid.
#[test]
fn auto_for_a_shard_is_refused() {
    let out = hppm(&[
        "render",
        "--graph",
        "auto",
        "--shard",
        "0/2",
        "--spp",
        "2",
        "--out",
        "/tmp/x.shard",
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("a shard needs a named graph"),
        "{}",
        stderr(&out)
    );
}
