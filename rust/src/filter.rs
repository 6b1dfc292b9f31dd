//! TODO: kernel `filter` (being written).
