"""The raw frames of the movement in progress, for classifiers of whole movements.

A classifier such as :class:`~visprim.classify.MotionClassifier` describes a movement by
windows around each frame and by its SEG-2 segments, so it cannot be advanced frame by
frame. :class:`MovementFrames` keeps the raw frames pushed (times, markers, joints, body
frame) in fixed ring buffers of ``max_movement`` seconds; :class:`WholeMovementClassifier`
hands the movement so far to the classifier's public ``predict`` (and ``distances`` for a
confidence) as a :class:`~visprim.trial.Trial`. Memory is fixed once the first chunk has
set the buffers up.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.online.recogniser import confidence
from visprim.online.ring import FrameRing
from visprim.online.segmenter import Frames
from visprim.trial import Trial

__all__ = ["MovementFrames", "WholeMovementClassifier"]


class MovementFrames:
    """The last ``max_movement`` seconds of raw frames, addressed by absolute frame index."""

    def __init__(self, max_movement: float) -> None:
        if not (math.isfinite(max_movement) and max_movement > 0):
            raise ValueError(
                f"max_movement must be a positive number of seconds, got {max_movement!r}"
            )
        self.max_movement = float(max_movement)
        self._rings: dict[str, FrameRing] = {}
        self._shapes: dict[str, tuple[int, ...]] = {}

    @property
    def nbytes(self) -> int:
        return sum(r.nbytes for r in self._rings.values())

    @property
    def start(self) -> int:
        """Absolute index of the oldest frame held."""
        return self._rings["times"].start if self._rings else 0

    @property
    def end(self) -> int:
        return self._rings["times"].end if self._rings else 0

    def _allocate(self, frames: Frames) -> None:
        k = len(frames)
        period = float(np.median(np.diff(frames.times))) if k > 1 else 1.0 / 30.0
        capacity = max(8, int(math.ceil(self.max_movement / (period if period > 0 else 1 / 30))))
        arrays = {"times": frames.times[:, None], "markers": frames.markers}
        if frames.joints is not None:
            arrays["joints"] = frames.joints
        if frames.body_frame is not None:
            arrays["body_frame"] = frames.body_frame
        for name, a in arrays.items():
            self._shapes[name] = tuple(a.shape[1:])
            self._rings[name] = FrameRing(capacity, int(np.prod(a.shape[1:])))

    def extend(self, frames: Frames) -> None:
        if len(frames) == 0:
            return
        if not self._rings:
            self._allocate(frames)
        k = len(frames)
        parts = {
            "times": frames.times,
            "markers": frames.markers,
            "joints": frames.joints,
            "body_frame": frames.body_frame,
        }
        for name, ring in self._rings.items():
            a = parts[name]
            if a is None:
                raise ValueError(f"the stream's first chunk had {name}; this chunk has none")
            ring.extend(np.asarray(a, dtype=np.float64).reshape(k, -1))

    def trial(self, a: int, b: int, arms: tuple[str, ...]) -> Trial:
        """Frames ``[a, b)`` (``a`` raised to the oldest frame held) as a Trial."""
        a = max(a, self.start)
        got: dict[str, NDArray[np.float64] | None] = {"joints": None, "body_frame": None}
        for name, ring in self._rings.items():
            got[name] = ring.window(a, b).reshape((b - a, *self._shapes[name]))
        times = got.pop("times")
        assert times is not None
        return Trial(
            times=times[:, 0],
            markers=got["markers"],  # type: ignore[arg-type]
            joints=got["joints"],
            body_frame=got["body_frame"],
            arms=arms,
            name="movement",
        )


class WholeMovementClassifier:
    """A fitted classifier's ``predict`` on the movement so far (module docstring)."""

    def __init__(self, classifier: Any, frames: MovementFrames, arms: tuple[str, ...]) -> None:
        if not callable(getattr(classifier, "predict", None)):
            raise TypeError(
                f"the classifier must have a predict method; got {type(classifier).__name__}"
            )
        fitted_arms = getattr(classifier, "arms_", None)
        if fitted_arms is not None and tuple(fitted_arms) != tuple(arms):
            raise ValueError(
                f"the classifier was fitted on arms {list(fitted_arms)}, the model on {list(arms)}"
            )
        self.classifier = classifier
        self.frames = frames
        self.arms = arms
        self.start = 0  #: first frame of the movement in progress (absolute index)

    def classify(self, upto: int) -> tuple[Any, float, float, int]:
        """``(label, confidence, cost, frames)`` of frames ``[start, upto)``; ``("", 0,
        NaN, n)`` when they are too few (fewer than two) or the classifier rejects them."""
        a = max(self.start, self.frames.start)
        n = upto - a
        if n < 2:
            return "", 0.0, math.nan, max(n, 0)
        trial = self.frames.trial(a, upto, self.arms)
        clf = self.classifier
        labels = getattr(clf, "train_labels_", None)
        try:
            d = None
            if hasattr(clf, "distances") and hasattr(clf, "predict_from_distances"):
                try:
                    d = np.asarray(clf.distances([trial]))
                except ValueError:  # e.g. a histogram classifier: no distances
                    d = None
            label = clf.predict([trial])[0] if d is None else clf.predict_from_distances(d)[0]
        except ValueError:
            return "", 0.0, math.nan, n
        if d is None or labels is None or d.shape[1] != len(labels):
            return label, 0.0, math.nan, n
        best, conf = confidence(d[0], np.asarray(labels))
        return label, conf, float(d[0, best]), n
