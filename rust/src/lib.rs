//! visprim numeric core: pure kernels on slices and views, no Python types.
//!
//! The PyO3 binding layer lives in [`py`] and is compiled only with the `python` feature
//! (maturin enables it); `cargo test` and `cargo bench` use the kernels directly.

pub mod error;

pub mod buffer;
pub mod checks;
pub mod clock;
pub mod filter;
pub mod gradient;
pub mod gram;
pub mod lanes;
pub mod ragged;
pub mod resample;
pub mod resample_online;
pub mod seg1;
pub mod simd;
pub mod zvc;

pub mod covariance;
pub mod eigh;
pub mod kmeans;
pub mod kmeanspp;
mod lloyd;
pub mod sqdist;

pub mod dtw;
pub mod dtw_online;
pub mod front_online;
pub mod segment_online;
pub mod sosfilt_online;

pub mod triangulate;

pub mod gif;
pub mod yuv;

pub use error::{Error, Result};

/// The SIMD level the kernels run at (the CPU's best, capped by `VISPRIM_SIMD`; see
/// [`simd`]): `"avx512f"`, `"avx2+fma"` or `"portable"` (plain Rust, any CPU).
///
/// Errors: an invalid `VISPRIM_SIMD` (InvalidArgument, see [`simd::level`]).
pub fn instruction_set() -> Result<&'static str> {
    Ok(simd::level()?.instruction_set())
}

/// What each kernel runs at the active level, as `(kernel, instruction set)`; the first word
/// of each description is `portable`, `avx2+fma`, `avx512f` or `faer's` (faer's own run-time
/// choice, which `VISPRIM_SIMD` does not cap). Kernels not listed are portable code.
///
/// Errors: as [`instruction_set`].
pub fn instruction_sets() -> Result<Vec<(&'static str, &'static str)>> {
    let level = simd::level()?;
    Ok(vec![
        ("sosfiltfilt", lanes::instruction_set(level)),
        ("resample_segments", resample::instruction_set(level)),
        ("covariance", covariance::instruction_set(level)),
        ("kmeans", kmeans::instruction_set(level)),
        ("kmeans_predict", level.instruction_set()),
        ("kmeans_plusplus", kmeanspp::instruction_set(level)),
        (
            "eigh",
            "faer's eigensolver (faer chooses its instructions itself)",
        ),
        ("dtw_distances", "portable"),
    ])
}

#[cfg(feature = "python")]
mod py;
