"""Consecutive segment curves joined into one trajectory with no step in angle or velocity.

A movement rebuilt from primitives is a chain of curves, one per segment, each stretched to
its segment's duration. Two neighbours need not meet: each primitive is the centre of many
segments, and its ends are that centre's, not this movement's. :class:`JoinedTrajectory`
makes the chain C¹ (continuous in angle and in angular velocity):

* every curve ``f_j`` (``n`` samples spread evenly over ``[s_j, e_j]``) becomes a cubic
  spline in time;
* at a boundary shared by two segments (``e_j = s_{j+1}``) the joined trajectory passes
  through the **mean** of the two curves' end values with the **mean** of their end
  velocities; at the first start and the last end each curve keeps its own value and
  velocity;
* each curve gets an additive cubic Hermite correction ``h_j`` over its segment that moves
  its two ends onto those boundary states (the smallest polynomial that fixes value and
  velocity at both ends; in the interior the curve keeps its shape up to a smooth ramp);
* a gap between segments (``e_j < s_{j+1}``, time no segment covers) is bridged by the cubic
  Hermite curve from the end state of one to the start state of the next.

Units: seconds and radians (velocities rad/s).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline

#: Relative tolerance (of a segment's duration) under which two boundaries are the same instant.
_SAME_INSTANT = 1e-9


def _hermite(
    u: NDArray[np.float64],
    p0: NDArray[np.float64],
    m0: NDArray[np.float64],
    p1: NDArray[np.float64],
    m1: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Cubic Hermite value and d/du at ``u`` (k,) in [0, 1] for end values ``p`` and end
    slopes ``m`` (per unit of u), each (C,). Returns two (k, C) arrays."""
    u = u[:, None]
    u2, u3 = u * u, u * u * u
    value = (
        (2 * u3 - 3 * u2 + 1) * p0
        + (u3 - 2 * u2 + u) * m0
        + (-2 * u3 + 3 * u2) * p1
        + (u3 - u2) * m1
    )
    slope = (
        (6 * u2 - 6 * u) * p0
        + (3 * u2 - 4 * u + 1) * m0
        + (-6 * u2 + 6 * u) * p1
        + (3 * u2 - 2 * u) * m1
    )
    return value, slope


@dataclass(frozen=True)
class _Piece:
    start: float
    end: float
    spline: CubicSpline | None  # None: a bridge (pure Hermite curve)
    p0: NDArray[np.float64]  # correction (or bridge) end values and slopes per unit of u
    m0: NDArray[np.float64]
    p1: NDArray[np.float64]
    m1: NDArray[np.float64]


class JoinedTrajectory:
    """A C¹ trajectory from consecutive segment curves (see the module docstring).

    Parameters
    ----------
    curves : sequence of (n_j, C) arrays, radians
        One curve per segment, its samples spread evenly from the segment's start to its end.
    bounds : (N, 2) array, seconds
        ``[start, end]`` of each segment, increasing and not overlapping.

    Call it with times (s) to get ``(angles (k, C) rad, velocities (k, C) rad/s)``; times
    outside ``[bounds[0, 0], bounds[-1, 1]]`` are clamped to the ends.
    """

    def __init__(self, curves: Sequence[ArrayLike], bounds: ArrayLike) -> None:
        b = np.asarray(bounds, dtype=np.float64).reshape(-1, 2)
        if len(curves) != b.shape[0] or b.shape[0] == 0:
            raise ValueError(
                f"JoinedTrajectory: {len(curves)} curve(s) for {b.shape[0]} segment(s); "
                "need one per segment and at least one"
            )
        if not np.all(np.isfinite(b)) or np.any(b[:, 1] <= b[:, 0]):
            raise ValueError("JoinedTrajectory: every segment needs finite start < end seconds")
        if np.any(b[1:, 0] < b[:-1, 1] - _SAME_INSTANT * (b[:-1, 1] - b[:-1, 0])):
            raise ValueError("JoinedTrajectory: segments overlap or are not in time order")
        splines = []
        for j, c in enumerate(curves):
            a = np.asarray(c, dtype=np.float64)
            if a.ndim != 2 or a.shape[0] < 2 or not np.all(np.isfinite(a)):
                raise ValueError(f"JoinedTrajectory: curve {j} must be a finite (n >= 2, C) array")
            splines.append(CubicSpline(np.linspace(b[j, 0], b[j, 1], a.shape[0]), a, axis=0))
        starts = [(s(b[j, 0]), s(b[j, 0], 1)) for j, s in enumerate(splines)]
        ends = [(s(b[j, 1]), s(b[j, 1], 1)) for j, s in enumerate(splines)]
        # Boundary states: the mean of the two curves where segments touch.
        start_state = list(starts)
        end_state = list(ends)
        touching = np.zeros(b.shape[0] - 1, dtype=bool)
        for j in range(b.shape[0] - 1):
            if b[j + 1, 0] - b[j, 1] <= _SAME_INSTANT * (b[j, 1] - b[j, 0]):
                touching[j] = True
                mean = (
                    (ends[j][0] + starts[j + 1][0]) / 2.0,
                    (ends[j][1] + starts[j + 1][1]) / 2.0,
                )
                end_state[j] = mean
                start_state[j + 1] = mean
        pieces: list[_Piece] = []
        for j, s in enumerate(splines):
            d = float(b[j, 1] - b[j, 0])
            pieces.append(
                _Piece(
                    float(b[j, 0]),
                    float(b[j, 1]),
                    s,
                    start_state[j][0] - starts[j][0],
                    (start_state[j][1] - starts[j][1]) * d,
                    end_state[j][0] - ends[j][0],
                    (end_state[j][1] - ends[j][1]) * d,
                )
            )
            if j < b.shape[0] - 1 and not touching[j]:
                g = float(b[j + 1, 0] - b[j, 1])
                pieces.append(
                    _Piece(
                        float(b[j, 1]),
                        float(b[j + 1, 0]),
                        None,
                        end_state[j][0],
                        end_state[j][1] * g,
                        start_state[j + 1][0],
                        start_state[j + 1][1] * g,
                    )
                )
        self._pieces = pieces
        self._edges = np.array([p.start for p in pieces[1:]])
        self.bounds = b
        self.n_channels = int(np.asarray(curves[0]).shape[1])

    @property
    def start(self) -> float:
        """First instant, seconds."""
        return float(self.bounds[0, 0])

    @property
    def end(self) -> float:
        """Last instant, seconds."""
        return float(self.bounds[-1, 1])

    def __call__(self, times: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        t = np.clip(np.atleast_1d(np.asarray(times, dtype=np.float64)), self.start, self.end)
        which = np.searchsorted(self._edges, t, side="right")
        angles = np.empty((t.shape[0], self.n_channels))
        velocities = np.empty_like(angles)
        for i in np.unique(which):
            sel = which == i
            piece = self._pieces[int(i)]
            d = piece.end - piece.start
            u = (t[sel] - piece.start) / d
            value, slope = _hermite(u, piece.p0, piece.m0, piece.p1, piece.m1)
            if piece.spline is not None:
                value = value + piece.spline(t[sel])
                slope = slope + piece.spline(t[sel], 1) * d
            angles[sel] = value
            velocities[sel] = slope / d
        return angles, velocities
