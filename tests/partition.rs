//! Graphs that would count light twice or not at all are refused before any GPU work, with the
//! file, the line of the node where the conflict arises and the reason (docs/graphs.md, "Render
//! graphs"). Each case edits a bundled graph in memory the way a user would get it wrong; each
//! of these rendered a wrong image before the check existed (about 2x too bright, or with the
//! caustic missing). The bundled graphs themselves must pass.

use std::path::{Path, PathBuf};

use hppm::graph::{GraphErrors, ValidGraph, parse_graph};
use hppm::passes::{builtin_kinds, paths};

fn bundled(name: &str) -> (PathBuf, String) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    (path, text)
}

/// `graph` with `from` replaced by `to` (which must occur), loaded and checked as a whole.
fn check(graph: &str, edits: &[(&str, &str)]) -> Result<ValidGraph, GraphErrors> {
    let (path, mut text) = bundled(graph);
    for (from, to) in edits {
        assert!(text.contains(from), "{graph} has no {from:?}");
        text = text.replacen(from, to, 1);
    }
    let graph = parse_graph(&path, &text, builtin_kinds())?;
    graph.check_transport(&paths::CLASSES)?;
    Ok(graph)
}

/// The graph is refused with one error whose message holds every needle, at `line`.
fn refused(graph: &str, edits: &[(&str, &str)], line: usize, needles: &[&str]) {
    let errors = match check(graph, edits) {
        Ok(_) => panic!("{graph} with {edits:?} must be refused"),
        Err(e) => e,
    };
    let text = errors.to_string();
    let hit = errors
        .0
        .iter()
        .find(|e| needles.iter().all(|n| e.message.contains(n)));
    let Some(e) = hit else {
        panic!("{graph} with {edits:?}: no error with {needles:?} in:\n{text}");
    };
    assert!(e.location.file.ends_with(graph), "{e}");
    assert_eq!(e.location.line, line, "{e}");
    eprintln!("{e}");
}

#[test]
fn the_bundled_graphs_count_every_path_once() {
    for graph in [
        "graphs/pt.ron",
        "graphs/hybrid.ron",
        "graphs/hybrid_ppm.ron",
        "graphs/hybrid_all_depths.ron",
        "graphs/hybrid_lbvh.ron",
        "graphs/hybrid_grid.ron",
        "graphs/hybrid_first_vertex.ron",
        "graphs/ppm_only.ron",
        "graphs/hybrid_glossy.ron",
        "graphs/glossy/hybrid_t0.02.ron",
        "graphs/glossy/hybrid_t0.05.ron",
        "graphs/glossy/hybrid_t0.1.ron",
        "graphs/glossy/hybrid_t0.2.ron",
        "graphs/glossy/hybrid_t0.3.ron",
    ] {
        check(graph, &[]).unwrap_or_else(|e| panic!("{graph}: {e}"));
    }
}

/// Photons depositing at every diffuse vertex while the camera pass also does next-event
/// estimation and continues past them: direct and indirect light twice (2x too bright).
#[test]
fn photons_in_mode_all_with_a_continuing_camera_count_twice() {
    refused(
        "graphs/hybrid.ron",
        &[("mode: Caustic", "mode: All")],
        // The camera node's line: the photon grid brings it the photons' direct and indirect
        // light (they meet again at the resolve node).
        9,
        &["counted twice", "direct light", "\"camera\"", "\"photons\""],
    );
}

/// A photon grid of photons in mode All, looked up past the hit points: the camera would add
/// direct and indirect light there that it also path traces (and sppm adds at the hit points).
#[test]
fn a_photon_grid_of_all_photons_counts_twice() {
    refused(
        "graphs/hybrid.ron",
        &[("mode: Caustic", "mode: All")],
        // The camera node's line: where its own light and the grid's meet.
        9,
        &["counted twice", "direct light", "\"camera\"", "\"photons\""],
    );
}

/// The camera stopping at its first photon-mapped vertex while photons deposit only caustics:
/// direct and indirect light at those vertices are counted by nobody.
#[test]
fn stopping_camera_paths_with_caustic_photons_loses_light() {
    refused(
        "graphs/ppm_only.ron",
        &[("mode: All", "mode: Caustic")],
        12,
        &["lacks", "direct light at photon-mapped vertices"],
    );
}

