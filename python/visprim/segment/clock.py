"""Conversions between seconds and fractional frame indices on a concatenated corpus."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from visprim import kernels

__all__ = ["frames_to_times", "times_to_frames"]


def frames_to_times(
    times: NDArray[np.float64],
    offsets: NDArray[np.int64],
    trial: NDArray[np.int64],
    frame: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Seconds of fractional frame indices (relative to each trial's first frame), by linear
    interpolation of the concatenated timestamps ``times`` (Rust kernel
    :func:`visprim.kernels.frames_to_times`)."""
    return kernels.frames_to_times(times, offsets, trial, np.asarray(frame, dtype=np.float64))


def times_to_frames(
    times: NDArray[np.float64],
    offsets: NDArray[np.int64],
    trial: NDArray[np.int64],
    t: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Fractional frame indices (relative to each trial's first frame) of times in seconds,
    by linear interpolation; clipped to the trial's first and last frame (Rust kernel
    :func:`visprim.kernels.times_to_frames`)."""
    return kernels.times_to_frames(times, offsets, trial, np.asarray(t, dtype=np.float64))
