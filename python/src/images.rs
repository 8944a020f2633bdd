//! Images between hppm and numpy: float32 arrays of shape (height, width, 3), linear RGB, rows
//! from the top.

use std::path::PathBuf;

use hppm::image::{Image, Provenance};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::errors::to_py;

/// A (height, width, 3) float32 array of `image`.
pub fn array<'py>(py: Python<'py>, image: &Image) -> PyResult<Bound<'py, PyAny>> {
    let values: Vec<f32> = image.pixels.iter().flatten().copied().collect();
    let flat = PyArray1::from_vec(py, values);
    Ok(flat
        .reshape([image.height as usize, image.width as usize, 3])?
        .into_any())
}

/// The image of a (height, width, 3) float32 array.
fn image_of(array: &PyReadonlyArray3<'_, f32>) -> PyResult<Image> {
    let [height, width, channels] = [0, 1, 2].map(|i| array.shape()[i]);
    if channels != 3 {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "an image is a (height, width, 3) array; this one is ({height}, {width}, {channels})"
        )));
    }
    let too_large = |_| pyo3::exceptions::PyValueError::new_err("image larger than 2^32 pixels");
    // Each pixel's RGB lane, rows from the top, whatever the array's strides.
    let pixels = array
        .as_array()
        .lanes(numpy::ndarray::Axis(2))
        .into_iter()
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(Image {
        width: u32::try_from(width).map_err(too_large)?,
        height: u32::try_from(height).map_err(too_large)?,
        pixels,
    })
}

/// An OpenEXR image's RGB as a (height, width, 3) float32 array (a reference, a render).
#[pyfunction]
pub fn read_exr(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let image = py.allow_threads(|| Image::read_exr(&path)).map_err(to_py)?;
    array(py, &image)
}

/// Writes a (height, width, 3) float32 array as OpenEXR (linear, float) or PNG (sRGB, 8-bit),
/// by the file's extension.
#[pyfunction]
pub fn write_image(path: PathBuf, image: PyReadonlyArray3<'_, f32>) -> PyResult<()> {
    image_of(&image)?
        .write(&path, &Provenance::default())
        .map_err(to_py)
}

/// Relative mean squared error, as `hppm compare` measures it: the mean over pixels and RGB of
/// (x - ref)^2 / (ref^2 + 0.01). Both are (height, width, 3) float32 arrays.
#[pyfunction]
pub fn relmse(
    image: PyReadonlyArray3<'_, f32>,
    reference: PyReadonlyArray3<'_, f32>,
) -> PyResult<f64> {
    image_of(&image)?
        .relmse(&image_of(&reference)?)
        .map_err(to_py)
}
