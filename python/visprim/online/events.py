"""The events an online pipeline emits (small frozen dataclasses, JSON-ready).

Times are seconds on the stream's clock (the timestamps pushed). ``emitted`` is the stream
time of the newest frame received when the event was produced, so ``emitted - end`` is the
event's latency on the stream's clock (the causal filter's delay comes on top of it: see
:mod:`visprim.online.segmenter`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

__all__ = ["ClassUpdate", "Event", "MovementEnded", "SegmentClosed", "event_to_dict"]


@dataclass(frozen=True)
class SegmentClosed:
    """A segment whose end is now known.

    start, end : seconds; primitive : index of the nearest primitive (cluster centre);
    distance : Euclidean distance of the segment's projection to it (radians, the units of
    :meth:`~visprim.model.PrimitiveModel.assign`); amplitude : least-squares gain of the
    primitive on the segment's shape (1.0 for models with ``offsets="turns"``);
    movement : index of the movement it belongs to; index : its index in that movement;
    forced : True when the segment was cut at the longest length allowed rather than at a
    SEG-2 boundary; emitted : stream time when the event was produced.
    """

    start: float
    end: float
    primitive: int
    distance: float
    amplitude: float
    movement: int
    index: int
    forced: bool
    emitted: float

    @property
    def latency(self) -> float:
        """Seconds of stream time between the segment's end and its event."""
        return self.emitted - self.end


@dataclass(frozen=True)
class ClassUpdate:
    """The running class of the movement in progress.

    label : the nearest reference's label; confidence : in [0, 1], ``1 - d₁ / d₂`` with
    ``d₁`` the best open-end DTW cost and ``d₂`` the best cost of another class (0 when
    they tie); cost : ``d₁``; movement : the movement's index; frames : frames of the
    movement seen; emitted : stream time.
    """

    label: str
    confidence: float
    cost: float
    movement: int
    frames: int
    emitted: float


@dataclass(frozen=True)
class MovementEnded:
    """A movement is over: the arm has been at rest for the stream's rest timeout, or the
    stream ended.

    start, end : seconds (onset and offset of its SEG-2 segments; NaN without a segment);
    label, confidence : the final class (closed-end DTW of the whole movement, ``""`` and 0
    without a recogniser); n_segments; movement : its index; emitted : stream time.
    """

    start: float
    end: float
    label: str
    confidence: float
    n_segments: int
    movement: int
    emitted: float


Event = SegmentClosed | ClassUpdate | MovementEnded

_KIND = {SegmentClosed: "segment", ClassUpdate: "class", MovementEnded: "movement_end"}


def event_to_dict(event: Event) -> dict[str, Any]:
    """The event as a flat dict with its kind first (``"segment"``, ``"class"``,
    ``"movement_end"``); NaN becomes None so that the dict is valid JSON."""
    out: dict[str, Any] = {"event": _KIND[type(event)]}
    for k, v in asdict(event).items():
        out[k] = None if isinstance(v, float) and v != v else v
    return out
