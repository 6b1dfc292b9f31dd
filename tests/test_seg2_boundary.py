"""SEG-2's boundary rules (``seg2_boundary``): the slowest frame of the gap between two runs,
or each run's first stop; offline on a hand-made z, and the online segmenter against the
offline one under the first-stop rule."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from visprim.model import PrimitiveModel
from visprim.online import MovementEnded, OnlinePipeline, SegmentClosed
from visprim.online.compare import compare_trial
from visprim.online.segmenter import OnlineSegmenter
from visprim.segment.seg2 import ROBUST_REST, seg2_boundaries
from visprim.trial import Trial

PERIOD = 0.034
#: Two runs of z = 4 (rad/s)² over c = 1, 10 frames each (travel 0.68 rad ≫ 5°), frame by
#: frame. After the first run z falls to a local minimum (0.3, frame 14) and then to the
#: gap's slowest frame (0.05, frame 17); after the second run a local minimum (0.2, frame
#: 31) comes before rest (0.02 ≤ c / 25, frame 34).
Z_TWO_RUNS = [0, 0, 0.5] + [4] * 10 + [0.6, 0.3, 0.4, 0.2, 0.05, 0.1, 0.5] + [4] * 10
Z_TWO_RUNS += [0.5, 0.2, 0.3, 0.1, 0.02, 0, 0]
#: One run whose speed falls straight to rest: first frame at rest 0.03 (frame 15), first
#: local minimum (z = 0 twice) at frame 17.
Z_EASE_OUT = [0, 0, 0.5] + [4] * 10 + [0.5, 0.2, 0.03, 0.01, 0, 0, 0]


def _frames(z: list[float], boundary: str, rest: float | None) -> list[int]:
    zz = np.asarray(z, dtype=np.float64)
    t = np.arange(zz.size) * PERIOD
    _, frame, _ = seg2_boundaries(
        t, zz, [0], 1.0, rest_fraction=rest, boundary=boundary, min_travel_deg=5.0
    )
    return frame.tolist()


@pytest.mark.parametrize(
    ("z", "boundary", "rest", "expected"),
    [
        (Z_TWO_RUNS, "slowest", None, [1, 17, 31]),
        (Z_TWO_RUNS, "slowest", ROBUST_REST, [1, 17, 34]),
        (Z_TWO_RUNS, "first_stop", None, [1, 14, 31]),
        (Z_TWO_RUNS, "first_stop", ROBUST_REST, [1, 14, 31]),
        (Z_EASE_OUT, "slowest", None, [1, 17]),
        (Z_EASE_OUT, "slowest", ROBUST_REST, [1, 15]),
        (Z_EASE_OUT, "first_stop", None, [1, 17]),
        (Z_EASE_OUT, "first_stop", ROBUST_REST, [1, 15]),
    ],
)
def test_boundary_rules_on_a_hand_made_speed(z, boundary, rest, expected) -> None:
    assert _frames(z, boundary, rest) == expected


def test_an_unknown_boundary_rule_is_refused() -> None:
    with pytest.raises(ValueError, match="boundary must be one of"):
        _frames(Z_TWO_RUNS, "middle", None)
    with pytest.raises(ValueError, match="seg2_boundary"):
        PrimitiveModel(seg2_boundary="middle")._validate_params()


HDM05 = [
    "HDM_bd_depositFloorR_001_120.amc",
    "HDM_bd_throwBasketball_001_120.amc",
    "HDM_bk_grabHighR_005_120.amc",
    "HDM_dg_depositFloorR_013_120.amc",
    "HDM_dg_throwBasketball_007_120.amc",
    "HDM_mm_grabHighR_017_120.amc",
    "HDM_mm_throwBasketball_010_120.amc",
]


@pytest.fixture(scope="module")
def first_stop(shared_data: Path) -> tuple[PrimitiveModel, list[Trial]]:
    from visprim.io import read

    folder = shared_data / "hdm05_cut_amc"
    missing = [f for f in HDM05 if not (folder / f).exists()]
    if missing:
        pytest.skip(f"HDM05 recordings missing: {missing[:2]}")
    trials = [read(folder / f, "both", resample=PERIOD) for f in HDM05]
    model = PrimitiveModel(seg2_boundary="first_stop", n_components=6, n_clusters=6, n_init=1).fit(
        trials
    )
    return model, trials


def test_online_cuts_where_offline_does_given_the_same_filtered_frames(first_stop) -> None:
    """Fed the offline (zero-phase) values, with the fitted c and one movement per
    recording, the online first-stop boundaries are the offline ones, frame for frame."""
    model, trials = first_stop
    checked = 0
    for trial in trials:
        corpus = model.prepare([trial], tune_seg2=False)
        c = float(model.seg2_threshold_)
        _, offline, _ = seg2_boundaries(
            trial.times,
            corpus.segmentation.z,
            [0],
            c,
            rest_fraction=ROBUST_REST,
            boundary="first_stop",
        )
        seg = OnlineSegmenter(model, threshold="fixed", rest_timeout=1e3, max_segment=1e3)
        events = seg.push_values(corpus.values, trial.times) + seg.flush()
        segs = [e for e in events if isinstance(e, SegmentClosed)]
        # Event times are the frames' shifted back by the causal filter's delay (not before
        # the first frame; the last frame, closed by the end of the stream, is itself).
        n = trial.n_frames
        expected = [
            trial.times[f if f == n - 1 else max(f - seg._shift, 0)] for f in offline.tolist()
        ]
        online = sorted({x for e in segs for x in (e.start, e.end)})
        assert online == pytest.approx(expected, abs=1e-12), trial.name
        checked += len(segs)
    assert checked >= len(trials)


def test_first_stop_events_come_right_after_the_stop_and_do_not_depend_on_chunks(
    first_stop,
) -> None:
    model, trials = first_stop
    streams = []
    for chunk in (1, 9, 10_000):
        streams.append(
            [
                e
                for t in trials
                for e in OnlinePipeline(model, None).replay(t, chunk=chunk)
                if isinstance(e, (SegmentClosed, MovementEnded))
            ]
        )

    def exact(e: SegmentClosed | MovementEnded) -> tuple:
        # Boundaries, primitives and event times exactly; distances to the last bits.
        if isinstance(e, MovementEnded):
            return (e.start, e.end, e.n_segments, e.movement, e.emitted)
        return (e.start, e.end, e.primitive, e.movement, e.index, e.forced, e.emitted)

    assert [exact(e) for e in streams[0]] == [exact(e) for e in streams[1]]
    assert [exact(e) for e in streams[0]] == [exact(e) for e in streams[2]]
    for other in streams[1:]:
        np.testing.assert_allclose(
            [getattr(e, "distance", 0.0) for e in other],
            [getattr(e, "distance", 0.0) for e in streams[0]],
            rtol=1e-9,
        )
    seg = OnlineSegmenter(model)
    # The filter's delay + the frame after the stop + its successor (velocity), at most.
    bound = (seg._shift + 2) * PERIOD + 1e-9
    results = [compare_trial(model, t, None, chunk=8) for t in trials]
    live = np.concatenate([r.latencies[~r.at_flush] for r in results])
    assert live.size, "no segment closed before the end of the stream"
    assert max(live) <= bound, (max(live), bound)
