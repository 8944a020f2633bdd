//! The guides to writing a pass and a BSDF quote their example crates: every Rust and WGSL block
//! of docs/writing-a-pass.md and docs/writing-a-bsdf.md is, line for line, part of a file of
//! examples/custom_pass or examples/custom_bsdf. An example changed without its guide, or a
//! guide showing code the example does not have, fails here. And the figures README.md and the
//! guides quote are BENCHMARKS.md's table of cited figures.

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

/// The rows of BENCHMARKS.md's "Figures cited in README.md and docs": (figure, value, files).
fn cited_figures() -> Vec<(String, String, Vec<String>)> {
    let text = std::fs::read_to_string(repo("BENCHMARKS.md")).expect("BENCHMARKS.md");
    let start = text
        .find("## Figures cited in README.md and docs")
        .expect("BENCHMARKS.md has its table of cited figures");
    text[start..]
        .lines()
        .skip_while(|l| !l.starts_with("| figure |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|row| {
            let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
            let files = cells[3].split(',').map(|f| f.trim().to_string()).collect();
            (cells[0].to_string(), cells[1].to_string(), files)
        })
        .collect()
}

/// The error figures of `text`: numbers written as 4.9e-4 or 0.00134 (relMSE as README.md
/// writes it).
fn error_figures(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for word in text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-')) {
        let word = word.trim_end_matches('.');
        let scientific = word.contains("e-")
            && word.split_once("e-").is_some_and(|(m, e)| {
                m.parse::<f64>().is_ok() && m.contains('.') && e.parse::<u32>().is_ok()
            });
        let small = word.starts_with("0.00") && word.parse::<f64>().is_ok();
        if scientific || small {
            found.push(word.to_string());
        }
    }
    found
}

/// Every figure of BENCHMARKS.md's cited table stands in each file it names, and every error
/// figure of README.md is one of the table's. Catches a figure remeasured in one place and not
/// the other: README.md quoting a relMSE the table (and the run behind it) no longer has.
#[test]
fn cited_figures_agree_with_benchmarks() {
    let rows = cited_figures();
    assert!(rows.len() >= 6, "{rows:?}");
    for (figure, value, files) in &rows {
        for file in files {
            let text =
                std::fs::read_to_string(repo(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert!(
                error_figures(&text).contains(value),
                "{file} does not quote {value} ({figure}) as BENCHMARKS.md's cited figures have it"
            );
        }
    }
    let readme = std::fs::read_to_string(repo("README.md")).expect("README.md");
    for figure in error_figures(&readme) {
        assert!(
            rows.iter().any(|(_, value, _)| *value == figure),
            "README.md quotes {figure}, which BENCHMARKS.md's cited figures do not have"
        );
    }
}
