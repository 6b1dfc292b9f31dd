//! Scalar arguments: Python integers and floats of any size, checked against their range.
//!
//! PyO3's own conversions raise `OverflowError` for a negative value given as `usize` or for
//! an integer beyond 64 bits. The bindings take integer arguments as [`Int`] instead: any
//! Python integer (or object with `__index__`, e.g. numpy integers) is accepted, and a value
//! outside the argument's range, however large, becomes a `ValueError` that names the argument
//! and the range. A non-integer (a float, a string) is a `TypeError` naming the argument.
//! Float arguments are taken as [`Real`]: an integer too large for a float becomes infinity,
//! which the kernels refuse with a `ValueError` naming the argument.

use pyo3::exceptions::{PyOverflowError, PyValueError};
use pyo3::prelude::*;
use pyo3::Borrowed;

/// Largest `n_threads` accepted (a local pool of that many threads is started).
pub(crate) const MAX_THREADS: usize = 1024;

/// A Python integer of any size.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Int {
    /// A value that fits in 64 bits.
    Small(i64),
    /// A larger value (`negative`: below `i64::MIN`), with its decimal text for messages.
    Huge { negative: bool, text: String },
}

impl<'a, 'py> FromPyObject<'a, 'py> for Int {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        match obj.extract::<i64>() {
            Ok(v) => Ok(Int::Small(v)),
            Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => Ok(Int::Huge {
                negative: obj.lt(0)?,
                text: obj.str()?.to_string(),
            }),
            Err(e) => Err(e),
        }
    }
}

impl Int {
    /// The value in `[min, max]`; `what` explains the argument in the error message.
    pub(crate) fn in_range(&self, name: &str, min: i64, max: i64, what: &str) -> PyResult<i64> {
        match self {
            Int::Small(v) if (min..=max).contains(v) => Ok(*v),
            _ => {
                let hi = if max == i64::MAX {
                    String::new()
                } else {
                    format!(" and <= {max}")
                };
                let got = match self {
                    Int::Small(v) => v.to_string(),
                    Int::Huge { text, .. } => text.clone(),
                };
                Err(PyValueError::new_err(format!(
                    "{name} ({what}) must be an integer >= {min}{hi}, got {got}"
                )))
            }
        }
    }

    /// A count or size in `[min, max]` (see [`Int::in_range`]).
    pub(crate) fn usize_in(
        &self,
        name: &str,
        min: usize,
        max: usize,
        what: &str,
    ) -> PyResult<usize> {
        let lo = i64::try_from(min).unwrap_or(i64::MAX);
        let hi = i64::try_from(max).unwrap_or(i64::MAX);
        // Non-negative: the lower bound is.
        self.in_range(name, lo, hi, what).map(|v| v as usize)
    }
}

/// An optional [`Int::usize_in`] argument (`None` stays `None`).
pub(crate) fn opt_usize_in(
    arg: Option<Int>,
    name: &str,
    min: usize,
    max: usize,
    what: &str,
) -> PyResult<Option<usize>> {
    arg.map(|a| a.usize_in(name, min, max, what)).transpose()
}

/// The optional `n_threads` argument: `1..=MAX_THREADS`, `None` for all cores.
pub(crate) fn n_threads_arg(arg: Option<Int>) -> PyResult<Option<usize>> {
    opt_usize_in(
        arg,
        "n_threads",
        1,
        MAX_THREADS,
        "threads to use; None for all cores",
    )
}

/// A real number; an integer too large for a float becomes an infinity of its sign (refused
/// by the kernels' finiteness checks, with the argument's name).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Real(pub f64);

impl<'a, 'py> FromPyObject<'a, 'py> for Real {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        match obj.extract::<f64>() {
            Ok(v) => Ok(Real(v)),
            Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => Ok(Real(if obj.lt(0)? {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            })),
            Err(e) => Err(e),
        }
    }
}
