"""From trials to segments: inverse kinematics → low-pass → segmentation, on a whole corpus.

Glue between :mod:`visprim.ik`, :mod:`visprim.filtering` and :mod:`visprim.segment` used by
:class:`~visprim.model.PrimitiveModel`, the report and the classifier. The corpus is
concatenated once; each stage runs on the concatenation (one Rust kernel call for the
filter, one for the zero-velocity crossings, one for the resampling).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from visprim.features import from_angles
from visprim.filtering import butterworth, default_padlen, lowpass_concatenated
from visprim.ik import arm_angles_corpus
from visprim.params import SHORT_POLICY
from visprim.segment import CorpusSegmentation, segment_concatenated
from visprim.trial import Trial

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PreparedCorpus:
    """A corpus after IK, low-pass and segmentation.

    Attributes
    ----------
    names : list of str — trial names.
    times_all : (F,) seconds — all trials' timestamps, concatenated.
    raw_angles_all : (F, 4 n_arms) radians — IK angles before the low-pass.
    angles_all : (F, 4 n_arms) radians — low-passed angles.
    offsets : (n_trials,) int — first frame of each trial in the concatenation.
    segmentation : CorpusSegmentation — segments (trial, start/end seconds and frames).
    features : str — what the segmentation and the vectors use (:mod:`visprim.features`).
    values_all : (F, C) — the low-passed angles in that description (``angles_all`` itself
        for ``"zyz"``; unit bone directions for ``"directions"``).
    arms : tuple of str — the arms of every trial.
    n_short : int — trials shorter than the filter's padding (filtered with less padding).
    """

    names: list[str]
    times_all: NDArray[np.float64]
    raw_angles_all: NDArray[np.float64]
    angles_all: NDArray[np.float64]
    offsets: NDArray[np.int64]
    segmentation: CorpusSegmentation
    features: str = "zyz"
    values_all: NDArray[np.float64] | None = None
    arms: tuple[str, ...] = ("right",)
    n_short: int = 0

    @property
    def values(self) -> NDArray[np.float64]:
        """(F, C) per-frame channels the segments are cut from and resampled."""
        return self.angles_all if self.values_all is None else self.values_all

    def _split(self, a: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        return np.split(a, self.offsets[1:])

    @property
    def times(self) -> list[NDArray[np.float64]]:
        """Per-trial timestamps (views), seconds."""
        return self._split(self.times_all)

    @property
    def angles(self) -> list[NDArray[np.float64]]:
        """Per-trial low-passed angles (views), (T_i, 4) radians."""
        return self._split(self.angles_all)

    @property
    def raw_angles(self) -> list[NDArray[np.float64]]:
        """Per-trial IK angles before filtering (views), (T_i, 4) radians."""
        return self._split(self.raw_angles_all)

    @property
    def segments(self) -> list[NDArray[np.float64]]:
        """Per-trial (n_i, 2) [start, end] seconds."""
        return self.segmentation.per_trial()

    @property
    def seg2_threshold(self) -> float | None:
        """SEG-2 constant c in (rad/s)² (None for SEG-1)."""
        return self.segmentation.threshold

    @property
    def n_trials(self) -> int:
        return int(self.offsets.size)


def prepare_corpus(
    trials: Sequence[Trial],
    *,
    filter_order: int,
    cutoff: float,
    segmentation: str,
    zvc_threshold_deg: float,
    window: float,
    seg2_threshold: float | None,
    seg2_tuning: str,
    features: str,
    seg2_boundary: str,
    seg1_adaptive: bool,
) -> PreparedCorpus:
    """IK, zero-phase low-pass and segmentation of ``trials`` (see the module docstring).

    ``seg2_threshold=None`` tunes SEG-2's constant on this corpus (``seg2_tuning``, see
    :func:`visprim.segment.tune_seg2_threshold`); the other parameters are those of
    :class:`~visprim.model.PrimitiveModel`. Trials shorter than the filter's padding are
    filtered with less padding (as scipy's ``padlen`` allows), said once in the log.
    """
    trials = list(trials)
    if not trials:
        raise ValueError("prepare_corpus: no trials given")
    names = [t.name or (t.source or f"#{i}") for i, t in enumerate(trials)]
    raw = np.concatenate(arm_angles_corpus(trials))
    times = np.concatenate([t.times for t in trials])
    lengths = np.array([t.n_frames for t in trials], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    pad = default_padlen(butterworth(filter_order, cutoff))
    n_short = int(np.sum(lengths <= pad))
    if n_short:
        log.info(
            "%d trial(s) have no more frames than the filter padding (%d frames); "
            "filtered with padding reduced to their length - 1",
            n_short,
            pad,
        )
    filtered = lowpass_concatenated(
        raw, offsets, order=filter_order, cutoff=cutoff, names=names, short=SHORT_POLICY
    )
    values = from_angles(filtered, features)
    seg = segment_concatenated(
        times,
        values,
        offsets,
        method=segmentation,  # type: ignore[arg-type]
        repetitions=np.array([t.repetitions for t in trials], dtype=np.int64),
        threshold=seg2_threshold,
        tuning=seg2_tuning,
        boundary=seg2_boundary,
        seg1_adaptive=seg1_adaptive,
        window=window,
        min_change_deg=zvc_threshold_deg,
    )
    return PreparedCorpus(
        names,
        times,
        raw,
        filtered,
        offsets,
        seg,
        features=features,
        values_all=None if features == "zyz" else values,
        arms=trials[0].arms,
        n_short=n_short,
    )
