//! TODO: kernel `covariance` (being written).
