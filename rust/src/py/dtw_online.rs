//! Binding of the open-end DTW kernel ([`crate::dtw_online`]): the class `OnlineDtw`.
//!
//! Checks the arrays (ndarray, float64 / int64, number of dimensions; a copy only when an
//! array is not C-contiguous), advances the rows with the GIL released and hands the costs to
//! numpy without a copy. Value checks (offsets, NaN/inf) live in the kernel and come back as
//! `ValueError`.

use numpy::{IntoPyArray, PyArray1, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::arrays::{check_dtype, f64_values, i64_values, ndarray, shape_str, F64Array};
use crate::dtw_online;

/// Open-end costs (f64) and the reference frames reached (i64), one per reference.
type CostsAndPositions<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<i64>>);

/// Open-end DTW of a growing query against fixed references, one row per reference.
///
/// ``OnlineDtw(references, offsets)``: references ``(frames, dim)`` float64 one after
/// another, ``offsets`` ``(n_references,)`` int64 first frame of each. ``push(frames)`` adds
/// ``(k, dim)`` query frames; ``costs()`` gives ``D(n−1, m−1) / (n + m)`` per reference (equal
/// to :func:`dtw_distances` of the whole query), ``open_end()`` the best prefix cost
/// ``min_j D(n−1, j) / (n + j + 1)`` and its ``j``; ``reset()`` starts a new query. Memory is
/// fixed at construction (``memory_bytes``).
#[pyclass(name = "OnlineDtw", module = "visprim._visprim")]
struct OnlineDtw {
    inner: dtw_online::OnlineDtw,
}

fn two_d<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<(F64Array<'py>, usize)> {
    let arr = ndarray(obj, name, "float64")?;
    check_dtype::<f64>(arr, name, "float64")?;
    if arr.ndim() != 2 {
        return Err(PyValueError::new_err(format!(
            "{name} must be 2-D (frames, channels), got shape {}",
            shape_str(arr.shape())
        )));
    }
    let cols = arr.shape()[1];
    Ok((f64_values(arr)?, cols))
}

#[pymethods]
impl OnlineDtw {
    #[new]
    fn new(
        py: Python<'_>,
        references: &Bound<'_, PyAny>,
        offsets: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let (arr_values, dim) = two_d(references, "references")?;
        let values = arr_values.values();
        let values: &[f64] = &values;
        let arr = ndarray(offsets, "offsets", "int64")?;
        check_dtype::<i64>(arr, "offsets", "int64")?;
        if arr.ndim() != 1 {
            return Err(PyValueError::new_err(format!(
                "offsets must be 1-D (the first frame of each reference), got shape {}",
                shape_str(arr.shape())
            )));
        }
        let off = i64_values(arr, "offsets")?;
        let inner = py.detach(|| dtw_online::OnlineDtw::new(values, &off, dim))?;
        Ok(Self { inner })
    }

    /// Advance by the query frames ``frames`` ``(k, dim)`` float64 (``k = 0`` allowed).
    fn push(&mut self, py: Python<'_>, frames: &Bound<'_, PyAny>) -> PyResult<()> {
        let (arr_values, dim) = two_d(frames, "frames")?;
        if dim != self.inner.dim() {
            return Err(PyValueError::new_err(format!(
                "frames have {dim} channels but the references have {}",
                self.inner.dim()
            )));
        }
        let values = arr_values.values();
        let values: &[f64] = &values;
        let inner = &mut self.inner;
        py.detach(|| inner.push(values))?;
        Ok(())
    }

    /// ``(n_references,)`` closed-end costs of the query so far (inf before any frame).
    fn costs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let mut out = vec![0.0; self.inner.n_references()];
        self.inner.closed_end_costs(&mut out)?;
        Ok(out.into_pyarray(py))
    }

    /// ``(costs, positions)``: open-end cost per reference and the reference frame reached.
    fn open_end<'py>(&self, py: Python<'py>) -> PyResult<CostsAndPositions<'py>> {
        let n = self.inner.n_references();
        let mut costs = vec![0.0; n];
        let mut at = vec![0usize; n];
        self.inner.open_end(&mut costs, &mut at)?;
        let at: Vec<i64> = at.into_iter().map(|j| j as i64).collect();
        Ok((costs.into_pyarray(py), at.into_pyarray(py)))
    }

    /// ``(best, confidence, cost)``: the reference of the smallest open-end cost, ``1 − d₁ /
    /// d₂`` against the best reference of another label (``codes`` ``(n_references,)`` int64,
    /// one label code per reference; 1 if every label is the same, 0 before any frame) and
    /// that cost ``d₁``.
    fn running(&self, py: Python<'_>, codes: &Bound<'_, PyAny>) -> PyResult<(usize, f64, f64)> {
        let arr = ndarray(codes, "codes", "int64")?;
        check_dtype::<i64>(arr, "codes", "int64")?;
        if arr.ndim() != 1 {
            return Err(PyValueError::new_err(format!(
                "codes must be 1-D (one label code per reference), got shape {}",
                shape_str(arr.shape())
            )));
        }
        let codes = i64_values(arr, "codes")?;
        let inner = &self.inner;
        let mut costs = crate::buffer::try_filled(inner.n_references(), 0.0, "the open-end costs")?;
        Ok(py.detach(|| inner.running(&codes, &mut costs))?)
    }

    /// Forget the query.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// Query frames pushed since the start or the last reset.
    #[getter]
    fn n_frames(&self) -> usize {
        self.inner.n_frames()
    }

    /// Number of references.
    #[getter]
    fn n_references(&self) -> usize {
        self.inner.n_references()
    }

    /// Channels per frame.
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    /// Bytes held by the references and the rows (fixed at construction).
    #[getter]
    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<OnlineDtw>()?;
    Ok(())
}
