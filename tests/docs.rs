//! The guides to writing a pass and a BSDF quote their example crates: every Rust and WGSL block
//! of docs/writing-a-pass.md and docs/writing-a-bsdf.md is, line for line, part of a file of
//! examples/custom_pass or examples/custom_bsdf. An example changed without its guide, or a
//! guide showing code the example does not have, fails here.

use std::path::{Path, PathBuf};

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// The fenced blocks of `markdown` tagged `rust` or `wgsl`, with their first line number.
fn code_blocks(markdown: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, Vec<&str>)> = None;
    for (n, line) in markdown.lines().enumerate() {
        match (&mut current, line.trim_start()) {
            (None, fence) if fence == "```rust" || fence == "```wgsl" => {
                current = Some((n + 2, Vec::new()));
            }
            (Some(_), "```") => {
                if let Some((at, lines)) = current.take() {
                    blocks.push((at, lines.join("\n")));
                }
            }
            (Some((_, lines)), _) => lines.push(line),
            _ => {}
        }
    }
    blocks
}

/// Every source file of an example crate, as text.
fn sources(example: &str) -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    let mut pending = vec![repo(example)];
    while let Some(path) = pending.pop() {
        if path.is_dir() {
            for entry in std::fs::read_dir(&path).expect("dir").flatten() {
                pending.push(entry.path());
            }
        } else if path.extension().is_some_and(|e| e == "rs" || e == "wgsl") {
            out.push((
                path.clone(),
                std::fs::read_to_string(&path).expect("source"),
            ));
        }
    }
    out
}

fn check(guide: &str, example: &str) {
    let text = std::fs::read_to_string(repo(guide)).expect("guide");
    let files = sources(example);
    let blocks = code_blocks(&text);
    assert!(!blocks.is_empty(), "{guide} has no code");
    let mut missing = Vec::new();
    for (line, block) in blocks {
        if !files.iter().any(|(_, source)| source.contains(&block)) {
            missing.push(format!("{guide}:{line}:\n{block}"));
        }
    }
    assert!(
        missing.is_empty(),
        "blocks that are not in {example}:\n{}",
        missing.join("\n---\n")
    );
}

#[test]
fn writing_a_bsdf_quotes_examples_custom_bsdf() {
    check("docs/writing-a-bsdf.md", "examples/custom_bsdf");
}

#[test]
fn writing_a_pass_quotes_examples_custom_pass() {
    check("docs/writing-a-pass.md", "examples/custom_pass");
}
