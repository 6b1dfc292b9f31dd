"""The online answers beside the offline pipeline's, on whole recordings.

For each recording, :func:`compare_trial` replays it through an
:class:`~visprim.online.pipeline.OnlinePipeline` and runs the offline pipeline of the same
model (:meth:`PrimitiveModel.prepare` with the fitted SEG-2 constant, the zero-phase
filter, :meth:`~PrimitiveModel.assign`; the classifier's ``predict`` on the whole
recording). :func:`summarise` pools the trials:

* **boundaries**: one-to-one matching within ``tolerance`` (default ±100 ms,
  :func:`visprim.segment.boundary_matches`), micro-averaged precision / recall / F1 with the
  offline boundaries as the reference;
* **primitives**: each offline segment paired with the online segment overlapping it most
  (at least half of the longer of the two); the fraction of offline segments whose pair has
  the same primitive (unpaired segments count as different);
* **class**: the online final class (the last movement's :class:`MovementEnded`) against
  ``predict``;
* **latency**: stream time from each segment's end to its event (``emitted − end``). The
  segment times are the filtered frames' shifted back by the causal filter's latency
  (:mod:`visprim.online.segmenter`), so the delay is part of it. Segments closed by the
  end of the stream (:meth:`~OnlinePipeline.flush`) are marked (``at_flush``): their
  latency says nothing of the detection. ``last`` marks a movement's last segment (closed
  at its offset after the rest timeout).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.model import PrimitiveModel
from visprim.online.events import MovementEnded, SegmentClosed
from visprim.online.pipeline import OnlinePipeline
from visprim.online.segmenter import Frames
from visprim.segment import boundary_matches, segment_boundaries
from visprim.trial import Trial

__all__ = [
    "TrialComparison",
    "boundary_counts",
    "compare_trial",
    "equal_primitives",
    "summarise",
]


@dataclass(frozen=True)
class TrialComparison:
    """One recording offline and online."""

    name: str
    offline_segments: NDArray[np.float64]  #: (n, 2) seconds
    offline_primitives: NDArray[np.int64]
    online_segments: NDArray[np.float64]  #: (m, 2) seconds
    online_primitives: NDArray[np.int64]
    latencies: NDArray[np.float64]  #: (m,) seconds of stream time
    at_flush: NDArray[np.bool_]  #: (m,) closed by the end of the stream
    last: NDArray[np.bool_]  #: (m,) the last segment of its movement
    offline_class: str
    online_class: str
    boundaries: tuple[int, int, int]  #: matched, online, offline
    primitives: tuple[int, int]  #: equal, offline segments


def _pairs(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.int64]:
    """For each segment of ``a``, the segment of ``b`` overlapping it most when the overlap
    is at least half of the longer of the two, else -1."""
    out = np.full(a.shape[0], -1, dtype=np.int64)
    if b.shape[0] == 0:
        return out
    for i, (s, e) in enumerate(a):
        ov = np.minimum(e, b[:, 1]) - np.maximum(s, b[:, 0])
        j = int(np.argmax(ov))
        longer = max(e - s, b[j, 1] - b[j, 0])
        if ov[j] > 0 and ov[j] >= 0.5 * longer:
            out[i] = j
    return out


def boundary_counts(
    online: NDArray[np.float64], offline: NDArray[np.float64], tolerance: float = 0.1
) -> tuple[int, int, int]:
    """(matched, online, offline) boundaries of two segmentations ``(n, 2)`` seconds, matched
    one to one within ``tolerance`` seconds (:func:`visprim.segment.boundary_matches`)."""
    on = segment_boundaries(online) if online.shape[0] else np.zeros(0)
    off = segment_boundaries(offline) if offline.shape[0] else np.zeros(0)
    matched = boundary_matches(on, off, tolerance)[0] if on.size and off.size else 0
    return int(matched), int(on.size), int(off.size)


def equal_primitives(
    offline: NDArray[np.float64],
    offline_primitives: NDArray[np.int64],
    online: NDArray[np.float64],
    online_primitives: NDArray[np.int64],
) -> int:
    """How many offline segments are paired with an online one (:func:`_pairs`) of the same
    primitive."""
    pair = _pairs(offline, online)
    if not (pair.size and online_primitives.size):
        return 0
    same = online_primitives[np.maximum(pair, 0)] == offline_primitives
    return int(np.sum((pair >= 0) & same))


def compare_trial(
    model: PrimitiveModel,
    trial: Trial,
    classifier: Any = None,
    *,
    chunk: int = 1,
    tolerance: float = 0.1,
    **options: Any,
) -> TrialComparison:
    """Replay ``trial`` online (``chunk`` frames per push, ``options`` for the
    segmenter) and run the offline pipeline on it (module docstring)."""
    corpus = model.prepare([trial], tune_seg2=False)
    off_seg = corpus.segments[0]
    if corpus.segmentation.n_segments:
        off_prim, _ = model.assign(model.transform(model.vectorize(corpus).vectors))
    else:
        off_prim = np.zeros(0, dtype=np.int64)
    off_class = "" if classifier is None else str(classifier.predict([trial])[0])
    pipe = OnlinePipeline(model, classifier, **options)
    segs: list[SegmentClosed] = []
    ends: list[MovementEnded] = []
    flushed: list[bool] = []
    streamed = []
    for a in range(0, trial.n_frames, int(chunk)):
        streamed.extend(pipe.push(_part(trial, a, min(trial.n_frames, a + int(chunk)))))
    n_streamed = len(streamed)
    for k, ev in enumerate(streamed + pipe.flush()):
        if isinstance(ev, SegmentClosed):
            segs.append(ev)
            flushed.append(k >= n_streamed)
        elif isinstance(ev, MovementEnded):
            ends.append(ev)
    last_of = {(e.movement, e.n_segments - 1) for e in ends}
    on_seg = np.array([[s.start, s.end] for s in segs]).reshape(-1, 2)
    on_prim = np.array([s.primitive for s in segs], dtype=np.int64)
    lat = np.array([s.latency for s in segs])
    matched, n_on, n_off = boundary_counts(on_seg, off_seg, tolerance)
    equal = equal_primitives(off_seg, off_prim, on_seg, on_prim)
    return TrialComparison(
        name=trial.name or (trial.source or ""),
        offline_segments=off_seg,
        offline_primitives=np.asarray(off_prim, dtype=np.int64),
        online_segments=on_seg,
        online_primitives=on_prim,
        latencies=lat,
        at_flush=np.array(flushed, dtype=bool),
        last=np.array([(x.movement, x.index) in last_of for x in segs], dtype=bool),
        offline_class=off_class,
        online_class=ends[-1].label if ends else "",
        boundaries=(int(matched), int(n_on), int(n_off)),
        primitives=(equal, int(off_seg.shape[0])),
    )


def _part(trial: Trial, a: int, b: int) -> Frames:
    return Frames(
        trial.times[a:b],
        trial.markers[a:b],
        None if trial.joints is None else trial.joints[a:b],
        None if trial.body_frame is None else trial.body_frame[a:b],
    )


def summarise(results: Sequence[TrialComparison], delay: float = 0.0) -> dict[str, float]:
    """Pooled figures (module docstring); ``delay`` (s) is added to every latency (default
    0: the segment times already carry the causal filter's delay). The latencies leave out
    the segments closed by the end of the stream."""
    m = sum(r.boundaries[0] for r in results)
    n_on = sum(r.boundaries[1] for r in results)
    n_off = sum(r.boundaries[2] for r in results)
    p = m / n_on if n_on else 1.0
    rc = m / n_off if n_off else 1.0
    f1 = 2 * p * rc / (p + rc) if p + rc > 0 else 0.0
    eq = sum(r.primitives[0] for r in results)
    n_seg = sum(r.primitives[1] for r in results)
    lat = np.concatenate([r.latencies for r in results]) + delay if results else np.zeros(0)
    live = np.concatenate([~r.at_flush for r in results]) if results else np.zeros(0, bool)
    last = np.concatenate([r.last for r in results]) if results else np.zeros(0, bool)
    inner = lat[live & ~last]
    ends = lat[live & last]
    classed = [r for r in results if r.offline_class]
    return {
        "trials": float(len(results)),
        "boundary_precision": p,
        "boundary_recall": rc,
        "boundary_f1": f1,
        "primitive_equal": eq / n_seg if n_seg else float("nan"),
        "offline_segments": float(n_seg),
        "online_segments": float(sum(r.online_segments.shape[0] for r in results)),
        "class_equal": (
            float(np.mean([r.online_class == r.offline_class for r in classed]))
            if classed
            else float("nan")
        ),
        "latency_median": _quantile(lat[live], 0.5),
        "latency_p95": _quantile(lat[live], 0.95),
        "latency_segments": float(np.sum(live)),
        "latency_inner_median": _quantile(inner, 0.5),
        "latency_inner_p95": _quantile(inner, 0.95),
        "latency_inner_segments": float(inner.size),
        "latency_last_median": _quantile(ends, 0.5),
        "latency_last_p95": _quantile(ends, 0.95),
        "latency_last_segments": float(ends.size),
    }


def _quantile(x: NDArray[np.float64], q: float) -> float:
    return float(np.quantile(x, q)) if x.size else float("nan")
