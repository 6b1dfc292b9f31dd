//! TODO: kernel `kmeans` (being written).
