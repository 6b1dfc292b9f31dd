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

pub use error::{Error, Result};

#[cfg(feature = "python")]
mod py;
