"""SEG-2: segmentation where the summed squared angular velocity drops below a threshold.

``z(t) = Σᵢ θ̇ᵢ(t)²`` in (rad/s)², velocities from the real timestamps. Frames with
``z < c`` are *rest*. Per trial (vectorised over a corpus):

* a rest run that touches neither end of the trial yields one boundary, at the frame where
  ``z`` is smallest in the run (the instant the arm is closest to standing still);
* a rest run at the start of the trial yields the movement's onset: the time where ``z``
  rises through ``c`` (linear interpolation between frames); one at the end yields the
  offset where ``z`` falls through ``c``. A trial that starts (ends) above ``c`` gets a
  boundary at its first (last) frame;
* consecutive boundaries delimit the segments, so SEG-2 **partitions** the movement from
  onset to offset; a trial that never exceeds ``c`` has no segment.

With ``n_dips(c)`` interior rest runs a trial has ``n_dips(c) + 1`` segments.

Threshold tuning (:func:`tune_seg2_threshold`)
----------------------------------------------
The paper chooses ``c`` so that every movement yields at least as many segments as its
number of repetitions. One global ``c`` serves the whole corpus:

1. Candidate thresholds: ``n_grid`` values spaced geometrically between the 1st percentile
   and the maximum of ``z`` over the corpus.
2. For every trial and candidate, the number of segments is counted exactly (vectorised:
   each frame adds one rest run on the interval of ``c`` where it starts one).
3. The feasible candidates are those for which every trial reaches its repetitions
   (``n_segments ≥ repetitions``); with ``coverage < 1`` a fraction ``1 − coverage`` of
   the trials may miss. If none is feasible, the candidate with most satisfied trials wins.
4. Among the feasible candidates, the chosen ``c`` is the one that segments the corpus the
   most consistently: the one maximising the total number of segments, i.e. separating the
   most rests; ties go to the *smallest* such c (the most conservative one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim.segment.velocity import velocity_concatenated

__all__ = [
    "Seg2Trace",
    "seg2",
    "seg2_boundaries",
    "seg2_segment_counts",
    "seg2_trace",
    "speed_squared",
    "speed_squared_concatenated",
    "tune_seg2_threshold",
    "tune_seg2_threshold_concatenated",
]


def speed_squared_concatenated(
    times: ArrayLike, angles: ArrayLike, offsets: ArrayLike
) -> NDArray[np.float64]:
    """``z = Σᵢ θ̇ᵢ²`` ((rad/s)²) of every frame of a concatenated corpus."""
    v = velocity_concatenated(times, angles, offsets)
    return np.einsum("ij,ij->i", v, v)


def speed_squared(times: ArrayLike, angles: ArrayLike) -> NDArray[np.float64]:
    """``z(t) = Σᵢ θ̇ᵢ(t)²`` of one trial, (T,) in (rad/s)²; angles (T, C) radians,
    times (T,) seconds."""
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim != 2:
        raise ValueError(f"angles must have shape (T, channels), got {a.shape}")
    return speed_squared_concatenated(times, a, np.zeros(1, dtype=np.int64))


def _layout(n: int, offsets: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    lengths = np.diff(np.append(offsets, n))
    return np.repeat(np.arange(offsets.size), lengths), np.append(offsets[1:], n) - 1


def seg2_boundaries(
    times: ArrayLike, z: ArrayLike, offsets: ArrayLike, threshold: float
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """SEG-2 boundaries of a concatenated corpus: ``(trial, time s)`` sorted by trial and
    time (rules in the module docstring). ``z`` in (rad/s)², ``threshold`` ``c`` likewise."""
    t = np.asarray(times, dtype=np.float64)
    zz = np.asarray(z, dtype=np.float64)
    off = np.asarray(offsets, dtype=np.int64)
    c = float(threshold)
    if not (np.isfinite(c) and c > 0):
        raise ValueError(f"threshold must be a positive number in (rad/s)^2, got {threshold!r}")
    n = zz.size
    trial_of, last = _layout(n, off)
    first_mask = np.zeros(n, dtype=bool)
    first_mask[off] = True
    last_mask = np.zeros(n, dtype=bool)
    last_mask[last] = True

    below = zz < c
    prev_below = np.concatenate([[False], below[:-1]]) & ~first_mask
    next_below = np.concatenate([below[1:], [False]]) & ~last_mask
    run_start = np.flatnonzero(below & ~prev_below)
    run_end = np.flatnonzero(below & ~next_below)
    lead = first_mask[run_start] & ~last_mask[run_end]
    trail = last_mask[run_end] & ~first_mask[run_start]
    inner = ~first_mask[run_start] & ~last_mask[run_end]

    # Interior runs: frame of minimal z in the run.
    run_id = np.cumsum(below & ~prev_below) - 1
    idx = np.flatnonzero(below)
    rid = run_id[idx]
    order = np.lexsort((zz[idx], rid))
    is_first = np.ones(order.size, dtype=bool)
    is_first[1:] = rid[order][1:] != rid[order][:-1]
    argmin = idx[order][is_first]  # one per run, in run order
    b_inner = t[argmin[inner]]

    # Onset after a leading run: z rises through c between frames e and e + 1.
    e = run_end[lead]
    b_lead = t[e] + (c - zz[e]) / (zz[e + 1] - zz[e]) * (t[e + 1] - t[e])
    # Offset before a trailing run: z falls through c between frames s - 1 and s.
    s = run_start[trail]
    b_trail = t[s - 1] + (zz[s - 1] - c) / (zz[s - 1] - zz[s]) * (t[s] - t[s - 1])
    # Trials that start / end above c.
    b_first = off[~below[off]]
    b_last = last[~below[last]]

    trial = np.concatenate(
        [
            trial_of[argmin[inner]],
            trial_of[e],
            trial_of[s],
            trial_of[b_first],
            trial_of[b_last],
        ]
    )
    time = np.concatenate([b_inner, b_lead, b_trail, t[b_first], t[b_last]])
    order = np.lexsort((time, trial))
    return trial[order], time[order]


def _segments_from_boundaries(
    trial: NDArray[np.int64], time: NDArray[np.float64]
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    same = trial[1:] == trial[:-1]
    return trial[:-1][same], time[:-1][same], time[1:][same]


def seg2_segment_counts(
    z: ArrayLike, offsets: ArrayLike, grid: ArrayLike
) -> NDArray[np.int64]:
    """Exact number of SEG-2 segments of every trial at every candidate threshold.

    Parameters
    ----------
    z : (N,) (rad/s)², concatenated; offsets : (n_trials,) first frames;
    grid : (K,) ascending candidate thresholds, (rad/s)².

    Returns
    -------
    (n_trials, K) int64.
    """
    zz = np.asarray(z, dtype=np.float64)
    off = np.asarray(offsets, dtype=np.int64)
    g = np.asarray(grid, dtype=np.float64)
    if g.ndim != 1 or g.size == 0 or np.any(np.diff(g) <= 0):
        raise ValueError("grid must be a non-empty strictly increasing 1-D array")
    n, m, k = zz.size, off.size, g.size
    trial_of, last = _layout(n, off)
    not_first = np.ones(n, dtype=bool)
    not_first[off] = False
    j = np.flatnonzero(not_first)
    # A rest run starts at frame j >= 1 exactly when z[j] < c <= z[j-1].
    lo = np.searchsorted(g, zz[j], side="right")
    hi = np.searchsorted(g, zz[j - 1], side="right")
    ok = lo < hi
    width = k + 1
    starts = np.bincount(trial_of[j][ok] * width + lo[ok], minlength=m * width)
    stops = np.bincount(trial_of[j][ok] * width + hi[ok], minlength=m * width)
    runs = np.cumsum((starts - stops).reshape(m, width), axis=1)[:, :k]
    cols = np.arange(k)[None, :]
    last_below = cols >= np.searchsorted(g, zz[last], side="right")[:, None]
    zmax = np.maximum.reduceat(zz, off)
    all_below = cols >= np.searchsorted(g, zmax, side="right")[:, None]
    inner = runs - last_below + all_below
    return np.where(all_below, 0, inner + 1).astype(np.int64)


def tune_seg2_threshold_concatenated(
    z: ArrayLike,
    offsets: ArrayLike,
    repetitions: ArrayLike | int = 1,
    *,
    coverage: float = 1.0,
    n_grid: int = 400,
) -> float:
    """Global SEG-2 threshold ``c`` ((rad/s)²) of a concatenated corpus (rules in the module
    docstring). ``repetitions``: one int per trial (or one for all)."""
    zz = np.asarray(z, dtype=np.float64)
    off = np.asarray(offsets, dtype=np.int64)
    reps = np.broadcast_to(np.asarray(repetitions, dtype=np.int64), off.shape)
    if np.any(reps < 1):
        raise ValueError("repetitions must be >= 1 for every trial")
    if not (0 < coverage <= 1):
        raise ValueError(f"coverage must be in (0, 1], got {coverage!r}")
    if int(n_grid) < 2:
        raise ValueError(f"n_grid must be >= 2, got {n_grid!r}")
    if zz.size == 0 or not np.all(np.isfinite(zz)):
        raise ValueError("z must be non-empty and finite")
    top = float(zz.max())
    low = float(np.quantile(zz, 0.01))
    low = max(low, top * 1e-12)
    if not top > 0:
        raise ValueError("the corpus never moves (z is 0 everywhere); no threshold exists")
    grid = np.geomspace(low, top, int(n_grid))
    counts = seg2_segment_counts(zz, off, grid)
    satisfied = (counts >= reps[:, None]).sum(axis=0)
    need = int(np.ceil(coverage * off.size - 1e-9))
    feasible = satisfied >= need
    if not np.any(feasible):
        feasible = satisfied == satisfied.max()
    total = np.where(feasible, counts.sum(axis=0), -1)
    return float(grid[int(np.argmax(total))])


def tune_seg2_threshold(
    times_list: Sequence[ArrayLike],
    angles_list: Sequence[ArrayLike],
    repetitions: Sequence[int] | int = 1,
    *,
    coverage: float = 1.0,
    n_grid: int = 400,
) -> float:
    """One SEG-2 threshold ``c`` ((rad/s)²) for a whole corpus of trials (times in seconds,
    angles (T_i, C) radians, normally low-passed); see the module docstring."""
    if len(times_list) != len(angles_list) or len(times_list) == 0:
        raise ValueError("times_list and angles_list must be non-empty and of equal length")
    lengths = np.array([np.shape(a)[0] for a in angles_list], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    z = speed_squared_concatenated(
        np.concatenate([np.asarray(t, dtype=np.float64) for t in times_list]),
        np.concatenate([np.asarray(a, dtype=np.float64) for a in angles_list]),
        offsets,
    )
    return tune_seg2_threshold_concatenated(
        z, offsets, repetitions, coverage=coverage, n_grid=n_grid
    )


@dataclass(frozen=True)
class Seg2Trace:
    """Everything SEG-2 computed on one trial (for plots such as the paper's Fig. 6)."""

    times: NDArray[np.float64]  #: (T,) seconds
    z: NDArray[np.float64]  #: (T,) Σ θ̇ᵢ², (rad/s)²
    threshold: float  #: c, (rad/s)²
    boundaries: NDArray[np.float64]  #: (n + 1,) seconds (empty if no segment)
    segments: NDArray[np.float64]  #: (n, 2) [start, end] seconds


def seg2_trace(
    times: ArrayLike,
    angles: ArrayLike,
    repetitions: int = 1,
    threshold: float | None = None,
    *,
    n_grid: int = 400,
) -> Seg2Trace:
    """:func:`seg2` with its intermediate results (z(t), c, boundaries)."""
    t = np.asarray(times, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim != 2:
        raise ValueError(f"angles must have shape (T, channels), got {a.shape}")
    off = np.zeros(1, dtype=np.int64)
    z = speed_squared_concatenated(t, a, off)
    if threshold is None:
        c = tune_seg2_threshold_concatenated(z, off, int(repetitions), n_grid=n_grid)
    else:
        c = float(threshold)
    _, b = seg2_boundaries(t, z, off, c)
    segs = np.stack([b[:-1], b[1:]], axis=1) if b.size >= 2 else np.zeros((0, 2))
    return Seg2Trace(t, z, c, b, segs)


def seg2(
    times: ArrayLike,
    angles: ArrayLike,
    repetitions: int = 1,
    threshold: float | None = None,
    *,
    n_grid: int = 400,
) -> NDArray[np.float64]:
    """SEG-2 segments of one trial.

    Parameters
    ----------
    times : (T,) seconds
        Timestamps (velocities are computed from them).
    angles : (T, C) radians
        Joint angles, normally low-passed first (:mod:`visprim.filtering`).
    repetitions : int
        Repetitions of the movement; used only when ``threshold`` is None.
    threshold : float, optional
        ``c`` in (rad/s)². Default: tuned on this trial alone with
        :func:`tune_seg2_threshold` (for a corpus, tune one ``c`` on all trials and pass it,
        or use :func:`visprim.segment.segment_corpus`).

    Returns
    -------
    (n, 2) float64 array of consecutive [start, end] times in seconds (a partition of the
    movement from onset to offset).
    """
    return seg2_trace(times, angles, repetitions, threshold, n_grid=n_grid).segments
