//! deploy/slurm/ run on real Slurm daemons: the one-node cluster of `.ci/slurm-cluster`
//! (slurmctld and slurmd on localhost, so the system temp dir is the shared file system). The
//! test submits `deploy/slurm/submit.sh` itself: a 4-task array of `hppm render --shard k/4`
//! with checkpoints, then `hppm merge` behind an `afterok` dependency. While task 1 renders, it
//! is requeued (`scontrol requeue`: Slurm kills it and queues it again, as a pre-emption does)
//! and must resume from its checkpoint. The merged frame must equal one render of the same
//! samples (relMSE <= 1e-9), and the requeued task's log must say from which iteration it
//! resumed, a point strictly inside its shard.
//!
//! Would catch: a shard lost or counted twice (a merge that sums what it finds); a requeued task
//! that restarts from zero (no "resumed" line, or it resumes from a checkpoint that another task
//! wrote) or double-counts the iterations it had checkpointed (the merge refuses its spp, or the
//! image differs); a merge that runs before the array ends (a missing shard); a log truncated by
//! the requeue (the first run's lines gone); options in the scripts that a real Slurm refuses.
//!
//! Skips with a message where `sbatch` is missing or its cluster is not this machine alone,
//! unless HPPM_REQUIRE_SLURM=1, which makes that a failure (CI sets it, so the test can never
//! pass there by testing nothing).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use hppm::image::Image;

