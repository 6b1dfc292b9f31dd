"""Angular velocities from the real (possibly jittered) timestamps."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["angular_velocity", "velocity_concatenated"]


def _check_times(t: NDArray[np.float64], n: int, where: str) -> None:
    if t.shape != (n,):
        raise ValueError(f"{where}: times must have shape ({n},) to match angles, got {t.shape}")
    if n < 2:
        raise ValueError(f"{where}: need at least 2 frames, got {n}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{where}: times contain NaN or infinity")


def angular_velocity(times: ArrayLike, angles: ArrayLike) -> NDArray[np.float64]:
    """Time derivative of (T, C) angles (rad → rad/s) with :func:`numpy.gradient` on the
    timestamps (second-order central differences, first-order at both ends)."""
    t = np.asarray(times, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim != 2:
        raise ValueError(f"angles must have shape (T, channels), got {a.shape}")
    _check_times(t, a.shape[0], "angular_velocity")
    if np.any(np.diff(t) <= 0):
        raise ValueError("angular_velocity: times must be strictly increasing")
    return np.gradient(a, t, axis=0)


def velocity_concatenated(
    times: ArrayLike, values: ArrayLike, offsets: ArrayLike
) -> NDArray[np.float64]:
    """:func:`angular_velocity` of every trial of a concatenated corpus in one numpy pass.

    Parameters
    ----------
    times : (N,) seconds, each trial's timestamps one after another (strictly increasing
        within a trial).
    values : (N, C) values (e.g. radians).
    offsets : (n_trials,) first frame of each trial; every trial needs ≥ 2 frames.

    Returns
    -------
    (N, C) float64: identical (to rounding) to ``np.gradient(values_i, times_i, axis=0)`` per
    trial.
    """
    t = np.ascontiguousarray(times, dtype=np.float64)
    x = np.ascontiguousarray(values, dtype=np.float64)
    off = np.asarray(offsets, dtype=np.int64)
    if x.ndim != 2:
        raise ValueError(f"values must have shape (N, channels), got {x.shape}")
    _check_times(t, x.shape[0], "velocity_concatenated")
    n = x.shape[0]
    ends = np.append(off[1:], n) - 1  # last frame of each trial
    if np.any(ends - off < 1):
        k = int(np.argmax(ends - off < 1))
        raise ValueError(f"velocity_concatenated: trial {k} has fewer than 2 frames")
    h = np.diff(t)  # h[i] = t[i+1] - t[i]; across trial joins it is meaningless but unused
    inner_ok = np.ones(n - 1, dtype=bool)
    inner_ok[ends[:-1]] = False  # the step from a trial's last frame to the next trial
    if np.any(h[inner_ok] <= 0):
        raise ValueError("velocity_concatenated: times must be strictly increasing in a trial")
    v = np.empty_like(x)
    if n > 2:
        # np.gradient's second-order weights for uneven steps (the steps that straddle a join
        # of two trials give garbage rows, overwritten by the one-sided ends below).
        h0 = h[:-1]  # t[i] - t[i-1]
        h1 = h[1:]  # t[i+1] - t[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            w_prev = (-h1 / (h0 * (h0 + h1)))[:, None]
            w_here = ((h1 - h0) / (h0 * h1))[:, None]
            w_next = (h0 / (h1 * (h0 + h1)))[:, None]
        np.multiply(w_prev, x[:-2], out=v[1:-1])
        v[1:-1] += w_here * x[1:-1]
        v[1:-1] += w_next * x[2:]
    v[off] = (x[off + 1] - x[off]) / h[off, None]
    v[ends] = (x[ends] - x[ends - 1]) / h[ends - 1, None]
    return v
