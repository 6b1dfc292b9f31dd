//! TODO: kernel `resample` (being written).
