//! The layers point one way (docs/architecture.md): `gpu/` names nothing above it, `graph/`
//! names only `gpu/`, `scene/` names no graph and no pass. A `use crate::passes::...` slipped
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
        for (n, line) in text.lines().enumerate() {
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
    let rules: &[(&str, &[&str])] = &[
        ("gpu", &["graph", "passes", "scene", "app", "cli", "image"]),
        ("graph", &["passes", "scene", "app", "cli", "image"]),
        ("scene", &["graph", "passes", "app", "cli", "gpu"]),
        ("passes", &["app", "cli"]),
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
