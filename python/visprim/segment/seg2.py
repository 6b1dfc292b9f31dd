"""SEG-2: segmentation where the summed squared angular velocity drops below a threshold.

``z(t) = Σᵢ θ̇ᵢ(t)²`` in (rad/s)², velocities from the real timestamps. Per trial
(vectorised over a corpus), for a threshold ``c``:

1. **Movement runs** are the maximal runs of frames with ``z ≥ c``. A run is *significant*
   when the arm travels more than ``min_travel_deg`` (default 5°) during it, travel being
   the joint-space path length ``∫ √z dt`` (radians, trapezoid rule). Insignificant runs —
   sensor jitter at rest, the filter's transients at a trial's ends — count as rest.
2. **Boundaries:**

   * between two consecutive significant runs: the frame where ``z`` is smallest in the
     rest between them (the instant the arm is closest to standing still);
   * before the first significant run: the movement's *onset*, found by walking back from
     the run's first frame down the slope of ``z`` to its last local minimum (the instant
     the speed starts rising, or the last frame where ``z ≤ 10⁻⁶ c``; this removes the delay
     of the crossing of ``c``, which grows with ``c``);
   * after the last significant run: the *offset*, symmetrically (first local minimum of
     ``z`` after the run).

   With ``boundary="first_stop"`` (``seg2_boundary`` of the model) the boundary after
   *every* significant run is its first stop, the same point whether or not another run
   follows: the first frame after the run's end that is a local minimum of ``z`` (its
   successor is not lower) or, with a ``rest`` level (the robust tuning), at rest, whichever
   comes first (it always comes before the next run starts). The rest before the next run
   then belongs to the next segment. The online segmenter can close every segment as soon
   as its stop is seen (:mod:`visprim.online.segmenter`), where the slowest frame of a gap
   is known only once the next run starts.

3. Consecutive boundaries delimit the segments, so SEG-2 **partitions** the movement from
   onset to offset; with ``n`` significant runs a trial has ``n`` segments (none if it never
   moves significantly).

Threshold tuning (:func:`tune_seg2_threshold`)
----------------------------------------------
The paper chooses ``c`` so that every movement yields at least as many segments as its number
of repetitions; one global ``c`` serves the whole corpus:

1. Candidates: ``n_grid`` (64) values spaced geometrically from the 1st percentile to the
   maximum of ``z`` over the corpus.
2. For every trial and candidate, the number of segments (significant runs) is counted.
3. *Feasible* candidates give every trial at least its repetitions (with ``coverage < 1``,
   at least that fraction of the trials; if no candidate is feasible, those satisfying the
   most trials are).
4. The repetitions alone do not pin ``c`` down (with one repetition per trial any ``c`` that
   keeps the movement is feasible), so the count must also have reached its *plateau*: the
   corpus' total number of segments must be at least ``plateau`` (0.98) times its largest
   value over all candidates. The chosen ``c`` is the **smallest** candidate that is both
   feasible and on the plateau: the lowest threshold that separates the rests between
   strokes (and repetitions) of the whole corpus.

A corpus of more than ``max_trials`` (2000) trials is tuned on ``max_trials`` trials spread
evenly over it (deterministic), which keeps the tuning cost bounded.

Robust tuning for real recordings (:func:`robust_seg2_thresholds`)
-------------------------------------------------------------------
Real recordings carry no repetition count, and the rule above then rests on the plateau of
the corpus' segment count, which one near-static trial (it needs a tiny ``c`` to give any
segment) or a few more or fewer trials move by orders of magnitude. ``tuning="robust"``
instead scales ``c`` to how fast the corpus moves:

* each trial's *movement speed* ``s_i`` is the 95th percentile of its ``z`` (a high
  quantile: most frames of a recording may be rest, yet one spike does not set it);
* the corpus' ``c = κ · median_i s_i`` with ``κ = 0.02`` (``ROBUST_FRACTION``): a stroke
  starts and ends where the squared speed is 2 % of a typical peak, i.e. the speed about
  14 % of it. The median ignores static trials and moves little when trials come or go;
* a slow trial (an elderly raise-up, a careful reach) is cut at the same *relative* speed:
  its own threshold is ``c_i = clip(κ s_i, c / ρ, c)`` with ``ρ = 100`` (``ROBUST_SLOWEST``),
  so movements down to 10x slower than typical keep their strokes, while a near-static
  trial's jitter is still judged against ``c / ρ`` (and the 5° travel of rule 1);
* a recording may start or end in the middle of a movement, or ease in and out of it more
  slowly than the threshold: the first and last boundaries are where the arm is at rest,
  ``z ≤ c_i / 25`` (a fifth of the threshold speed, ``ROBUST_REST``), or the trial's ends,
  rather than the nearest local minimum of ``z``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import params
from visprim.segment.velocity import velocity_concatenated

__all__ = [
    "DEFAULT_MIN_TRAVEL_DEG",
    "Seg2Trace",
    "seg2",
    "seg2_boundaries",
    "robust_seg2_thresholds",
    "seg2_segment_counts",
    "seg2_trace",
    "speed_squared",
    "speed_squared_concatenated",
    "tune_seg2_threshold",
    "tune_seg2_threshold_concatenated",
]

#: A movement run counts as a movement (not jitter) when the arm travels more than this in
#: joint space during it, degrees.
DEFAULT_MIN_TRAVEL_DEG: float = params.SEG2_MIN_TRAVEL_DEG
_PLATEAU = 0.98
_N_GRID = 64
_MAX_TRIALS = 2000
#: z below this fraction of c counts as standing still when walking to an onset / offset.
_STILL = 1e-6
#: Robust tuning: c as a fraction κ of the median trial's 95th-percentile z.
ROBUST_FRACTION: float = 0.02
#: Robust tuning: a trial's own threshold may go down to c / ρ for slow movements.
ROBUST_SLOWEST: float = 100.0
_ROBUST_QUANTILE = 0.95
#: Robust tuning: the arm is at rest (onset / offset) below this fraction of c_i.
ROBUST_REST: float = 1.0 / 25.0
#: Names of the threshold tunings (:func:`tune_seg2_threshold_concatenated`).
TUNINGS = params.TUNINGS
#: Names of the boundary rules (module docstring, rule 2).
BOUNDARIES = params.SEG2_BOUNDARIES


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


@dataclass(frozen=True)
class _Corpus:
    """Frame layout of a concatenated corpus and the running joint-space travel."""

    t: NDArray[np.float64]
    z: NDArray[np.float64]
    offsets: NDArray[np.int64]
    trial_of: NDArray[np.int64]
    first: NDArray[np.bool_]
    last: NDArray[np.bool_]
    travel: NDArray[np.float64]  # travel[i] = path length (rad) from the trial's start to i

    @classmethod
    def build(cls, times: ArrayLike, z: ArrayLike, offsets: ArrayLike) -> _Corpus:
        t = np.ascontiguousarray(times, dtype=np.float64)
        zz = np.ascontiguousarray(z, dtype=np.float64)
        off = np.ascontiguousarray(offsets, dtype=np.int64)
        n = zz.size
        if t.shape != (n,):
            raise ValueError(f"times {t.shape} and z {zz.shape} must have the same length")
        if off.ndim != 1 or off.size == 0 or off[0] != 0 or np.any(np.diff(off) <= 0):
            raise ValueError("offsets must be a non-empty increasing 1-D array starting at 0")
        if off[-1] >= n:
            raise ValueError(f"offsets must be < the number of frames ({n})")
        if not np.all(np.isfinite(zz)) or np.any(zz < 0):
            raise ValueError("z must be finite and >= 0")
        lengths = np.diff(np.append(off, n))
        trial_of = np.repeat(np.arange(off.size), lengths)
        first = np.zeros(n, dtype=bool)
        first[off] = True
        last = np.zeros(n, dtype=bool)
        last[off + lengths - 1] = True
        speed = np.sqrt(zz)
        step = 0.5 * (speed[1:] + speed[:-1]) * np.diff(t)
        step[last[:-1]] = 0.0  # no travel across the join of two trials
        travel = np.concatenate([[0.0], np.cumsum(step)])
        return cls(t, zz, off, trial_of, first, last, travel)

    def significant_runs(
        self, c: float | NDArray[np.float64], min_travel: float
    ) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """First and last frame of every significant run of ``z ≥ c``, in corpus order
        (``c`` one value or one per frame)."""
        above = self.z >= c
        prev = np.concatenate([[False], above[:-1]]) & ~self.first
        nxt = np.concatenate([above[1:], [False]]) & ~self.last
        start = np.flatnonzero(above & ~prev)
        end = np.flatnonzero(above & ~nxt)
        keep = self.travel[end] - self.travel[start] > min_travel
        return start[keep], end[keep]


def _boundaries(
    corpus: _Corpus,
    c: float | NDArray[np.float64],
    min_travel: float,
    rest: float | NDArray[np.float64] | None = None,
    boundary: str = "slowest",
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """(trial, frame) of every SEG-2 boundary, sorted by trial and frame; ``rest`` (z at
    or below which the arm is at rest) replaces the local minima as onsets and offsets;
    ``boundary`` the rule after a run (module docstring)."""
    z, n = corpus.z, corpus.z.size
    s, e = corpus.significant_runs(c, min_travel)
    if s.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    tr = corpus.trial_of[s]
    first_run = np.concatenate([[True], tr[1:] != tr[:-1]])
    last_run = np.concatenate([tr[1:] != tr[:-1], [True]])
    idx = np.arange(n)
    still = z <= _STILL * c  # numerically at rest (exact data): stop walking there
    # Onset: last local minimum of z at or before the run's start (a "stop" frame is a
    # trial's first frame, one not above its predecessor, or one at rest).
    stop_back = corpus.first | still
    if rest is None:
        stop_back[1:] |= z[:-1] >= z[1:]
    else:
        stop_back |= z <= rest
    last_stop = np.maximum.accumulate(np.where(stop_back, idx, 0))
    onset = last_stop[s[first_run]]
    # Offset: first local minimum of z at or after the run's end.
    stop_fwd = corpus.last | still
    if rest is None:
        stop_fwd[:-1] |= z[1:] >= z[:-1]
    else:
        stop_fwd |= z <= rest
    next_stop = np.minimum.accumulate(np.where(stop_fwd, idx, n)[::-1])[::-1]
    offset = next_stop[e[last_run]]
    if boundary == "first_stop":
        # After every run its first stop: a local minimum of z or, with a rest level, rest.
        stop_any = stop_fwd.copy()
        stop_any[:-1] |= z[1:] >= z[:-1]
        first_stop = np.minimum.accumulate(np.where(stop_any, idx, n)[::-1])[::-1][e]
        # Never past the next run's start (it cannot be, with one c per trial).
        first_stop[:-1] = np.where(
            last_run[:-1], first_stop[:-1], np.minimum(first_stop[:-1], s[1:])
        )
        frame = np.concatenate([onset, first_stop])
        trial = corpus.trial_of[frame]
        order = np.lexsort((frame, trial))
        return trial[order], frame[order]
    # Between consecutive significant runs of a trial: argmin of z over the rest between.
    between = ~last_run[:-1]
    gap_start = e[:-1][between] + 1
    gap_stop = s[1:][between]  # exclusive
    if gap_start.size:
        mark = np.zeros(n + 1, dtype=np.int64)
        np.add.at(mark, gap_start, 1)
        np.add.at(mark, gap_stop, -1)
        frames = np.flatnonzero(np.cumsum(mark[:-1]) > 0)
        gap = np.searchsorted(gap_start, frames, side="right") - 1
        order = np.lexsort((z[frames], gap))
        head = np.concatenate([[True], gap[order][1:] != gap[order][:-1]])
        inner = frames[order][head]
    else:
        inner = np.zeros(0, dtype=np.int64)
    frame = np.concatenate([onset, inner, offset])
    trial = corpus.trial_of[frame]
    order = np.lexsort((frame, trial))
    return trial[order], frame[order]


def seg2_boundaries(
    times: ArrayLike,
    z: ArrayLike,
    offsets: ArrayLike,
    threshold: float | ArrayLike,
    *,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
    rest_fraction: float | None = None,
    boundary: str = "slowest",
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """SEG-2 boundaries of a concatenated corpus (rules in the module docstring).

    Parameters
    ----------
    times : (N,) seconds; z : (N,) (rad/s)²; offsets : (n_trials,) first frames.
    threshold : float or (n_trials,) array, c in (rad/s)² (one for all, or per trial).
    min_travel_deg : float, degrees.
    rest_fraction : float, optional
        If given, a trial's first (last) boundary is the last frame before its first (the
        first frame after its last) significant run where ``z ≤ rest_fraction · c``, or the
        trial's end: slow lead-ins and returns stay in the movement. Default: the nearest
        local minimum of z (the paper-faithful rule of the module docstring).
    boundary : {"slowest", "first_stop"}
        The boundary between two runs at the slowest frame of the rest between them, or
        the boundary after every run at its first stop (module docstring, rule 2).

    Returns
    -------
    ``(trial, frame, time)``: trial index, frame index within the trial and time in seconds of
    every boundary, sorted by trial then time. A trial with ``n`` segments has ``n + 1``
    boundaries (none without a segment).
    """
    c = np.asarray(threshold, dtype=np.float64)
    if not (np.all(np.isfinite(c)) and np.all(c > 0)):
        raise ValueError(f"threshold must be a positive number in (rad/s)^2, got {threshold!r}")
    corpus = _Corpus.build(times, z, offsets)
    if c.ndim == 1:
        if c.shape != corpus.offsets.shape:
            raise ValueError(f"{c.size} thresholds for {corpus.offsets.size} trials")
        c = c[corpus.trial_of]
    elif c.ndim != 0:
        raise ValueError(f"threshold must be a number or one per trial, got shape {c.shape}")
    if boundary not in BOUNDARIES:
        raise ValueError(f"boundary must be one of {list(BOUNDARIES)}, got {boundary!r}")
    cc = c if c.ndim else float(c)
    rest = None if rest_fraction is None else float(rest_fraction) * cc
    trial, frame = _boundaries(corpus, cc, _min_travel(min_travel_deg), rest, boundary)
    return trial, frame - corpus.offsets[trial], corpus.t[frame]


def robust_seg2_thresholds(
    z: ArrayLike,
    offsets: ArrayLike,
    *,
    threshold: float | None = None,
    fraction: float = ROBUST_FRACTION,
    slowest: float = ROBUST_SLOWEST,
) -> tuple[float, NDArray[np.float64]]:
    """The robust SEG-2 thresholds of a concatenated corpus (module docstring).

    Parameters
    ----------
    z : (N,) (rad/s)², concatenated; offsets : (n_trials,) first frames.
    threshold : the corpus' c if already known (e.g. fitted on training data); then only
        the trials' own thresholds are derived here.
    fraction : κ, c as a fraction of the median trial's movement speed (z units).
    slowest : ρ, how far below c a slow trial's own threshold may go.

    Returns
    -------
    ``(c, c_i)``: the corpus' threshold and each trial's, (rad/s)².
    """
    zz = np.ascontiguousarray(z, dtype=np.float64)
    off = np.ascontiguousarray(offsets, dtype=np.int64)
    if not (0 < fraction < 1) or not slowest >= 1:
        raise ValueError(f"need 0 < fraction < 1 and slowest >= 1, got {fraction}, {slowest}")
    speeds = np.array([np.quantile(part, _ROBUST_QUANTILE) for part in np.split(zz, off[1:])])
    moving = speeds[speeds > 0]
    if threshold is not None:
        c = float(threshold)
    elif moving.size == 0:
        raise ValueError("the corpus never moves (z is 0 everywhere); no threshold exists")
    else:
        c = float(fraction * np.median(moving))
    return c, np.clip(fraction * speeds, c / float(slowest), c)


def _min_travel(min_travel_deg: float) -> float:
    if not (np.isfinite(min_travel_deg) and min_travel_deg >= 0):
        raise ValueError(f"min_travel_deg must be a number of degrees >= 0, got {min_travel_deg!r}")
    return float(np.deg2rad(min_travel_deg))


def _segment_counts(
    corpus: _Corpus, grid: NDArray[np.float64], min_travel: float
) -> NDArray[np.int64]:
    m = corpus.offsets.size
    counts = np.empty((m, grid.size), dtype=np.int64)
    for k, c in enumerate(grid):
        s, _ = corpus.significant_runs(float(c), min_travel)
        counts[:, k] = np.bincount(corpus.trial_of[s], minlength=m)
    return counts


def seg2_segment_counts(
    times: ArrayLike,
    z: ArrayLike,
    offsets: ArrayLike,
    grid: ArrayLike,
    *,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
) -> NDArray[np.int64]:
    """Number of SEG-2 segments of every trial at every candidate threshold.

    Parameters
    ----------
    times : (N,) seconds; z : (N,) (rad/s)², concatenated; offsets : (n_trials,) first frames;
    grid : (K,) candidate thresholds, (rad/s)².

    Returns
    -------
    (n_trials, K) int64.
    """
    g = np.asarray(grid, dtype=np.float64)
    if g.ndim != 1 or g.size == 0 or not np.all(g > 0):
        raise ValueError("grid must be a non-empty 1-D array of positive thresholds")
    return _segment_counts(_Corpus.build(times, z, offsets), g, _min_travel(min_travel_deg))


def _subset(
    offsets: NDArray[np.int64], n: int, keep: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Frame rows and new offsets of the trials ``keep`` of a concatenation."""
    lengths = np.diff(np.append(offsets, n))[keep]
    new_off = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    rows = np.repeat(offsets[keep] - new_off, lengths) + np.arange(lengths.sum())
    return rows, new_off


