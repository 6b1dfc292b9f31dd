//! Bindings of the signal kernels (filter, velocity, zero-velocity crossings, SEG-1 events,
//! time to frame conversion, resampling).
//!
//! Each function only converts and checks its Python arguments (ndarray type, dtype, ndim; a
//! copy when an array is not C-contiguous), runs the pure kernel with the GIL released, and
//! returns numpy arrays that take ownership of the kernel's buffers (no copy). Value checks
//! (NaN/inf, ranges, lengths) live in the kernels and come back as `ValueError`.

use numpy::ndarray::{Array2, ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::args::{opt_usize_in, Int, Real};
use super::arrays::{check_dtype, f64_values, i64_values, ndarray, shape_str, F64Array};
use crate::filter::{self, Sos};
use crate::{clock, gradient, resample, seg1, zvc};

/// `obj` as a float64 array with one of the allowed numbers of dimensions.
fn f64_arg<'py>(obj: &Bound<'py, PyAny>, name: &str, ndims: &[usize]) -> PyResult<F64Array<'py>> {
    let arr = ndarray(obj, name, "float64")?;
    check_dtype::<f64>(arr, name, "float64")?;
    if !ndims.contains(&arr.ndim()) {
        let want = ndims
            .iter()
            .map(|d| format!("{d}-D"))
            .collect::<Vec<_>>()
            .join(" or ");
        return Err(PyValueError::new_err(format!(
            "{name} must be {want}, got shape {}",
            shape_str(arr.shape())
        )));
    }
    f64_values(arr)
}

/// A 1-D int64 array argument, copied to a vector; `detail` says what it holds (for the
/// message of a wrong number of dimensions).
fn i64_arg(obj: &Bound<'_, PyAny>, name: &str, detail: &str) -> PyResult<Vec<i64>> {
    let arr = ndarray(obj, name, "int64")?;
    check_dtype::<i64>(arr, name, "int64")?;
    if arr.ndim() != 1 {
        return Err(PyValueError::new_err(format!(
            "{name} must be 1-D{detail}, got shape {}",
            shape_str(arr.shape())
        )));
    }
    i64_values(arr, name)
}

/// `times` `(frames,)` and the float64 `(frames, channels)` (1-D: one channel) array `values`
/// named `name`, with their number of channels; the frame counts must match.
fn timed_frames<'py>(
    times: &Bound<'py, PyAny>,
    values: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<(F64Array<'py>, F64Array<'py>, usize)> {
    let t = f64_arg(times, "times", &[1])?;
    let v = f64_arg(values, name, &[1, 2])?;
    let (frames, channels) = frames_channels(&v.shape);
    if t.shape[0] != frames {
        return Err(PyValueError::new_err(format!(
            "times must have shape ({frames},) to match {name} {}, got {}",
            shape_str(&v.shape),
            shape_str(&t.shape)
        )));
    }
    Ok((t, v, channels))
}

/// `offsets` as a 1-D int64 array, copied to a vector.
fn offsets_arg(obj: &Bound<'_, PyAny>) -> PyResult<Vec<i64>> {
    i64_arg(obj, "offsets", " (the first frame of each trial)")
}

/// A 1-D int64 array argument, copied to a vector.
fn i64_vec(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<i64>> {
    i64_arg(obj, name, "")
}

/// `sos` as a list of sections.
fn sos_arg(obj: &Bound<'_, PyAny>) -> PyResult<Vec<Sos>> {
    let arg = f64_arg(obj, "sos", &[2])?;
    if arg.shape[1] != 6 {
        return Err(PyValueError::new_err(format!(
            "sos must have shape (n_sections, 6), got {}",
            shape_str(&arg.shape)
        )));
    }
    Ok(arg
        .values()
        .chunks_exact(6)
        .map(|c| c.try_into().expect("chunks of 6"))
        .collect())
}

fn padlen_arg(padlen: Option<Int>) -> PyResult<Option<usize>> {
    opt_usize_in(
        padlen,
        "padlen",
        0,
        usize::MAX,
        "samples of odd extension at each end",
    )
}

fn min_change_arg(min_change: Real) -> PyResult<f64> {
    let min_change = min_change.0;
    if !(min_change.is_finite() && min_change >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "min_change must be a finite number >= 0, got {min_change}"
        )));
    }
    Ok(min_change)
}

/// Rows x channels of a 1-D (one channel) or 2-D `(frames, channels)` argument.
fn frames_channels(shape: &[usize]) -> (usize, usize) {
    match shape {
        [n] => (*n, 1),
        [n, c] => (*n, *c),
        _ => unreachable!("ndim checked"),
    }
}

