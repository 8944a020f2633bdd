//! Rendering from Python: `hppm.render` (a whole render, as `hppm render` makes it) and
//! `hppm.Renderer` (iterate, look at the image, go on). Arrays are float32 numpy arrays of
//! shape (height, width, 3), linear RGB.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard};

use hppm::passes::Registry;
use hppm::render::{Budget, BudgetField, Renderer, RunSummary, Stop, auto};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::to_py;
use crate::images::array;
use crate::{PyGraph, PyScene};

/// A scene given as a loaded `hppm.Scene` or as a file to load.
#[derive(FromPyObject)]
pub enum SceneArg<'py> {
    Loaded(PyRef<'py, PyScene>),
    File(PathBuf),
}

/// A graph given as a loaded `hppm.Graph`, a file or a bundled graph's name.
#[derive(FromPyObject)]
pub enum GraphArg<'py> {
    Loaded(PyRef<'py, PyGraph>),
    NameOrFile(PathBuf),
}

/// The budget's fields as the Python keywords name them.
fn keyword(field: BudgetField) -> &'static str {
    match field {
        BudgetField::Seconds => "time",
        other => other.field_name(),
    }
}

/// Renderer(scene, graph="hybrid", *, size=None, seed=0): a progressive render.
///
/// Prepares `graph` (a `hppm.Graph`, a RON file or a bundled graph's name) for `scene` (a
/// `hppm.Scene` or a file) at `size` = (width, height) (default: the scene's film), with random
/// streams from `seed`. Nothing is rendered until `iterate` or `run`; `image`, `aovs` and
/// `error_estimate` read the render so far.
// Any Python thread may use it: pyo3's borrow flag lets one call at a time change it (another
// gets "already borrowed", e.g. `image()` from a `progress` callback), and the mutex makes the
// renderer, which is Send, Sync as pyo3 asks.
#[pyclass(name = "Renderer", module = "hppm")]
pub struct PyRenderer {
    renderer: Mutex<Renderer<'static>>,
    gpu: &'static hppm::gpu::GpuContext,
    /// The scene's sample count, the default budget of `run`.
    scene_spp: Option<u32>,
}

/// The scene a call was given, loaded where it is a file.
fn loaded(py: Python<'_>, scene: SceneArg<'_>) -> PyResult<std::sync::Arc<hppm::scene::Scene>> {
    Ok(match scene {
        SceneArg::Loaded(s) => s.scene.clone(),
        SceneArg::File(path) => crate::load_scene(py, path, None)?.scene,
    })
}

/// Builds a renderer of `scene` through `graph` on the process's device.
fn build(
    py: Python<'_>,
    scene: SceneArg<'_>,
    graph: GraphArg<'_>,
    size: Option<(u32, u32)>,
    seed: u64,
) -> PyResult<PyRenderer> {
    let registry = Registry::builtin();
    let scene = loaded(py, scene)?;
    let graph = match graph {
        GraphArg::Loaded(g) => g.instance(&registry)?,
        GraphArg::NameOrFile(path) => PyGraph::load(&registry, &path)?.1,
    };
    let (width, height) = size.unwrap_or((scene.camera.width, scene.camera.height));
    let gpu = crate::gpu(None)?;
    let renderer = py
        .allow_threads(|| {
            hppm::render::Renderer::builder(gpu, &scene, graph)
                .registry(registry)
                .size(width, height)
                .seed(seed)
                .build()
        })
        .map_err(to_py)?;
    // What `hppm render` warns of before it renders.
    if let Some(warning) = scene.no_light_warning() {
        crate::warn(py, &warning)?;
    }
    if let Some(warning) = renderer.unsampled_light_warning() {
        crate::warn(py, warning.strip_prefix("warning: ").unwrap_or(&warning))?;
    }
    Ok(PyRenderer {
        renderer: Mutex::new(renderer),
        gpu,
        scene_spp: scene.spp_hint,
    })
}

