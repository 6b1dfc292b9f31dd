//! Binding of the causal stream resampler ([`crate::resample_online`]): the class
//! `StreamResampler`.
//!
//! Checks the arrays (ndarray, float64, shapes; a copy only when an array is not
//! C-contiguous), resamples with the GIL released and hands the frames to numpy without a
//! further copy. Value checks (NaN/inf, times) live in the kernel and come back as
//! `ValueError`.

use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::arrays::{check_dtype, f64_values, ndarray, shape_str};
use crate::resample_online;

/// A stream's frames onto a clock of ``period`` seconds from its first frame, causally.
///
/// ``StreamResampler(period, width, rotations_from=None, max_gap=inf)``: frames of
/// ``width`` values; columns from ``rotations_from`` on are row-major 3×3 rotation
/// matrices, brought back to the nearest rotation after interpolation. ``push(times,
/// rows)`` (``(k,)`` s, ``(k, width)``) returns ``(times (m,), arrivals (m,), rows (m,
/// width), dropped, unchanged, breaks)``: the clock's frames the chunk completes, each the
/// input frame on it or the linear interpolation of the two around it (independent of how
/// the stream is cut into chunks); ``arrivals`` the time of the input frame that completed
/// each; ``dropped`` the input frames left out for a NaN or infinite value; ``unchanged``
/// whether the output frames are the input ones, one for one; ``breaks`` the indices of
/// the output frames where the clock starts again after a gap longer than ``max_gap``
/// seconds between kept frames (not interpolated across). ``reset()`` starts a new stream.
#[pyclass(name = "StreamResampler", module = "visprim._visprim")]
struct StreamResampler {
    inner: resample_online::StreamResampler,
}

type Pushed<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    usize,
    bool,
    Vec<usize>,
);

#[pymethods]
impl StreamResampler {
    #[new]
    #[pyo3(signature = (period, width, rotations_from=None, max_gap=f64::INFINITY))]
    fn new(
        period: f64,
        width: usize,
        rotations_from: Option<usize>,
        max_gap: f64,
    ) -> PyResult<Self> {
        Ok(Self {
            inner: resample_online::StreamResampler::new(period, width, rotations_from, max_gap)?,
        })
    }

    /// The clock's frames completed by the chunk (class docstring).
    fn push<'py>(
        &mut self,
        py: Python<'py>,
        times: &Bound<'py, PyAny>,
        rows: &Bound<'py, PyAny>,
    ) -> PyResult<Pushed<'py>> {
        let t = ndarray(times, "times", "float64")?;
        check_dtype::<f64>(t, "times", "float64")?;
        let x = ndarray(rows, "rows", "float64")?;
        check_dtype::<f64>(x, "rows", "float64")?;
        let width = self.inner.width();
        if t.ndim() != 1 || x.ndim() != 2 || x.shape()[0] != t.shape()[0] || x.shape()[1] != width {
            return Err(PyValueError::new_err(format!(
                "need times (k,) and rows (k, {width}), got {} and {}",
                shape_str(t.shape()),
                shape_str(x.shape())
            )));
        }
        let (t, x) = (f64_values(t)?, f64_values(x)?);
        let mut out = resample_online::Resampled::default();
        let (tv, xv) = (t.values(), x.values());
        let (ts, xs): (&[f64], &[f64]) = (&tv, &xv);
        let inner = &mut self.inner;
        py.detach(|| inner.push(ts, xs, &mut out))?;
        let m = out.times.len();
        let rows = Array2::from_shape_vec((m, width), out.rows)
            .map_err(|e| PyValueError::new_err(format!("rows: {e}")))?;
        Ok((
            Array1::from_vec(out.times).into_pyarray(py),
            Array1::from_vec(out.arrivals).into_pyarray(py),
            rows.into_pyarray(py),
            out.dropped,
            out.unchanged,
            out.breaks,
        ))
    }

    /// Forget the stream.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// The clock's period, seconds.
    #[getter]
    fn period(&self) -> f64 {
        self.inner.period()
    }

    /// Values per frame.
    #[getter]
    fn width(&self) -> usize {
        self.inner.width()
    }

    /// Clock frames emitted since the stream began.
    #[getter]
    fn emitted(&self) -> u64 {
        self.inner.emitted()
    }

    /// Bytes held by the state.
    #[getter]
    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<StreamResampler>()?;
    Ok(())
}
