//! Graph parsing, validation and scheduling over fake pass kinds (no GPU): one file per error
//! kind under tests/data/graphs, each error checked for its message and line.

#![allow(non_upper_case_globals)]

use std::path::PathBuf;

use hppm::graph::pass::{
    ExecCtx, IMAGE, Pass, PassKind, PrepareCtx, Recorder, ResourceKind, Size, SlotDecl,
    parse_params,
};
use hppm::graph::{GraphErrors, ValidGraph, load_graph, parse_graph};
use serde::Deserialize;

struct Fake;

impl Pass for Fake {
    fn prepare(&mut self, _: PrepareCtx<'_>) -> Result<(), hppm::Error> {
        Ok(())
    }
    fn execute(&mut self, _: &ExecCtx<'_>, _: &mut Recorder<'_>) -> Result<(), hppm::Error> {
        Ok(())
    }
}

#[derive(Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
#[allow(dead_code)]
struct CameraParams {
    max_depth: Option<u32>,
}

#[derive(Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
struct NoParams {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct PhotonParams {
    photons_per_iteration: u32,
}

#[derive(Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
#[allow(dead_code)]
struct SppmParams {
    alpha: f32,
}

fn with<P: serde::de::DeserializeOwned>(
    params: &str,
) -> Result<Box<dyn Pass>, ron::error::SpannedError> {
    parse_params::<P>(params).map(|_| Box::new(Fake) as Box<dyn Pass>)
}

// Kinds of the fake passes; only their names matter to validation.
const Radiance: ResourceKind = IMAGE;
const HitPoints: ResourceKind = ResourceKind::new("hit_points", 0, 48);
const HitPointTree: ResourceKind = ResourceKind::new("hit_point_tree", 16, 32);
const Deposits: ResourceKind = ResourceKind::new("deposits", 0, 16);

static FAKE_KINDS: &[PassKind] = &[
    PassKind {
        name: "path_trace",
        description: "camera",
        slots: &[
            SlotDecl::output("radiance", Radiance, Size::Pixels).persistent(),
            SlotDecl::output("hit_points", HitPoints, Size::Pixels),
        ],
        shaders: &[],
        layouts: &[],
        construct: with::<CameraParams>,
    },
    PassKind {
        name: "hit_point_bvh_sah",
        description: "bvh",
        slots: &[
            SlotDecl::input("hit_points", HitPoints),
            SlotDecl::output("tree", HitPointTree, Size::Pixels),
        ],
        shaders: &[],
        layouts: &[],
        construct: with::<NoParams>,
    },
    PassKind {
        name: "photon_trace",
        description: "photons",
        slots: &[
            SlotDecl::input("hit_point_tree", HitPointTree),
            SlotDecl::input("hit_points", HitPoints),
            SlotDecl::output("deposits", Deposits, Size::Pixels),
        ],
        shaders: &[],
        layouts: &[],
        construct: with::<PhotonParams>,
    },
    PassKind {
        name: "sppm",
        description: "estimator",
        slots: &[
            SlotDecl::input("deposits", Deposits),
            SlotDecl::input("hit_points", HitPoints),
            SlotDecl::output("radiance", Radiance, Size::Pixels).persistent(),
        ],
        shaders: &[],
        layouts: &[],
        construct: with::<SppmParams>,
    },
    PassKind {
        name: "resolve",
        description: "resolve",
        slots: &[
            SlotDecl::input("pt", Radiance),
            SlotDecl::input("caustic", Radiance).optional(),
            SlotDecl::output("combined", Radiance, Size::Pixels),
        ],
        shaders: &[],
        layouts: &[],
        construct: with::<NoParams>,
    },
    PassKind {
        name: "relay",
        description: "passes radiance through",
        slots: &[
            SlotDecl::input("in", Radiance),
            SlotDecl::output("out", Radiance, Size::Pixels),
        ],
        shaders: &[],
        layouts: &[],
        construct: with::<NoParams>,
    },
];

/// The fake kinds as a registry's list.
fn fake_registry() -> Vec<&'static PassKind> {
    FAKE_KINDS.iter().collect()
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/graphs/{name}.ron"))
}

fn errors(name: &str) -> GraphErrors {
    match load_graph(&data(name), &fake_registry()) {
        Ok(_) => panic!("{name}.ron should not validate"),
        Err(e) => e,
    }
}

/// The file has exactly one error, on `line`, whose message contains `needle`.
fn single_error(name: &str, line: usize, needle: &str) {
    let errs = errors(name);
    assert_eq!(errs.0.len(), 1, "{name}: {errs}");
    let e = &errs.0[0];
    assert!(e.location.file.ends_with(format!("{name}.ron")), "{e}");
    assert_eq!(e.location.line, line, "{name}: {e}");
    assert!(
        e.message.contains(needle),
        "{name}: expected {needle:?} in {e}"
    );
}

