"""Resampling a trial to another frame period (e.g. the original study's 34 ms).

New timestamps are ``t0 + k × period`` up to the last original timestamp. Positions (markers,
joint centres, and ``truth.angles`` if present) are interpolated with a not-a-knot cubic spline
through the original (possibly non-uniform) timestamps; the torso frame by spherical linear
interpolation of its rotations. When the new period is longer than the original one (fewer
samples), an anti-aliasing low-pass is applied first: a zero-phase 4th-order Butterworth at
``0.8 ×`` the new Nyquist frequency. It is linear, so the virtual markers stay exactly the
midpoints of the joint centres they came from.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation, Slerp

from visprim import kernels
from visprim.io.assemble import MAX_FRAMES, period_problem
from visprim.trial import Trial, Truth

#: Anti-aliasing cutoff as a fraction of the new Nyquist frequency.
ANTIALIAS_FRACTION = 0.8


def _lowpass(values: NDArray[np.float64], fs: float, cutoff: float) -> NDArray[np.float64]:
    """Zero-phase order-4 Butterworth low-pass along time (axis 0); ``fs``, ``cutoff`` in Hz.
    Runs in the Rust filter kernel (channels along the last axis there)."""
    sos = kernels.butter_sos(4, cutoff / (0.5 * fs))
    flat = np.ascontiguousarray(values.reshape(values.shape[0], -1).T)
    padlen = min(3 * (2 * len(sos) + 1), flat.shape[1] - 1)
    return kernels.sosfiltfilt(sos, flat, padlen=padlen).T.reshape(values.shape)


def check_resample_period(period: float) -> float:
    """``period`` (seconds) as a float if it is a plausible frame period, else a ValueError
    naming the argument (see :data:`~visprim.io.assemble.MIN_FRAME_PERIOD`)."""
    try:
        value = float(period)
    except (TypeError, ValueError):
        raise ValueError(f"resample must be a frame period in seconds, got {period!r}") from None
    problem = period_problem(value)
    if problem is not None:
        raise ValueError(f"resample: the frame period {problem}")
    return value


def resample_trial(trial: Trial, period: float, *, antialias: bool = True) -> Trial:
    """A copy of ``trial`` sampled every ``period`` seconds.

    Parameters
    ----------
    trial : Trial
    period : float
        New frame period in seconds (> 0).
    antialias : bool
        Low-pass before downsampling (see the module docstring). Default True.

    Raises
    ------
    ValueError
        For a period outside 10 µs – 10 s, one so long that fewer than 2 frames remain, or so
        short that more than :data:`~visprim.io.assemble.MAX_FRAMES` frames would result.
    """
    period = check_resample_period(period)
    where = trial.source or trial.name or "trial"
    t = trial.times
    span = float(t[-1] - t[0])
    if span / period + 1 > MAX_FRAMES:
        raise ValueError(
            f"{where}: resampling {span:.6g} s every {period:g} s would give "
            f"{span / period + 1:.3g} frames (more than {MAX_FRAMES:,}); is the period in seconds?"
        )
    n_new = int(np.floor(span / period + 1e-9)) + 1
    if n_new < 2:
        raise ValueError(
            f"{where}: resampling {trial.duration:.3f} s at {period:g} s leaves {n_new} frame(s)"
        )
    new_t = t[0] + np.arange(n_new) * period
    old_period = trial.frame_period
    cutoff = None
    if antialias and period > old_period * 1.001:
        cutoff = ANTIALIAS_FRACTION * 0.5 / period

    def pos(values: NDArray[np.float64]) -> NDArray[np.float64]:
        if cutoff is not None and values.shape[0] > 3:
            values = _lowpass(values, 1.0 / old_period, cutoff)
        return CubicSpline(t, values, axis=0)(new_t)

    markers = pos(trial.markers)
    joints = pos(trial.joints) if trial.joints is not None else None
    body = None
    if trial.body_frame is not None:
        rots = Rotation.from_matrix(trial.body_frame)
        body = Slerp(t, rots)(new_t).as_matrix()
    truth = trial.truth
    if truth is not None:
        truth = Truth(
            angles=CubicSpline(t, truth.angles, axis=0)(new_t),
            boundaries=truth.boundaries.copy(),
            labels=truth.labels.copy(),
            repetitions=truth.repetitions,
        )
    meta = dict(trial.meta)
    meta["resampled"] = {
        "period_s": period,
        "from_period_s": old_period,
        "antialias_cutoff_hz": cutoff,
        "method": "cubic spline (positions), slerp (body frame)",
    }
    return dataclasses.replace(
        trial,
        times=new_t,
        markers=markers,
        joints=joints,
        body_frame=body,
        truth=truth,
        meta=meta,
    )
