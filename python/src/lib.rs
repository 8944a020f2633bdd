//! hppm's Python module, installed as `hppm._hppm` and re-exported by `hppm`
//! (python/hppm/__init__.py): scenes and graphs loaded from files, renders into numpy arrays, a
//! progressive renderer, and the command line. The GPU work runs with the GIL released; errors
//! are `hppm.Error` subclasses carrying the file, line and column they point at.

mod errors;
mod images;
mod render;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use hppm::gpu::GpuContext;
use hppm::graph::bundled::BUNDLED_GRAPHS;
use hppm::passes::Registry;
use hppm::scene::Scene;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};

use errors::to_py;

/// The device every render of this process runs on, opened at first use and kept for the
/// process's life (a renderer borrows it; pipelines are cached on it, so a second render of a
/// scene compiles nothing).
static GPU: Mutex<Option<(&'static GpuContext, Option<String>)>> = Mutex::new(None);

/// The device, opened on `adapter` (an index or part of a name; `None`: the best) if none is
/// open yet. Asking for a different adapter once one is open is an error, not a silent switch.
fn gpu(adapter: Option<&str>) -> PyResult<&'static GpuContext> {
    let mut held = GPU
        .lock()
        .map_err(|_| errors::Error::new_err("the device lock was poisoned by a panic"))?;
    if let Some((gpu, chosen)) = held.as_ref() {
        if adapter.is_some() && adapter != chosen.as_deref() {
            return Err(errors::Error::new_err(format!(
                "the device is already open on {}; choose the adapter before the first render",
                gpu.adapter_label()
            )));
        }
        return Ok(gpu);
    }
    let opened: &'static GpuContext = Box::leak(Box::new(
        GpuContext::new(adapter).map_err(|e| to_py(e.into()))?,
    ));
    *held = Some((opened, adapter.map(str::to_owned)));
    Ok(opened)
}

/// Opens the device renders run on (an adapter index or part of its name, as
/// `hppm info` lists them; default: the best) and returns its description. Without a call,
/// the first render opens the best adapter.
#[pyfunction]
#[pyo3(signature = (adapter = None))]
fn device(py: Python<'_>, adapter: Option<String>) -> PyResult<String> {
    let gpu = py.allow_threads(|| gpu(adapter.as_deref()))?;
    Ok(gpu.adapter_label())
}

/// A scene loaded from a Mitsuba 3 XML, hppm RON or OBJ file (`hppm.load_scene`).
#[pyclass(frozen, name = "Scene", module = "hppm")]
pub struct PyScene {
    scene: Arc<Scene>,
}

#[pymethods]
impl PyScene {
    /// The file it was loaded from.
    #[getter]
    fn path(&self) -> String {
        self.scene.source.display().to_string()
    }

    /// The film's (width, height): a render's default size.
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.scene.camera.width, self.scene.camera.height)
    }

    /// The sampler's sample count, a render's default budget (None when the file gives none).
    #[getter]
    fn spp(&self) -> Option<u32> {
        self.scene.spp_hint
    }

    #[getter]
    fn triangles(&self) -> usize {
        self.scene.triangles.len()
    }

    /// What the scene holds (shapes, materials, lights), as `hppm render` reports it.
    #[getter]
    fn features(&self) -> String {
        self.scene.features().to_string()
    }

    fn __repr__(&self) -> String {
        let (w, h) = self.size();
        format!(
            "hppm.Scene('{}', {w}x{h}, {} triangles)",
            self.scene.source.display(),
            self.scene.triangles.len()
        )
    }
}

/// Loads a scene. Keyword arguments are Mitsuba's `-D name=value` parameters (`$name` in the
/// XML): numbers, strings and booleans. Warnings (e.g. a property hppm ignores) are issued as
/// Python warnings; errors raise `hppm.SceneError` with `file`, `line` and `column`.
#[pyfunction]
#[pyo3(signature = (path, **params))]
fn load_scene(
    py: Python<'_>,
    path: PathBuf,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyScene> {
    let mut defines = Vec::new();
    if let Some(params) = params {
        for (name, value) in params.iter() {
            defines.push((name.extract::<String>()?, define_text(&value)?));
        }
    }
    let (scene, warnings) = py.allow_threads(|| {
        let mut warnings = Vec::new();
        let scene = hppm::loaders::load_reporting(
            &path,
            &defines,
            hppm::bsdfs::BsdfRegistry::builtin_ref(),
            |w| warnings.push(w.to_string()),
        );
        (scene, warnings)
    });
    for warning in warnings {
        warn(py, &warning)?;
    }
    let scene = scene.map_err(|e| to_py(e.into()))?;
    Ok(PyScene {
        scene: Arc::new(scene),
    })
}

/// Issues `message` as a Python `UserWarning` (what `hppm render` prints as "warning: ...").
pub fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    PyErr::warn(py, &category, &std::ffi::CString::new(message)?, 1)
}

