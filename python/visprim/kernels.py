"""visprim's numeric kernels (implemented in Rust, :mod:`visprim._visprim`).

Thin, documented re-exports: every function validates its input (dtype, shape, NaN/inf,
empty input) and raises :class:`ValueError` or :class:`TypeError` with a readable message;
the computation runs with the GIL released and results come back as numpy arrays without a
copy. Arrays are float64; signals are laid out with time along the first axis of
``(frames, channels)`` for the ragged forms and along the last axis for ``sosfiltfilt``.
"""

from __future__ import annotations

from visprim import _visprim  # noqa: F401

# --- signal kernels (filter, zvc, resample) ---

# --- linalg kernels (covariance, eigh, kmeans) ---