/// Hit points used only for the radius AOV: the camera must not drop caustics nobody adds. The
/// graph is accepted and the camera pass then counts everything itself.
#[test]
fn hit_points_feeding_only_the_radius_aov_drop_nothing() {
    let (path, text) = bundled("graphs/pt.ron");
    let text = text.replace(
        "nodes: [",
        "nodes: [\n        (name: \"resolve\", pass: \"resolve\", params: ()),",
    );
    let text = text
        .replace("edges: [],", "edges: [\"camera.radiance -> resolve.pt\", \"camera.hit_points -> resolve.hit_points\"],")
        .replace("output: \"camera.radiance\"", "output: \"resolve.combined\"");
    let graph = parse_graph(&path, &text, builtin_kinds()).unwrap_or_else(|e| panic!("{e}"));
    graph
        .check_transport(&paths::CLASSES)
        .unwrap_or_else(|e| panic!("{e}"));
    let camera = graph.nodes.iter().position(|n| n.name == "camera");
    let consumed = graph.consumed(camera.expect("camera"));
    assert!(!consumed.contains("hit_points"), "an AOV is no consumer");
}

/// A second camera pass feeding the same image: everything it renders twice.
#[test]
fn two_camera_passes_into_one_image_count_twice() {
    refused(
        "graphs/hybrid.ron",
        &[
            (
                "(name: \"resolve\"",
                "(name: \"camera2\", pass: \"path_trace\", params: ()),\n        (name: \"resolve\"",
            ),
            (
                "\"estimate.radiance -> resolve.caustic\"",
                "\"camera2.radiance -> resolve.caustic\"",
            ),
        ],
        14,
        &[
            "counted twice",
            "\"camera\" and \"photons\" and \"camera2\"",
        ],
    );
}

/// Two estimators reading one camera pass's hit points would both shrink their radii.
#[test]
fn two_estimators_on_one_set_of_hit_points_are_refused() {
    refused(
        "graphs/hybrid.ron",
        &[
            (
                "(name: \"resolve\"",
                "(name: \"estimate2\", pass: \"sppm\", params: ()),\n        (name: \"resolve\"",
            ),
            (
                "\"gather.deposits -> estimate.deposits\",",
                "\"gather.deposits -> estimate.deposits\",\n        \"camera.hit_points -> estimate2.hit_points\",\n        \"gather.deposits -> estimate2.deposits\",",
            ),
        ],
        22,
        &[
            "already feeds \"estimate.hit_points\"",
            "estimate2.hit_points",
        ],
    );
}

/// An estimator whose radii do not go back to the camera: the gather would search with first
/// radii forever while the estimate divides by shrinking ones.
#[test]
fn radii_that_feed_nothing_are_refused() {
    refused(
        "graphs/hybrid.ron",
        &[("        \"estimate.radii -> camera.radii\",\n", "")],
        12,
        &["\"estimate.radii\" must feed a node"],
    );
}

/// Camera and photon passes that stop paths at different depths: the photon-mapped part would
/// be cut at another length than the path-traced part.
#[test]
fn camera_and_photon_depths_must_agree() {
    refused(
        "graphs/hybrid.ron",
        &[(
            "params: (mode: Caustic, glossy_threshold: 0.2)",
            "params: (mode: Caustic, glossy_threshold: 0.2, max_depth: 5)",
        )],
        13,
        &["different depths", "max_depth 5", "the scene's max_depth"],
    );
    check(
        "graphs/hybrid.ron",
        &[
            (
                "params: (mode: Caustic, glossy_threshold: 0.2)",
                "params: (mode: Caustic, glossy_threshold: 0.2, max_depth: 5)",
            ),
            (
                "params: (merge_depth: 1, glossy_threshold: 0.2)",
                "params: (merge_depth: 1, glossy_threshold: 0.2, max_depth: 5)",
            ),
        ],
    )
    .unwrap_or_else(|e| panic!("equal depths must pass: {e}"));
}

