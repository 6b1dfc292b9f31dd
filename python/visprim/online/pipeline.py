"""The online pipeline: a stream in, events out (:class:`OnlinePipeline`).

Push frames in chunks of any size; each call returns the events it produced, in order:

* :class:`~visprim.online.events.SegmentClosed` — a SEG-2 segment and its nearest primitive
  (:mod:`visprim.online.segmenter`);
* :class:`~visprim.online.events.ClassUpdate` — the running class of the movement in
  progress (:mod:`visprim.online.recogniser`), when a segment closes and whenever the
  leading label changes (checked at the end of each pushed chunk);
* :class:`~visprim.online.events.MovementEnded` — the movement is over, with its final class.

Two kinds of classifier:

* a :class:`~visprim.classify.DTWClassifier` (1-NN, no band) is advanced frame by frame by
  open-end DTW in Rust (:class:`~visprim.online.recogniser.OnlineRecogniser`); its final
  class is the closed-end DTW of the movement's frames, which is ``predict``'s cost;
* any other fitted classifier of whole movements with ``predict`` (a
  :class:`~visprim.classify.MotionClassifier`) gets the movement's raw frames, kept in a
  ring of ``max_movement`` seconds (:class:`~visprim.online.movement.MovementFrames`): its
  ``predict`` on the movement so far gives the running class at each closed segment and the
  final class when the movement ends (confidence ``1 − d₁ / d₂`` from its ``distances``).

The frames of a movement, for either, are those received since the stream began or the
previous movement ended, up to the frame where its end was decided.

:meth:`OnlinePipeline.replay` runs a whole recording through it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import numpy as np

from visprim.classify import DTWClassifier, arm_directions
from visprim.model import PrimitiveModel
from visprim.online.events import ClassUpdate, Event, MovementEnded, SegmentClosed
from visprim.online.movement import MovementFrames, WholeMovementClassifier
from visprim.online.recogniser import OnlineRecogniser
from visprim.online.segmenter import Frames, OnlineSegmenter, frames_of
from visprim.params import ONLINE_OPTIONS
from visprim.trial import Trial

__all__ = ["OnlinePipeline"]


class OnlinePipeline:
    """Segment, recognise and report a movement stream as it arrives.

    Parameters
    ----------
    model : fitted PrimitiveModel (segmentation and primitives).
    classifier : fitted classifier of whole movements, optional — running and final class
        (a DTWClassifier by open-end DTW, any other through its ``predict``: module
        docstring).
    max_movement : float, seconds
        Longest movement whose raw frames are kept for a classifier other than a
        DTWClassifier (default 60 s; a longer movement is classified on its last
        ``max_movement`` seconds).
    **options : passed to :class:`~visprim.online.segmenter.OnlineSegmenter`
        (``filter_order``, ``threshold``, ``rest_timeout``, ``max_segment``, ...).
    """

    def __init__(
        self,
        model: PrimitiveModel,
        classifier: Any = None,
        *,
        max_movement: float = ONLINE_OPTIONS["max_movement"].default,
        **options: Any,
    ) -> None:
        self.segmenter = OnlineSegmenter(model, **options)
        self.recogniser: OnlineRecogniser | None = None
        self.whole: WholeMovementClassifier | None = None
        if isinstance(classifier, DTWClassifier) and _streamable(classifier):
            self.recogniser = OnlineRecogniser.from_classifier(classifier)
        elif classifier is not None:
            self.whole = WholeMovementClassifier(
                classifier, MovementFrames(max_movement), self.segmenter.arms
            )
        self._features: np.ndarray | None = None
        self._fed = 0  # stream frames given to the recogniser
        self._chunk_base = 0
        self._label: Any = None
        self._emitted = math.nan

    @property
    def buffer_bytes(self) -> int:
        """Bytes of every buffer the pipeline holds (fixed after the first chunk)."""
        extra = 0 if self.recogniser is None else self.recogniser.memory_bytes
        if self.whole is not None:
            extra += self.whole.frames.nbytes
        return self.segmenter.buffer_bytes + extra

    def push(self, chunk: Trial | Frames | None = None, **arrays: Any) -> list[Event]:
        """Add a chunk (a Trial, a :class:`Frames`, or ``times=``, ``markers=``,
        ``joints=``, ``body_frame=`` arrays); returns the events produced."""
        frames = frames_of(chunk, **arrays)
        if len(frames) == 0:
            return []
        out: list[Event] = []
        seg = self.segmenter
        self._emitted = float(frames.times[-1])
        if self.recogniser is not None:
            self._chunk_base = seg.n_frames
        events = seg.push(frames)
        # The frames the segmenter took (on the model's clock): the classifiers get the same.
        frames = seg.frames if seg.frames is not None else frames
        if self.whole is not None and len(frames):
            self.whole.frames.extend(frames)
        if self.recogniser is not None:
            # The classifier's per-frame description: the front end computed the bone
            # directions already; another description goes through a Trial of the chunk.
            if self.recogniser.describe is arm_directions or not len(frames):
                self._features = seg.bone_directions
            else:
                self._features = self.recogniser.features(frames.as_trial(seg.arms))[: len(frames)]
        for event in events:
            out.extend(self._on_event(event))
        if self.recogniser is not None:
            self._feed(seg.n_frames)
            out.extend(self._running(force=False))
        return out

    def flush(self) -> list[Event]:
        """End of the stream: the open movement ends (its last segment, its final class)."""
        out: list[Event] = []
        seg = self.segmenter
        if self.recogniser is not None:
            self._feed(seg.n_frames)
        for event in seg.flush():
            out.extend(self._on_event(event))
        return out

    def replay(self, trial: Trial, chunk: int = 1) -> Iterator[Event]:
        """All the events of ``trial`` pushed ``chunk`` frames at a time, then flushed."""
        for a in range(0, trial.n_frames, int(chunk)):
            b = min(trial.n_frames, a + int(chunk))
            frames = Frames(
                trial.times[a:b],
                trial.markers[a:b],
                None if trial.joints is None else trial.joints[a:b],
                None if trial.body_frame is None else trial.body_frame[a:b],
            )
            yield from self.push(frames)
        yield from self.flush()

    # ------------------------------------------------------------------ internals

    def _feed(self, upto: int) -> None:
        """Give the recogniser the stream's features up to frame ``upto`` (exclusive)."""
        if self.recogniser is None or self._features is None:
            return
        a = self._fed - self._chunk_base
        b = upto - self._chunk_base
        if b > a:
            self.recogniser.push_features(self._features[a:b])
            self._fed = upto

    def _on_event(self, event: SegmentClosed | MovementEnded) -> list[Event]:
        if isinstance(event, MovementEnded):
            return [self._movement_end(event)]
        out: list[Event] = [event]
        if self.recogniser is not None and self.segmenter._open:
            out.extend(self._running(force=True))
        if self.whole is not None and self.segmenter._open:
            label, conf, cost, n = self.whole.classify(self.segmenter.n_frames)
            out.append(
                ClassUpdate(
                    label=str(label),
                    confidence=conf,
                    cost=cost,
                    movement=self.segmenter.movement,
                    frames=n,
                    emitted=self._emitted,
                )
            )
        return out

    def _running(self, *, force: bool) -> list[Event]:
        assert self.recogniser is not None
        if not self.segmenter._open or self.recogniser.n_frames == 0:
            return []
        label, conf, cost = self.recogniser.running()
        if not force and label == self._label:
            return []
        self._label = label
        return [
            ClassUpdate(
                label=str(label),
                confidence=conf,
                cost=cost,
                movement=self.segmenter.movement,
                frames=self.recogniser.n_frames,
                emitted=self._emitted,
            )
        ]

    def _movement_end(self, event: MovementEnded) -> MovementEnded:
        """The movement's final class: the closed-end DTW of the frames received when its
        end was decided; the recogniser then starts a new query."""
        if self.whole is not None:
            upto = self.segmenter.decided.pop(0)
            label, conf, _, _ = self.whole.classify(upto)
            self.whole.start = upto
            return replace(event, label=str(label), confidence=conf)
        if self.recogniser is None:
            self.segmenter.decided.clear()
            return event
        self._feed(self.segmenter.decided.pop(0))
        label, conf, _ = self.recogniser.final()
        self.recogniser.reset()
        self._label = None
        return replace(event, label=str(label), confidence=conf)


def _streamable(classifier: DTWClassifier) -> bool:
    """True when open-end DTW gives the classifier's answers: 1-NN without a band."""
    return classifier.band is None and int(classifier.n_neighbors) == 1
