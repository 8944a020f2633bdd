//! Sharded renders, their merge, and checkpoint/resume, through the `hppm` binary as a cluster
//! job runs it: every shard a separate process, `hppm merge` summing their files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use hppm::image::Image;
use hppm::render::state::{StateFile, StateKind};

const SCENE: &str = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
const SIZE: &str = "48x32";
/// Merged and resumed images equal one render up to float addition order: measured on
/// lavapipe 1.7e-15 merged (the sums differ in their last bits) and 0 to 2e-18 resumed. A shard
/// missing or counted twice, a random stream that depends on the shard instead of the global
/// index, or a state buffer left out of a checkpoint is 1e-3 or more (each test checks that a
/// wrong image fails by far).
const EQUAL: f64 = 1e-9;

fn hppm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hppm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run hppm")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn ok(out: Output) -> Output {
    assert!(out.status.success(), "{}", stderr(&out));
    out
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hppm-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn text(path: &Path) -> String {
    path.to_string_lossy().into_owned()
}

fn read(path: &Path) -> Image {
    Image::read_exr(path).unwrap_or_else(|e| panic!("{e}"))
}

/// Renders `graph` at `spp` into `out` in one process.
fn single(graph: &str, spp: u64, seed: u64, out: &Path) -> Image {
    ok(hppm(&[
        "render",
        SCENE,
        "--graph",
        graph,
        "--spp",
        &spp.to_string(),
        "--size",
        SIZE,
        "--seed",
        &seed.to_string(),
        "--out",
        &text(out),
    ]));
    read(out)
}

/// Runs shards 0..n of `graph` as n processes at once; returns their files.
fn shards(dir: &Path, graph: &str, spp: u64, seed: u64, n: u64) -> Vec<PathBuf> {
    let mut children = Vec::new();
    let mut files = Vec::new();
    for k in 0..n {
        let file = dir.join(format!("shard-{k}.hppm"));
        let child = Command::new(env!("CARGO_BIN_EXE_hppm"))
            .args(["render", SCENE, "--graph", graph, "--size", SIZE])
            .args(["--spp", &spp.to_string(), "--seed", &seed.to_string()])
            .args(["--shard", &format!("{k}/{n}"), "--out", &text(&file)])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("spawn hppm");
        children.push(child);
        files.push(file);
    }
    for child in children {
        let out = child.wait_with_output().expect("wait");
        assert!(out.status.success(), "{}", stderr(&out));
    }
    files
}