#[test]
fn syntax_error() {
    single_error("syntax", 4, "");
}

#[test]
fn unknown_top_level_field() {
    single_error("unknown_top_field", 5, "outputs");
}

#[test]
fn wrong_version() {
    single_error("wrong_version", 2, "version 7 is not supported");
}

#[test]
fn unknown_pass_kind_suggests_the_closest() {
    single_error(
        "unknown_kind",
        4,
        "unknown pass kind \"path_trcae\" (did you mean \"path_trace\"?)",
    );
}

#[test]
fn unknown_param_points_at_the_key() {
    single_error("unknown_param", 5, "unknown param \"max_dpth\"");
    let e = &errors("unknown_param").0[0];
    assert_eq!(e.location.col, 33, "{e}");
}

#[test]
fn bad_param_type() {
    single_error("bad_param_type", 5, "params:");
}

#[test]
fn missing_param() {
    single_error(
        "missing_param",
        6,
        "missing param \"photons_per_iteration\"",
    );
}

#[test]
fn duplicate_node() {
    single_error(
        "duplicate_node",
        5,
        "duplicate node name \"camera\" (first defined on line 4)",
    );
}

#[test]
fn malformed_edge() {
    single_error("malformed_edge", 5, "malformed edge");
}

#[test]
fn unknown_node_in_edge() {
    single_error("unknown_node_in_edge", 6, "no node named \"kamera\"");
}

#[test]
fn unknown_slot_lists_the_slots() {
    single_error(
        "unknown_slot",
        5,
        "has no slot \"radiance_x\"; its slots: radiance, hit_points",
    );
}

#[test]
fn slot_kind_mismatch() {
    single_error(
        "type_mismatch",
        5,
        "\"camera.radiance\" (radiance) -> \"bvh.hit_points\" (hit_points)",
    );
}

#[test]
fn input_connected_twice() {
    single_error("connected_twice", 6, "connected twice (first on line 5)");
}

#[test]
fn missing_producer() {
    single_error(
        "missing_producer",
        5,
        "input \"resolve.pt\" has no producer",
    );
}

#[test]
fn bad_output() {
    single_error("bad_output", 5, "no output slot \"hit_pointz\"");
}

#[test]
fn output_must_be_an_image() {
    let text = r#"(version: 1, nodes: [(name: "camera", pass: "path_trace")], edges: [],
        output: "camera.hit_points")"#;
    let errs = match parse_graph(&PathBuf::from("inline.ron"), text, &fake_registry()) {
        Ok(_) => panic!("hit points are not an image"),
        Err(e) => e,
    };
    assert!(
        errs.0[0]
            .message
            .contains("carries hit_points, not radiance"),
        "{errs}"
    );
    assert_eq!(errs.0[0].location.line, 2);
}

#[test]
fn cycle_names_its_nodes() {
    single_error("cycle", 10, "cycle: a -> b -> c -> a");
}

#[test]
fn every_problem_is_reported_at_once() {
    let errs = errors("many_problems");
    let lines: Vec<usize> = errs.0.iter().map(|e| e.location.line).collect();
    assert_eq!(errs.0.len(), 3, "{errs}");
    assert_eq!(lines, [4, 5, 10], "{errs}");
    assert!(errs.to_string().ends_with("3 errors in graph"));
}

fn names_in_order(g: &ValidGraph) -> Vec<&str> {
    g.order.iter().map(|&i| g.nodes[i].name.as_str()).collect()
}

#[test]
fn valid_graph_schedules_in_dependency_order() {
    let g = load_graph(&data("valid_hybrid"), &fake_registry()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        names_in_order(&g),
        ["camera", "bvh", "photons", "estimate", "resolve"]
    );
    assert_eq!(g.edges.len(), 7);
    assert!(g.warnings.is_empty());
    let text = g.schedule_text();
    assert!(text.contains("1. camera (path_trace)"), "{text}");
    assert!(text.contains("in  caustic <- estimate.radiance"), "{text}");
    let dot = g.to_dot();
    for node in ["camera", "bvh", "photons", "estimate", "resolve"] {
        assert!(dot.contains(&format!("label=\"{node}\\n(")), "{dot}");
    }
    assert_eq!(dot.matches(" -> n").count(), 7, "{dot}");
}

#[test]
fn ties_are_broken_by_file_order_and_dead_nodes_warned() {
    let text = r#"(version: 1, nodes: [(name: "z", pass: "path_trace"), (name: "a", pass: "path_trace")],
        edges: [], output: "a.radiance")"#;
    let g = parse_graph(&PathBuf::from("inline.ron"), text, &fake_registry())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(names_in_order(&g), ["z", "a"]);
    assert_eq!(g.warnings.len(), 1);
    assert!(g.warnings[0].message.contains("\"z\""));
}

