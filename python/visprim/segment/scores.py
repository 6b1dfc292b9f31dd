"""Scoring found segment boundaries against ground truth (precision / recall / F1).

Boundaries match **one to one**: a found boundary matches at most one true boundary and
vice versa, and only if they are at most ``tolerance`` seconds apart (default 0.1 s =
±100 ms). The number of matches is the maximum possible; on a line a sweep over both sorted
lists (match the earliest compatible pair, otherwise advance the earlier one) achieves it.

Conventions for empty inputs: with nothing found, precision is 1 (no false boundary); with
no true boundary, recall is 1; F1 is 0 when precision + recall is 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "BoundaryScores",
    "boundary_matches",
    "boundary_scores",
    "corpus_boundary_scores",
    "segment_boundaries",
]

#: Segment ends closer than this (seconds) are the same boundary.
_SAME_BOUNDARY = 1e-9


class BoundaryScores(NamedTuple):
    precision: float
    recall: float
    f1: float


def segment_boundaries(found: ArrayLike) -> NDArray[np.float64]:
    """Sorted distinct boundary times (seconds) of (n, 2) segments, or of (n,) boundary
    times as they are. Touching segments share their common boundary."""
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
    found: ArrayLike, truth: ArrayLike, tolerance: float = 0.1
) -> tuple[int, int, int]:
    """``(n_matched, n_found, n_truth)`` under one-to-one matching within ``tolerance``
    seconds. ``found``: (n, 2) segments or (n,) times; ``truth``: (m,) times (or segments)."""
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise ValueError(f"tolerance must be a number of seconds >= 0, got {tolerance!r}")
    f = segment_boundaries(found)
    t = segment_boundaries(truth)
    i = j = matched = 0
    fl, tl = f.tolist(), t.tolist()
    while i < len(fl) and j < len(tl):
        if fl[i] < tl[j] - tolerance:
            i += 1
        elif fl[i] > tl[j] + tolerance:
            j += 1
        else:
            matched += 1
            i += 1
            j += 1
    return matched, len(fl), len(tl)


def _scores(matched: int, n_found: int, n_truth: int) -> BoundaryScores:
    precision = matched / n_found if n_found else 1.0
    recall = matched / n_truth if n_truth else 1.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return BoundaryScores(float(precision), float(recall), float(f1))


def boundary_scores(found: ArrayLike, truth: ArrayLike, tolerance: float = 0.1) -> BoundaryScores:
    """Precision, recall and F1 of one trial's found boundaries against the true ones.

    Parameters
    ----------
    found : (n, 2) segments [start, end] or (n,) boundary times, seconds
        E.g. the output of :func:`~visprim.segment.seg1` or :func:`~visprim.segment.seg2`.
    truth : (m,) boundary times, seconds (e.g. ``trial.truth.boundaries``).
    tolerance : float, seconds
        Largest distance of a match (default 0.1 s).
    """
    return _scores(*boundary_matches(found, truth, tolerance))


def corpus_boundary_scores(
    found: Sequence[ArrayLike], truth: Sequence[ArrayLike], tolerance: float = 0.1
) -> BoundaryScores:
    """Micro-averaged scores over many trials: matches, found and true boundaries are summed
    over trials (no boundary of one trial matches another's) before the ratios."""
    if len(found) != len(truth):
        raise ValueError(f"found has {len(found)} trials but truth has {len(truth)}")
    total = np.zeros(3, dtype=np.int64)
    for f, t in zip(found, truth, strict=True):
        total += boundary_matches(f, t, tolerance)
    return _scores(*(int(x) for x in total))
