//! The core error type shared by every kernel.

/// Everything a kernel can refuse. The binding layer maps each variant to a Python exception.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum Error {
    /// An argument outside its domain (order < 1, cutoff outside (0, 1), k > n, ...).
    #[error("{0}")]
    InvalidArgument(String),
    /// Array shapes that do not fit together, or an empty input.
    #[error("{0}")]
    Shape(String),
    /// NaN or infinity where finite numbers are required.
    #[error("{0}")]
    NonFinite(String),
    /// A numerical failure (e.g. an eigensolver that did not converge).
    #[error("{0}")]
    Numerical(String),
    /// A buffer too large to allocate: a size that overflows, exceeds the machine's memory,
    /// or an allocation that failed. The message names the sizes.
    #[error("{0}")]
    Memory(String),
}

pub type Result<T> = std::result::Result<T, Error>;
