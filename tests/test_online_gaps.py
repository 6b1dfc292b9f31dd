"""A gap in a live stream longer than ``max_gap`` (a long occlusion, a stalled feed) splits
it: what comes before it is segmented as a stream of its own, and so is what comes after.

The reference is the online path on each part alone, in a fresh pipeline (its events with
the movement numbers of the parts before it): no knowledge of the gap handling is used.
"""

from __future__ import annotations

import math
from dataclasses import fields, replace
from pathlib import Path

import numpy as np
import pytest
from visprim.classify import DTWClassifier
from visprim.model import PrimitiveModel
from visprim.online import (
    ClassUpdate,
    Frames,
    MovementEnded,
    OnlinePipeline,
    OnlineSegmenter,
    SegmentClosed,
)
from visprim.online.events import Event
from visprim.trial import Trial

RECORDINGS = ["HDM_bd_grabHighR_001_120.amc", "HDM_mm_throwBasketball_010_120.amc"]
PERIOD = 0.034


@pytest.fixture(scope="module")
def trials(shared_data: Path) -> list[Trial]:
    from visprim.io import read

    folder = shared_data / "hdm05_cut_amc"
    missing = [f for f in RECORDINGS if not (folder / f).exists()]
    if missing:
        pytest.skip(f"HDM05 recordings missing: {missing}")
    return [read(folder / f, "both", resample=PERIOD) for f in RECORDINGS]


@pytest.fixture(scope="module")
def model(trials: list[Trial]) -> PrimitiveModel:
    return PrimitiveModel(n_components=4, n_clusters=3, n_init=1, seed=0).fit(trials)


@pytest.fixture(scope="module")
def classifier(trials: list[Trial]) -> DTWClassifier:
    return DTWClassifier().fit(trials, ["grab", "throw"])


def _joined(a: Trial, b: Trial, gap: float) -> tuple[Trial, float]:
    """``a`` then ``b``, ``b``'s first frame ``gap`` seconds after ``a``'s last; and the
    shift of ``b``'s times."""
    shift = a.times[-1] + gap - b.times[0]
    return (
        Trial(
            np.concatenate([a.times, b.times + shift]),
            np.concatenate([a.markers, b.markers]),
            np.concatenate([a.joints, b.joints]),
            np.concatenate([a.body_frame, b.body_frame]),
            arms=a.arms,
        ),
        shift,
    )


def _later(events: list[Event], shift: float, movements: int) -> list[Event]:
    """Events of a part alone as the joined stream would give them: times ``shift`` s later,
    movement numbers after the ``movements`` of the parts before."""
    out = []
    for e in events:
        change = {f.name: getattr(e, f.name) + shift for f in fields(e) if f.name in TIMES}
        out.append(replace(e, movement=e.movement + movements, **change))
    return out


TIMES = ("start", "end", "emitted")


def _same(got: list[Event], want: list[Event]) -> None:
    assert [type(e) for e in got] == [type(e) for e in want]
    for g, w in zip(got, want, strict=True):
        for f in fields(g):
            x, y = getattr(g, f.name), getattr(w, f.name)
            if isinstance(x, float):
                assert math.isclose(x, y, rel_tol=1e-9, abs_tol=1e-9), (f.name, g, w)
            else:
                assert x == y, (f.name, g, w)


def _alone(
    pipe: OnlinePipeline, part: Trial, chunk: int, found: float | None = None
) -> list[Event]:
    """The events of ``part`` replayed alone; those of its end (the flush) emitted at
    ``found`` (s) if given: in the joined stream, when the frame after the gap arrived."""
    streamed = []
    for k in range(0, part.n_frames, chunk):
        b = min(part.n_frames, k + chunk)
        streamed += pipe.push(
            Frames(
                part.times[k:b],
                part.markers[k:b],
                part.joints[k:b] if part.joints is not None else None,
                part.body_frame[k:b] if part.body_frame is not None else None,
            )
        )
    flushed = pipe.flush()
    if found is not None:
        flushed = [replace(e, emitted=float(found)) for e in flushed]
    return streamed + flushed


def _movements(events: list[Event]) -> int:
    return sum(isinstance(e, MovementEnded) for e in events)


@pytest.mark.parametrize("clock", ["model", "stream"])
@pytest.mark.parametrize("chunk", [1, 37])
def test_a_stalled_stream_is_two_streams(trials, model, classifier, clock, chunk) -> None:
    a, b = trials
    joined, shift = _joined(a, b, gap=1.0)
    pipe = OnlinePipeline(model, classifier, clock=clock)
    got = list(pipe.replay(joined, chunk=chunk))
    first = _alone(
        OnlinePipeline(model, classifier, clock=clock), a, chunk, joined.times[a.n_frames]
    )
    second = _alone(OnlinePipeline(model, classifier, clock=clock), b, chunk)
    assert _movements(first) >= 1 and any(isinstance(e, SegmentClosed) for e in second)
    want = first + _later(second, shift, _movements(first))
    if chunk > 1:
        # A running class is checked at the end of each chunk (visprim.online.pipeline): in
        # the chunk that holds the gap, after frames of both parts.
        got, want = ([e for e in x if not isinstance(e, ClassUpdate)] for x in (got, want))
    _same(got, want)
    assert pipe.segmenter.gaps == 1 and pipe.segmenter.n_frames == joined.n_frames


def test_a_gap_up_to_max_gap_is_bridged(trials, model) -> None:
    a, b = trials
    joined, _ = _joined(a, b, gap=0.15)
    seg = OnlineSegmenter(model)
    for k in range(0, joined.n_frames, 16):
        seg.push(Frames(joined.times[k : k + 16], joined.markers[k : k + 16]))
    assert seg.gaps == 0
    wide = OnlineSegmenter(model, max_gap=2.0)
    joined, _ = _joined(a, b, gap=1.0)
    wide.push(Frames(joined.times, joined.markers))
    assert wide.gaps == 0


@pytest.mark.parametrize("clock", ["model", "stream"])
def test_a_long_occlusion_splits_the_stream(trials, model, clock) -> None:
    """NaN markers for half a second: the frames before and after are two streams."""
    trial = trials[1]
    hole = np.arange(40, 55)  # 15 frames, 0.51 s between the complete frames around them
    markers = trial.markers.copy()
    markers[hole, 2, 0] = np.nan
    pipe = OnlinePipeline(model, clock=clock)
    got = []
    for k in range(0, trial.n_frames, 8):
        part = Frames(trial.times[k : k + 8], markers[k : k + 8], None, None)
        got += pipe.push(part)
    got += pipe.flush()
    assert pipe.segmenter.gaps == 1 and pipe.segmenter.missing_frames == hole.size

    def alone(lo: int, hi: int, found: float | None = None) -> list[Event]:
        part = Trial(trial.times[lo:hi], trial.markers[lo:hi], arms=trial.arms)
        return _alone(OnlinePipeline(model, clock=clock), part, 8, found)

    before = alone(0, hole[0], found=trial.times[hole[-1] + 1])
    after = alone(hole[-1] + 1, trial.n_frames)
    _same(got, before + _later(after, 0.0, _movements(before)))


def test_max_gap_is_checked(model) -> None:
    for bad in (0.0, -1.0, math.nan, math.inf, "1"):
        with pytest.raises(ValueError, match="max_gap must be a positive number of seconds"):
            OnlineSegmenter(model, max_gap=bad)