/// Low-pass Butterworth design as second-order sections, `(n_sections, 6)`, equal to
/// `scipy.signal.butter(order, cutoff, output="sos")`.
#[pyfunction]
fn butter_sos<'py>(
    py: Python<'py>,
    order: Int,
    cutoff: Real,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let order = order.usize_in("order", 1, filter::MAX_ORDER, "the filter order")?;
    let sos = filter::butter_sos(order, cutoff.0)?;
    let n = sos.len();
    let flat: Vec<f64> = sos.into_iter().flatten().collect();
    PyArray1::from_vec(py, flat).reshape([n, 6])
}

/// scipy's default `padlen` of `sosfiltfilt` for this filter (samples of odd extension at each
/// end; a signal must be longer).
#[pyfunction]
fn default_padlen(sos: &Bound<'_, PyAny>) -> PyResult<usize> {
    let sos = sos_arg(sos)?;
    filter::validate_sos(&sos)?;
    Ok(filter::default_padlen(&sos))
}

/// Zero-phase filtering along the last axis of a 1-D or 2-D float64 array, equal to
/// `scipy.signal.sosfiltfilt(sos, x, padlen=padlen)`.
#[pyfunction]
#[pyo3(signature = (sos, x, padlen=None))]
fn sosfiltfilt<'py>(
    py: Python<'py>,
    sos: &Bound<'py, PyAny>,
    x: &Bound<'py, PyAny>,
    padlen: Option<Int>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let sos = sos_arg(sos)?;
    let padlen = padlen_arg(padlen)?;
    let x = f64_arg(x, "x", &[1, 2])?;
    let (rows, n) = match x.shape[..] {
        [n] => (1, n),
        [r, n] => (r, n),
        _ => unreachable!("ndim checked"),
    };
    let values = x.values();
    let values: &[f64] = &values;
    let out = py.detach(|| filter::sosfiltfilt_rows(&sos, values, rows, n, padlen))?;
    Ok(ArrayD::from_shape_vec(IxDyn(&x.shape), out)
        .expect("shape of the input")
        .into_pyarray(py))
}

/// Zero-phase filtering of every trial of a ragged corpus `values` `(total_frames, channels)`
/// (or 1-D, one channel) along time, trial `i` starting at frame `offsets[i]`.
#[pyfunction]
#[pyo3(signature = (sos, values, offsets, padlen=None))]
fn sosfiltfilt_ragged<'py>(
    py: Python<'py>,
    sos: &Bound<'py, PyAny>,
    values: &Bound<'py, PyAny>,
    offsets: &Bound<'py, PyAny>,
    padlen: Option<Int>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let sos = sos_arg(sos)?;
    let padlen = padlen_arg(padlen)?;
    let v = f64_arg(values, "values", &[1, 2])?;
    let offsets = offsets_arg(offsets)?;
    let (_, channels) = frames_channels(&v.shape);
    let data = v.values();
    let data: &[f64] = &data;
    let out = py.detach(|| filter::sosfiltfilt_ragged(&sos, data, channels, &offsets, padlen))?;
    Ok(ArrayD::from_shape_vec(IxDyn(&v.shape), out)
        .expect("shape of the input")
        .into_pyarray(py))
}

/// `positions` checked against the velocity's shape.
fn positions_arg<'py>(
    positions: Option<&Bound<'py, PyAny>>,
    shape: &[usize],
) -> PyResult<Option<F64Array<'py>>> {
    let Some(p) = positions else { return Ok(None) };
    let p = f64_arg(p, "positions", &[1, 2])?;
    if p.shape != shape {
        return Err(PyValueError::new_err(format!(
            "positions must have the shape of velocity {}, got {}",
            shape_str(shape),
            shape_str(&p.shape)
        )));
    }
    Ok(Some(p))
}

type Crossings1<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<i64>>);

/// Zero-velocity crossings of `velocity` `(frames, channels)` (1-D: one channel) as
/// `(frames float64, channels int64)`, sorted by channel then frame.
#[pyfunction]
#[pyo3(signature = (velocity, min_change=Real(0.0), positions=None))]
fn zero_velocity_crossings<'py>(
    py: Python<'py>,
    velocity: &Bound<'py, PyAny>,
    min_change: Real,
    positions: Option<&Bound<'py, PyAny>>,
) -> PyResult<Crossings1<'py>> {
    let v = f64_arg(velocity, "velocity", &[1, 2])?;
    let min_change = min_change_arg(min_change)?;
    let p = positions_arg(positions, &v.shape)?;
    let (_, channels) = frames_channels(&v.shape);
    let vel = v.values();
    let vel: &[f64] = &vel;
    let pos = p.as_ref().map(|p| p.values());
    let pos: Option<&[f64]> = pos.as_deref();
    let (frames, chans) =
        py.detach(|| zvc::zero_velocity_crossings(vel, channels, min_change, pos))?;
    Ok((frames.into_pyarray(py), chans.into_pyarray(py)))
}

