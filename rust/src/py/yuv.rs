//! Binding of the RGB → YUV 4:2:0 conversion ([`crate::yuv`]).
//!
//! Takes a frame as `bytes` (or any buffer of bytes), or as the Arrow C data interface
//! capsules of a Pillow image (`Image.__arrow_c_array__()`: the image's own memory, read in
//! place), converts it with the GIL released and hands the planes to numpy without a copy.
//! Size checks live in the kernel and come back as `ValueError` (`MemoryError` for a frame
//! too large to allocate).

use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyCapsule;

use super::arrow::arrow_pixels;
use crate::yuv;

/// The ``yuv420p`` planes (Y, then U, then V; uint8, 1-D) of a ``width`` × ``height`` frame of
/// packed RGB (3 bytes a pixel) or RGBX (4, the fourth ignored) ``pixels``: BT.601 studio
/// range, chroma of each 2 × 2 block's mean colour, odd sizes rounded up to even by
/// repeating the last column and row.
#[pyfunction]
fn rgb_to_yuv420<'py>(
    py: Python<'py>,
    pixels: &[u8],
    width: usize,
    height: usize,
) -> PyResult<Bound<'py, PyArray1<u8>>> {
    let out = py.detach(|| yuv::rgb_to_yuv420_vec(pixels, width, height))?;
    Ok(out.into_pyarray(py))
}

/// As ``rgb_to_yuv420``, from the capsules ``(schema, array)`` of a Pillow RGB image's
/// ``__arrow_c_array__()`` (one block of RGBX pixels, read in place).
#[pyfunction]
fn rgb_to_yuv420_arrow<'py>(
    py: Python<'py>,
    schema: &Bound<'py, PyCapsule>,
    array: &Bound<'py, PyCapsule>,
    width: usize,
    height: usize,
) -> PyResult<Bound<'py, PyArray1<u8>>> {
    let pixels = arrow_pixels(schema, array)?;
    rgb_to_yuv420(py, pixels, width, height)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(rgb_to_yuv420, m)?)?;
    m.add_function(wrap_pyfunction!(rgb_to_yuv420_arrow, m)?)?;
    Ok(())
}