/// Every graph under graphs/, its subfolders (graphs/glossy/) included.
#[test]
fn shipped_graphs_validate_against_the_real_registry() {
    let mut folders = vec![PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("graphs")];
    let mut graphs = 0;
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
                continue;
            }
            if let Err(e) = load_graph(&path, hppm::passes::builtin_kinds()) {
                panic!("{}: {e}", path.display());
            }
            graphs += 1;
        }
    }
    assert!(graphs >= 15, "only {graphs} graphs found");
}

/// Truncations at every byte and seeded token swaps never panic; every error points inside the
/// file.
#[test]
fn mangled_graphs_never_panic() {
    let text = std::fs::read_to_string(data("valid_hybrid")).unwrap();
    let path = PathBuf::from("mangled.ron");
    let lines = text.lines().count();
    let check = |t: &str| {
        if let Err(errs) = parse_graph(&path, t, &fake_registry()) {
            for e in &errs.0 {
                assert!(e.location.line >= 1 && e.location.line <= lines + 1, "{e}");
            }
        }
    };
    for end in (0..text.len()).filter(|&i| text.is_char_boundary(i)) {
        check(&text[..end]);
    }
    let tokens: Vec<&str> = text.split_inclusive([' ', ',', '(', ')', '"']).collect();
    let mut seed = 2024u64;
    let mut next = |n: usize| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 33) as usize % n
    };
    let junk = [
        "",
        "(",
        ")",
        "\"",
        ",",
        "1e999",
        "-1",
        "x",
        "[",
        "::",
        "->",
        "None",
        "\"a.b -> c.d\"",
    ];
    for _ in 0..300 {
        let mut t: Vec<&str> = tokens.clone();
        let (i, j) = (next(t.len()), next(t.len()));
        t.swap(i, j);
        let k = next(t.len());
        t[k] = junk[next(junk.len())];
        check(&t.concat());
    }
}

/// Pruning with the real pass kinds: without a specular surface the hybrid keeps only what path
/// tracing needs; photon mapping alone (photons in `All` mode) keeps everything.
#[test]
fn pruning_drops_the_photon_nodes_when_the_scene_has_no_specular_surface() {
    let load = |name: &str| {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(name);
        load_graph(&path, hppm::passes::builtin_kinds()).unwrap_or_else(|e| panic!("{e}"))
    };
    let mut hybrid = load("graphs/hybrid.ron");
    let pruned = hybrid.prune(|_| false).expect("prune");
    let names: Vec<&str> = pruned.iter().map(|p| p.node.as_str()).collect();
    assert_eq!(names, ["photons", "photon_grid", "gather", "estimate"]);
    assert!(pruned[0].reason.contains("specular"), "{}", pruned[0]);
    let kept: Vec<&str> = hybrid
        .order
        .iter()
        .map(|&i| hybrid.nodes[i].name.as_str())
        .collect();
    assert_eq!(kept, ["camera", "resolve"]);
    assert_eq!(hybrid.nodes[hybrid.output.0].name, "resolve");
    assert!(
        hybrid
            .edges
            .iter()
            .all(|e| e.from_node < 2 && e.to_node < 2)
    );

    let mut with_glass = load("graphs/hybrid.ron");
    assert!(with_glass.prune(|_| true).expect("prune").is_empty());
    assert_eq!(with_glass.nodes.len(), 6);

    let mut ppm_only = load("graphs/ppm_only.ron");
    assert!(ppm_only.prune(|_| false).expect("prune").is_empty());
}

#[test]
fn pruning_the_output_node_is_an_error() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("graphs/hybrid.ron");
    let text = std::fs::read_to_string(&path).expect("read").replace(
        "output: \"resolve.combined\"",
        "output: \"estimate.radiance\"",
    );
    let mut graph = parse_graph(&path, &text, hppm::passes::builtin_kinds()).expect("valid");
    let error = graph.prune(|_| false).expect_err("output pruned");
    assert!(
        error.to_string().contains("output node \"estimate\""),
        "{error}"
    );
}

/// A pass that needs a scene feature only a program's own test can answer.
struct NeedsEmissiveSphere;

const EMISSIVE_SPHERE: hppm::graph::pass::SceneNeed = hppm::graph::pass::SceneNeed {
    name: "emissive_sphere",
    description: "sphere that emits",
    glossy_below: 0.0,
};

impl Pass for NeedsEmissiveSphere {
    fn prepare(&mut self, _: PrepareCtx<'_>) -> Result<(), hppm::Error> {
        Ok(())
    }
    fn execute(&mut self, _: &ExecCtx<'_>, _: &mut Recorder<'_>) -> Result<(), hppm::Error> {
        Ok(())
    }
    fn needs(&self) -> Vec<hppm::graph::pass::SceneNeed> {
        vec![EMISSIVE_SPHERE]
    }
}

