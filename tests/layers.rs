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

/// The sibling modules `file` (a file of folder `dir`, module path `module`) names: through
/// `super::x` or `crate::<module>::x`, where `x` is a file of the folder.
fn sibling_imports(file: &Path, module: &str, siblings: &[String]) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{e}"));
    let library = text.split("\n#[cfg(test)]\n").next().unwrap_or(&text);
    // Code only: a doc comment's link is not an import.
    let library: String = library
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    let own = file.file_stem().map(|s| s.to_string_lossy().into_owned());
    let mut found = Vec::new();
    for sibling in siblings.iter().filter(|s| Some(*s) != own.as_ref()) {
        let paths = [
            format!("super::{sibling}"),
            format!("crate::{module}::{sibling}"),
        ];
        let named = paths.iter().any(|path| {
            library.match_indices(path.as_str()).any(|(at, _)| {
                let next = library[at + path.len()..].chars().next();
                !next.is_some_and(|c| c.is_alphanumeric() || c == '_')
            })
        });
        if named {
            found.push(sibling.clone());
        }
    }
    found
}

/// No two files of a folder import each other, directly or around a longer circle: a circle
/// makes two files one unit that neither can be read without. (A folder's mod.rs, which
/// declares its files, is left out.)
#[test]
fn no_import_circle_inside_a_folder() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut dirs = vec![src.clone()];
    let mut circles = Vec::new();
    while let Some(dir) = dirs.pop() {
        let mut files = Vec::new();
        for entry in std::fs::read_dir(&dir).expect("dir").flatten() {
            let path = entry.path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs")
                && path
                    .file_stem()
                    .is_some_and(|s| s != "mod" && s != "lib" && s != "main")
            {
                files.push(path);
            }
        }
        let module = dir
            .strip_prefix(&src)
            .expect("under src")
            .to_string_lossy()
            .replace('/', "::");
        let names: Vec<String> = files
            .iter()
            .map(|f| f.file_stem().expect("stem").to_string_lossy().into_owned())
            .collect();
        let edges: Vec<Vec<usize>> = files
            .iter()
            .map(|f| {
                sibling_imports(f, &module, &names)
                    .iter()
                    .filter_map(|n| names.iter().position(|m| m == n))
                    .collect()
            })
            .collect();
        // A file that reaches itself through its siblings is in a circle.
        for start in 0..files.len() {
            let mut seen = vec![false; files.len()];
            let mut pending = edges[start].clone();
            while let Some(next) = pending.pop() {
                if next == start {
                    circles.push(files[start].display().to_string());
                    break;
                }
                if !std::mem::replace(&mut seen[next], true) {
                    pending.extend(edges[next].iter().copied());
                }
            }
        }
    }
    assert!(
        circles.is_empty(),
        "files in an import circle:\n{}",
        circles.join("\n")
    );
}

/// No top-level folder of the code (src/ and shaders/, Rust and WGSL) holds more than 30% of
/// its lines: a folder that large mixes what should be apart.
#[test]
fn no_folder_holds_most_of_the_code() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lines = |path: &Path| -> usize {
        let mut files = Vec::new();
        let mut pending = vec![path.to_path_buf()];
        while let Some(p) = pending.pop() {
            if p.is_dir() {
                for entry in std::fs::read_dir(&p).expect("dir").flatten() {
                    pending.push(entry.path());
                }
            } else if p.extension().is_some_and(|e| e == "rs" || e == "wgsl") {
                files.push(p);
            }
        }
        files
            .iter()
            .map(|f| std::fs::read_to_string(f).map_or(0, |t| t.lines().count()))
            .sum()
    };
    let total = lines(&root.join("src")) + lines(&root.join("shaders"));
    let mut folders = Vec::new();
    for top in ["src", "shaders"] {
        for entry in std::fs::read_dir(root.join(top)).expect("dir").flatten() {
            if entry.path().is_dir() {
                folders.push((entry.path(), lines(&entry.path())));
            }
        }
    }
    folders.push((root.join("shaders"), lines(&root.join("shaders"))));
    for (folder, n) in folders {
        assert!(
            n * 10 <= total * 3,
            "{} holds {n} of {total} lines",
            folder.display()
        );
    }
}
