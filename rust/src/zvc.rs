//! TODO: kernel `zvc` (being written).
