"""Angular velocities from the real (possibly jittered) timestamps (``numpy.gradient``
semantics; the corpus form runs in the Rust kernel :func:`visprim.kernels.gradient_ragged`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import kernels

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
    """:func:`angular_velocity` of every trial of a concatenated corpus in one call of the
    Rust kernel :func:`visprim.kernels.gradient_ragged`.

    Parameters
    ----------
    times : (N,) seconds, each trial's timestamps one after another (strictly increasing
        within a trial).
    values : (N, C) values (e.g. radians).
    offsets : (n_trials,) first frame of each trial; every trial needs ≥ 2 frames.

    Returns
    -------
    (N, C) float64 (units of ``values`` per second): identical to
    ``np.gradient(values_i, times_i, axis=0)`` per trial.
    """
    t = np.ascontiguousarray(times, dtype=np.float64)
    x = np.ascontiguousarray(values, dtype=np.float64)
    off = np.asarray(offsets, dtype=np.int64)
    if x.ndim != 2:
        raise ValueError(f"values must have shape (N, channels), got {x.shape}")
    if t.shape != (x.shape[0],):
        raise ValueError(
            f"velocity_concatenated: times must have shape ({x.shape[0]},) to match values, "
            f"got {t.shape}"
        )
    try:  # the kernel checks the offsets, trial lengths and timestamps (finite, increasing)
        return kernels.gradient_ragged(t, x, off)
    except ValueError as err:
        raise ValueError(f"velocity_concatenated: {err}") from None