type Crossings3<'py> = (
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<f64>>,
);

/// Zero-velocity crossings of every trial of a ragged corpus as `(trial, channel, frame)`,
/// frames relative to each trial's first frame, sorted by trial, channel, frame.
#[pyfunction]
#[pyo3(signature = (velocity, offsets, min_change=Real(0.0), positions=None))]
fn zero_velocity_crossings_ragged<'py>(
    py: Python<'py>,
    velocity: &Bound<'py, PyAny>,
    offsets: &Bound<'py, PyAny>,
    min_change: Real,
    positions: Option<&Bound<'py, PyAny>>,
) -> PyResult<Crossings3<'py>> {
    let v = f64_arg(velocity, "velocity", &[1, 2])?;
    let offsets = offsets_arg(offsets)?;
    let min_change = min_change_arg(min_change)?;
    let p = positions_arg(positions, &v.shape)?;
    let (_, channels) = frames_channels(&v.shape);
    let vel = v.values();
    let vel: &[f64] = &vel;
    let pos = p.as_ref().map(|p| p.values());
    let pos: Option<&[f64]> = pos.as_deref();
    let c = py
        .detach(|| zvc::zero_velocity_crossings_ragged(vel, channels, &offsets, min_change, pos))?;
    Ok((
        c.trial.into_pyarray(py),
        c.channel.into_pyarray(py),
        c.frame.into_pyarray(py),
    ))
}

/// Zero-velocity crossings of the velocity (`numpy.gradient` on `times`) of `positions`
/// `(total_frames, channels)` (1-D: one channel), without a corpus-sized velocity array.
#[pyfunction]
#[pyo3(signature = (times, positions, offsets, min_change=Real(0.0)))]
fn zero_velocity_crossings_of_positions<'py>(
    py: Python<'py>,
    times: &Bound<'py, PyAny>,
    positions: &Bound<'py, PyAny>,
    offsets: &Bound<'py, PyAny>,
    min_change: Real,
) -> PyResult<Crossings3<'py>> {
    let (t, p, channels) = timed_frames(times, positions, "positions")?;
    let offsets = offsets_arg(offsets)?;
    let min_change = min_change_arg(min_change)?;
    let tv = t.values();
    let tv: &[f64] = &tv;
    let pv = p.values();
    let pv: &[f64] = &pv;
    let c = py.detach(|| {
        zvc::zero_velocity_crossings_of_positions(tv, pv, channels, &offsets, min_change)
    })?;
    Ok((
        c.trial.into_pyarray(py),
        c.channel.into_pyarray(py),
        c.frame.into_pyarray(py),
    ))
}

/// Time derivative of every trial of a ragged corpus `values` `(total_frames, channels)` (1-D:
/// one channel) on its timestamps `times` `(total_frames,)`: `numpy.gradient` per trial.
#[pyfunction]
fn gradient_ragged<'py>(
    py: Python<'py>,
    times: &Bound<'py, PyAny>,
    values: &Bound<'py, PyAny>,
    offsets: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let (t, v, channels) = timed_frames(times, values, "values")?;
    let offsets = offsets_arg(offsets)?;
    let tv = t.values();
    let tv: &[f64] = &tv;
    let data = v.values();
    let data: &[f64] = &data;
    let out = py.detach(|| gradient::gradient_ragged(tv, data, channels, &offsets))?;
    Ok(ArrayD::from_shape_vec(IxDyn(&v.shape), out)
        .expect("shape of the input")
        .into_pyarray(py))
}

type Events<'py> = (
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
);

/// SEG-1 events of crossings `(trial, channel, time)` (trial non-decreasing): `(trial, median
/// time, distinct channels)` per event, sorted by trial then time.
#[pyfunction]
fn seg1_events<'py>(
    py: Python<'py>,
    trial: &Bound<'py, PyAny>,
    channel: &Bound<'py, PyAny>,
    time: &Bound<'py, PyAny>,
    window: Real,
) -> PyResult<Events<'py>> {
    let window = window.0;
    let trial = i64_vec(trial, "trial")?;
    let channel = i64_vec(channel, "channel")?;
    let t = f64_arg(time, "time", &[1])?;
    let tv = t.values();
    let tv: &[f64] = &tv;
    let ev = py.detach(|| seg1::seg1_events(&trial, &channel, tv, window))?;
    Ok((
        ev.trial.into_pyarray(py),
        ev.time.into_pyarray(py),
        ev.n_channels.into_pyarray(py),
    ))
}