/// The renderer `auto` chooses for `scene` and `budget` (its pilots rendered, the winner's kept),
/// and what is left of the budget; the choice is logged on the `hppm` logger.
fn build_auto(
    py: Python<'_>,
    scene: SceneArg<'_>,
    budget: Budget,
    size: Option<(u32, u32)>,
    seed: u64,
) -> PyResult<(PyRenderer, Budget)> {
    let registry = Registry::builtin();
    let scene = loaded(py, scene)?;
    let budget = budget.or_scene_spp(scene.spp_hint);
    budget.check_named(keyword).map_err(to_py)?;
    let (width, height) = size.unwrap_or((scene.camera.width, scene.camera.height));
    let gpu = crate::gpu(None)?;
    if let Some(warning) = scene.no_light_warning() {
        crate::warn(py, &warning)?;
    }
    let cancel = AtomicBool::new(false);
    let choice = py
        .allow_threads(|| {
            auto::choose(budget, &cancel, |name| {
                let (file, text) = hppm::graph::bundled::bundled_graph(name)?;
                let graph = registry.parse_graph(Path::new(file), text)?;
                let renderer = Renderer::builder(gpu, &scene, graph)
                    .registry(registry.clone())
                    .size(width, height)
                    .seed(seed)
                    .build()?;
                Ok((renderer, ()))
            })
        })
        .map_err(to_py)?;
    let logger = py.import("logging")?.call_method1("getLogger", ("hppm",))?;
    logger.call_method1("info", (choice.report.summary(),))?;
    let left = Budget {
        seconds: budget
            .seconds
            .map(|s| (s - choice.report.seconds).max(f64::MIN_POSITIVE)),
        ..budget
    };
    let renderer = PyRenderer {
        renderer: Mutex::new(choice.renderer),
        gpu,
        scene_spp: scene.spp_hint,
    };
    Ok((renderer, left))
}

/// A panic inside a call (a bug) leaves the renderer unusable rather than half-updated.
fn poisoned<T>(_: T) -> PyErr {
    crate::errors::Error::new_err("the renderer is unusable after an internal error")
}

impl PyRenderer {
    /// The renderer for a call that holds this object mutably.
    fn inner_mut(&mut self) -> PyResult<&mut Renderer<'static>> {
        self.renderer.get_mut().map_err(poisoned)
    }

    /// The renderer for a read (pyo3 refuses the read while a mutable call runs, so the lock
    /// is never contended).
    fn inner(&self) -> PyResult<MutexGuard<'_, Renderer<'static>>> {
        self.renderer.lock().map_err(poisoned)
    }

    /// Renders to `budget` (counted from the renderer's start for samples and photons, from
    /// now for time) with the GIL released, calling `progress` with the GIL after each
    /// iteration. Ctrl-C (a pending signal) and an exception from `progress` stop it and are
    /// raised; `progress` returning False stops it quietly, keeping what was rendered.
    fn run_to(
        &mut self,
        py: Python<'_>,
        budget: Budget,
        progress: Option<PyObject>,
    ) -> PyResult<RunSummary> {
        budget.check_named(keyword).map_err(to_py)?;
        let cancel = AtomicBool::new(false);
        let mut raised: Option<PyErr> = None;
        let renderer = self.inner_mut()?;
        let summary = py.allow_threads(|| {
            renderer.run(budget, &cancel, |r, seconds| {
                Python::with_gil(|py| {
                    let outcome = py.check_signals().and_then(|()| match &progress {
                        Some(callback) => {
                            let stop = callback.call1(py, (progress_info(py, r, seconds)?,))?;
                            Ok(stop.bind(py).is(pyo3::types::PyBool::new(py, false)))
                        }
                        None => Ok(false),
                    });
                    match outcome {
                        Ok(false) => {}
                        Ok(true) => cancel.store(true, Ordering::Relaxed),
                        Err(e) => {
                            raised = Some(e);
                            cancel.store(true, Ordering::Relaxed);
                        }
                    }
                })
            })
        });
        if let Some(e) = raised {
            return Err(e);
        }
        summary.map_err(to_py)
    }
}

/// What `progress` receives after each iteration.
fn progress_info<'py>(
    py: Python<'py>,
    renderer: &hppm::render::Renderer<'_>,
    seconds: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let info = PyDict::new(py);
    info.set_item("iterations", renderer.iterations())?;
    info.set_item("spp", renderer.samples_per_pixel())?;
    info.set_item("photons", renderer.photons())?;
    info.set_item("seconds", seconds)?;
    info.set_item(
        "estimated_relmse",
        renderer.latest_error().map(|e| e.relmse),
    )?;
    Ok(info)
}

