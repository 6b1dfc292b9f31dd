"""Zero-velocity crossings (ZVCs) per degree of freedom, with the significant-movement test.

A ZVC of a DOF is where its angular velocity (from the real timestamps,
:func:`~visprim.segment.velocity.velocity_concatenated`) changes sign between two frames; its
position is the fractional frame found by linear interpolation of the velocity (exact zeros
carry no sign: see :func:`visprim.kernels.zero_velocity_crossings`), converted to seconds by
linear interpolation of the timestamps. Detection runs in the Rust kernel
:func:`visprim.kernels.zero_velocity_crossings_ragged` on a whole corpus at once.

Significant movement (``min_change_deg``): walking a DOF's crossings in time order, a
crossing is kept only if the DOF's angle changed by more than ``min_change_deg`` degrees
since the previous *kept* crossing of that DOF (or since the trial's first frame). This
drops the many crossings of a DOF that merely jitters around rest (sensor noise, the
filter's ripple) and keeps the stops and reversals of real movements.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import kernels
from visprim.segment.clock import frames_to_times

__all__ = [
    "DEFAULT_MIN_CHANGE_DEG",
    "CorpusCrossings",
    "Crossings",
    "zvc",
    "zvc_concatenated",
]

#: Default significant-movement threshold, degrees: a DOF's crossing counts only after the
#: angle moved more than this since its previous kept crossing. 5° is several times the
#: angle jitter left after the low-pass on tracker-like data (~1° RMS in the generated
#: experiment) and well below the tens of degrees of an arm stroke.
DEFAULT_MIN_CHANGE_DEG: float = 5.0


class Crossings(NamedTuple):
    """ZVCs of one trial, sorted by DOF then time."""

    time: NDArray[np.float64]  #: (n,) seconds, on the trial's clock
    frame: NDArray[np.float64]  #: (n,) fractional frame index in the trial
    dof: NDArray[np.int64]  #: (n,) DOF (angle column) index


class CorpusCrossings(NamedTuple):
    """ZVCs of a concatenated corpus, sorted by trial, DOF, time."""

    trial: NDArray[np.int64]  #: (n,) trial index
    dof: NDArray[np.int64]  #: (n,) DOF index
    frame: NDArray[np.float64]  #: (n,) fractional frame index relative to the trial's start
    time: NDArray[np.float64]  #: (n,) seconds, on the trial's clock


def zvc_concatenated(
    times: ArrayLike,
    angles: ArrayLike,
    offsets: ArrayLike,
    *,
    min_change_deg: float = DEFAULT_MIN_CHANGE_DEG,
    velocity: ArrayLike | None = None,
) -> CorpusCrossings:
    """ZVCs of every DOF of every trial of a concatenated corpus (one kernel call).

    Parameters
    ----------
    times : (N,) seconds; angles : (N, C) radians; offsets : (n_trials,) first frames.
    min_change_deg : float
        Significant-movement threshold in **degrees** (see the module docstring).
    velocity : (N, C) rad/s, optional
        Precomputed :func:`~visprim.segment.velocity.velocity_concatenated`.
    """
    if not np.isfinite(min_change_deg) or min_change_deg < 0:
        raise ValueError(f"min_change_deg must be a finite number >= 0, got {min_change_deg!r}")
    t = np.ascontiguousarray(times, dtype=np.float64)
    a = np.ascontiguousarray(angles, dtype=np.float64)
    off = np.ascontiguousarray(offsets, dtype=np.int64)
    min_change = float(np.deg2rad(min_change_deg))
    if velocity is None:
        # Velocity trial by trial inside the kernel (no corpus-sized array).
        trial, dof, frame = kernels.zero_velocity_crossings_of_positions(t, a, off, min_change)
    else:
        v = np.ascontiguousarray(velocity, dtype=np.float64)
        trial, dof, frame = kernels.zero_velocity_crossings_ragged(v, off, min_change, positions=a)
    trial = np.asarray(trial, dtype=np.int64)
    frame = np.asarray(frame, dtype=np.float64)
    return CorpusCrossings(
        trial, np.asarray(dof, dtype=np.int64), frame, frames_to_times(t, off, trial, frame)
    )


def zvc(
    times: ArrayLike,
    angles: ArrayLike,
    *,
    min_change_deg: float = DEFAULT_MIN_CHANGE_DEG,
) -> Crossings:
    """Zero-velocity crossings of each DOF of one trial.

    Parameters
    ----------
    times : (T,) seconds
        Timestamps (strictly increasing; need not be uniform). Velocities come from them.
    angles : (T, C) radians
        Joint angles, normally low-passed first (:mod:`visprim.filtering`).
    min_change_deg : float
        Significant-movement threshold in **degrees** (default
        :data:`DEFAULT_MIN_CHANGE_DEG`; see the module docstring).

    Returns
    -------
    :class:`Crossings` (time s, fractional frame, dof), sorted by DOF then time.
    """
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim != 2:
        raise ValueError(f"angles must have shape (T, channels), got {a.shape}")
    c = zvc_concatenated(times, a, np.zeros(1, dtype=np.int64), min_change_deg=min_change_deg)
    return Crossings(c.time, c.frame, c.dof)
