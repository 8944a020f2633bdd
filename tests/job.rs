//! A render job run as a library call (`hppm::app::job::run`), what `hppm render` runs: it
//! renders and writes its image, reports through the watcher it is given, and names its own
//! fields, not command-line flags, when it refuses one.

mod common;

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use hppm::app::job::{JobWatcher, RenderJob};
use hppm::passes::Registry;
use hppm::render::{Budget, Renderer};

#[derive(Default)]
struct Recorder {
    notes: Vec<String>,
    written: Vec<String>,
    iterations: u32,
    started: Option<Budget>,
}

impl JobWatcher for Recorder {
    fn note(&mut self, line: &str) {
        self.notes.push(line.to_string());
    }
    fn written(&mut self, line: &str) {
        self.written.push(line.to_string());
    }
    fn cancel_flag(&mut self) -> Arc<AtomicBool> {
        Arc::new(AtomicBool::new(false))
    }
    fn start(&mut self, budget: Budget) {
        self.started = Some(budget);
    }
    fn progress(&mut self, _: &Renderer, _: f64) {
        self.iterations += 1;
    }
}

fn job(out: std::path::PathBuf) -> RenderJob {
    RenderJob {
        scene: common::repo_path("scenes/cornell_box.ron"),
        defines: Vec::new(),
        graph: common::repo_path("graphs/hybrid.ron"),
        out,
        size: Some((16, 12)),
        seed: None,
        shard: None,
        spp: Some(3),
        seconds: None,
        photons: None,
        target_error: None,
        adaptive: false,
        checkpoint: None,
        checkpoint_every: 300.0,
        resume: None,
        aovs: true,
        profile: false,
        adapter: std::env::var("HPPM_TEST_ADAPTER").ok(),
    }
}

/// The job renders 3 iterations of the hybrid, writes the PNG and its AOVs, and tells its
/// watcher what it did (the scene loaded, the stop, the files) and each iteration.
#[test]
fn a_job_renders_writes_and_reports_to_its_watcher() {
    let dir = std::env::temp_dir().join(format!("hppm_job_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let out = dir.join("box.png");
    let mut watch = Recorder::default();
    hppm::app::job::run(&job(out.clone()), &Registry::builtin(), &mut watch)
        .unwrap_or_else(|e| panic!("{e}"));
    let png = std::fs::read(&out).expect("the image");
    assert!(png.starts_with(b"\x89PNG"));
    assert_eq!(watch.iterations, 3);
    assert_eq!(watch.started.and_then(|b| b.spp), Some(3));
    assert!(
        watch.notes.iter().any(|n| n.starts_with("scene: ")),
        "{:?}",
        watch.notes
    );
    assert!(
        watch
            .notes
            .iter()
            .any(|n| n.starts_with("stopped: the samples asked for (spp)")),
        "{:?}",
        watch.notes
    );
    assert!(
        watch.written.iter().any(|w| w.ends_with("box.pt.png: pt")),
        "{:?}",
        watch.written
    );
    assert!(dir.join("box.pt.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Refusals name the job's fields as a program sets them (`shard`, `target_error`,
/// `checkpoint_every`), where the command line names its flags.
#[test]
fn a_jobs_refusals_name_its_fields() {
    let out = std::env::temp_dir().join("hppm_job_refused.png");
    let mut shard = job(out.clone());
    shard.shard = Some((0, 2));
    shard.spp = None;
    shard.target_error = Some(0.01);
    shard.seconds = Some(1.0);
    let err = hppm::app::job::run(&shard, &Registry::builtin(), &mut Recorder::default())
        .expect_err("a shard cannot stop at an error")
        .to_string();
    assert!(err.starts_with("shard and target_error:"), "{err}");
    let mut checkpoint = job(out);
    checkpoint.checkpoint = Some(std::env::temp_dir().join("hppm_job.state"));
    checkpoint.checkpoint_every = 0.0;
    let err = hppm::app::job::run(&checkpoint, &Registry::builtin(), &mut Recorder::default())
        .expect_err("a zero interval")
        .to_string();
    assert!(
        err.starts_with("checkpoint_every must be a positive"),
        "{err}"
    );
}

/// An image side of 0 (or past the largest film) given to the library is an error, not a
/// division by zero: the command line refuses it in its own parser, a program (or the Python
/// module) reaches the renderer directly.
#[test]
fn a_renderer_of_an_empty_or_huge_image_is_refused() {
    let gpu = common::gpu();
    let scene = hppm::loaders::load(&common::repo_path("scenes/cornell_box.ron")).expect("scene");
    let registry = Registry::builtin();
    for (w, h) in [(0, 8), (8, 0), (hppm::scene::MAX_FILM_SIDE + 1, 8)] {
        let graph = registry.bundled_graph("pt").expect("pt");
        let err = Renderer::builder(&gpu, &scene, graph)
            .size(w, h)
            .build()
            .err()
            .unwrap_or_else(|| panic!("{w}x{h} was accepted"))
            .to_string();
        assert!(err.starts_with(&format!("image size {w}x{h}")), "{err}");
    }
    let graph = registry.bundled_graph("pt").expect("pt");
    assert!(
        Renderer::builder(&gpu, &scene, graph)
            .size(1, 1)
            .build()
            .is_ok()
    );
}

/// A graph given by a bundled graph's name, or by its repository path where no file is there
/// (a program run away from the repository, an installed wheel), renders the compiled-in graph:
/// the image is the one the file renders, bit for bit (`pt`). A name that is neither a file nor
/// a bundled graph is refused with the bundled names.
#[test]
fn a_bundled_graph_is_found_by_name_or_by_its_repository_path() {
    let dir = std::env::temp_dir().join(format!("hppm_job_bundled_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let render = |graph: std::path::PathBuf, name: &str| {
        let out = dir.join(name);
        let mut job = job(out.clone());
        job.graph = graph;
        job.aovs = false;
        hppm::app::job::run(&job, &Registry::builtin(), &mut Recorder::default())
            .map(|()| hppm::image::Image::read_exr(&out).expect("the image"))
    };
    let from_file = render(common::repo_path("graphs/pt.ron"), "file.exr").expect("file");
    let by_name = render("pt".into(), "name.exr").expect("by name");
    let elsewhere = render("/nowhere/hppm/graphs/pt.ron".into(), "moved.exr").expect("moved");
    assert_eq!(from_file.pixels, by_name.pixels);
    assert_eq!(from_file.pixels, elsewhere.pixels);
    // The registry's loader (compare, `hppm graph`) finds it the same way.
    let loaded = Registry::builtin()
        .load_graph(std::path::Path::new("pt"))
        .expect("pt by name");
    assert_eq!(loaded.file, std::path::Path::new("graphs/pt.ron"));
    let err = render("no_such_graph".into(), "none.exr")
        .expect_err("not a file, not bundled")
        .to_string();
    assert!(
        err.starts_with("no_such_graph: ") && err.contains("hybrid_pppm"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
