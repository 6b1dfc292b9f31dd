//! Bindings of the DTW kernel ([`crate::dtw`]).
//!
//! Checks the Python arguments (ndarray, dtype float64 / int64, number of dimensions; a copy
//! when an array is not C-contiguous), runs the kernel with the GIL released (inside an
//! optional local rayon pool of `n_threads` threads) and hands the result to numpy without a
//! copy. Value checks (offsets, NaN/inf, band) live in the kernel and come back as
//! `ValueError`.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::args::{n_threads_arg, Int};
use super::arrays::{check_dtype, f64_values, i64_values, ndarray, shape_str, F64Array};
use crate::dtw::{self, DtwOptions};

/// A read-only `(frames, dim)` float64 argument.
fn frames<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<F64Array<'py>> {
    let arr = ndarray(obj, name, "float64")?;
    check_dtype::<f64>(arr, name, "float64")?;
    if arr.ndim() != 2 {
        return Err(PyValueError::new_err(format!(
            "{name} must be 2-D (frames, channels), got shape {}",
            shape_str(arr.shape())
        )));
    }
    f64_values(arr)
}

fn offsets(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<i64>> {
    let arr = ndarray(obj, name, "int64")?;
    check_dtype::<i64>(arr, name, "int64")?;
    if arr.ndim() != 1 {
        return Err(PyValueError::new_err(format!(
            "{name} must be 1-D (the first frame of each sequence), got shape {}",
            shape_str(arr.shape())
        )));
    }
    i64_values(arr, name)
}

/// Run `f` in a local pool of `n_threads` threads (`None`: rayon's global pool).
fn in_pool<T: Send>(n_threads: Option<usize>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    match n_threads {
        None => Ok(f()),
        Some(0) => Err(PyValueError::new_err(
            "n_threads must be ≥ 1 (or None for all cores)",
        )),
        Some(t) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .map_err(|e| PyValueError::new_err(format!("cannot start {t} threads: {e}")))?;
            Ok(pool.install(f))
        }
    }
}

/// DTW costs ``(n_queries, n_references)`` between ragged sets of sequences; without
/// ``references`` the symmetric costs among the queries (each pair computed once).
#[pyfunction]
#[pyo3(signature = (
    queries, query_offsets, references=None, reference_offsets=None,
    *, band=None, normalize=true, n_threads=None
))]
#[allow(clippy::too_many_arguments)]
fn dtw_distances<'py>(
    py: Python<'py>,
    queries: &Bound<'py, PyAny>,
    query_offsets: &Bound<'py, PyAny>,
    references: Option<&Bound<'py, PyAny>>,
    reference_offsets: Option<&Bound<'py, PyAny>>,
    band: Option<f64>,
    normalize: bool,
    n_threads: Option<Int>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let n_threads = n_threads_arg(n_threads)?;
    let options = DtwOptions { band, normalize };
    let q = frames(queries, "queries")?;
    let qo = offsets(query_offsets, "query_offsets")?;
    let qv = q.values();
    let qv: &[f64] = &qv;
    let dim = q.shape[1];
    let (rows, cols, out) = match (references, reference_offsets) {
        (None, None) => {
            let n = qo.len();
            let out =
                py.detach(|| in_pool(n_threads, || dtw::dtw_pairwise(qv, &qo, dim, &options)))??;
            (n, n, out)
        }
        (Some(r), Some(ro)) => {
            let r = frames(r, "references")?;
            if r.shape[1] != dim {
                return Err(PyValueError::new_err(format!(
                    "references have {} channels but queries have {dim}",
                    r.shape[1]
                )));
            }
            let ro = offsets(ro, "reference_offsets")?;
            let rv = r.values();
            let rv: &[f64] = &rv;
            let out = py.detach(|| {
                in_pool(n_threads, || {
                    dtw::dtw_cross(qv, &qo, rv, &ro, dim, &options)
                })
            })??;
            (qo.len(), ro.len(), out)
        }
        _ => {
            return Err(PyValueError::new_err(
                "give both references and reference_offsets, or neither",
            ))
        }
    };
    Ok(Array2::from_shape_vec((rows, cols), out)
        .expect("kernel output has the announced shape")
        .into_pyarray(py))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(dtw_distances, m)?)?;
    Ok(())
}
