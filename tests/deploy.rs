//! The cluster jobs in deploy/, checked without a cluster: the Kubernetes manifests parse as
//! YAML and say what a sharded render needs (an Indexed Job whose completions, parallelism and
//! `--shard k/N` agree, the shard index from JOB_COMPLETION_INDEX, one shared volume for shards
//! and merge); the Slurm scripts pass `bash -n` and their array agrees with `--shard`; the merge
//! waits for the render; the container installs lavapipe. tests/slurm.rs runs the Slurm scripts
//! on a one-node cluster. Would catch a manifest that stopped
//! parsing, a shard count changed in one place only (a frame merged from the wrong shards, or a
//! merge refused for a missing one), and shards written where the merge does not look.

mod common;

use common::repo_path;
use serde_norway::Value;

fn yaml(relative: &str) -> Value {
    let text = std::fs::read_to_string(repo_path(relative)).expect(relative);
    serde_norway::from_str(&text).unwrap_or_else(|e| panic!("{relative}: {e}"))
}

fn at<'a>(value: &'a Value, path: &[&str]) -> &'a Value {
    path.iter().fold(value, |v, key| {
        v.get(*key)
            .unwrap_or_else(|| panic!("no field {key} on the way to {}", path.join(".")))
    })
}

fn text(value: &Value) -> String {
    match value {
        Value::String(s) => s.clone(),
        Value::Sequence(items) => items.iter().map(text).collect::<Vec<_>>().join(" "),
        other => panic!("expected text, got {other:?}"),
    }
}

