//! Mapping of core errors to Python exceptions.

use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::PyErr;

use crate::Error;

impl From<Error> for PyErr {
    fn from(err: Error) -> PyErr {
        match err {
            Error::InvalidArgument(msg) | Error::Shape(msg) | Error::NonFinite(msg) => {
                PyValueError::new_err(msg)
            }
            Error::Numerical(msg) => PyRuntimeError::new_err(msg),
            Error::Memory(msg) => PyMemoryError::new_err(msg),
        }
    }
}
