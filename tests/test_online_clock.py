"""The model's clock (:mod:`visprim.online.clock`): a stream at another rate is resampled
causally onto the model's frame period before it is segmented.

References are independent of the code under test: :func:`numpy.interp` of each column at
the clock's times, scipy's ``Slerp`` for the body frames, and the online path on the
stream already at the model's period (which the clock must leave exactly as it is).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp
from visprim import kernels
from visprim.model import PrimitiveModel
from visprim.online import Frames, OnlinePipeline, SegmentClosed
from visprim.online.clock import ModelClock
from visprim.trial import Trial

RECORDINGS = ["HDM_bd_grabHighR_001_120.amc", "HDM_mm_throwBasketball_010_120.amc"]
PERIOD = 0.034


@pytest.fixture(scope="module")
def native(shared_data: Path) -> list[Trial]:
    """The recordings at their own 120 Hz, and at 60 Hz (every second frame)."""
    from visprim.io import read

    folder = shared_data / "hdm05_cut_amc"
    missing = [f for f in RECORDINGS if not (folder / f).exists()]
    if missing:
        pytest.skip(f"HDM05 recordings missing: {missing}")
    return [read(folder / f, "both") for f in RECORDINGS]


@pytest.fixture(scope="module")
def model(native: list[Trial]) -> PrimitiveModel:
    from visprim.io import resample_trial

    on_clock = [resample_trial(t, PERIOD) for t in native]
    return PrimitiveModel(n_components=4, n_clusters=3, n_init=1, seed=0).fit(on_clock)


def _chunks(trial: Trial, chunk: int) -> list[Frames]:
    return [
        Frames(
            trial.times[a : a + chunk],
            trial.markers[a : a + chunk],
            None if trial.joints is None else trial.joints[a : a + chunk],
            None if trial.body_frame is None else trial.body_frame[a : a + chunk],
        )
        for a in range(0, trial.n_frames, chunk)
    ]


def test_the_clock_interpolates_each_column_and_slerps_the_body_frame(native) -> None:
    trial = native[0]
    assert trial.body_frame is not None and trial.joints is not None
    clock = ModelClock(PERIOD)
    parts = [clock.push(f) for f in _chunks(trial, 5)]
    times = np.concatenate([p[0].times for p in parts])
    arrivals = np.concatenate([p[1] for p in parts])
    markers = np.concatenate([p[0].markers for p in parts])
    body = np.concatenate([p[0].body_frame for p in parts])
    grid = trial.times[0] + np.arange(times.size) * PERIOD
    np.testing.assert_allclose(times, grid, atol=1e-12)
    assert grid[-1] <= trial.times[-1] + 1e-9 < grid[-1] + PERIOD  # every frame the input covers
    # Each clock frame emitted at the first input frame at or after it.
    first_after = trial.times[np.searchsorted(trial.times, grid - 1e-9)]
    np.testing.assert_array_equal(arrivals, first_after)
    flat = trial.markers.reshape(trial.n_frames, -1)
    want = np.stack([np.interp(grid, trial.times, c) for c in flat.T], axis=1)
    np.testing.assert_allclose(markers.reshape(times.size, -1), want, atol=1e-12)
    slerp = Slerp(trial.times, Rotation.from_matrix(trial.body_frame))(grid).as_matrix()
    np.testing.assert_allclose(body, slerp, atol=1e-6)
    np.testing.assert_allclose(
        body @ body.transpose(0, 2, 1), np.broadcast_to(np.eye(3), body.shape), atol=1e-12
    )


def test_a_stream_on_the_models_clock_is_left_as_it_is(native, model) -> None:
    from visprim.io import resample_trial

    trial = resample_trial(native[1], PERIOD)
    on = list(OnlinePipeline(model).replay(trial, chunk=7))
    off = list(OnlinePipeline(model, clock="stream").replay(trial, chunk=7))
    assert on == off and any(isinstance(e, SegmentClosed) for e in on)


def test_a_60_hz_stream_is_cut_on_the_clock_whatever_the_chunks(native, model) -> None:
    """At 60 Hz: the same events for chunks of 1 and 64 frames; segment times on the
    model's clock; each emitted after the input frame that decided it arrived."""
    trial = native[1]
    sixty = Trial(
        trial.times[::2], trial.markers[::2], trial.joints[::2], trial.body_frame[::2],
        arms=trial.arms, name="60 Hz",
    )  # fmt: skip
    runs = [list(OnlinePipeline(model).replay(sixty, chunk=c)) for c in (1, 64)]
    assert runs[0] == runs[1]
    closed = [e for e in runs[0] if isinstance(e, SegmentClosed)]
    assert closed
    for e in closed:
        for t in (e.start, e.end):
            n = (t - sixty.times[0]) / PERIOD
            assert abs(n - round(n)) < 1e-6 or t == sixty.times[0]
        assert e.latency >= 0


def test_the_clock_refuses_a_change_of_arrays_and_bad_times(native) -> None:
    trial = native[0]
    clock = ModelClock(PERIOD)
    clock.push(_chunks(trial, 4)[0])
    bare = Frames(trial.times[4:8], trial.markers[4:8])
    with pytest.raises(ValueError, match="same arrays"):
        clock.push(bare)
    again = _chunks(trial, 4)[0]
    with pytest.raises(ValueError, match="timestamps must increase"):
        clock.push(again)
    with pytest.raises(ValueError, match="period"):
        kernels.StreamResampler(0.0, 3)
    with pytest.raises(ValueError, match="rows"):
        kernels.StreamResampler(0.1, 3).push(np.zeros(2), np.zeros((2, 4)))


def test_frames_with_missing_values_are_left_out_and_counted(native, model) -> None:
    """A stream with occluded markers (NaN) in a few frames: those frames are left out and
    counted, and the events are those of the stream without them."""
    from visprim.io import resample_trial

    trial = resample_trial(native[1], PERIOD)
    holes = np.array([5, 40, 41, 42, 70])
    markers = trial.markers.copy()
    markers[holes, 1, 2] = np.nan
    joints = trial.joints.copy()
    joints[holes[:2], 0, 0] = np.inf
    keep = np.setdiff1d(np.arange(trial.n_frames), holes)
    kept = Trial(
        trial.times[keep], trial.markers[keep], trial.joints[keep], trial.body_frame[keep],
        arms=trial.arms,
    )  # fmt: skip
    pipe = OnlinePipeline(model)
    got = []
    for a in range(0, trial.n_frames, 16):
        b = min(trial.n_frames, a + 16)
        got += pipe.push(Frames(trial.times[a:b], markers[a:b], joints[a:b], trial.body_frame[a:b]))
    got += pipe.flush()
    assert pipe.segmenter.missing_frames == holes.size
    assert got == list(OnlinePipeline(model).replay(kept, chunk=16))
    assert any(isinstance(e, SegmentClosed) for e in got)
