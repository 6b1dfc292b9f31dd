"""Whole-corpus segmentation: velocities, ZVCs, SEG-1 / SEG-2 on all trials at once.

The trials are concatenated once; velocities (numpy on the concatenation), ZVCs (one call of
the Rust ragged kernel) and the SEG-1 / SEG-2 rules (numpy, no loop over trials) then run on
the whole corpus. Results come back as one table of segments with, for each, the trial it
belongs to, its start and end in seconds and as fractional frame indices (ready for
:func:`visprim.kernels.resample_segments` on the concatenated angles, see
:meth:`CorpusSegmentation.global_frames`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import params
from visprim.segment.clock import times_to_frames
from visprim.segment.seg1 import DEFAULT_WINDOW, seg1_from_crossings
from visprim.segment.seg2 import (
    DEFAULT_MIN_TRAVEL_DEG,
    ROBUST_REST,
    TUNINGS,
    robust_seg2_thresholds,
    seg2_boundaries,
    tune_seg2_threshold_concatenated,
)
from visprim.segment.velocity import velocity_concatenated
from visprim.segment.zvc import DEFAULT_MIN_CHANGE_DEG, zvc_concatenated

__all__ = ["CorpusSegmentation", "segment_concatenated", "segment_corpus"]

Method = Literal["seg1", "seg2"]


@dataclass(frozen=True)
class CorpusSegmentation:
    """Segments of a concatenated corpus, sorted by trial then time.

    Attributes
    ----------
    method : "seg1" or "seg2"
    trial : (n,) int64, index of each segment's trial
    start, end : (n,) float64, seconds on the trial's clock
    start_frame, end_frame : (n,) float64, fractional frame indices within the trial
    offsets : (n_trials,) int64, first frame of each trial in the concatenation
    n_frames : int, total frames of the concatenation
    threshold : float or None, the SEG-2 threshold c in (rad/s)² (None for SEG-1)
    z : (n_frames,) float64 or None, SEG-2's Σ θ̇ᵢ² per frame, (rad/s)² (None for SEG-1)
    trial_thresholds : (n_trials,) float64 or None, each trial's own c (robust tuning; None
        when every trial uses ``threshold``)
    """

    method: str
    trial: NDArray[np.int64]
    start: NDArray[np.float64]
    end: NDArray[np.float64]
    start_frame: NDArray[np.float64]
    end_frame: NDArray[np.float64]
    offsets: NDArray[np.int64]
    n_frames: int
    threshold: float | None = None
    z: NDArray[np.float64] | None = None
    trial_thresholds: NDArray[np.float64] | None = None

    @property
    def n_segments(self) -> int:
        return int(self.trial.size)

    @property
    def n_trials(self) -> int:
        return int(self.offsets.size)

    @property
    def durations(self) -> NDArray[np.float64]:
        """(n,) seconds."""
        return self.end - self.start

    def global_frames(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Start and end as fractional frame indices into the concatenated corpus."""
        base = self.offsets[self.trial].astype(np.float64)
        return base + self.start_frame, base + self.end_frame

    def counts(self) -> NDArray[np.int64]:
        """(n_trials,) number of segments of each trial."""
        return np.bincount(self.trial, minlength=self.n_trials).astype(np.int64)

    def per_trial(self) -> list[NDArray[np.float64]]:
        """One (n_i, 2) [start, end] seconds array per trial."""
        pairs = np.stack([self.start, self.end], axis=1)
        return np.split(pairs, np.cumsum(self.counts())[:-1])


