//! The only PyO3 code in the crate: conversions, input checks, error mapping, the module.

use pyo3::prelude::*;

mod args;
mod arrays;
mod dtw;
mod dtw_online;
mod errors;
mod linalg;
mod signal;

/// The compiled extension `visprim._visprim`; its public face is `visprim.kernels`.
#[pymodule]
fn _visprim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(instruction_set, m)?)?;
    signal::register(m)?;
    linalg::register(m)?;
    dtw::register(m)?;
    dtw_online::register(m)?;
    Ok(())
}

/// The widest SIMD instruction set the kernels use on this CPU.
#[pyfunction]
fn instruction_set() -> &'static str {
    crate::instruction_set()
}
