"""Continuous-time joint-space motion: a schedule of holds and minimum-jerk strokes.

A :class:`Motion` is a sequence of pieces covering ``[0, duration]`` seconds. Each piece
moves the four angles (radians, :mod:`visprim.arm` convention) from ``start`` by
``delta`` with minimum-jerk progress φ(s), plus an optional closed loop in (γ, β)::

    θ(t) = start + delta·φ + (A_γ sin 2πφ, A_β (1 − cos 2πφ), 0, 0)

Holds and pauses are pieces with zero delta and zero loop. Angles and their exact time
derivatives can be evaluated at any times (vectorised), so the ground truth is sampled at
the real (jittered) sample instants.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim.datasets.vocabulary import minimum_jerk


@dataclass(frozen=True)
class Motion:
    """A piecewise joint-space movement.

    Attributes
    ----------
    piece_start : (K,) float array, seconds
        Start time of each piece (the first is 0), increasing.
    piece_duration : (K,) float array, seconds (> 0)
    start : (K, 4) float array, radians
        Angles at the start of each piece.
    delta : (K, 4) float array, radians
        Net change over each piece (0 for holds and for a closed loop).
    loop : (K, 2) float array, radians
        Loop half-axes (A_γ, A_β); 0 for straight pieces.
    boundaries : (n_strokes + 1,) float array, seconds
        Ground-truth stroke boundaries: start of the first stroke, one boundary between
        consecutive strokes (the shared instant, or the middle of a pause between them),
        end of the last stroke.
    labels : (n_strokes,) int array
        Primitive label of each stroke.
    """

    piece_start: NDArray[np.float64]
    piece_duration: NDArray[np.float64]
    start: NDArray[np.float64]
    delta: NDArray[np.float64]
    loop: NDArray[np.float64]
    boundaries: NDArray[np.float64]
    labels: NDArray[np.int64]

    @property
    def duration(self) -> float:
        """Total length in seconds."""
        return float(self.piece_start[-1] + self.piece_duration[-1])

    def _locate(self, times: ArrayLike) -> tuple[NDArray[np.intp], NDArray[np.float64]]:
        t = np.asarray(times, dtype=np.float64)
        idx = np.searchsorted(self.piece_start, t, side="right") - 1
        idx = np.clip(idx, 0, self.piece_start.size - 1)
        s = np.clip((t - self.piece_start[idx]) / self.piece_duration[idx], 0.0, 1.0)
        return idx, s

    def angles(self, times: ArrayLike) -> NDArray[np.float64]:
        """Angles (T, 4) in radians at ``times`` (s); constant outside [0, duration]."""
        idx, s = self._locate(times)
        phi = minimum_jerk(s)
        out = self.start[idx] + self.delta[idx] * phi[:, None]
        two_pi_phi = 2.0 * np.pi * phi
        out[:, 0] += self.loop[idx, 0] * np.sin(two_pi_phi)
        out[:, 1] += self.loop[idx, 1] * (1.0 - np.cos(two_pi_phi))
        return out

    def velocities(self, times: ArrayLike) -> NDArray[np.float64]:
        """Exact angular velocities (T, 4) in rad/s at ``times`` (s)."""
        idx, s = self._locate(times)
        phi = minimum_jerk(s)
        dphi_dt = 30.0 * s * s * (1.0 - s) ** 2 / self.piece_duration[idx]
        two_pi_phi = 2.0 * np.pi * phi
        d = self.delta[idx].copy()
        d[:, 0] += self.loop[idx, 0] * 2.0 * np.pi * np.cos(two_pi_phi)
        d[:, 1] += self.loop[idx, 1] * 2.0 * np.pi * np.sin(two_pi_phi)
        return d * dphi_dt[:, None]