/// The N of the first `--shard .../N` in a command line.
fn shard_count(command: &str) -> u64 {
    let at = command.find("--shard").expect("--shard in the command");
    let rest = &command[at..];
    let slash = rest.find('/').expect("K/N");
    let digits: String = rest[slash + 1..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().expect("N of --shard")
}

/// The one container of a Job, and the shared volume's claim name with its mount path.
fn container(job: &Value) -> (&Value, String, String) {
    let pod = at(job, &["spec", "template", "spec"]);
    let containers = at(pod, &["containers"]).as_sequence().expect("containers");
    assert_eq!(containers.len(), 1);
    let volume = &at(pod, &["volumes"]).as_sequence().expect("volumes")[0];
    let claim = text(at(volume, &["persistentVolumeClaim", "claimName"]));
    let mount = &at(&containers[0], &["volumeMounts"])
        .as_sequence()
        .expect("mounts")[0];
    assert_eq!(text(at(mount, &["name"])), text(at(volume, &["name"])));
    (&containers[0], claim, text(at(mount, &["mountPath"])))
}

#[test]
fn kubernetes_jobs_shard_and_merge_one_frame() {
    let render = yaml("deploy/kubernetes/render-job.yaml");
    let merge = yaml("deploy/kubernetes/merge-job.yaml");
    let volume = yaml("deploy/kubernetes/volume.yaml");
    for job in [&render, &merge] {
        assert_eq!(text(at(job, &["apiVersion"])), "batch/v1");
        assert_eq!(text(at(job, &["kind"])), "Job");
        assert_eq!(
            text(at(job, &["spec", "template", "spec", "restartPolicy"])),
            "Never"
        );
    }
    assert_eq!(text(at(&render, &["spec", "completionMode"])), "Indexed");
    let completions = at(&render, &["spec", "completions"]).as_u64().expect("n");
    let parallelism = at(&render, &["spec", "parallelism"]).as_u64().expect("n");
    let (shard, claim, mount) = container(&render);
    let command = format!(
        "{} {}",
        text(at(shard, &["command"])),
        text(at(shard, &["args"]))
    );
    assert!(command.contains("hppm render"), "{command}");
    assert!(command.contains("${JOB_COMPLETION_INDEX}"), "{command}");
    assert!(
        command.contains("--checkpoint") && command.contains("--resume"),
        "{command}"
    );
    assert_eq!(
        shard_count(&command),
        completions,
        "--shard N vs completions"
    );
    assert_eq!(parallelism, completions);
    let (merger, merge_claim, merge_mount) = container(&merge);
    let merge_command = format!(
        "{} {}",
        text(at(merger, &["command"])),
        text(at(merger, &["args"]))
    );
    assert!(merge_command.contains("hppm merge"), "{merge_command}");
    assert_eq!(merge_claim, claim, "shards and merge share one volume");
    assert_eq!(merge_mount, mount);
    assert!(
        command.contains(&format!("{mount}/shards/shard-")),
        "{command}"
    );
    assert!(
        merge_command.contains(&format!("{mount}/shards/shard-*.hppm")),
        "{merge_command}"
    );
    assert_eq!(text(at(&volume, &["kind"])), "PersistentVolumeClaim");
    assert_eq!(text(at(&volume, &["metadata", "name"])), claim);
    assert_eq!(
        text(&at(&volume, &["spec", "accessModes"])[0]),
        "ReadWriteMany"
    );
}

#[test]
fn slurm_array_shards_and_a_dependent_merge() {
    let scripts = [
        "deploy/slurm/render.sbatch",
        "deploy/slurm/merge.sbatch",
        "deploy/slurm/submit.sh",
    ];
    for script in scripts {
        let status = std::process::Command::new("bash")
            .arg("-n")
            .arg(repo_path(script))
            .status()
            .expect("bash");
        assert!(status.success(), "{script}: bash -n");
    }
    let render = std::fs::read_to_string(repo_path(scripts[0])).expect("render.sbatch");
    let array = render
        .lines()
        .find_map(|l| l.strip_prefix("#SBATCH --array="))
        .expect("#SBATCH --array");
    let (first, last) = array.split_once('-').expect("--array=0-M");
    assert_eq!(first, "0");
    let tasks: u64 = last.parse::<u64>().expect("M") + 1;
    assert_eq!(shard_count(&render), tasks, "--shard N vs the array");
    assert!(render.contains("SLURM_ARRAY_TASK_ID"));
    assert!(render.contains("#SBATCH --requeue") && render.contains("--resume"));
    let merge = std::fs::read_to_string(repo_path(scripts[1])).expect("merge.sbatch");
    assert!(merge.contains("merge \"$OUT\"/shard-*.hppm"), "{merge}");
    assert!(render.contains("--out \"$OUT/shard-$k.hppm\""), "{render}");
    // A requeued task appends to its log (truncated, it would lose the run it resumes), and
    // the test cluster's overrides reach the render (tests/slurm.rs runs these on real daemons).
    assert!(render.contains("#SBATCH --open-mode=append"), "{render}");
    for knob in ["--spp \"$SPP\"", "--checkpoint-every \"$CHECKPOINT_EVERY\""] {
        assert!(render.contains(knob), "{knob} in {render}");
    }
    let submit = std::fs::read_to_string(repo_path(scripts[2])).expect("submit.sh");
    assert!(submit.contains("--dependency=afterok:"), "{submit}");
    assert!(
        submit.contains("sbatch --parsable \"$@\" \"$here/render.sbatch\""),
        "{submit}"
    );
}

#[test]
fn container_builds_hppm_with_lavapipe() {
    let file = std::fs::read_to_string(repo_path("deploy/Containerfile")).expect("Containerfile");
    assert!(file.contains("cargo build --release --locked --bin hppm"));
    assert!(file.contains("mesa-vulkan-drivers") && file.contains("libvulkan1"));
    assert!(file.contains("ENTRYPOINT [\"hppm\"]"));
    // Everything the build copies exists in the repository.
    for line in file
        .lines()
        .filter(|l| l.starts_with("COPY ") && !l.contains("--from"))
    {
        let words: Vec<&str> = line.split_whitespace().skip(1).collect();
        for source in &words[..words.len() - 1] {
            assert!(repo_path(source).exists(), "Containerfile copies {source}");
        }
    }
}
