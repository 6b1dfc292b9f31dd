//! The only PyO3 code in the crate: conversions, input checks, error mapping, the module.

use pyo3::prelude::*;

mod args;
mod arrays;
mod dtw;
mod errors;
mod linalg;
mod signal;

/// The compiled extension `visprim._visprim`; its public face is `visprim.kernels`.
#[pymodule]
fn _visprim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    signal::register(m)?;
    linalg::register(m)?;
    dtw::register(m)?;
    Ok(())
}
