//! Binding of the online segmenter's front end ([`crate::front_online`]): the class
//! `OnlineFrontEnd`.
//!
//! Checks the arguments (ndarray, float64, shapes against the arms; a copy only when an array
//! is not C-contiguous), runs the kernel with the GIL released and hands its outputs to numpy
//! without a further copy. Value checks (NaN/inf, timestamps, zero-length bones) live in the
//! kernel and come back as `ValueError`.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::arrays::{check_dtype, f64_values, ndarray, shape_str, F64Array};
use crate::filter::Sos;
use crate::front_online::{self, Chunk, Config, Features, Output, Threshold, SPEED_COLUMNS};

/// ``(angles (k, 4 n_arms), values (k, channels), directions (k, 6 n_arms), speeds (m, 4))``.
type PushOutput<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// The online segmenter's stages 1–3 and its threshold, state kept between chunks.
///
/// ``OnlineFrontEnd(sos, arms, features, singular_angle, c, adaptive, quantile, fraction,
/// slowest, every, speed_window)``: ``sos`` ``(n_sections, 6)`` float64, the causal
/// low-pass of the angles; ``arms`` ``["right"]``, ``["right", "left"]``, ...; ``features``
/// ``"zyz"`` or ``"directions"``; ``singular_angle`` radians; the threshold ``c``
/// (rad/s)², adaptive or not, ``quantile`` of ``z`` over ``speed_window`` seconds, scaled
/// by ``fraction``, not below ``c / slowest``, recomputed every ``every`` frames.
///
/// ``push(times, markers, joints=None, body_frame=None)`` (``(k,)`` s, ``(k, 4 n_arms, 3)``
/// m, ``(k, 3 n_arms, 3)`` m, ``(k, 3, 3)``) returns ``(angles, values, directions,
/// speeds)``: the raw arm angles ``(k, 4 n_arms)`` radians, the low-passed channels
/// ``(k, channels)``, the unit bone directions in the torso's axes ``(k, 6 n_arms)`` and, for
/// the ``m`` frames whose velocity became known (all but the newest), the rows
/// ``(z, t, decided_at, threshold)``. ``push_values(times, values)`` gives the speeds of
/// already filtered channels, ``finish()`` those of the last frame (backward difference),
/// ``reset()`` starts a new stream.
#[pyclass(name = "OnlineFrontEnd", module = "visprim._visprim")]
struct OnlineFrontEnd {
    inner: front_online::OnlineFrontEnd,
}

fn array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    shape: &[Option<usize>],
) -> PyResult<F64Array<'py>> {
    let arr = ndarray(obj, name, "float64")?;
    check_dtype::<f64>(arr, name, "float64")?;
    let got = arr.shape();
    let fits = got.len() == shape.len()
        && got
            .iter()
            .zip(shape)
            .all(|(&g, w)| w.is_none_or(|w| g == w));
    if !fits {
        let want: Vec<String> = shape
            .iter()
            .map(|w| w.map_or("k".into(), |v| v.to_string()))
            .collect();
        return Err(PyValueError::new_err(format!(
            "{name} must have shape ({}), got {}",
            want.join(", "),
            shape_str(got)
        )));
    }
    f64_values(arr)
}

fn matrix<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let rows = values.len().checked_div(cols).unwrap_or(0);
    let arr = Array2::from_shape_vec((rows, cols), values)
        .map_err(|e| PyValueError::new_err(format!("output: {e}")))?;
    Ok(arr.into_pyarray(py))
}

