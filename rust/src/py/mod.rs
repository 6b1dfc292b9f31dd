//! The only PyO3 code in the crate: conversions, input checks, error mapping, the module.

use pyo3::prelude::*;

mod args;
mod arrays;
mod arrow;
mod dtw;
mod dtw_online;
mod errors;
mod front_online;
mod gif;
mod linalg;
mod resample_online;
mod signal;
mod sosfilt_online;
mod triangulate;
mod yuv;

/// The compiled extension `visprim._visprim`; its public face is `visprim.kernels`.
#[pymodule]
fn _visprim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(instruction_set, m)?)?;
    m.add_function(wrap_pyfunction!(instruction_sets, m)?)?;
    m.add_function(wrap_pyfunction!(simd_levels, m)?)?;
    signal::register(m)?;
    linalg::register(m)?;
    dtw::register(m)?;
    dtw_online::register(m)?;
    sosfilt_online::register(m)?;
    front_online::register(m)?;
    resample_online::register(m)?;
    triangulate::register(m)?;
    gif::register(m)?;
    yuv::register(m)?;
    Ok(())
}

/// The SIMD level the kernels run at (ValueError for an invalid `VISPRIM_SIMD`).
#[pyfunction]
fn instruction_set() -> PyResult<&'static str> {
    Ok(crate::instruction_set()?)
}

/// `(kernel, instruction set)` of every kernel that chooses one (ValueError as above).
#[pyfunction]
fn instruction_sets() -> PyResult<Vec<(&'static str, &'static str)>> {
    Ok(crate::instruction_sets()?)
}

/// The `VISPRIM_SIMD` values this CPU runs, lowest first (whatever the variable says).
#[pyfunction]
fn simd_levels() -> Vec<&'static str> {
    crate::simd::supported()
        .into_iter()
        .map(crate::simd::Level::name)
        .collect()
}
