//! Array arguments shared by the bindings: the ndarray type check, the dtype check and
//! read-only float64 / int64 values, with one wording for their errors.

use std::borrow::Cow;

use numpy::{
    Element, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

/// A read-only float64 array argument and its shape.
pub(crate) struct F64Array<'py> {
    arr: PyReadonlyArrayDyn<'py, f64>,
    pub shape: Vec<usize>,
}

impl F64Array<'_> {
    /// The values in C (row-major) order: borrowed when the array is C-contiguous, else copied.
    pub fn values(&self) -> Cow<'_, [f64]> {
        let view = self.arr.as_array();
        match view.to_slice() {
            Some(s) => Cow::Borrowed(s),
            None => Cow::Owned(view.iter().copied().collect()),
        }
    }
}

/// `(n,)` or `(a, b, ...)`, as numpy prints shapes.
pub(crate) fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// `obj` as a numpy array; otherwise a `TypeError` whose message `message` builds from the
/// name of `obj`'s type.
pub(crate) fn ndarray_or<'a, 'py>(
    obj: &'a Bound<'py, PyAny>,
    message: impl FnOnce(&str) -> String,
) -> PyResult<&'a Bound<'py, PyUntypedArray>> {
    obj.cast::<PyUntypedArray>().map_err(|_| {
        let ty = obj
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into());
        PyTypeError::new_err(message(&ty))
    })
}

/// `obj` as a numpy array ("`name` must be a numpy.ndarray of `what`" otherwise).
pub(crate) fn ndarray<'a, 'py>(
    obj: &'a Bound<'py, PyAny>,
    name: &str,
    what: &str,
) -> PyResult<&'a Bound<'py, PyUntypedArray>> {
    ndarray_or(obj, |ty| {
        format!("{name} must be a numpy.ndarray of {what}, got {ty}")
    })
}

/// A `TypeError` unless `arr` has the dtype of `T`, named `dtype` (e.g. "float64") in the
/// message, which says how to convert.
pub(crate) fn check_dtype<T: Element>(
    arr: &Bound<'_, PyUntypedArray>,
    name: &str,
    dtype: &str,
) -> PyResult<()> {
    if arr.dtype().is_equiv_to(&numpy::dtype::<T>(arr.py())) {
        return Ok(());
    }
    Err(PyTypeError::new_err(format!(
        "{name} must have dtype {dtype}, got {}; convert it with .astype(numpy.{dtype})",
        arr.dtype()
    )))
}

/// The read-only float64 values of `arr` (whose dtype was checked).
pub(crate) fn f64_values<'py>(arr: &Bound<'py, PyUntypedArray>) -> PyResult<F64Array<'py>> {
    let shape = arr.shape().to_vec();
    let arr = arr.cast::<PyArrayDyn<f64>>()?.readonly();
    Ok(F64Array { arr, shape })
}

/// The int64 values of `arr` (whose dtype was checked), copied: one memory copy when the array
/// is contiguous. `name` names the buffer if it cannot be allocated.
pub(crate) fn i64_values(arr: &Bound<'_, PyUntypedArray>, name: &str) -> PyResult<Vec<i64>> {
    let arr = arr.cast::<PyArrayDyn<i64>>()?.readonly();
    match arr.as_slice() {
        Ok(values) => Ok(crate::buffer::try_copy(values, name)?),
        Err(_) => Ok(arr.as_array().iter().copied().collect()),
    }
}
