//! hppm's errors as Python exceptions: `hppm.Error` and a subclass per origin, each instance
//! with `file`, `line` and `column` (None where the error has no place in a file).

use hppm::Location;
use hppm::scene::SceneError as SceneFileError;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    hppm,
    Error,
    PyException,
    "An error of hppm; `file`, `line` and `column` say where it points, when it points at a file."
);
create_exception!(hppm, SceneError, Error, "A scene file hppm cannot render.");
create_exception!(
    hppm,
    GraphError,
    Error,
    "A render graph that is invalid, or a node of it that failed."
);
create_exception!(
    hppm,
    GpuError,
    Error,
    "The device refused the work (no adapter, a buffer too large, a lost device)."
);

pub fn add_to(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // Class attributes: an error without a place reads None rather than raising AttributeError.
    let base = py.get_type::<Error>();
    for name in ["file", "line", "column"] {
        base.setattr(name, py.None())?;
    }
    m.add("Error", base)?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("GraphError", py.get_type::<GraphError>())?;
    m.add("GpuError", py.get_type::<GpuError>())?;
    Ok(())
}

/// A `GraphError` about `file` as a whole (one that cannot be read).
pub fn graph_file_error(file: &std::path::Path, message: String) -> PyErr {
    let exception = GraphError::new_err(message);
    Python::with_gil(|py| {
        let _ = exception
            .value(py)
            .setattr("file", file.display().to_string());
    });
    exception
}

/// The exception for `error`, its message hppm's and its place set as attributes.
pub fn to_py(error: hppm::Error) -> PyErr {
    let place = place_of(&error);
    let message = error.to_string();
    let exception = match error {
        hppm::Error::Scene(_) => SceneError::new_err(message),
        hppm::Error::Graph(_) | hppm::Error::InNode { .. } => GraphError::new_err(message),
        hppm::Error::Gpu(_) => GpuError::new_err(message),
        _ => Error::new_err(message),
    };
    Python::with_gil(|py| {
        let value = exception.value(py);
        let (file, line, column) = match place {
            Some((file, Some((line, column)))) => (Some(file), Some(line), Some(column)),
            Some((file, None)) => (Some(file), None, None),
            None => (None, None, None),
        };
        // Setting an attribute on a fresh exception instance cannot fail but for memory.
        let _ = value.setattr("file", file);
        let _ = value.setattr("line", line);
        let _ = value.setattr("column", column);
    });
    exception
}

/// A file, and the line and column in it when known.
type Place = (String, Option<(usize, usize)>);

fn at(location: &Location) -> Option<Place> {
    Some((
        location.file.display().to_string(),
        Some((location.line, location.col)),
    ))
}

/// The file, line and column an error points at (the first of several).
fn place_of(error: &hppm::Error) -> Option<Place> {
    match error {
        hppm::Error::Scene(e) => scene_place(e),
        hppm::Error::Graph(e) => e.0.first().and_then(|g| at(&g.location)),
        hppm::Error::Io { path, .. } => Some((path.display().to_string(), None)),
        hppm::Error::InNode { place, .. } => node_place(place),
        _ => None,
    }
}

fn scene_place(error: &SceneFileError) -> Option<Place> {
    match error {
        SceneFileError::At { location, .. } => at(location),
        SceneFileError::Several(all) => all.iter().find_map(scene_place),
        SceneFileError::Io { file, .. } | SceneFileError::File { file, .. } => {
            Some((file.display().to_string(), None))
        }
    }
}

/// A node's place, `FILE:LINE:COL: node "name" (kind)` (the graph executor's `in_node`).
fn node_place(place: &str) -> Option<Place> {
    let (location, _) = place.split_once(": node \"")?;
    let mut parts = location.rsplitn(3, ':');
    let column = parts.next()?.parse().ok()?;
    let line = parts.next()?.parse().ok()?;
    Some((parts.next()?.to_string(), Some((line, column))))
}