#[pymethods]
impl OnlineFrontEnd {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (sos, arms, features, singular_angle, c, adaptive, quantile, fraction, slowest, every, speed_window))]
    fn new(
        sos: &Bound<'_, PyAny>,
        arms: Vec<String>,
        features: &str,
        singular_angle: f64,
        c: f64,
        adaptive: bool,
        quantile: f64,
        fraction: f64,
        slowest: f64,
        every: usize,
        speed_window: f64,
    ) -> PyResult<Self> {
        let sections = sos_sections(sos)?;
        let left = arms
            .iter()
            .map(|a| match a.as_str() {
                "right" => Ok(false),
                "left" => Ok(true),
                other => Err(PyValueError::new_err(format!(
                    "arms must be 'right' or 'left', got {other:?}"
                ))),
            })
            .collect::<PyResult<Vec<bool>>>()?;
        let features = features_arg(features)?;
        let cfg = Config {
            left,
            features,
            singular_angle,
            sos: sections,
            threshold: Threshold {
                c,
                adaptive,
                quantile,
                fraction,
                slowest,
                every,
                speed_window,
            },
        };
        Ok(Self {
            inner: front_online::OnlineFrontEnd::new(cfg)?,
        })
    }

    /// Stages 1–3 of a chunk of raw frames (class docstring).
    #[pyo3(signature = (times, markers, joints=None, body_frame=None))]
    fn push<'py>(
        &mut self,
        py: Python<'py>,
        times: &Bound<'py, PyAny>,
        markers: &Bound<'py, PyAny>,
        joints: Option<&Bound<'py, PyAny>>,
        body_frame: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<PushOutput<'py>> {
        let n_arms = self.inner.n_arms();
        let t = array(times, "times", &[None])?;
        let k = Some(t.shape[0]);
        let m = array(markers, "markers", &[k, Some(4 * n_arms), Some(3)])?;
        let j = joints
            .filter(|o| !o.is_none())
            .map(|o| array(o, "joints", &[k, Some(3 * n_arms), Some(3)]))
            .transpose()?;
        let b = body_frame
            .filter(|o| !o.is_none())
            .map(|o| array(o, "body_frame", &[k, Some(3), Some(3)]))
            .transpose()?;
        let (tv, mv) = (t.values(), m.values());
        let jv = j.as_ref().map(|a| a.values());
        let bv = b.as_ref().map(|a| a.values());
        let chunk = Chunk {
            times: &tv,
            markers: &mv,
            joints: jv.as_deref(),
            body_frame: bv.as_deref(),
        };
        let mut out = Output::default();
        let inner = &mut self.inner;
        py.detach(|| inner.push(chunk, &mut out))?;
        let channels = self.inner.channels();
        Ok((
            matrix(py, out.angles, 4 * n_arms)?,
            matrix(py, out.values, channels)?,
            matrix(py, out.directions, 6 * n_arms)?,
            matrix(py, out.speeds, SPEED_COLUMNS)?,
        ))
    }

    /// The speed rows of already filtered channels ``values`` ``(k, channels)`` at ``times``.
    fn push_values<'py>(
        &mut self,
        py: Python<'py>,
        times: &Bound<'py, PyAny>,
        values: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = array(times, "times", &[None])?;
        let v = array(
            values,
            "values",
            &[Some(t.shape[0]), Some(self.inner.channels())],
        )?;
        let (tv, vv) = (t.values(), v.values());
        let mut out = Output::default();
        let inner = &mut self.inner;
        py.detach(|| inner.push_values(&tv, &vv, &mut out))?;
        matrix(py, out.speeds, SPEED_COLUMNS)
    }

    /// The speed rows of the frames still waiting (the end of the stream).
    fn finish<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let mut out = Output::default();
        let inner = &mut self.inner;
        py.detach(|| inner.finish(&mut out))?;
        matrix(py, out.speeds, SPEED_COLUMNS)
    }

    /// Forget the stream (the frame period and window the first chunk set are kept).
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// Channels per frame.
    #[getter]
    fn channels(&self) -> usize {
        self.inner.channels()
    }

    /// Frames received.
    #[getter]
    fn n_frames(&self) -> usize {
        self.inner.n_frames()
    }

    /// Frame period set by the first chunk (seconds), None before it.
    #[getter]
    fn period(&self) -> Option<f64> {
        self.inner.period()
    }

    /// Frames of the adaptive threshold's window, None before the first chunk or when fixed.
    #[getter]
    fn window_frames(&self) -> Option<usize> {
        self.inner.window_frames()
    }

    /// Bytes held by the state.
    #[getter]
    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }
}

/// The second-order sections of ``sos`` ``(n_sections, 6)``, float64.
fn sos_sections(sos: &Bound<'_, PyAny>) -> PyResult<Vec<Sos>> {
    let values = array(sos, "sos", &[None, Some(6)])?;
    Ok(values
        .values()
        .chunks_exact(6)
        .map(|s| s.try_into().expect("chunks of 6"))
        .collect())
}

fn features_arg(features: &str) -> PyResult<Features> {
    match features {
        "zyz" => Ok(Features::Zyz),
        "directions" => Ok(Features::Directions),
        other => Err(PyValueError::new_err(format!(
            "features must be 'zyz' or 'directions', got {other:?}"
        ))),
    }
}

/// ``segment_channels(sos, raw, start, stop, features)``: the channels ``(stop − start,
/// channels)`` of frames ``start:stop`` of the raw arm angles ``raw`` ``(n, 4 n_arms)``
/// radians after the zero-phase filter ``sos`` ``(n_sections, 6)`` of the whole window
/// (scipy's default padding, ``n − 1`` frames for a shorter window), ``features``
/// ``"zyz"`` or ``"directions"`` (:mod:`visprim.online.segmenter`). ValueError for bad
/// shapes, ``not start < stop <= n`` or a non-finite angle.
#[pyfunction]
fn segment_channels<'py>(
    py: Python<'py>,
    sos: &Bound<'py, PyAny>,
    raw: &Bound<'py, PyAny>,
    start: usize,
    stop: usize,
    features: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let features = features_arg(features)?;
    let sections = sos_sections(sos)?;
    let r = array(raw, "raw", &[None, None])?;
    let width = r.shape[1];
    let values = r.values();
    let out = py.detach(|| {
        crate::segment_online::segment_channels(&sections, &values, width, start, stop, features)
    })?;
    matrix(py, out, width / 4 * features.per_arm())
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<OnlineFrontEnd>()?;
    m.add_function(wrap_pyfunction!(segment_channels, m)?)?;
    Ok(())
}
