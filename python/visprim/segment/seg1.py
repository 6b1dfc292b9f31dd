"""SEG-1: segmentation at zero-velocity crossings shared by several DOFs.

Algorithm (per trial, a whole corpus per call; the grouping of step 2 runs in the Rust kernel
:func:`visprim.kernels.seg1_events`):

1. Find the significant ZVCs of every DOF (:mod:`visprim.segment.zvc`).
2. Merge the ZVCs of all DOFs, in time order, into *events*: a ZVC closer than ``window``
   seconds (default 0.3 s = 300 ms) to the previous ZVC joins that ZVC's event (single
   linkage along time). An event's time is the **median** time of its ZVCs (robust to the
   late or early crossing of a DOF that stops slowly and jitters around zero velocity).
3. An event is a *snip* when ZVCs of at least ``min_dofs`` (default 2, "more than one")
   distinct DOFs fall in it; otherwise it is a lone ZVC.
4. The movement is cut at every event; a segment between two consecutive events is kept
   only if **both** ends are snips. Segments next to a lone ZVC are dropped, so SEG-1 does
   not partition the movement (unlike SEG-2), and the first onset of a trial (from rest,
   where no velocity changes sign) is never a snip.

Consecutive snips are more than ``window`` apart, so every segment lasts more than
``window`` seconds.

Fast cyclic motion (``adaptive=True``, the default): when a trial's DOFs reverse faster than
the window (a wave, arm swing in a run), single linkage chains every crossing of the trial
into one event and SEG-1 finds nothing. So a trial's window is ``min(window, h / 2)``, with
``h`` the trial's typical half-cycle: the median time between consecutive crossings of the
same DOF. Each half-cycle's reversal is then an event of its own, and a segment per
half-cycle is cut. Slower movements keep the paper's window. ``adaptive=False`` is the
paper's rule.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import kernels
from visprim.segment.zvc import DEFAULT_MIN_CHANGE_DEG, CorpusCrossings, zvc_concatenated

__all__ = ["DEFAULT_WINDOW", "Seg1Events", "seg1", "seg1_events", "seg1_from_crossings"]

#: Seconds within which ZVCs of different DOFs count as one event (300 ms, as the paper).
DEFAULT_WINDOW: float = 0.3


class Seg1Events(NamedTuple):
    """Events of a corpus, sorted by trial then time."""

    trial: NDArray[np.int64]  #: (m,) trial index
    time: NDArray[np.float64]  #: (m,) seconds, median time of the event's ZVCs
    n_dofs: NDArray[np.int64]  #: (m,) number of distinct DOFs with a ZVC in the event
    is_snip: NDArray[np.bool_]  #: (m,) n_dofs >= min_dofs


def _trial_windows(
    trial: NDArray[np.int64], dof: NDArray[np.int64], time: NDArray[np.float64], window: float
) -> NDArray[np.float64]:
    """Per crossing, its trial's window ``min(window, h / 2)`` (module docstring)."""
    out = np.full(time.size, float(window))
    if time.size < 2:
        return out
    order = np.lexsort((time, dof, trial))
    t, d, tr = time[order], dof[order], trial[order]
    same = (tr[1:] == tr[:-1]) & (d[1:] == d[:-1])
    gaps, gap_trial = np.diff(t)[same], tr[1:][same]
    if gaps.size == 0:
        return out
    # Median gap of each trial, all trials at once: gaps sorted by (trial, gap), then the
    # middle one (or the mean of the middle two) of each trial's run.
    by = np.lexsort((gaps, gap_trial))
    gaps, gap_trial = gaps[by], gap_trial[by]
    trials, first, counts = np.unique(gap_trial, return_index=True, return_counts=True)
    medians = 0.5 * (gaps[first + (counts - 1) // 2] + gaps[first + counts // 2])
    per_trial = np.full(int(trial.max()) + 1, float(window))
    per_trial[trials] = np.minimum(window, 0.5 * medians)
    return per_trial[trial]


def seg1_events(
    crossings: CorpusCrossings,
    *,
    window: float = DEFAULT_WINDOW,
    min_dofs: int = 2,
    adaptive: bool = True,
) -> Seg1Events:
    """Group the ZVCs of a corpus into events (steps 2–3 of the module docstring; with
    ``adaptive``, a shorter window for trials of fast cyclic motion)."""
    if not (np.isfinite(window) and window > 0):
        raise ValueError(f"window must be a positive number of seconds, got {window!r}")
    if int(min_dofs) < 1:
        raise ValueError(f"min_dofs must be >= 1, got {min_dofs!r}")
    trial = np.asarray(crossings.trial, dtype=np.int64)
    dof = np.asarray(crossings.dof, dtype=np.int64)
    time = np.asarray(crossings.time, dtype=np.float64)
    if trial.size > 1 and np.any(trial[1:] < trial[:-1]):
        order = np.argsort(trial, kind="stable")  # the kernel wants crossings grouped by trial
        trial, dof, time = trial[order], dof[order], time[order]
    if not adaptive:
        ev_trial, ev_time, n_dofs = kernels.seg1_events(trial, dof, time, float(window))
        return Seg1Events(ev_trial, ev_time, n_dofs, n_dofs >= int(min_dofs))
    # A trial's own window w_i: its clock is scaled by window / w_i for the kernel (one
    # window for all), and the event times scaled back.
    scale = float(window) / _trial_windows(trial, dof, time, float(window))
    ev_trial, ev_time, n_dofs = kernels.seg1_events(trial, dof, time * scale, float(window))
    trial_scale = np.ones(int(trial.max()) + 1 if trial.size else 0)
    trial_scale[trial] = scale
    ev_time = np.asarray(ev_time) / trial_scale[np.asarray(ev_trial, dtype=np.int64)]
    return Seg1Events(ev_trial, ev_time, n_dofs, n_dofs >= int(min_dofs))


def seg1_from_crossings(
    crossings: CorpusCrossings,
    *,
    window: float = DEFAULT_WINDOW,
    min_dofs: int = 2,
    adaptive: bool = True,
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """SEG-1 segments of a corpus from its ZVCs: ``(trial, start s, end s)`` arrays, sorted
    by trial then time."""
    ev = seg1_events(crossings, window=window, min_dofs=min_dofs, adaptive=adaptive)
    keep = (ev.trial[1:] == ev.trial[:-1]) & ev.is_snip[1:] & ev.is_snip[:-1]
    return ev.trial[:-1][keep], ev.time[:-1][keep], ev.time[1:][keep]


def seg1(
    times: ArrayLike,
    angles: ArrayLike,
    window: float = DEFAULT_WINDOW,
    *,
    min_change_deg: float = DEFAULT_MIN_CHANGE_DEG,
    min_dofs: int = 2,
    adaptive: bool = True,
) -> NDArray[np.float64]:
    """SEG-1 segments of one trial (see the module docstring).

    Parameters
    ----------
    times : (T,) seconds
        Timestamps (velocities are computed from them).
    angles : (T, C) radians
        Joint angles, normally low-passed first (:mod:`visprim.filtering`).
    window : float, seconds
        ZVCs of different DOFs closer than this form one event (default 0.3 s).
    min_change_deg : float, degrees
        Significant-movement threshold of the ZVCs (:mod:`visprim.segment.zvc`).
    min_dofs : int
        Distinct DOFs an event needs to be a snip (default 2: "more than one DOF").
    adaptive : bool
        Shorter window for fast cyclic motion (default True; False: the paper's rule).

    Returns
    -------
    (n, 2) float64 array of [start, end] times in seconds, in time order (may be empty;
    consecutive segments need not touch).
    """
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim != 2:
        raise ValueError(f"angles must have shape (T, channels), got {a.shape}")
    c = zvc_concatenated(times, a, np.zeros(1, dtype=np.int64), min_change_deg=min_change_deg)
    _, start, end = seg1_from_crossings(c, window=window, min_dofs=min_dofs, adaptive=adaptive)
    return np.stack([start, end], axis=1) if start.size else np.zeros((0, 2))
