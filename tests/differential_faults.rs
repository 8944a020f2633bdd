//! The differential test (tests/differential.rs) shown able to fail: three deliberate faults,
//! each put into a copy of the shaders (`HPPM_SHADER_DIR`, read by the `hppm` binary these
//! tests run), and each must make the corpus's bias statistic flag a scene it applies to.
//!
//! - Traversal: rays with a negative x direction never visit a node's farther child, so they
//!   miss whatever lies behind the nearer one. A fault of one direction only, like the coplanar
//!   ties of tests/coplanar.rs.
//! - A BSDF's pdf: the rough conductor reports half its sampling density, so multiple
//!   importance sampling weighs its light hits wrongly (its evaluation's pdf is left right).
//! - The photon partition: photons that reach a diffuse surface straight from the light deposit
//!   there too, so the hybrid counts direct light (`L D`) twice, by photons and by the camera's
//!   next-event estimation.
//!
//! Each fault is rendered over the scenes it can show in (at most `MAX_SCENES` of them) until one
//! is flagged; the test prints which, and the statistic.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::differential::*;
use hppm::image::Image;
use hppm::scene::Scene;

const SEEDS: u64 = 6;
const SPP: u64 = 8;
const MAX_SCENES: usize = 8;

struct Fault {
    name: &'static str,
    file: &'static str,
    correct: &'static str,
    faulty: &'static str,
    graph: &'static str,
    shows_in: fn(&Scene) -> bool,
}

/// A copy of the repository's WGSL files with `fault` applied (the text must occur exactly once).
fn faulty_shaders(fault: &Fault) -> PathBuf {
    let root = std::env::temp_dir().join(format!(
        "hppm-fault-{}-{}",
        fault.name.replace(' ', "-"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&root);
    // Every WGSL file of the repository: shaders/, and those kept beside their Rust under src/.
    copy_tree(&common::repo_path("shaders"), &root.join("shaders"));
    copy_tree(&common::repo_path("src"), &root.join("src"));
    let path = root.join(fault.file);
    let text = std::fs::read_to_string(&path).expect("shader");
    assert_eq!(
        text.matches(fault.correct).count(),
        1,
        "{}: the text to change must occur once in {}",
        fault.name,
        fault.file
    );
    std::fs::write(&path, text.replace(fault.correct, fault.faulty)).expect("write shader");
    root
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read dir") {
        let entry = entry.expect("entry");
        let target = to.join(entry.file_name());
        if entry.file_type().expect("type").is_dir() {
            copy_tree(&entry.path(), &target);
        } else if entry.path().extension().is_some_and(|e| e == "wgsl") {
            std::fs::copy(entry.path(), target).expect("copy");
        }
    }
}

/// Renders `case` through `graph` with the shaders under `shader_dir`, one process per seed.
fn render_with(shader_dir: &Path, case: &Case, graph: &str) -> Vec<Image> {
    (0..SEEDS)
        .map(|seed| {
            let out = shader_dir.join(format!("{}-{seed}.exr", case.name));
            let status = Command::new(env!("CARGO_BIN_EXE_hppm"))
                .env("HPPM_SHADER_DIR", shader_dir)
                .current_dir(common::repo_path("."))
                .args(["render"])
                .arg(case.dir.join("scene.xml"))
                .args(["--graph", graph, "--spp", &SPP.to_string()])
                .args(["--seed", &seed.to_string(), "--out"])
                .arg(&out)
                .output()
                .expect("run hppm");
            assert!(
                status.status.success(),
                "hppm render failed: {}",
                String::from_utf8_lossy(&status.stderr)
            );
            Image::read_exr(&out).unwrap_or_else(|e| panic!("{e}"))
        })
        .collect()
}

fn assert_caught(fault: Fault) {
    let shaders = faulty_shaders(&fault);
    let cases = corpus(CORPUS);
    let mut tried = Vec::new();
    for case in cases.iter() {
        let graph_name = Path::new(fault.graph)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default();
        if !case.graphs.iter().any(|g| g == graph_name) || !(fault.shows_in)(&case.scene()) {
            continue;
        }
        let images = render_with(&shaders, case, fault.graph);
        let (flagged, worst) = flagged(case, &images, SPP);
        eprintln!("{}: scene {} worst {worst}", fault.name, case.name);
        tried.push(case.name.clone());
        if !flagged.is_empty() {
            eprintln!(
                "{}: caught in scene {} ({} of 16 blocks biased)",
                fault.name,
                case.name,
                flagged.len()
            );
            let _ = std::fs::remove_dir_all(&shaders);
            return;
        }
        if tried.len() == MAX_SCENES {
            break;
        }
    }
    let _ = std::fs::remove_dir_all(&shaders);
    panic!("{}: not caught in scenes {tried:?}", fault.name);
}

#[test]
fn a_traversal_fault_in_one_direction_is_caught() {
    assert_caught(Fault {
        name: "far child skipped for dir.x < 0",
        file: "shaders/common/traversal.wgsl",
        correct: "if t_far < T_INFINITE && top < BVH_STACK_SIZE {",
        faulty: "if t_far < T_INFINITE && top < BVH_STACK_SIZE && dir.x >= 0.0 {",
        graph: "graphs/pt.ron",
        // Scenes past the every-primitive limit walk the BVH.
        shows_in: |scene| {
            scene.triangles.len() + scene.spheres.len()
                > hppm::gpu_scene::resources::EVERY_PRIM_LIMIT
        },
    });
}

#[test]
fn a_wrong_bsdf_pdf_is_caught() {
    assert_caught(Fault {
        name: "rough conductor sampling pdf halved",
        file: "src/bsdfs/roughconductor/roughconductor.wgsl",
        correct: "let pdf = microfacet_pdf(mf, wi, h) / (4.0 * dot(wo, h));",
        faulty: "let pdf = 0.5 * microfacet_pdf(mf, wi, h) / (4.0 * dot(wo, h));",
        graph: "graphs/pt.ron",
        shows_in: |scene| {
            scene
                .materials
                .iter()
                .any(|m| m.bsdf.kind() == "roughconductor")
        },
    });
}

#[test]
fn a_photon_partition_fault_is_caught() {
    assert_caught(Fault {
        name: "photons straight from the light deposited",
        file: "shaders/passes/photon_trace.wgsl",
        correct: "if after_specular {",
        faulty: "if true {",
        graph: "graphs/hybrid.ron",
        // The hybrid traces photons where some surface is specular.
        shows_in: |scene| {
            let f = scene.features();
            f.delta || f.microfacet
        },
    });
}
