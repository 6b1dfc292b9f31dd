//! TODO: kernel `eigh` (being written).