fn summary_dict<'py>(py: Python<'py>, summary: &RunSummary) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("seconds", summary.seconds)?;
    out.set_item("iterations", summary.iterations)?;
    out.set_item("spp", summary.samples_per_pixel)?;
    out.set_item("photons", summary.photons)?;
    let stop = match summary.stop {
        Stop::Count => "count",
        Stop::Time => "time",
        Stop::TargetError => "target_error",
        Stop::Cancelled => "cancelled",
    };
    out.set_item("stop", stop)?;
    Ok(out)
}

#[pymethods]
impl PyRenderer {
    #[new]
    #[pyo3(signature = (scene, graph = None, *, size = None, seed = 0))]
    fn new(
        py: Python<'_>,
        scene: SceneArg<'_>,
        graph: Option<GraphArg<'_>>,
        size: Option<(u32, u32)>,
        seed: u64,
    ) -> PyResult<Self> {
        let graph = graph.unwrap_or(GraphArg::NameOrFile(PathBuf::from("hybrid")));
        build(py, scene, graph, size, seed)
    }

    /// Runs `n` iterations of the graph (each adds its samples per pixel and photons).
    #[pyo3(signature = (n = 1))]
    fn iterate(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        for _ in 0..n {
            let gpu = self.gpu;
            let renderer = self.inner_mut()?;
            py.allow_threads(|| {
                renderer.iterate()?;
                // Waiting keeps Ctrl-C within one iteration, as `run` does.
                gpu.wait().map_err(hppm::Error::from)
            })
            .map_err(to_py)?;
            py.check_signals()?;
        }
        Ok(())
    }

    /// Renders until a budget is met: `spp` and `photons` count from the renderer's start,
    /// `time` (seconds) from this call; `target_error` stops once the estimated relMSE falls
    /// below it (with another budget as a cap; `adaptive` also stops sampling pixels already
    /// below it). With no budget, the scene's sample count (else 64). `progress(info)` is called
    /// after each iteration with a dict (iterations, spp, photons, seconds,
    /// estimated_relmse); returning False stops the render. Returns a summary dict, `stop`
    /// saying which budget ended it.
    #[pyo3(signature = (*, spp = None, time = None, photons = None, target_error = None, adaptive = false, progress = None))]
    #[allow(clippy::too_many_arguments)]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        spp: Option<u64>,
        time: Option<f64>,
        photons: Option<u64>,
        target_error: Option<f64>,
        adaptive: bool,
        progress: Option<PyObject>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let budget = Budget {
            spp,
            seconds: time,
            photons,
            target_error,
            adaptive,
        }
        .or_scene_spp(self.scene_spp);
        let summary = self.run_to(py, budget, progress)?;
        summary_dict(py, &summary)
    }

    /// The image so far: a (height, width, 3) float32 array.
    fn image<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        // `&mut`: a renderer is Send, not Sync, and the GIL is released around the readback.
        let renderer = self.inner_mut()?;
        let image = py.allow_threads(move || renderer.image()).map_err(to_py)?;
        array(py, &image)
    }

    /// Every image slot of the output node (e.g. `combined`, `pt`, `caustic`, `radius` of
    /// `resolve`), by slot name.
    fn aovs<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        // `&mut`: a renderer is Send, not Sync, and the GIL is released around the readback.
        let renderer = self.inner_mut()?;
        let aovs = py.allow_threads(move || renderer.aovs()).map_err(to_py)?;
        let out = PyDict::new(py);
        for (slot, image) in aovs {
            out.set_item(slot, array(py, &image)?)?;
        }
        Ok(out)
    }

    /// The image's estimated error without a reference (docs/error-estimate.md): a dict of
    /// `relmse` (= `variance` + `bias`, the same definition as `hppm compare`'s relMSE) and
    /// `per_pixel` (its (height, width, 3) terms); None before two iterations.
    fn error_estimate<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        // `&mut`: a renderer is Send, not Sync, and the GIL is released around the readback.
        let renderer = self.inner_mut()?;
        let estimate = py
            .allow_threads(move || renderer.error_estimate())
            .map_err(to_py)?;
        estimate
            .map(|e| {
                let out = PyDict::new(py);
                out.set_item("relmse", e.relmse)?;
                out.set_item("variance", e.variance)?;
                out.set_item("bias", e.bias)?;
                out.set_item("per_pixel", array(py, &e.per_pixel)?)?;
                Ok(out)
            })
            .transpose()
    }

    /// The passes' counters (photons traced, stored, hit points, ...), summed over the nodes.
    fn counters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let counters = self.inner()?.counters().map_err(to_py)?;
        let out = PyDict::new(py);
        for (name, value) in &counters.0 {
            out.set_item(*name, *value)?;
        }
        Ok(out)
    }

    #[getter]
    fn iterations(&self) -> PyResult<u64> {
        Ok(self.inner()?.iterations())
    }

    /// Camera samples per pixel so far.
    #[getter]
    fn spp(&self) -> PyResult<u64> {
        Ok(self.inner()?.samples_per_pixel())
    }

    /// Photons emitted so far.
    #[getter]
    fn photons(&self) -> PyResult<u64> {
        Ok(self.inner()?.photons())
    }

    #[getter]
    fn spp_per_iteration(&self) -> PyResult<u64> {
        Ok(self.inner()?.spp_per_iteration())
    }

    #[getter]
    fn photons_per_iteration(&self) -> PyResult<u64> {
        Ok(self.inner()?.photons_per_iteration())
    }

    /// (width, height).
    #[getter]
    fn size(&self) -> PyResult<(u32, u32)> {
        Ok(self.inner()?.size())
    }

    #[getter]
    fn seed(&self) -> PyResult<u64> {
        Ok(self.inner()?.seed())
    }

    /// The nodes the scene had no use for, removed before preparing, and why.
    #[getter]
    fn pruned(&self) -> PyResult<Vec<String>> {
        Ok(self
            .inner()?
            .pruned()
            .iter()
            .map(ToString::to_string)
            .collect())
    }

    fn __repr__(&self) -> PyResult<String> {
        let renderer = self.inner()?;
        let (w, h) = renderer.size();
        Ok(format!(
            "hppm.Renderer({w}x{h}, {} iterations, {} spp, {} photons)",
            renderer.iterations(),
            renderer.samples_per_pixel(),
            renderer.photons()
        ))
    }
}