def segment_concatenated(
    times: ArrayLike,
    angles: ArrayLike,
    offsets: ArrayLike,
    *,
    method: Method,
    tuning: str,
    seg1_adaptive: bool,
    boundary: str = params.SEG2_BOUNDARIES[0],
    repetitions: ArrayLike | int = 1,
    threshold: float | None = None,
    coverage: float = 1.0,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
    window: float = DEFAULT_WINDOW,
    min_change_deg: float = DEFAULT_MIN_CHANGE_DEG,
    min_dofs: int = 2,
) -> CorpusSegmentation:
    """Segment every trial of a concatenated corpus.

    Parameters
    ----------
    times : (N,) seconds; angles : (N, C) radians (normally low-passed);
    offsets : (n_trials,) first frame of each trial.
    method : "seg1" or "seg2"
    tuning, seg1_adaptive
        The method's choices (below), required: their defaults are
        :class:`~visprim.model.PrimitiveModel`'s (:mod:`visprim.params`).
    repetitions : int or (n_trials,) ints
        SEG-2 only: repetitions of each trial, for tuning the global threshold.
    threshold : float, optional
        SEG-2 only: c in (rad/s)²; default: tuned on this corpus.
    tuning : "repetitions" or "robust"
        SEG-2 only, how an unset threshold is tuned: the paper's rule from the repetitions
        (:func:`~visprim.segment.tune_seg2_threshold`, with ``coverage``), or scaled to the
        corpus' movement speed with per-trial thresholds for slow trials
        (:func:`~visprim.segment.seg2.robust_seg2_thresholds`).
    boundary : "slowest" or "first_stop"
        SEG-2 only: where the boundary after a run is (:mod:`.seg2`; default "slowest",
        the model's is ``seg2_boundary``).
    min_travel_deg : float, degrees
        SEG-2 only: travel that makes a run of ``z ≥ c`` a movement (:mod:`.seg2`).
    window, min_change_deg, min_dofs
        SEG-1 only: see :func:`~visprim.segment.seg1`.
    seg1_adaptive : bool
        SEG-1 only: shorter window for fast cyclic motion (:mod:`.seg1`; False: the paper's).
    """
    t = np.ascontiguousarray(times, dtype=np.float64)
    a = np.ascontiguousarray(angles, dtype=np.float64)
    off = np.ascontiguousarray(offsets, dtype=np.int64)
    if a.ndim != 2 or t.shape != (a.shape[0],):
        raise ValueError(
            f"need times (N,) and angles (N, channels) of equal N, got {t.shape} and {a.shape}"
        )
    if off.ndim != 1 or off.size == 0 or off[0] != 0 or np.any(np.diff(off) <= 0):
        raise ValueError("offsets must be a non-empty increasing 1-D array starting at 0")
    if off[-1] >= a.shape[0]:
        raise ValueError(f"offsets must be < the number of frames ({a.shape[0]})")
    z = None
    c = None
    per_trial = None
    if method == "seg1":
        crossings = zvc_concatenated(t, a, off, min_change_deg=min_change_deg)
        trial, start, end = seg1_from_crossings(
            crossings, window=window, min_dofs=min_dofs, adaptive=seg1_adaptive
        )
        # One kernel call for both ends (each queried trial's clock is checked once).
        frames = times_to_frames(t, off, np.tile(trial, 2), np.concatenate([start, end]))
        start_frame, end_frame = frames[: trial.size], frames[trial.size :]
    elif method == "seg2":
        v = velocity_concatenated(t, a, off)
        z = np.einsum("ij,ij->i", v, v)
        if tuning not in TUNINGS:
            raise ValueError(f"tuning must be one of {list(TUNINGS)}, got {tuning!r}")
        if tuning == "robust":
            c, per_trial = robust_seg2_thresholds(z, off, threshold=threshold)
        elif threshold is not None:
            c = float(threshold)
        else:
            c = tune_seg2_threshold_concatenated(
                t, z, off, repetitions, min_travel_deg=min_travel_deg, coverage=coverage
            )
        used = c if per_trial is None else per_trial
        b_trial, b_frame, b_time = seg2_boundaries(
            t,
            z,
            off,
            used,
            min_travel_deg=min_travel_deg,
            rest_fraction=ROBUST_REST if tuning == "robust" else None,
            boundary=boundary,
        )
        same = b_trial[1:] == b_trial[:-1]
        trial = b_trial[:-1][same]
        start, end = b_time[:-1][same], b_time[1:][same]
        start_frame = b_frame[:-1][same].astype(np.float64)
        end_frame = b_frame[1:][same].astype(np.float64)
    else:
        raise ValueError(f"method must be 'seg1' or 'seg2', got {method!r}")
    return CorpusSegmentation(
        method=method,
        trial=trial,
        start=start,
        end=end,
        start_frame=start_frame,
        end_frame=end_frame,
        offsets=off,
        n_frames=int(a.shape[0]),
        threshold=c,
        z=z,
        trial_thresholds=per_trial,
    )


def segment_corpus(
    times_list: Sequence[ArrayLike],
    angles_list: Sequence[ArrayLike],
    method: Method,
    *,
    tuning: str = params.PAPER["seg2_tuning"],
    seg1_adaptive: bool = params.PAPER["seg1_adaptive"],
    boundary: str = params.SEG2_BOUNDARIES[0],
    repetitions: Sequence[int] | int = 1,
    threshold: float | None = None,
    coverage: float = 1.0,
    min_travel_deg: float = DEFAULT_MIN_TRAVEL_DEG,
    window: float = DEFAULT_WINDOW,
    min_change_deg: float = DEFAULT_MIN_CHANGE_DEG,
    min_dofs: int = 2,
) -> CorpusSegmentation:
    """:func:`segment_concatenated` on lists of per-trial times (T_i,) s and angles
    (T_i, C) rad (concatenated here once), with the paper's choices unless ``tuning`` and
    ``seg1_adaptive`` say otherwise (:data:`visprim.params.PAPER`)."""
    if len(times_list) != len(angles_list) or len(times_list) == 0:
        raise ValueError("times_list and angles_list must be non-empty and of equal length")
    lengths = np.array([np.shape(a)[0] for a in angles_list], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return segment_concatenated(
        np.concatenate([np.asarray(t, dtype=np.float64) for t in times_list]),
        np.concatenate([np.asarray(a, dtype=np.float64) for a in angles_list]),
        offsets,
        method=method,
        tuning=tuning,
        seg1_adaptive=seg1_adaptive,
        boundary=boundary,
        repetitions=np.asarray(repetitions, dtype=np.int64),
        threshold=threshold,
        coverage=coverage,
        min_travel_deg=min_travel_deg,
        window=window,
        min_change_deg=min_change_deg,
        min_dofs=min_dofs,
    )