fn merge(files: &[PathBuf], out: &Path, partial: bool) -> Output {
    let mut args = vec!["merge".to_string()];
    args.extend(files.iter().map(|f| text(f)));
    args.extend(["--out".to_string(), text(out)]);
    if partial {
        args.push("--partial".into());
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    hppm(&args)
}

/// 4 shards of `pt` and of the pppm hybrid, each its own process, merged, equal the single
/// render of the same 16 spp (relMSE <= 1e-9); a merge of 3 of them (--partial) does not, by
/// far, so the comparison can fail. Would catch: shards that draw other random numbers than the
/// iterations they stand for (seed per shard, a local iteration count), a pppm radius schedule
/// indexed by local iterations, accumulators averaged instead of summed, a lost or doubled
/// shard.
#[test]
fn merged_shards_equal_one_render() {
    let dir = temp_dir("shards");
    for graph in ["graphs/pt.ron", "graphs/hybrid_pppm.ron"] {
        let reference = single(graph, 16, 5, &dir.join("single.exr"));
        let files = shards(&dir, graph, 16, 5, 4);
        let merged_path = dir.join("merged.exr");
        let out = ok(merge(&files, &merged_path, false));
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("4 of 4 shards, 48x32, 16 spp"),
            "{}",
            String::from_utf8_lossy(&out.stdout)
        );
        let merged = read(&merged_path);
        let error = merged.relmse(&reference).expect("same size");
        ok(merge(&files[..3], &merged_path, true));
        let partial = read(&merged_path).relmse(&reference).expect("same size");
        eprintln!("{graph}: merged vs single relMSE {error:.3e}; 3 of 4 shards {partial:.3e}");
        assert!(
            reference.mean()[0] > 0.01,
            "{graph}: a black image proves nothing"
        );
        assert!(error <= EQUAL, "{graph}: merged vs single relMSE {error}");
        assert!(partial > 1e3 * EQUAL, "{graph}: 3 of 4 shards {partial}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Shards of different renders are refused with the field that differs (scene, graph, seed),
/// and sppm refuses to shard with the reason. Would catch a merge that sums anything of the
/// right size.
#[test]
fn merge_refuses_shards_of_other_renders_and_sppm_refuses_to_shard() {
    let dir = temp_dir("shard-mismatch");
    let render = |name: &str, graph: &str, size: &str, seed: &str, shard: &str| {
        let file = dir.join(name);
        ok(hppm(&[
            "render",
            SCENE,
            "--graph",
            graph,
            "--size",
            size,
            "--spp",
            "2",
            "--seed",
            seed,
            "--shard",
            shard,
            "--out",
            &text(&file),
        ]));
        file
    };
    let base = render("a.hppm", "graphs/pt.ron", "16x16", "1", "0/2");
    let cases = [
        (
            render("b.hppm", "graphs/pt.ron", "16x16", "2", "1/2"),
            "field seed",
        ),
        (
            render("c.hppm", "graphs/hybrid_pppm.ron", "16x16", "1", "1/2"),
            "field graph_hash",
        ),
        (
            render("d.hppm", "graphs/pt.ron", "16x8", "1", "1/2"),
            "field scene_hash",
        ),
    ];
    let out = dir.join("m.exr");
    for (other, field) in &cases {
        let result = merge(&[base.clone(), other.clone()], &out, false);
        let err = stderr(&result);
        assert!(!result.status.success());
        assert!(err.contains(field), "expected {field}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let refused = hppm(&[
        "render",
        SCENE,
        "--graph",
        "graphs/hybrid.ron",
        "--size",
        "16x16",
        "--spp",
        "2",
        "--shard",
        "0/2",
        "--out",
        &text(&dir.join("e.hppm")),
    ]);
    let err = stderr(&refused);
    assert!(!refused.status.success());
    assert!(
        err.contains("sppm") && err.contains("depend on every earlier iteration"),
        "{err}"
    );
    let timed = hppm(&[
        "render",
        SCENE,
        "--graph",
        "graphs/pt.ron",
        "--size",
        "16x16",
        "--time",
        "1",
        "--shard",
        "0/2",
        "--out",
        &text(&dir.join("f.hppm")),
    ]);
    assert!(stderr(&timed).contains("--shard needs a budget in --spp or --photons"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A render checkpointed at 8 spp and resumed to 16 equals the uninterrupted 16-spp render
/// (relMSE <= 1e-9), for `pt`, the pppm hybrid and the sppm hybrid (whose per-pixel N, R, tau
/// and radii travel in the checkpoint); the 8-spp image is far from it. Would catch state left
/// out of the checkpoint (sppm statistics or radii: the caustic restarts), a resumed render
/// that restarts its random streams or its pppm schedule, or one that runs too many iterations.
#[test]
fn resumed_renders_equal_uninterrupted_ones() {
    let dir = temp_dir("resume");
    for graph in [
        "graphs/pt.ron",
        "graphs/hybrid_pppm.ron",
        "graphs/hybrid.ron",
    ] {
        let reference = single(graph, 16, 9, &dir.join("single.exr"));
        let checkpoint = dir.join("state.hppm");
        let half = dir.join("half.exr");
        ok(hppm(&[
            "render",
            SCENE,
            "--graph",
            graph,
            "--size",
            SIZE,
            "--spp",
            "8",
            "--seed",
            "9",
            "--checkpoint",
            &text(&checkpoint),
            "--out",
            &text(&half),
        ]));
        let saved = StateFile::read(&checkpoint).expect("checkpoint");
        assert_eq!(saved.header.kind, StateKind::Checkpoint);
        assert_eq!(saved.header.samples_per_pixel, 8);
        let resumed_path = dir.join("resumed.exr");
        let out = ok(hppm(&[
            "render",
            SCENE,
            "--graph",
            graph,
            "--spp",
            "16",
            "--resume",
            &text(&checkpoint),
            "--out",
            &text(&resumed_path),
        ]));
        assert!(stderr(&out).contains("resumed"), "{}", stderr(&out));
        let error = read(&resumed_path).relmse(&reference).expect("size");
        let early = read(&half).relmse(&reference).expect("size");
        eprintln!("{graph}: resumed vs uninterrupted relMSE {error:.3e}; 8 spp {early:.3e}");
        assert!(error <= EQUAL, "{graph}: resumed vs uninterrupted {error}");
        assert!(early > 1e3 * EQUAL, "{graph}: the 8-spp image {early}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The cluster's pre-emption path: shard 1 of 2 checkpointed halfway and resumed with the same
/// command line plus `--resume` (as deploy/ does), merged with an uninterrupted shard 0, equals
/// the single render; the checkpoint of a shard refuses to resume as another shard, and a shard
/// file refuses to resume at all. Would catch a resumed shard that forgets its schedule (renders
/// iterations 0, 1, ... instead of 1, 3, ...) or writes a checkpoint instead of accumulators.
#[test]
fn a_resumed_shard_merges_like_an_uninterrupted_one() {
    let dir = temp_dir("resume-shard");
    let graph = "graphs/hybrid_pppm.ron";
    let reference = single(graph, 16, 2, &dir.join("single.exr"));
    let state = dir.join("checkpoint-1.hppm");
    let shard = |spp: &str, k: &str, extra: &[&str], out: &Path| {
        let mut args = vec![
            "render", SCENE, "--graph", graph, "--size", SIZE, "--seed", "2", "--spp", spp,
            "--shard", k,
        ];
        args.extend_from_slice(extra);
        let out_text = text(out);
        args.extend(["--out", &out_text]);
        hppm(&args)
    };
    let state_text = text(&state);
    let halfway = dir.join("halfway.hppm");
    ok(shard("8", "1/2", &["--checkpoint", &state_text], &halfway));
    let files = [dir.join("shard-0.hppm"), dir.join("shard-1.hppm")];
    ok(shard("16", "0/2", &[], &files[0]));
    let other = shard("16", "0/2", &["--resume", &state_text], &dir.join("x.hppm"));
    assert!(!other.status.success());
    assert!(stderr(&other).contains("field shard"), "{}", stderr(&other));
    let wrong_kind = shard(
        "16",
        "1/2",
        &["--resume", &text(&halfway)],
        &dir.join("y.hppm"),
    );
    assert!(stderr(&wrong_kind).contains("is a shard, not a checkpoint"));
    ok(shard(
        "16",
        "1/2",
        &["--checkpoint", &state_text, "--resume", &state_text],
        &files[1],
    ));
    let merged = dir.join("merged.exr");
    ok(merge(&files, &merged, false));
    let error = read(&merged).relmse(&reference).expect("size");
    eprintln!("resumed shard 1/2 merged with shard 0/2 vs single render: relMSE {error:.3e}");
    assert!(error <= EQUAL, "{error}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A damaged shard (cut short, as by a full disk) or a file that is not one is refused by
/// `merge` and `--resume` with its name, without a panic.
#[test]
fn damaged_state_files_are_refused_by_name() {
    let dir = temp_dir("damaged");
    let good = dir.join("shard-0.hppm");
    ok(hppm(&[
        "render",
        SCENE,
        "--graph",
        "graphs/pt.ron",
        "--size",
        "16x16",
        "--spp",
        "2",
        "--shard",
        "0/1",
        "--out",
        &text(&good),
    ]));
    let bytes = std::fs::read(&good).expect("shard");
    let cut = dir.join("cut.hppm");
    std::fs::write(&cut, &bytes[..bytes.len() - 7]).expect("write");
    let image = dir.join("not-a-shard.exr");
    ok(hppm(&[
        "render",
        SCENE,
        "--graph",
        "graphs/pt.ron",
        "--size",
        "16x16",
        "--spp",
        "1",
        "--out",
        &text(&image),
    ]));
    for (file, expected) in [(&cut, "truncated"), (&image, "no HPPMST01 magic")] {
        for args in [
            vec!["merge", &text(file), "--out", &text(&dir.join("m.exr"))],
            vec![
                "render",
                SCENE,
                "--graph",
                "graphs/pt.ron",
                "--resume",
                &text(file),
                "--out",
                &text(&dir.join("r.exr")),
            ],
        ] {
            let args: Vec<&str> = args.iter().map(|a| a.as_ref()).collect();
            let out = hppm(&args);
            let err = stderr(&out);
            assert!(!out.status.success(), "{args:?}");
            assert!(err.contains(&text(file)) && err.contains(expected), "{err}");
            assert!(!err.contains("panicked"), "{err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Ctrl-C writes a checkpoint (besides the image), and resuming it to a budget gives the image
/// of one render to that budget. Would catch a checkpoint not written on interrupt, or one
/// written before the last iteration finished.
#[cfg(unix)]
#[test]
fn interrupt_writes_a_checkpoint_that_resumes() {
    let dir = temp_dir("interrupt-checkpoint");
    let checkpoint = dir.join("state.hppm");
    let graph = "graphs/hybrid_pppm.ron";
    let mut child = Command::new(env!("CARGO_BIN_EXE_hppm"))
        .args([
            "render", SCENE, "--graph", graph, "--size", SIZE, "--seed", "4",
        ])
        .args([
            "--time",
            "120",
            "--checkpoint-every",
            "0.05",
            "--checkpoint",
        ])
        .arg(&checkpoint)
        .arg("--out")
        .arg(dir.join("partial.exr"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn hppm");
    let mut err = String::new();
    let mut reader = std::io::BufReader::new(child.stderr.take().expect("stderr"));
    loop {
        let mut line = String::new();
        let read = std::io::BufRead::read_line(&mut reader, &mut line).expect("read stderr");
        assert!(read > 0, "hppm ended before rendering: {err}");
        err.push_str(&line);
        if line.starts_with("rendering ") {
            break;
        }
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    assert!(killed.is_ok_and(|s| s.success()));
    std::io::Read::read_to_string(&mut reader, &mut err).expect("read stderr");
    let out = child.wait_with_output().expect("wait");
    assert!(out.status.success(), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    let saved = StateFile::read(&checkpoint).expect("checkpoint written");
    let done = saved.header.samples_per_pixel;
    let target = done + 4;
    let resumed_path = dir.join("resumed.exr");
    ok(hppm(&[
        "render",
        SCENE,
        "--graph",
        graph,
        "--spp",
        &target.to_string(),
        "--resume",
        &text(&checkpoint),
        "--out",
        &text(&resumed_path),
    ]));
    let reference = single(graph, target, 4, &dir.join("single.exr"));
    let error = read(&resumed_path).relmse(&reference).expect("size");
    eprintln!("interrupted at {done} spp, resumed to {target}: relMSE {error:.3e}");
    assert!(error <= EQUAL, "resumed vs uninterrupted {error}");
    let _ = std::fs::remove_dir_all(&dir);
}
