//! Binding of the causal stream filter ([`crate::sosfilt_online`]): the class `CausalSos`.
//!
//! Checks the arrays (ndarray, float64, number of dimensions, channels), filters a copy of the
//! chunk with the GIL released and hands it to numpy without a further copy. Value checks
//! (NaN/inf, sections) live in the kernel and come back as `ValueError`.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::arrays::{check_dtype, f64_values, ndarray, shape_str, F64Array};
use crate::filter::Sos;
use crate::sosfilt_online;

/// Causal ``sosfilt`` of a ``(frames, channels)`` stream, state kept between chunks.
///
/// ``CausalSos(sos, channels)``: ``sos`` ``(n_sections, 6)`` float64 (``a0 == 1``).
/// ``filter(x)`` returns the filtered ``(k, channels)`` chunk (``k = 0`` allowed); the first
/// frame of the stream starts the filter in its steady state (``sosfilt_zi · x[0]``), as
/// ``scipy.signal.sosfilt`` with that ``zi``. The output does not depend on how the stream is
/// cut into chunks. ``reset()`` starts a new stream.
#[pyclass(name = "CausalSos", module = "visprim._visprim")]
struct CausalSos {
    inner: sosfilt_online::CausalSos,
}

fn two_d<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<(F64Array<'py>, usize, usize)> {
    let arr = ndarray(obj, name, "float64")?;
    check_dtype::<f64>(arr, name, "float64")?;
    if arr.ndim() != 2 {
        return Err(PyValueError::new_err(format!(
            "{name} must be 2-D, got shape {}",
            shape_str(arr.shape())
        )));
    }
    let (rows, cols) = (arr.shape()[0], arr.shape()[1]);
    Ok((f64_values(arr)?, rows, cols))
}

#[pymethods]
impl CausalSos {
    #[new]
    fn new(sos: &Bound<'_, PyAny>, channels: usize) -> PyResult<Self> {
        let (values, _, cols) = two_d(sos, "sos")?;
        if cols != 6 {
            return Err(PyValueError::new_err(format!(
                "sos must have shape (n_sections, 6), got {} columns",
                cols
            )));
        }
        let sections: Vec<Sos> = values
            .values()
            .chunks_exact(6)
            .map(|c| c.try_into().expect("chunks of 6"))
            .collect();
        Ok(Self {
            inner: sosfilt_online::CausalSos::new(&sections, channels)?,
        })
    }

    /// The filtered chunk ``x`` ``(k, channels)`` float64, as a new array.
    fn filter<'py>(
        &mut self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (values, rows, cols) = two_d(x, "x")?;
        if cols != self.inner.channels() {
            return Err(PyValueError::new_err(format!(
                "x has {cols} channels but the filter has {}",
                self.inner.channels()
            )));
        }
        let mut out = values.values().into_owned();
        let inner = &mut self.inner;
        py.detach(|| inner.filter(&mut out))?;
        let arr = Array2::from_shape_vec((rows, cols), out)
            .map_err(|e| PyValueError::new_err(format!("x: {e}")))?;
        Ok(arr.into_pyarray(py))
    }

    /// Forget the stream.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// Channels per frame.
    #[getter]
    fn channels(&self) -> usize {
        self.inner.channels()
    }

    /// Bytes held by the sections and the state (fixed at construction).
    #[getter]
    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<CausalSos>()?;
    Ok(())
}
