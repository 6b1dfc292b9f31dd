"""The running class of the movement in progress: open-end DTW against the classifier's
references, advanced frame by frame in Rust (:class:`visprim.kernels.OnlineDtw`).

The query is every frame since the stream began or the last movement ended, described as
the classifier describes a movement (:func:`visprim.classify.arm_directions` for a
:class:`~visprim.classify.DTWClassifier`: per frame, so causal and exact). The running class
is the label of the reference whose *beginning* matches the query best (open-end cost
``min_j D(n, j) / (n + j + 1)``); the final class, when the movement ends, is the label of
the nearest reference under the closed-end cost ``D(n, m) / (n + m)``, which is
:meth:`DTWClassifier.predict`'s cost of the same frames. Memory: one DTW row per reference
(``memory_bytes``), fixed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim import kernels
from visprim.classify import DTWClassifier, arm_directions
from visprim.trial import Trial

__all__ = ["OnlineRecogniser", "confidence"]


def confidence(costs: NDArray[np.float64], labels: NDArray[Any]) -> tuple[int, float]:
    """``(index of the best reference, 1 - d₁ / d₂)``: ``d₂`` the best cost of another
    label (confidence 1 when every reference has the same label, 0 on a tie)."""
    best = int(np.argmin(costs))
    d1 = float(costs[best])
    other = costs[labels != labels[best]]
    if other.size == 0:
        return best, 1.0
    d2 = float(np.min(other))
    if not np.isfinite(d1) or not d2 > 0:
        return best, 0.0
    return best, max(0.0, 1.0 - d1 / d2)


class OnlineRecogniser:
    """Open-end DTW of the stream against labelled reference sequences.

    Parameters
    ----------
    references : list of (T_i, D) arrays — the classifier's training features.
    labels : (n,) — their labels.
    describe : callable Trial → (T, D) — per-frame features of a chunk (causal).
    """

    def __init__(
        self,
        references: Sequence[NDArray[np.float64]],
        labels: Sequence[Any] | NDArray[Any],
        describe: Any = arm_directions,
    ) -> None:
        refs = [np.ascontiguousarray(r, dtype=np.float64) for r in references]
        if not refs:
            raise ValueError("no reference sequences")
        lengths = [r.shape[0] for r in refs]
        offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
        self.dtw = kernels.OnlineDtw(np.concatenate(refs), offsets)
        self.labels = np.asarray(list(labels))
        if self.labels.shape[0] != len(refs):
            raise ValueError(f"{len(refs)} references but {self.labels.shape[0]} labels")
        # Integer codes of the labels: the running class compares them at every push.
        self._codes = np.ascontiguousarray(
            np.unique(self.labels, return_inverse=True)[1].reshape(-1), dtype=np.int64
        )
        self.describe = describe
        #: The labels as a list (indexed at every push: cheaper than a numpy index).
        self._label_list = list(self.labels)

    @classmethod
    def from_classifier(cls, classifier: Any) -> OnlineRecogniser:
        """From a fitted :class:`~visprim.classify.DTWClassifier` (its training features
        and labels; its ``band`` must be None: the online rows are unbanded)."""
        if not isinstance(classifier, DTWClassifier):
            raise TypeError(
                "online recognition needs a fitted DTWClassifier (per-frame features); got "
                f"{type(classifier).__name__}"
            )
        classifier._check_fitted()
        if classifier.band is not None:
            raise ValueError("online recognition needs band=None (the rows are unbanded)")
        return cls(classifier.train_features_, classifier.train_labels_, arm_directions)

    @property
    def n_frames(self) -> int:
        return int(self.dtw.n_frames)

    @property
    def memory_bytes(self) -> int:
        return int(self.dtw.memory_bytes)

    def features(self, chunk: Trial) -> NDArray[np.float64]:
        return np.ascontiguousarray(self.describe(chunk), dtype=np.float64)

    def push_features(self, features: NDArray[np.float64]) -> None:
        if features.shape[0]:
            self.dtw.push(features)

    def running(self) -> tuple[Any, float, float]:
        """``(label, confidence, cost)`` of the open-end match so far: :func:`confidence` of
        the open-end costs, in one Rust call (:meth:`visprim.kernels.OnlineDtw.running`)."""
        best, conf, cost = self.dtw.running(self._codes)
        return self._label_list[best], conf, cost

    def final(self) -> tuple[Any, float, float]:
        """``(label, confidence, cost)`` of the closed-end match of the whole query."""
        costs = np.asarray(self.dtw.costs())
        best, conf = confidence(costs, self._codes)
        return self.labels[best], conf, float(costs[best])

    def reset(self) -> None:
        self.dtw.reset()
