"""Scoring found segment boundaries against ground truth (precision / recall / F1).

Boundaries match **one to one**: a found boundary matches at most one true boundary and
vice versa, and only if it lies within ``tolerance`` seconds (default 0.1 s = ±100 ms) of
it. The number of matches is the largest possible (a sweep over the sorted found
boundaries that gives each one the compatible true boundary whose window closes first; this
is optimal for windows on a line).

*Pauses.* A true boundary may be known only up to an interval: when a subject pauses between
two strokes, the generator marks the middle of the pause, but every instant of the pause is
a correct boundary. ``truth_halfwidth`` (seconds, one per true boundary; e.g. from
:func:`truth_pause_halfwidths`) widens the window of a true boundary to
``± (halfwidth + tolerance)``. With the default ``None`` every window is ``± tolerance``.

Conventions for empty inputs: with nothing found, precision is 1 (no false boundary); with
no true boundary, recall is 1; F1 is 0 when precision + recall is 0.
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim.trial import Trial

__all__ = [
    "BoundaryScores",
    "boundary_matches",
    "boundary_scores",
    "corpus_boundary_scores",
    "segment_boundaries",
    "truth_pause_halfwidths",
]

#: Segment ends closer than this (seconds) are the same boundary.
_SAME_BOUNDARY = 1e-9


class BoundaryScores(NamedTuple):
    precision: float
    recall: float
    f1: float


def segment_boundaries(found: ArrayLike) -> NDArray[np.float64]:
    """Sorted distinct boundary times (seconds) of (n, 2) segments, or of (n,) boundary
    times. Touching segments share their common boundary."""
    a = np.asarray(found, dtype=np.float64)
    if a.ndim == 2 and a.shape[1] == 2:
        a = a.ravel()
    elif a.ndim != 1:
        raise ValueError(
            f"found must be (n, 2) segments or (n,) boundary times in seconds, got {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError("boundary times contain NaN or infinity")
    a = np.sort(a)
    if a.size:
        a = a[np.concatenate([[True], np.diff(a) > _SAME_BOUNDARY])]
    return a


def boundary_matches(
    found: ArrayLike,
    truth: ArrayLike,
    tolerance: float = 0.1,
    *,
    truth_halfwidth: ArrayLike | None = None,
) -> tuple[int, int, int]:
    """``(n_matched, n_found, n_truth)`` under one-to-one matching (module docstring).

    ``found``: (n, 2) segments or (n,) times; ``truth``: (m,) times, seconds;
    ``truth_halfwidth``: (m,) seconds ≥ 0, or None.
    """
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise ValueError(f"tolerance must be a number of seconds >= 0, got {tolerance!r}")
    f = segment_boundaries(found)
    t = np.asarray(truth, dtype=np.float64)
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise ValueError(f"truth must be a 1-D array of finite times in seconds, got {t.shape}")
    if truth_halfwidth is None:
        h = np.zeros_like(t)
    else:
        h = np.asarray(truth_halfwidth, dtype=np.float64)
        if h.shape != t.shape or not np.all(np.isfinite(h)) or np.any(h < 0):
            raise ValueError(
                f"truth_halfwidth must be {t.shape} finite seconds >= 0, got shape {h.shape}"
            )
    lo_all = t - h - tolerance
    order = np.argsort(lo_all, kind="stable")  # windows in order of opening
    lo = lo_all[order].tolist()
    hi = (t + h + tolerance)[order].tolist()
    open_windows: list[float] = []  # right ends of windows that have opened
    j = matched = 0
    for x in f.tolist():
        while j < len(lo) and lo[j] <= x:
            heapq.heappush(open_windows, hi[j])
            j += 1
        while open_windows and open_windows[0] < x:
            heapq.heappop(open_windows)
        if open_windows:
            heapq.heappop(open_windows)
            matched += 1
    return matched, int(f.size), int(t.size)


def _scores(matched: int, n_found: int, n_truth: int) -> BoundaryScores:
    precision = matched / n_found if n_found else 1.0
    recall = matched / n_truth if n_truth else 1.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return BoundaryScores(float(precision), float(recall), float(f1))


def boundary_scores(
    found: ArrayLike,
    truth: ArrayLike,
    tolerance: float = 0.1,
    *,
    truth_halfwidth: ArrayLike | None = None,
) -> BoundaryScores:
    """Precision, recall and F1 of one trial's found boundaries against the true ones.

    Parameters
    ----------
    found : (n, 2) segments [start, end] or (n,) boundary times, seconds
        E.g. the output of :func:`~visprim.segment.seg1` or :func:`~visprim.segment.seg2`.
    truth : (m,) boundary times, seconds (e.g. ``trial.truth.boundaries``).
    tolerance : float, seconds
        Largest distance of a match (default 0.1 s).
    truth_halfwidth : (m,) seconds, optional
        Half-width of the interval each true boundary stands for (pauses; see the module
        docstring). Default: exact boundaries.
    """
    return _scores(*boundary_matches(found, truth, tolerance, truth_halfwidth=truth_halfwidth))


def corpus_boundary_scores(
    found: Sequence[ArrayLike],
    truth: Sequence[ArrayLike],
    tolerance: float = 0.1,
    *,
    truth_halfwidth: Sequence[ArrayLike] | None = None,
) -> BoundaryScores:
    """Micro-averaged scores over many trials: matches, found and true boundaries are summed
    over trials (no boundary of one trial matches another's) before the ratios. Arguments
    are per-trial lists of those of :func:`boundary_scores`."""
    if len(found) != len(truth):
        raise ValueError(f"found has {len(found)} trials but truth has {len(truth)}")
    if truth_halfwidth is not None and len(truth_halfwidth) != len(truth):
        raise ValueError(
            f"truth_halfwidth has {len(truth_halfwidth)} trials but truth has {len(truth)}"
        )
    halves = truth_halfwidth if truth_halfwidth is not None else [None] * len(truth)
    total = np.zeros(3, dtype=np.int64)
    for f, t, h in zip(found, truth, halves, strict=True):
        total += boundary_matches(f, t, tolerance, truth_halfwidth=h)
    return _scores(*(int(x) for x in total))


def truth_pause_halfwidths(trial: Trial, *, still: float = 1e-9) -> NDArray[np.float64]:
    """Half-width (seconds) of the pause around each true boundary of a generated trial.

    A pause is a run of frames over which every true angle changes by less than ``still``
    radians per frame (the generator holds the posture exactly). For a boundary inside a
    pause the half-width is the distance to the nearer end of the pause (the generator puts
    the boundary in the middle, so this is half the pause as sampled); for any other
    boundary, including the start of the first and the end of the last stroke, it is 0.
    """
    if trial.truth is None:
        raise ValueError(f"trial {trial.name!r} has no ground truth")
    times = trial.times
    steps_still = np.all(np.abs(np.diff(trial.truth.angles, axis=0)) < still, axis=1)
    b = np.asarray(trial.truth.boundaries, dtype=np.float64)
    out = np.zeros(b.size)
    # Frame step i covers [times[i], times[i + 1]]; find the step containing each boundary.
    step = np.clip(np.searchsorted(times, b, side="right") - 1, 0, steps_still.size - 1)
    for k in np.flatnonzero(steps_still[step]):
        lo = hi = int(step[k])
        while lo > 0 and steps_still[lo - 1]:
            lo -= 1
        while hi + 1 < steps_still.size and steps_still[hi + 1]:
            hi += 1
        out[k] = max(0.0, min(b[k] - times[lo], times[hi + 1] - b[k]))
    return out
