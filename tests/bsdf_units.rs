//! The BSDF registry is the one source of what each BSDF unit declares: kind numbers, their WGSL
//! constants, the material dispatch, shader defs and plugin rows are generated from it, and
//! nothing written by hand repeats them. Each check below names what it would catch.

use std::path::{Path, PathBuf};

use hppm::bsdfs::BsdfRegistry;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir` with extension `ext`.
fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(path) = pending.pop() {
        if path.is_dir() {
            for entry in std::fs::read_dir(&path).expect("dir").flatten() {
                pending.push(entry.path());
            }
        } else if path.extension().is_some_and(|e| e == ext) {
            out.push(path);
        }
    }
    out
}

/// The WGSL files written by hand: shaders/ and those beside their Rust under src/.
fn wgsl_files() -> Vec<(PathBuf, String)> {
    let mut all = files(&repo().join("shaders"), "wgsl");
    all.extend(files(&repo().join("src"), "wgsl"));
    all.into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("wgsl");
            (p, text)
        })
        .collect()
}

/// No hand-written WGSL or Rust declares a material kind's number: a `const MATERIAL_X` in a
/// WGSL file or a Rust constant of the same name would be a second place for the registry's
/// numbering, free to drift from it.
#[test]
fn kind_numbers_are_declared_only_by_the_registry() {
    let registry = BsdfRegistry::builtin();
    let mut found = Vec::new();
    for (path, text) in wgsl_files() {
        for (n, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("const MATERIAL_") {
                found.push(format!("{}:{}: {line}", path.display(), n + 1));
            }
        }
    }
    for path in files(&repo().join("src"), "rs") {
        let text = std::fs::read_to_string(&path).expect("rs");
        for (n, line) in text.lines().enumerate() {
            if line.contains("const MATERIAL_") {
                found.push(format!("{}:{}: {line}", path.display(), n + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "kind numbers written by hand:\n{}",
        found.join("\n")
    );
    // The generated constants are the registry's order, each kind once.
    let generated = registry.kinds_wgsl();
    for (i, (_, kind)) in registry.kinds().enumerate() {
        let line = format!("const {}: u32 = {i}u;", kind.constant());
        assert_eq!(
            generated.matches(&line).count(),
            1,
            "{line} in\n{generated}"
        );
    }
}

/// A kind the generated dispatch calls is named by no hand-written WGSL but its own unit's: a
/// `m.kind == MATERIAL_X` branch elsewhere would be a second dispatch entry for it. (The kinds the
/// passes handle themselves, which make the partition's diffuse and specular vertices, are named
/// by the passes, and have no dispatch entry.)
#[test]
fn dispatched_kinds_are_named_only_by_the_generated_dispatch() {
    let registry = BsdfRegistry::builtin();
    let wgsl = wgsl_files();
    let mut found = Vec::new();
    for (unit, kind) in registry.kinds() {
        if kind.eval.is_none() && kind.sample.is_none() {
            continue;
        }
        let own = unit.wgsl.map(|f| repo().join(f.path));
        for (path, text) in &wgsl {
            if Some(path) != own.as_ref() && text.contains(&kind.constant()) {
                found.push(format!("{} names {}", path.display(), kind.constant()));
            }
        }
        // Each of its calls has a branch that tests its kind and returns the call.
        let dispatch = registry.dispatch_wgsl();
        let lines: Vec<&str> = dispatch.lines().collect();
        for call in [kind.eval, kind.sample].into_iter().flatten() {
            let test = format!("m.kind == {}", kind.constant());
            let branch = lines.windows(2).any(|w| {
                let condition = w[0].trim().trim_start_matches("if ").trim_end_matches(" {");
                w[0].trim_start().starts_with("if ")
                    && condition.split(" || ").any(|t| t == test)
                    && w[1]
                        .trim_start()
                        .starts_with(&format!("return {}(", call.function))
            });
            assert!(
                branch,
                "no branch of {test} to {} in\n{dispatch}",
                call.function
            );
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// Each BSDF shader def is declared by units only: none is also in the list of the scene's
/// other defs (which would compile a unit's WGSL in or out by a second rule), and every def a
/// unit declares is one its WGSL, or the dispatch for its kinds, is compiled under.
#[test]
fn bsdf_defs_are_declared_by_their_units_only() {
    let registry = BsdfRegistry::builtin();
    for def in registry.all_defs() {
        assert!(
            !hppm::passes::SCENE_DEFS.contains(&def),
            "{def} is both a unit's def and a scene def"
        );
    }
    let dispatch = registry.dispatch_wgsl();
    for unit in registry.units() {
        let Some(def) = unit.def else { continue };
        let used = dispatch.contains(&format!("#ifdef {def}"))
            || wgsl_files()
                .iter()
                .any(|(_, text)| text.contains(&format!("#ifdef {def}")));
        assert!(used, "{}'s def {def} compiles nothing in", unit.name);
    }
}

/// Every kind a unit adds is numbered once, and its model names it: a scene's BSDF whose kind
/// the registry does not number could not be packed.
#[test]
fn every_kind_is_numbered_once() {
    let registry = BsdfRegistry::builtin();
    let names: Vec<&str> = registry.kinds().map(|(_, k)| k.name).collect();
    for (i, name) in names.iter().enumerate() {
        assert_eq!(registry.number_of(name), Some(i as u32), "{name}");
        assert_eq!(
            names.iter().filter(|n| *n == name).count(),
            1,
            "{name} twice"
        );
    }
}
