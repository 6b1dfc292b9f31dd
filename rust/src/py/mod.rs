//! The only PyO3 code in the crate: conversions, input checks, error mapping, the module.

use pyo3::prelude::*;

mod args;
mod arrays;
mod dtw;
mod errors;
mod linalg;
mod signal;
mod triangulate;

/// The compiled extension `visprim._visprim`; its public face is `visprim.kernels`.
#[pymodule]
fn _visprim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(instruction_set, m)?)?;
    signal::register(m)?;
    linalg::register(m)?;
    dtw::register(m)?;
    triangulate::register(m)?;
    Ok(())
}

/// The widest SIMD instruction set the kernels use on this CPU.
#[pyfunction]
fn instruction_set() -> &'static str {
    crate::instruction_set()
}
