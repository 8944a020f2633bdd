//! The `tonemap` pass, registered from outside hppm, is validated, pruned, rendered and profiled
//! like a built-in one, on lavapipe (or `HPPM_TEST_ADAPTER`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use custom_pass::{Curve, TonemapParams, registry, tonemap};
use hppm::gpu::GpuContext;
use hppm::passes::Registry;
use hppm::render::Renderer;

fn here(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// A file of hppm's own tree (its scenes).
fn hppm_file(relative: &str) -> PathBuf {
    here("../..").join(relative)
}

fn gpu() -> GpuContext {
    let choice = std::env::var("HPPM_TEST_ADAPTER").ok();
    GpuContext::new(choice.as_deref()).unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

fn graph_text(params: &str) -> String {
    std::fs::read_to_string(here("graphs/hybrid_tonemapped.ron"))
        .expect("graph")
        .replace("(exposure: 1.0, curve: Aces)", params)
}

/// Each curve at an exposure unlike 0: the pass's image is the CPU's tone mapping of the image
/// hppm's own hybrid renders with the same seed (the same iterations, the same random
/// numbers), pixel by pixel to float precision. Would catch the kernel reading the wrong
/// slot, a curve or the exposure off, the node not run, or its pixels shifted.
#[test]
fn tonemap_maps_the_hybrids_image_as_the_cpu_does() {
    let gpu = gpu();
    let scene = hppm::loaders::load(&hppm_file("scenes/cornell_box.ron")).expect("scene");
    let builtin = Registry::builtin();
    let render = |registry: &Registry, graph| {
        let mut renderer = Renderer::builder(&gpu, &scene, graph)
            .registry(registry.clone())
            .size(24, 20)
            .seed(3)
            .build()
            .expect("prepare");
        for _ in 0..2 {
            renderer.iterate().expect("iterate");
        }
        renderer.image().expect("image")
    };
    let plain = render(&builtin, builtin.bundled_graph("hybrid").expect("hybrid"));
    assert!(
        plain.pixels.iter().any(|p| p[0] > 0.0),
        "the hybrid renders light"
    );
    for (params, expected) in [
        ("(exposure: 1.0, curve: Aces)", (1.0, Curve::Aces)),
        ("(exposure: -0.5, curve: Reinhard)", (-0.5, Curve::Reinhard)),
        ("(exposure: 2.0, curve: Linear)", (2.0, Curve::Linear)),
    ] {
        let graph = registry()
            .parse_graph(Path::new("tonemapped.ron"), &graph_text(params))
            .unwrap_or_else(|e| panic!("{e}"));
        let mapped = render(&registry(), graph);
        let params = TonemapParams {
            exposure: expected.0,
            curve: expected.1,
        };
        for (i, (got, input)) in mapped.pixels.iter().zip(&plain.pixels).enumerate() {
            let want = tonemap(*input, params);
            for c in 0..3 {
                let tolerance = 1e-5 * want[c].abs().max(1.0);
                assert!(
                    (got[c] - want[c]).abs() <= tolerance,
                    "{params:?} pixel {i}: GPU {got:?}, CPU {want:?} of {input:?}"
                );
            }
        }
    }
}

/// The graph checks a custom node as a built-in one: an unknown param is an error at its line
/// naming the known ones, a non-finite exposure is refused, and hppm's own registry does not
/// know the kind (with a did-you-mean-free list of what it knows).
#[test]
fn a_custom_node_is_validated_like_a_builtin() {
    let file = Path::new("tonemapped.ron");
    let err = registry()
        .parse_graph(file, &graph_text("(exposure: 1.0, gamma: 2.2)"))
        .expect_err("unknown param")
        .to_string();
    assert!(err.contains("tonemapped.ron:13:"), "{err}");
    assert!(
        err.contains("unknown param \"gamma\"; known params: exposure, curve"),
        "{err}"
    );
    let err = registry()
        .parse_graph(file, &graph_text("(exposure: inf)"))
        .expect_err("infinite exposure")
        .to_string();
    assert!(err.contains("exposure is a number of stops"), "{err}");
    let err = Registry::builtin()
        .parse_graph(file, &graph_text("()"))
        .expect_err("unknown kind")
        .to_string();
    assert!(err.contains("unknown pass kind \"tonemap\""), "{err}");
}

/// On a scene without specular surfaces the photon nodes are pruned and the custom node kept;
/// rendering the pruned graph with profiling on times every node left, `tonemap` included.
/// Its uploaded struct matches the WGSL one, checked as the built-ins' are.
#[test]
fn a_custom_node_is_pruned_profiled_and_layout_checked_like_a_builtin() {
    let gpu = gpu();
    let scene = hppm::loaders::load(&hppm_file("scenes/cornell_diffuse.ron")).expect("scene");
    let registry = registry();
    let graph = registry
        .load_graph(&here("graphs/hybrid_tonemapped.ron"))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut renderer = Renderer::builder(&gpu, &scene, graph)
        .registry(registry.clone())
        .size(16, 16)
        .build()
        .expect("prepare");
    let pruned: Vec<&str> = renderer.pruned().iter().map(|p| p.node.as_str()).collect();
    assert_eq!(pruned, ["photons", "photon_grid", "gather", "estimate"]);
    renderer.enable_profiling().expect("profiling");
    for _ in 0..3 {
        renderer.iterate().expect("iterate");
    }
    let times = renderer.node_times();
    let names: Vec<&str> = times.iter().map(|t| t.name.as_str()).collect();
    assert!(names.contains(&"tonemap"), "timed nodes: {names:?}");
    assert!(names.contains(&"camera"), "timed nodes: {names:?}");
    let checked = registry
        .check_layouts()
        .unwrap_or_else(|e| panic!("{}", e.join("\n")));
    let builtin = Registry::builtin()
        .check_layouts()
        .expect("built-in layouts");
    assert_eq!(checked.len(), builtin.len() + 1);
    assert!(checked.contains(&"TonemapUniform"), "{checked:?}");
}

/// The command line with the custom registry renders a PNG through the custom graph, and
/// `graph` prints the node in its schedule.
#[test]
fn the_command_line_renders_with_the_custom_node() {
    let out = std::env::temp_dir().join(format!("custom_pass_{}.png", std::process::id()));
    let args = [
        "custom_pass".into(),
        "render".into(),
        hppm_file("scenes/cornell_box.ron").into_os_string(),
        "--graph".into(),
        here("graphs/hybrid_tonemapped.ron").into_os_string(),
        "--size".into(),
        "16x12".into(),
        "--spp".into(),
        "2".into(),
        "--out".into(),
        out.clone().into_os_string(),
    ];
    let code = hppm::cli::run_from(args, registry());
    assert_eq!(code, ExitCode::SUCCESS);
    let bytes = std::fs::read(&out).expect("the PNG was written");
    assert!(bytes.starts_with(b"\x89PNG"), "not a PNG");
    let _ = std::fs::remove_file(&out);
}

/// The pass lives in this crate alone: hppm's `src/` and `shaders/` never name it, so nothing in
/// hppm was changed to add it.
#[test]
fn hppm_itself_never_names_the_custom_pass() {
    fn files(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("folder").flatten() {
            let path = entry.path();
            if path.is_dir() {
                files(&path, out);
            } else {
                out.push(path);
            }
        }
    }
    let mut all = Vec::new();
    files(&hppm_file("src"), &mut all);
    files(&hppm_file("shaders"), &mut all);
    assert!(all.len() > 50, "{} files", all.len());
    for file in all {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        // What names the pass: its kind, its shaders and their modules, its crate (Mitsuba 0.6's
        // ldrfilm property `tonemap_method`, which hppm's loader reads, does not).
        let names = [
            "\"tonemap\"",
            "tonemap.wgsl",
            "tonemap::",
            "tone_curves",
            "custom_pass",
        ];
        assert!(
            !names.iter().any(|name| text.contains(name)),
            "{} names the custom pass",
            file.display()
        );
    }
}