/// A parameter's value as Mitsuba's `-D` would spell it on the command line.
fn define_text(value: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(flag) = value.downcast::<PyBool>() {
        return Ok(if flag.is_true() { "true" } else { "false" }.into());
    }
    Ok(value.str()?.to_string())
}

/// A render graph (`hppm.load_graph`): its file and text, validated against hppm's pass kinds.
/// Each renderer prepares its own instance of it.
#[pyclass(frozen, name = "Graph", module = "hppm")]
pub struct PyGraph {
    file: PathBuf,
    text: String,
    /// (name, kind) of each node, in file order.
    nodes: Vec<(String, String)>,
}

impl PyGraph {
    /// The graph at `name_or_path` (a file or a bundled graph's name), and its first instance.
    fn load(
        registry: &Registry,
        name_or_path: &Path,
    ) -> PyResult<(PyGraph, hppm::graph::ValidGraph)> {
        let (file, text) = hppm::graph::bundled::read_graph(name_or_path)
            .map_err(|e| errors::graph_file_error(name_or_path, e.to_string()))?;
        let graph = registry
            .parse_graph(&file, &text)
            .map_err(|e| to_py(e.into()))?;
        let nodes = graph
            .nodes
            .iter()
            .map(|n| (n.name.clone(), n.kind.name.to_string()))
            .collect();
        Ok((PyGraph { file, text, nodes }, graph))
    }

    /// A fresh instance to prepare on the device.
    fn instance(&self, registry: &Registry) -> PyResult<hppm::graph::ValidGraph> {
        registry
            .parse_graph(&self.file, &self.text)
            .map_err(|e| to_py(e.into()))
    }
}

#[pymethods]
impl PyGraph {
    /// The graph file (for a bundled graph, its path in hppm's repository).
    #[getter]
    fn file(&self) -> String {
        self.file.display().to_string()
    }

    /// The graph file's RON text.
    #[getter]
    fn text(&self) -> &str {
        &self.text
    }

    /// (name, kind) of each node.
    #[getter]
    fn nodes(&self) -> Vec<(String, String)> {
        self.nodes.clone()
    }

    fn __repr__(&self) -> String {
        let kinds: Vec<&str> = self.nodes.iter().map(|(_, k)| k.as_str()).collect();
        format!(
            "hppm.Graph('{}', [{}])",
            self.file.display(),
            kinds.join(", ")
        )
    }
}

/// Loads a render graph: a RON file, or the name of a graph shipped with hppm (`"hybrid"`,
/// `"pt"`, `"hybrid_pppm"`, ...; `hppm.bundled_graphs()` lists them). Errors raise
/// `hppm.GraphError` with `file`, `line` and `column`.
#[pyfunction]
fn load_graph(name_or_path: PathBuf) -> PyResult<PyGraph> {
    Ok(PyGraph::load(&Registry::builtin(), &name_or_path)?.0)
}

/// The names of the graphs shipped with hppm.
#[pyfunction]
fn bundled_graphs() -> Vec<&'static str> {
    BUNDLED_GRAPHS.iter().map(|g| g.0).collect()
}

/// Runs the `hppm` command line on `args` (the first is the program's name) and returns its
/// exit status; the `hppm` command the package installs calls it.
#[pyfunction]
fn cli(args: Vec<std::ffi::OsString>) -> i32 {
    let code = hppm::cli::run_from(args, Registry::builtin());
    // ExitCode cannot be read back; these are the two the command line returns besides success.
    if code == std::process::ExitCode::SUCCESS {
        0
    } else if code == std::process::ExitCode::from(2) {
        2
    } else {
        1
    }
}

#[pymodule]
fn _hppm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(device, m)?)?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(load_graph, m)?)?;
    m.add_function(wrap_pyfunction!(bundled_graphs, m)?)?;
    m.add_function(wrap_pyfunction!(cli, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(images::read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(images::write_image, m)?)?;
    m.add_function(wrap_pyfunction!(images::relmse, m)?)?;
    m.add_class::<PyScene>()?;
    m.add_class::<PyGraph>()?;
    m.add_class::<render::PyRenderer>()?;
    errors::add_to(m)?;
    Ok(())
}
