"""Hand-made arm trajectories for trying the simulation without a learned model."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def minimum_jerk(
    postures: ArrayLike, durations: ArrayLike, rate: float = 100.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Minimum-jerk strokes through a sequence of postures (rest-to-rest in every angle).

    Parameters
    ----------
    postures : (n, 4) array, radians
        Successive arm postures (γ, β, α, elbow) of :mod:`visprim.arm`; n >= 2. (n, 8) for
        both arms (right, then left).
    durations : (n - 1,) array, seconds
        Duration of each stroke, > 0.
    rate : float, Hz
        Samples per second of the returned trajectory.

    Returns
    -------
    times : (T,) seconds from 0; angles : (T, 4) (or (T, 8)) radians.
    """
    p = np.asarray(postures, dtype=np.float64)
    d = np.atleast_1d(np.asarray(durations, dtype=np.float64))
    if p.ndim != 2 or p.shape[1] not in (4, 8) or p.shape[0] < 2:
        raise ValueError(
            f"postures must have shape (n >= 2, 4) radians (or (n, 8) for two arms), got {p.shape}"
        )
    if d.shape != (p.shape[0] - 1,) or not np.all(np.isfinite(d)) or np.any(d <= 0):
        raise ValueError(
            f"durations must be {p.shape[0] - 1} positive seconds values, got {d.tolist()}"
        )
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate must be > 0 Hz, got {rate}")
    bounds = np.concatenate([[0.0], np.cumsum(d)])
    times = np.arange(int(np.floor(bounds[-1] * rate)) + 1) / rate
    if bounds[-1] - times[-1] > 1e-9:
        times = np.append(times, bounds[-1])
    stroke = np.clip(np.searchsorted(bounds, times, side="right") - 1, 0, d.size - 1)
    s = np.clip((times - bounds[stroke]) / d[stroke], 0.0, 1.0)
    h = s**3 * (10.0 - 15.0 * s + 6.0 * s * s)
    angles = p[stroke] + (p[stroke + 1] - p[stroke]) * h[:, None]
    return times, angles
