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
pub mod seg1;
pub mod zvc;

pub mod covariance;
pub mod eigh;
pub mod kmeans;
pub mod kmeanspp;
mod lloyd;
pub mod sqdist;

pub mod dtw;

pub mod triangulate;

pub use error::{Error, Result};

/// The widest SIMD instruction set the kernels use on this CPU, chosen at run time:
/// `"avx512f"`, `"avx2+fma"` or `"portable"` (plain Rust, any CPU).
pub fn instruction_set() -> &'static str {
    match sqdist::detected_level() {
        sqdist::Level::Avx512 => "avx512f",
        sqdist::Level::Avx2 => "avx2+fma",
        sqdist::Level::Scalar => "portable",
    }
}

#[cfg(feature = "python")]
mod py;