const SCENE: &str = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
const GRAPH: &str = "graphs/hybrid_pppm.ron";
const SIZE: &str = "64x64";
/// 500 iterations a task: about 13 s with two tasks sharing 2 cores of lavapipe, long enough
/// to requeue one after its first checkpoint and before its end.
const SPP: u64 = 2000;
const SHARDS: u64 = 4;
/// Seconds between checkpoints (render.sbatch's CHECKPOINT_EVERY).
const CHECKPOINT_EVERY: &str = "0.5";
/// The array task requeued mid-render.
const REQUEUED: u64 = 1;
/// As in tests/shards.rs: equal up to the order of float additions.
const EQUAL: f64 = 1e-9;
const TIMEOUT: Duration = Duration::from_secs(300);

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// Runs `program` with `args`: its stdout, or why it failed with what it printed.
fn try_run(program: &str, args: &[&str]) -> Result<String, String> {
    let out = Command::new(program)
        .args(args)
        .output()
        .map_err(|e| format!("{program}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{program} {}: {}{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Why this machine cannot run the test, if it cannot: the shards are written to the local
/// temp dir, so the cluster must be this machine alone.
fn unusable_cluster() -> Option<String> {
    if let Err(e) = try_run("sbatch", &["--version"]) {
        return Some(format!("no sbatch ({e})"));
    }
    match try_run("sinfo", &["--noheader", "--Node", "--format=%N"]) {
        Err(e) => Some(format!("no Slurm controller answers ({e})")),
        Ok(nodes) if nodes.split_whitespace().collect::<Vec<_>>() != ["localhost"] => Some(
            format!("the cluster's nodes are {nodes:?}, not localhost alone"),
        ),
        Ok(_) => None,
    }
}

/// Every array task's and the merge's (id, state, reason), one line each.
fn job_states(array: &str, merge: &str) -> Vec<(String, String, String)> {
    let jobs = format!("{array},{merge}");
    let out = try_run(
        "squeue",
        &[
            "--noheader",
            "--states=all",
            "--array",
            "--jobs",
            &jobs,
            "--format=%i|%T|%r",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    out.lines()
        .filter_map(|line| {
            let mut fields = line.trim().split('|').map(str::to_string);
            Some((fields.next()?, fields.next()?, fields.next()?))
        })
        .collect()
}

fn state_of<'a>(states: &'a [(String, String, String)], id: &str) -> Option<&'a str> {
    states
        .iter()
        .find(|(job, _, _)| job == id)
        .map(|(_, state, _)| state.as_str())
}

/// States from which a job does not move on by itself.
fn finished(state: &str) -> bool {
    !matches!(
        state,
        "PENDING" | "RUNNING" | "REQUEUED" | "COMPLETING" | "CONFIGURING" | "SUSPENDED"
    )
}

/// The jobs' logs, for failure messages.
fn logs(dir: &Path) -> String {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("temp dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "log"))
        .collect();
    names.sort();
    names
        .iter()
        .map(|p| {
            let text = std::fs::read_to_string(p).unwrap_or_default();
            format!("==> {} <==\n{text}", p.display())
        })
        .collect()
}

/// Cancels the jobs when the test ends early, so that a failure leaves no render running.
struct Jobs(String, String);

impl Drop for Jobs {
    fn drop(&mut self) {
        if std::thread::panicking() {
            let _ = Command::new("scancel").args([&self.0, &self.1]).output();
        }
    }
}

/// "resumed PATH: N iterations done (M spp)" in `log`: (N, M).
fn resumed_from(log: &str) -> Option<(u64, u64)> {
    let line = log.lines().find(|l| l.starts_with("resumed "))?;
    let (_, rest) = line.rsplit_once(": ")?;
    let mut words = rest.split_whitespace();
    let iterations = words.next()?.parse().ok()?;
    let spp = words.nth(2)?.trim_start_matches('(').parse().ok()?;
    Some((iterations, spp))
}

fn read(path: &Path) -> Image {
    Image::read_exr(path).unwrap_or_else(|e| panic!("{e}"))
}

/// See the module's comment.
#[test]
fn slurm_array_with_a_requeued_task_merges_to_one_render() {
    if let Some(why) = unusable_cluster() {
        if std::env::var("HPPM_REQUIRE_SLURM").as_deref() == Ok("1") {
            panic!("HPPM_REQUIRE_SLURM=1, but {why}: .ci/slurm-cluster starts a one-node cluster");
        }
        eprintln!(
            "skipped: {why} (.ci/slurm-cluster starts a one-node cluster; HPPM_REQUIRE_SLURM=1 \
             makes this a failure)"
        );
        return;
    }
    let started = Instant::now();
    let dir = std::env::temp_dir().join(format!("hppm-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let shards = dir.join("shards");
    let frame = dir.join("frame.exr");

    // The node has no GPU and may have fewer than the 4 CPUs a task asks for: submit.sh passes
    // these on to sbatch, where they beat the scripts' #SBATCH lines.
    let out = Command::new(repo("deploy/slurm/submit.sh"))
        .args(["--gres=none", "--cpus-per-task=1"])
        .current_dir(&dir)
        .env("HPPM", env!("CARGO_BIN_EXE_hppm"))
        .env("SCENE", repo(SCENE))
        .env("GRAPH", repo(GRAPH))
        .env("OUT", &shards)
        .env("FRAME", &frame)
        .env("SPP", SPP.to_string())
        .env("CHECKPOINT_EVERY", CHECKPOINT_EVERY)
        .env("SIZE", SIZE)
        .output()
        .expect("run submit.sh");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "submit.sh: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let words: Vec<&str> = stdout.split_whitespace().collect();
    let (array, merge) = match words[..] {
        ["array", array, "merge", merge] => (array.to_string(), merge.to_string()),
        _ => panic!("submit.sh printed {stdout:?}, not \"array ID merge ID\""),
    };
    let _jobs = Jobs(array.clone(), merge.clone());
    let task = format!("{array}_{REQUEUED}");
    let checkpoint = shards.join(format!("checkpoint-{REQUEUED}.hppm"));
    eprintln!("array {array}, merge {merge} in {}", dir.display());

    // Requeue the task once it has checkpointed, while it still renders.
    let deadline = Instant::now() + TIMEOUT;
    loop {
        let states = job_states(&array, &merge);
        let state = state_of(&states, &task);
        if state == Some("RUNNING") && checkpoint.exists() {
            break;
        }
        assert!(
            !state.is_some_and(finished),
            "task {task} ended ({state:?}) before it could be requeued: raise SPP\n{}",
            logs(&dir)
        );
        assert!(
            Instant::now() < deadline,
            "task {task} never checkpointed while running: {states:?}\n{}",
            logs(&dir)
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    try_run("scontrol", &["requeue", &task]).unwrap_or_else(|e| panic!("{e}"));
    eprintln!(
        "requeued {task} at {:.1} s",
        started.elapsed().as_secs_f64()
    );

    // Slurm 22.05 holds a requeued job for two minutes (Reason=BeginTime); let it start at once.
    let states = loop {
        let states = job_states(&array, &merge);
        let requeued = states.iter().find(|(job, _, _)| *job == task);
        if let Some((_, state, reason)) = requeued
            && state == "PENDING"
            && reason == "BeginTime"
        {
            let _ = try_run(
                "scontrol",
                &["update", &format!("JobId={task}"), "StartTime=now"],
            );
        }
        if state_of(&states, &merge).is_some_and(finished) {
            break states;
        }
        let never = states
            .iter()
            .any(|(_, _, reason)| reason == "DependencyNeverSatisfied");
        assert!(
            !never,
            "an array task failed, the merge will never run: {states:?}\n{}",
            logs(&dir)
        );
        assert!(
            Instant::now() < deadline,
            "the jobs did not end in {TIMEOUT:?}: {states:?}\n{}",
            logs(&dir)
        );
        std::thread::sleep(Duration::from_millis(500));
    };
    let array_seconds = started.elapsed().as_secs_f64();
    let all_logs = logs(&dir);
    for k in 0..SHARDS {
        let id = format!("{array}_{k}");
        assert_eq!(
            state_of(&states, &id),
            Some("COMPLETED"),
            "{id}: {states:?}\n{all_logs}"
        );
    }
    assert_eq!(
        state_of(&states, &merge),
        Some("COMPLETED"),
        "merge: {states:?}\n{all_logs}"
    );
    let shown = try_run("scontrol", &["show", "job", &task]).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        shown.contains("Restarts=1"),
        "{task} was not restarted once: {shown}"
    );

    // The requeued task's log holds both runs; only it resumed, from inside its shard.
    let per_shard = SPP / SHARDS;
    let mut resumed = None;
    for k in 0..SHARDS {
        let path = dir.join(format!("hppm-render-{array}_{k}.log"));
        let log = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e}\n{all_logs}", path.display()));
        let runs = log.matches(&format!("rendering {SIZE} through")).count();
        if k == REQUEUED {
            let cut = log
                .find("DUE TO JOB REQUEUE")
                .unwrap_or_else(|| panic!("no requeue in {}:\n{log}", path.display()));
            let (iterations, spp) = resumed_from(&log[cut..])
                .unwrap_or_else(|| panic!("no \"resumed\" after the requeue:\n{log}"));
            assert_eq!(runs, 2, "two runs in {}:\n{log}", path.display());
            assert!(
                0 < iterations && iterations < per_shard,
                "task {k} resumed from iteration {iterations} of {per_shard}: not mid-render\n{log}"
            );
            resumed = Some((iterations, spp));
        } else {
            assert_eq!(runs, 1, "one run in {}:\n{log}", path.display());
            assert!(
                resumed_from(&log).is_none(),
                "task {k} was not requeued, yet resumed:\n{log}"
            );
        }
    }
    let (iterations, spp) = resumed.expect("the requeued task's log");
    eprintln!(
        "task {REQUEUED} resumed from its checkpoint at {iterations} of {per_shard} iterations \
         ({spp} spp)"
    );
    let merge_log =
        std::fs::read_to_string(dir.join(format!("hppm-merge-{merge}.log"))).expect("merge log");
    assert!(
        merge_log.contains(&format!("4 of 4 shards, {SIZE}, {SPP} spp")),
        "{merge_log}"
    );

    // One render of the same samples, and the frame without the requeued shard for contrast.
    let single = dir.join("single.exr");
    try_run(
        env!("CARGO_BIN_EXE_hppm"),
        &[
            "render",
            &repo(SCENE).to_string_lossy(),
            "--graph",
            &repo(GRAPH).to_string_lossy(),
            "--spp",
            &SPP.to_string(),
            "--seed",
            "1",
            "--size",
            SIZE,
            "--out",
            &single.to_string_lossy(),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let reference = read(&single);
    let error = read(&frame).relmse(&reference).expect("same size");
    let partial_path = dir.join("partial.exr");
    let mut args = vec!["merge".to_string(), "--partial".to_string()];
    args.extend((0..SHARDS).filter(|&k| k != REQUEUED).map(|k| {
        shards
            .join(format!("shard-{k}.hppm"))
            .to_string_lossy()
            .into_owned()
    }));
    args.extend([
        "--out".to_string(),
        partial_path.to_string_lossy().into_owned(),
    ]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    try_run(env!("CARGO_BIN_EXE_hppm"), &args).unwrap_or_else(|e| panic!("{e}"));
    let partial = read(&partial_path).relmse(&reference).expect("same size");
    eprintln!(
        "merged vs single relMSE {error:.3e}; without shard {REQUEUED} {partial:.3e}; jobs \
         {array_seconds:.1} s, test {:.1} s",
        started.elapsed().as_secs_f64()
    );
    assert!(reference.mean()[0] > 0.01, "a black image proves nothing");
    assert!(error <= EQUAL, "merged vs single relMSE {error}");
    assert!(partial > 1e3 * EQUAL, "3 of 4 shards: relMSE {partial}");
    let _ = std::fs::remove_dir_all(&dir);
}
