"""Conversions between seconds and fractional frame indices on a concatenated corpus."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["frames_to_times", "times_to_frames"]


def _last_frames(n: int, offsets: NDArray[np.int64]) -> NDArray[np.int64]:
    return np.append(offsets[1:], n) - 1


def frames_to_times(
    times: NDArray[np.float64],
    offsets: NDArray[np.int64],
    trial: NDArray[np.int64],
    frame: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Seconds of fractional frame indices (relative to each trial's first frame), by linear
    interpolation of the concatenated timestamps ``times``."""
    last = _last_frames(times.shape[0], offsets)
    g = offsets[trial] + np.asarray(frame, dtype=np.float64)
    i = np.minimum(np.floor(g).astype(np.int64), last[trial] - 1)
    i = np.maximum(i, offsets[trial])
    return times[i] + (g - i) * (times[i + 1] - times[i])


def times_to_frames(
    times: NDArray[np.float64],
    offsets: NDArray[np.int64],
    trial: NDArray[np.int64],
    t: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Fractional frame indices (relative to each trial's first frame) of times in seconds,
    by linear interpolation; clipped to the trial's first and last frame."""
    n = times.shape[0]
    last = _last_frames(n, offsets)
    lengths = last - offsets + 1
    trial_of = np.repeat(np.arange(offsets.size), lengths)
    local = times - times[offsets][trial_of]
    span = float(local.max()) + 1.0
    key = local + trial_of * span  # increasing over the whole corpus
    q = np.asarray(t, dtype=np.float64) - times[offsets][trial]
    q = np.clip(q, 0.0, local[last][trial]) + trial * span
    i = np.searchsorted(key, q, side="right") - 1
    i = np.clip(i, offsets[trial], last[trial] - 1)
    frac = (q - key[i]) / (key[i + 1] - key[i])
    return (i - offsets[trial]) + np.clip(frac, 0.0, 1.0)
