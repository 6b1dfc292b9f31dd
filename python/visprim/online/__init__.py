"""Online segmentation, recognition and reporting of a movement stream as it arrives.

* :class:`OnlinePipeline` — push frames in chunks of any size, get events back
  (:mod:`visprim.online.pipeline`);
* :class:`OnlineSegmenter` — causal low-pass, SEG-2 with the model's fitted constant and the
  nearest primitive of each closed segment (:mod:`visprim.online.segmenter`, which states the
  latency);
* :class:`OnlineRecogniser` — open-end DTW against a classifier's references, in Rust
  (:class:`visprim.kernels.OnlineDtw`);
* :mod:`visprim.online.movement` — the raw frames of the movement in progress for any other
  classifier of whole movements (:class:`~visprim.classify.MotionClassifier`);
* :mod:`visprim.online.compare` — the online answers beside the offline pipeline's;
  :mod:`visprim.online.early` — accuracy against the fraction of the movement seen.
"""

from visprim.online.events import ClassUpdate, Event, MovementEnded, SegmentClosed, event_to_dict
from visprim.online.pipeline import OnlinePipeline
from visprim.online.recogniser import OnlineRecogniser
from visprim.online.segmenter import Frames, OnlineSegmenter

__all__ = [
    "ClassUpdate",
    "Event",
    "Frames",
    "MovementEnded",
    "OnlinePipeline",
    "OnlineRecogniser",
    "OnlineSegmenter",
    "SegmentClosed",
    "event_to_dict",
]