/// A pass-through on images with a scene need of its own.
static GLOW: PassKind = PassKind {
    name: "glow",
    description: "test pass-through",
    slots: &[
        SlotDecl::input("image", Radiance),
        SlotDecl::output("glowing", Radiance, Size::Pixels),
    ],
    shaders: &[],
    layouts: &[],
    construct: |params| {
        parse_params::<NoParams>(params).map(|_| Box::new(NeedsEmissiveSphere) as Box<dyn Pass>)
    },
};

/// The registry is a value: a kind added from outside resolves in a graph file (and hppm's own
/// registry refuses the same file), a kind of a built-in's name replaces it, a need is met only
/// as the test registered for it says (a need no test answers never is, so its node is pruned),
/// and modules are added after hppm's. Would catch a registry that ignores what is added to it,
/// or pruning that asks something other than the registry.
#[test]
fn a_registry_takes_kinds_needs_and_modules_from_outside() {
    use hppm::passes::Registry;
    let path = PathBuf::from("glow.ron");
    let text = r#"(
        version: 1,
        nodes: [
            (name: "camera", pass: "path_trace", params: ()),
            (name: "glow", pass: "glow"),
        ],
        edges: ["camera.radiance -> glow.image"],
        output: "glow.glowing",
    )"#;
    let err = Registry::builtin()
        .parse_graph(&path, text)
        .expect_err("hppm does not know glow")
        .to_string();
    assert!(err.contains("unknown pass kind \"glow\""), "{err}");

    let scene = hppm::loaders::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box.ron"),
    )
    .expect("scene");
    let features = scene.features();
    let has_sphere_light = |scene: &hppm::scene::Scene,
                            _: &hppm::scene::SceneFeatures,
                            _: &hppm::graph::pass::SceneNeed| {
        scene
            .spheres
            .iter()
            .any(|s| scene.materials[s.material as usize].emission.max_element() > 0.0)
    };
    let always = |_: &hppm::scene::Scene,
                  _: &hppm::scene::SceneFeatures,
                  _: &hppm::graph::pass::SceneNeed| true;
    for (registry, kept) in [
        (Registry::builtin().with(&GLOW), false),
        (
            Registry::builtin()
                .with(&GLOW)
                .with_need("emissive_sphere", has_sphere_light),
            false,
        ),
        (
            Registry::builtin()
                .with(&GLOW)
                .with_need("emissive_sphere", always),
            true,
        ),
    ] {
        let mut graph = registry
            .parse_graph(&path, text)
            .unwrap_or_else(|e| panic!("{e}"));
        let pruned = graph.prune(|need| registry.scene_meets(&scene, &features, need));
        match (kept, pruned) {
            (true, Ok(pruned)) => assert!(pruned.iter().all(|p| p.node != "glow"), "{pruned:?}"),
            (false, Err(e)) => assert!(
                e.to_string().contains("the scene has no sphere that emits"),
                "{e}"
            ),
            (kept, other) => panic!("kept {kept}: {other:?}"),
        }
    }

    // Replacing a built-in: the graph resolves `resolve` to the replacement.
    static MY_RESOLVE: PassKind = PassKind {
        name: "resolve",
        description: "a program's own resolve",
        ..GLOW
    };
    let registry = Registry::builtin().with(&MY_RESOLVE);
    assert_eq!(registry.kinds().len(), hppm::passes::builtin_kinds().len());
    assert_eq!(
        registry.kind("resolve").map(|k| k.description),
        Some("a program's own resolve")
    );
    let modules = Registry::builtin()
        .with_module(hppm::shader_file!("shaders/common/rng.wgsl"))
        .modules()
        .len();
    assert_eq!(
        modules,
        hppm::passes::common_modules(&hppm::bsdfs::BsdfRegistry::builtin()).len() + 1
    );
}

/// docs/pass-kinds.md is the registry's own reference (`hppm info --markdown`): a slot or param
/// added to a kind without regenerating it fails here. Each built-in kind's params are read
/// from its params struct, so none is missing.
#[test]
fn the_pass_kind_reference_is_the_registrys() {
    let registry = hppm::passes::Registry::builtin();
    let generated = registry.markdown();
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/pass-kinds.md");
    let written = std::fs::read_to_string(&path).expect("docs/pass-kinds.md");
    assert!(
        written == generated,
        "docs/pass-kinds.md differs from `hppm info --markdown`: regenerate it"
    );
    for kind in registry.kinds() {
        assert!(
            kind.param_names().is_some(),
            "{} accepts unknown params",
            kind.name
        );
    }
    let path_trace = registry.kind("path_trace").and_then(|k| k.param_names());
    assert!(
        path_trace.is_some_and(|p| p.contains(&"merge_depth") && p.contains(&"glossy_threshold"))
    );
}