def tune_seg2_threshold_concatenated(
    times: ArrayLike,
    z: ArrayLike,
    offsets: ArrayLike,
    repetitions: ArrayLike | int = 1,
    *,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
    coverage: float = 1.0,
    plateau: float = _PLATEAU,
    n_grid: int = _N_GRID,
    max_trials: int = _MAX_TRIALS,
) -> float:
    """Global SEG-2 threshold ``c`` ((rad/s)²) of a concatenated corpus (rules in the module
    docstring). ``repetitions``: one int per trial, or one for all."""
    off = np.ascontiguousarray(offsets, dtype=np.int64)
    reps = np.broadcast_to(np.asarray(repetitions, dtype=np.int64), off.shape)
    if np.any(reps < 1):
        raise ValueError("repetitions must be >= 1 for every trial")
    if not (0 < coverage <= 1):
        raise ValueError(f"coverage must be in (0, 1], got {coverage!r}")
    if not (0 < plateau <= 1):
        raise ValueError(f"plateau must be in (0, 1], got {plateau!r}")
    if int(n_grid) < 2 or int(max_trials) < 1:
        raise ValueError(f"n_grid must be >= 2 and max_trials >= 1, got {n_grid}, {max_trials}")
    t = np.ascontiguousarray(times, dtype=np.float64)
    zz = np.ascontiguousarray(z, dtype=np.float64)
    if off.size > max_trials:
        keep = np.unique(np.linspace(0, off.size - 1, int(max_trials)).round().astype(np.int64))
        rows, off = _subset(off, zz.size, keep)
        t, zz, reps = t[rows], zz[rows], reps[keep]
    corpus = _Corpus.build(t, zz, off)
    top = float(zz.max())
    if not top > 0:
        raise ValueError("the corpus never moves (z is 0 everywhere); no threshold exists")
    low = max(float(np.quantile(zz, 0.01)), top * 1e-9)
    grid = np.geomspace(low, top, int(n_grid))
    counts = _segment_counts(corpus, grid, _min_travel(min_travel_deg))
    satisfied = (counts >= reps[:, None]).sum(axis=0)
    feasible = satisfied >= int(np.ceil(coverage * off.size - 1e-9))
    if not np.any(feasible):
        feasible = satisfied == satisfied.max()
    total = counts.sum(axis=0)
    ok = feasible & (total >= plateau * total[feasible].max())
    return float(grid[int(np.argmax(ok))])