/// A kernel of [`clock`]: `(times, offsets, trial, query) -> values`.
type ClockConversion = fn(&[f64], &[i64], &[i64], &[f64]) -> crate::Result<Vec<f64>>;

/// A clock conversion of the ragged corpus's `times` (`offsets`) at the queries `(trial, q)`;
/// `query` is the query array with its argument name.
fn clock_map<'py>(
    py: Python<'py>,
    times: &Bound<'py, PyAny>,
    offsets: &Bound<'py, PyAny>,
    trial: &Bound<'py, PyAny>,
    query: (&Bound<'py, PyAny>, &str),
    convert: ClockConversion,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let times = f64_arg(times, "times", &[1])?;
    let offsets = offsets_arg(offsets)?;
    let trial = i64_vec(trial, "trial")?;
    let q = f64_arg(query.0, query.1, &[1])?;
    let tv = times.values();
    let tv: &[f64] = &tv;
    let qv = q.values();
    let qv: &[f64] = &qv;
    let out = py.detach(|| convert(tv, &offsets, &trial, qv))?;
    Ok(out.into_pyarray(py))
}

/// Fractional frames (relative to each trial's first frame) of times `t` (seconds) of trials
/// `trial`, by linear interpolation of the ragged corpus's `times`, clamped to the trial.
#[pyfunction]
fn times_to_frames<'py>(
    py: Python<'py>,
    times: &Bound<'py, PyAny>,
    offsets: &Bound<'py, PyAny>,
    trial: &Bound<'py, PyAny>,
    t: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    clock_map(py, times, offsets, trial, (t, "t"), clock::times_to_frames)
}

/// Seconds of fractional frames `frame` (relative to each trial's first frame) of trials
/// `trial`, by linear interpolation of the ragged corpus's `times`.
#[pyfunction]
fn frames_to_times<'py>(
    py: Python<'py>,
    times: &Bound<'py, PyAny>,
    offsets: &Bound<'py, PyAny>,
    trial: &Bound<'py, PyAny>,
    frame: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    clock_map(
        py,
        times,
        offsets,
        trial,
        (frame, "frame"),
        clock::frames_to_times,
    )
}

/// Each segment `[starts[i], ends[i]]` (fractional frames) of `values` `(frames, channels)`
/// linearly resampled to `n` points per channel: `(n_segments, channels * n)`, channel-major.
#[pyfunction]
#[pyo3(signature = (values, starts, ends, n=Int::Small(100)))]
fn resample_segments<'py>(
    py: Python<'py>,
    values: &Bound<'py, PyAny>,
    starts: &Bound<'py, PyAny>,
    ends: &Bound<'py, PyAny>,
    n: Int,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let v = f64_arg(values, "values", &[1, 2])?;
    let s = f64_arg(starts, "starts", &[1])?;
    let e = f64_arg(ends, "ends", &[1])?;
    let n = n.usize_in("n", 2, usize::MAX, "samples per channel")?;
    let (_, channels) = frames_channels(&v.shape);
    let data = v.values();
    let data: &[f64] = &data;
    let starts = s.values();
    let starts: &[f64] = &starts;
    let ends = e.values();
    let ends: &[f64] = &ends;
    let out = py.detach(|| resample::resample_segments(data, channels, starts, ends, n))?;
    let rows = starts.len();
    let row = resample::output_row(channels, n)?;
    Ok(Array2::from_shape_vec((rows, row), out)
        .expect("kernel output has the announced shape")
        .into_pyarray(py))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(butter_sos, m)?)?;
    m.add_function(wrap_pyfunction!(default_padlen, m)?)?;
    m.add_function(wrap_pyfunction!(sosfiltfilt, m)?)?;
    m.add_function(wrap_pyfunction!(sosfiltfilt_ragged, m)?)?;
    m.add_function(wrap_pyfunction!(gradient_ragged, m)?)?;
    m.add_function(wrap_pyfunction!(zero_velocity_crossings, m)?)?;
    m.add_function(wrap_pyfunction!(zero_velocity_crossings_ragged, m)?)?;
    m.add_function(wrap_pyfunction!(seg1_events, m)?)?;
    m.add_function(wrap_pyfunction!(times_to_frames, m)?)?;
    m.add_function(wrap_pyfunction!(zero_velocity_crossings_of_positions, m)?)?;
    m.add_function(wrap_pyfunction!(frames_to_times, m)?)?;
    m.add_function(wrap_pyfunction!(resample_segments, m)?)?;
    Ok(())
}
