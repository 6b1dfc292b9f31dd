//! Binding of the triangulation kernel ([`crate::triangulate`]).
//!
//! Checks the Python arguments (ndarray, dtype float64, shapes `(V, 3, 4)`, `(N, V, 2)`,
//! `(N, V)`; a copy when an array is not C-contiguous), runs the kernel with the GIL released
//! and hands the `(N, 3)` result to numpy without a copy. Value checks (non-finite
//! projections, negative weights) live in the kernel and come back as `ValueError`.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::arrays::{check_dtype, f64_values, ndarray, shape_str, F64Array};
use crate::triangulate;

fn array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    ndim: usize,
    what: &str,
) -> PyResult<F64Array<'py>> {
    let arr = ndarray(obj, name, "float64")?;
    check_dtype::<f64>(arr, name, "float64")?;
    if arr.ndim() != ndim {
        return Err(PyValueError::new_err(format!(
            "{name} must be {ndim}-D {what}, got shape {}",
            shape_str(arr.shape())
        )));
    }
    f64_values(arr)
}

/// Weighted DLT triangulation: ``projections`` (V, 3, 4), ``points`` (N, V, 2) image
/// coordinates (NaN: not seen), ``weights`` (N, V) ≥ 0 → (N, 3) points (NaN where fewer than
/// ``min_views`` views have a positive weight).
#[pyfunction]
#[pyo3(signature = (projections, points, weights, *, min_views=2))]
fn triangulate_points<'py>(
    py: Python<'py>,
    projections: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
    weights: &Bound<'py, PyAny>,
    min_views: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let p = array(projections, "projections", 3, "(views, 3, 4)")?;
    let x = array(points, "points", 3, "(points, views, 2)")?;
    let w = array(weights, "weights", 2, "(points, views)")?;
    let views = p.shape[0];
    if p.shape[1..] != [3, 4] {
        return Err(PyValueError::new_err(format!(
            "projections must have shape (views, 3, 4), got {}",
            shape_str(&p.shape)
        )));
    }
    let n = x.shape[0];
    if x.shape[1..] != [views, 2] || w.shape != [n, views] {
        return Err(PyValueError::new_err(format!(
            "points {} and weights {} do not fit {views} views: expected ({n}, {views}, 2) and \
             ({n}, {views})",
            shape_str(&x.shape),
            shape_str(&w.shape)
        )));
    }
    let (pv, xv, wv) = (p.values(), x.values(), w.values());
    let (pv, xv, wv): (&[f64], &[f64], &[f64]) = (&pv, &xv, &wv);
    let out = py.detach(|| triangulate::triangulate(pv, xv, wv, views, min_views))?;
    Ok(Array2::from_shape_vec((n, 3), out)
        .expect("kernel output has the announced shape")
        .into_pyarray(py))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(triangulate_points, m)?)?;
    Ok(())
}