def tune_seg2_threshold(
    times_list: Sequence[ArrayLike],
    angles_list: Sequence[ArrayLike],
    repetitions: Sequence[int] | int = 1,
    *,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
    coverage: float = 1.0,
    plateau: float = _PLATEAU,
    n_grid: int = _N_GRID,
    max_trials: int = _MAX_TRIALS,
) -> float:
    """One SEG-2 threshold ``c`` ((rad/s)²) for a whole corpus of trials (times (T_i,)
    seconds, angles (T_i, C) radians, normally low-passed); rules in the module docstring.

    ``repetitions``: per trial (e.g. ``[t.repetitions for t in trials]``) or one for all.
    """
    if len(times_list) != len(angles_list) or len(times_list) == 0:
        raise ValueError("times_list and angles_list must be non-empty and of equal length")
    lengths = np.array([np.shape(a)[0] for a in angles_list], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    t = np.concatenate([np.asarray(x, dtype=np.float64) for x in times_list])
    z = speed_squared_concatenated(
        t, np.concatenate([np.asarray(a, dtype=np.float64) for a in angles_list]), offsets
    )
    return tune_seg2_threshold_concatenated(
        t,
        z,
        offsets,
        np.asarray(repetitions, dtype=np.int64),
        min_travel_deg=min_travel_deg,
        coverage=coverage,
        plateau=plateau,
        n_grid=n_grid,
        max_trials=max_trials,
    )


@dataclass(frozen=True)
class Seg2Trace:
    """Everything SEG-2 computed on one trial (for plots such as the paper's Fig. 6)."""

    times: NDArray[np.float64]  #: (T,) seconds
    z: NDArray[np.float64]  #: (T,) Σ θ̇ᵢ², (rad/s)²
    threshold: float  #: c, (rad/s)²
    boundaries: NDArray[np.float64]  #: (n + 1,) seconds (empty without a segment)
    boundary_frames: NDArray[np.int64]  #: (n + 1,) frame indices of the boundaries
    segments: NDArray[np.float64]  #: (n, 2) [start, end] seconds


def seg2_trace(
    times: ArrayLike,
    angles: ArrayLike,
    repetitions: int = 1,
    threshold: float | None = None,
    *,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
) -> Seg2Trace:
    """:func:`seg2` with its intermediate results (z(t), c, boundaries)."""
    t = np.asarray(times, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim != 2:
        raise ValueError(f"angles must have shape (T, channels), got {a.shape}")
    off = np.zeros(1, dtype=np.int64)
    z = speed_squared_concatenated(t, a, off)
    if threshold is None:
        c = tune_seg2_threshold_concatenated(
            t, z, off, int(repetitions), min_travel_deg=min_travel_deg
        )
    else:
        c = float(threshold)
    _, frames, b = seg2_boundaries(t, z, off, c, min_travel_deg=min_travel_deg)
    segs = np.stack([b[:-1], b[1:]], axis=1) if b.size >= 2 else np.zeros((0, 2))
    return Seg2Trace(t, z, c, b, frames, segs)


def seg2(
    times: ArrayLike,
    angles: ArrayLike,
    repetitions: int = 1,
    threshold: float | None = None,
    *,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
) -> NDArray[np.float64]:
    """SEG-2 segments of one trial.

    Parameters
    ----------
    times : (T,) seconds
        Timestamps (velocities are computed from them).
    angles : (T, C) radians
        Joint angles, normally low-passed first (:mod:`visprim.filtering`).
    repetitions : int
        Repetitions of the movement; used only to tune ``threshold`` when it is None.
    threshold : float, optional
        ``c`` in (rad/s)². Default: tuned on this trial alone (:func:`tune_seg2_threshold`).
        For a corpus, tune one ``c`` on all trials and pass it, or use
        :func:`visprim.segment.segment_corpus`.
    min_travel_deg : float, degrees
        Joint-space travel that makes a run of ``z ≥ c`` a movement (default 5°).

    Returns
    -------
    (n, 2) float64 array of consecutive [start, end] times in seconds (a partition of the
    movement from onset to offset).
    """
    return seg2_trace(times, angles, repetitions, threshold, min_travel_deg=min_travel_deg).segments