/// Camera and photon passes that call different microfacet lobes specular (`glossy_threshold`):
/// the light through a lobe whose roughness lies between the two thresholds would be path
/// traced by the camera and deposited by the photons (counted twice), or left to photons by the
/// camera and stopped by them (counted by neither). Refused where the two meet, naming both
/// nodes and their values: at the camera when the photon grid brings it the photons' rule, at
/// the resolve node without a grid.
#[test]
fn camera_and_photon_glossy_thresholds_must_agree() {
    refused(
        "graphs/hybrid.ron",
        &[(
            "params: (merge_depth: 1, glossy_threshold: 0.2)",
            "params: (merge_depth: 1, glossy_threshold: 0.1)",
        )],
        9,
        &[
            "different glossy_threshold",
            "\"camera\": 0.1",
            "\"photons\": 0.2",
            "same glossy_threshold",
        ],
    );
    refused(
        "graphs/hybrid_first_vertex.ron",
        &[(
            "params: (mode: Caustic)",
            "params: (mode: Caustic, glossy_threshold: 0.2)",
        )],
        11,
        &[
            "different glossy_threshold",
            "\"camera\": 0",
            "\"photons\": 0.2",
        ],
    );
    refused(
        "graphs/hybrid_glossy.ron",
        &[(
            "params: (mode: Caustic, glossy_threshold: 0.1)",
            "params: (mode: Caustic, glossy_threshold: 0.05)",
        )],
        8,
        &[
            "different glossy_threshold",
            "\"camera\": 0.1",
            "\"photons\": 0.05",
        ],
    );
    check(
        "graphs/hybrid_first_vertex.ron",
        &[
            (
                "params: (mode: Caustic)",
                "params: (mode: Caustic, glossy_threshold: 0.2)",
            ),
            (
                "params: (merge_depth: 1)",
                "params: (merge_depth: 1, glossy_threshold: 0.2)",
            ),
        ],
    )
    .unwrap_or_else(|e| panic!("equal thresholds must pass: {e}"));
    // Photon mapping alone splits nothing at glossy lobes (its photons deposit at every diffuse
    // vertex, its camera stops at the first): a threshold there is no conflict.
    check(
        "graphs/ppm_only.ron",
        &[("mode: All", "mode: All, glossy_threshold: 0.3")],
    )
    .unwrap_or_else(|e| panic!("ppm_only with a photon threshold must pass: {e}"));
}

/// A `glossy_threshold` that is no roughness is refused where it is written.
#[test]
fn a_glossy_threshold_must_be_a_roughness() {
    for (from, to) in [
        (
            "params: (merge_depth: 1, glossy_threshold: 0.2)",
            "params: (merge_depth: 1, glossy_threshold: -0.1)",
        ),
        (
            "params: (mode: Caustic, glossy_threshold: 0.2)",
            "params: (mode: Caustic, glossy_threshold: inf)",
        ),
        (
            "params: (mode: Caustic, glossy_threshold: 0.2)",
            "params: (mode: Caustic, glossy_threshold: NaN)",
        ),
    ] {
        let errors = check("graphs/hybrid.ron", &[(from, to)]).err();
        let text = errors.map(|e| e.to_string()).unwrap_or_default();
        assert!(
            text.contains("glossy_threshold is a roughness"),
            "{to}: {text}"
        );
        assert!(text.contains("hybrid.ron:"), "{text}");
    }
}

/// Params that would render nothing or never end are refused where they are written.
#[test]
fn params_that_render_nothing_are_refused() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "params: (mode: Caustic, glossy_threshold: 0.2)",
            "params: (mode: Caustic, glossy_threshold: 0.2, photons_per_iteration: 0)",
            "photons_per_iteration must be at least 1",
        ),
        (
            "params: (merge_depth: 1, glossy_threshold: 0.2)",
            "params: (merge_depth: 1, glossy_threshold: 0.2, samples_per_iteration: 0)",
            "samples_per_iteration must lie in",
        ),
        (
            "params: (merge_depth: 1, glossy_threshold: 0.2)",
            "params: (merge_depth: 1, glossy_threshold: 0.2, samples_per_iteration: 100000)",
            "samples_per_iteration must lie in",
        ),
        (
            "params: (merge_depth: 1, glossy_threshold: 0.2)",
            "params: (merge_depth: 1, glossy_threshold: 0.2, max_depth: 0)",
            "max_depth must be at least 1",
        ),
        (
            "params: (alpha: 0.7)",
            "params: (alpha: 0.7, radius_pixels: 1e9)",
            "radius_pixels must lie in",
        ),
    ];
    for (from, to, needle) in cases {
        let errors = check("graphs/hybrid.ron", &[(from, to)]).err();
        let text = errors.map(|e| e.to_string()).unwrap_or_default();
        assert!(text.contains(needle), "{to}: expected {needle:?} in {text}");
        assert!(text.contains("hybrid.ron:"), "{text}");
    }
}
