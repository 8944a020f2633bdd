//! The layers point one way (docs/architecture.md): `gpu/` names nothing above it, `graph/`
//! names only `gpu/`, `scene/` names no graph, no pass and no loader, `loaders/` only the scene,
//! `gpu_scene/` only `gpu/` and the scene, `passes/` no loader and no render, `render/` no
//! loader. A `use crate::passes::...` slipped
//! into the graph core, or a scene loader reaching for a pass, fails here with file and line.

use std::path::{Path, PathBuf};

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// Every `crate::<module>` a layer's files name that the layer may not.
fn violations(layer: &str, forbidden: &[&str]) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src")
        .join(layer);
    let mut files = Vec::new();
    sources(&root, &mut files);
    assert!(!files.is_empty(), "no sources under src/{layer}");
    let mut found = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{e}"));
        // A file's test module (the last item, as clippy keeps it) may use any layer.
        let library = text.split("\n#[cfg(test)]\n").next().unwrap_or(&text);
        for (n, line) in library.lines().enumerate() {
            for module in forbidden {
                let path = format!("crate::{module}");
                let hit = line.match_indices(&path).any(|(at, _)| {
                    // `crate::scene` but not `crate::scene_x`.
                    let next = line[at + path.len()..].chars().next();
                    !next.is_some_and(|c| c.is_alphanumeric() || c == '_')
                });
                if hit {
                    found.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
    }
    found
}

#[test]
fn layers_point_one_way() {
    let above_gpu: &[&str] = &[
        "graph",
        "passes",
        "scene",
        "loaders",
        "gpu_scene",
        "render",
        "app",
        "cli",
        "image",
    ];
    let rules: &[(&str, &[&str])] = &[
        ("gpu", above_gpu),
        (
            "graph",
            &[
                "passes",
                "scene",
                "loaders",
                "gpu_scene",
                "render",
                "app",
                "cli",
                "image",
            ],
        ),
        (
            "scene",
            &[
                "graph",
                "passes",
                "loaders",
                "gpu_scene",
                "render",
                "app",
                "cli",
                "gpu",
            ],
        ),
        (
            "loaders",
            &[
                "graph",
                "passes",
                "gpu_scene",
                "render",
                "app",
                "cli",
                "gpu",
            ],
        ),
        (
            "gpu_scene",
            &["graph", "passes", "loaders", "render", "app", "cli"],
        ),
        ("passes", &["loaders", "render", "app", "cli"]),
        ("render", &["loaders", "app", "cli"]),
        ("app", &["cli"]),
    ];
    let mut all = Vec::new();
    for (layer, forbidden) in rules {
        all.extend(violations(layer, forbidden));
    }
    assert!(
        all.is_empty(),
        "imports against the layering:\n{}",
        all.join("\n")
    );
}