/// Renders `scene` (a `hppm.Scene` or a file) through `graph` (a `hppm.Graph`, a RON file, a
/// bundled graph's name, or "auto": the graph `hppm render` would choose, by the same pilots,
/// reported on the `hppm` logger; default: the bundled hybrid) as `hppm render` does with the
/// same budget, seed and size, and returns the image as a (height, width, 3) float32 array; with
/// `aovs=True`, a pair (image, dict) whose dict holds the output node's other images and
/// `error`, the per-pixel error estimate. Budgets, the default budget and `progress` are those
/// of `Renderer.run`.
#[pyfunction]
#[pyo3(signature = (scene, graph = None, *, spp = None, time = None, photons = None, target_error = None, adaptive = false, seed = 0, size = None, aovs = false, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    scene: SceneArg<'_>,
    graph: Option<GraphArg<'_>>,
    spp: Option<u64>,
    time: Option<f64>,
    photons: Option<u64>,
    target_error: Option<f64>,
    adaptive: bool,
    seed: u64,
    size: Option<(u32, u32)>,
    aovs: bool,
    progress: Option<PyObject>,
) -> PyResult<Bound<'py, PyAny>> {
    let graph = graph.unwrap_or(GraphArg::NameOrFile(PathBuf::from("hybrid")));
    let budget = Budget {
        spp,
        seconds: time,
        photons,
        target_error,
        adaptive,
    };
    let (mut renderer, budget) = match graph {
        GraphArg::NameOrFile(path) if auto::is_auto(&path) => {
            build_auto(py, scene, budget, size, seed)?
        }
        graph => {
            let renderer = build(py, scene, graph, size, seed)?;
            let budget = budget.or_scene_spp(renderer.scene_spp);
            (renderer, budget)
        }
    };
    // As `hppm render`: the estimate is made as it renders (a target error needs it).
    renderer.inner_mut()?.watch_error();
    renderer.run_to(py, budget, progress)?;
    let inner = renderer.inner_mut()?;
    let (image, estimate) = py
        .allow_threads(move || inner.image_and_error_estimate())
        .map_err(to_py)?;
    let image = array(py, &image)?;
    if !aovs {
        return Ok(image);
    }
    let others = renderer.aovs(py)?;
    if let Some(e) = estimate {
        others.set_item("error", array(py, &e.per_pixel)?)?;
    }
    Ok((image, others).into_pyobject(py)?.into_any())
}
