"""visprim.online: the open-end DTW kernel, the causal segmenter and the pipeline replayed on
shared recordings against the offline pipeline of the same model."""

from __future__ import annotations

import json
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from visprim import kernels
from visprim.classify import DTWClassifier, MotionClassifier, dtw_matrix
from visprim.model import PrimitiveModel
from visprim.online import (
    ClassUpdate,
    Frames,
    MovementEnded,
    OnlinePipeline,
    SegmentClosed,
    event_to_dict,
)
from visprim.online.compare import compare_trial, summarise
from visprim.online.ring import FrameRing
from visprim.trial import Trial

HDM05 = [
    "HDM_bd_depositFloorR_001_120.amc",
    "HDM_bd_grabHighR_001_120.amc",
    "HDM_bd_throwBasketball_001_120.amc",
    "HDM_bk_depositFloorR_007_120.amc",
    "HDM_bk_grabHighR_005_120.amc",
    "HDM_bk_throwBasketball_004_120.amc",
    "HDM_dg_depositFloorR_013_120.amc",
    "HDM_dg_grabHighR_011_120.amc",
    "HDM_dg_throwBasketball_007_120.amc",
    "HDM_mm_depositFloorR_019_120.amc",
    "HDM_mm_grabHighR_017_120.amc",
    "HDM_mm_throwBasketball_010_120.amc",
]


def _label(name: str) -> str:
    return name.split("_")[2]


@pytest.fixture(scope="module")
def hdm05(shared_data: Path) -> list[Trial]:
    from visprim.io import read

    folder = shared_data / "hdm05_cut_amc"
    missing = [f for f in HDM05 if not (folder / f).exists()]
    if missing:
        pytest.skip(f"HDM05 recordings missing: {missing[:2]}")
    return [read(folder / f, "both", resample=0.034) for f in HDM05]


@pytest.fixture(scope="module")
def fitted(hdm05: list[Trial]) -> tuple[PrimitiveModel, DTWClassifier, list[Trial]]:
    train = [t for t in hdm05 if not t.name.startswith("HDM_mm")]
    test = [t for t in hdm05 if t.name.startswith("HDM_mm")] + train[:3]
    model = PrimitiveModel(n_components=8, n_clusters=8, n_init=2).fit(train)
    clf = DTWClassifier().fit(train, [_label(t.name) for t in train])
    return model, clf, test


# ---------------------------------------------------------------------- kernel


def test_online_dtw_closed_end_is_the_offline_dtw_and_open_end_the_best_prefix() -> None:
    rng = np.random.default_rng(0)
    refs = [rng.normal(size=(n, 3)) for n in (4, 9, 15)]
    query = rng.normal(size=(11, 3))
    off = np.array([0, 4, 13], dtype=np.int64)
    dtw = kernels.OnlineDtw(np.concatenate(refs), off)
    for a in range(0, 11, 3):
        dtw.push(query[a : a + 3])
    np.testing.assert_array_equal(dtw.costs(), dtw_matrix([query], refs)[0])
    costs, at = dtw.open_end()
    for k, r in enumerate(refs):
        prefixes = [dtw_matrix([query], [r[: j + 1]])[0, 0] for j in range(r.shape[0])]
        assert costs[k] == pytest.approx(min(prefixes), rel=1e-12)
        assert at[k] == int(np.argmin(prefixes))
    bytes_before = dtw.memory_bytes
    dtw.push(rng.normal(size=(500, 3)))
    assert dtw.memory_bytes == bytes_before
    dtw.reset()
    assert dtw.n_frames == 0
    with pytest.raises(ValueError, match="channels"):
        dtw.push(np.zeros((2, 4)))
    with pytest.raises(ValueError, match="NaN"):
        dtw.push(np.full((1, 3), np.nan))


def test_causal_filter_is_scipy_sosfilt_whatever_the_chunks() -> None:
    from scipy import signal
    from visprim.filtering import butterworth

    sos = butterworth(4, 0.25)
    x = np.random.default_rng(1).normal(size=(120, 3)).cumsum(axis=0)
    zi = signal.sosfilt_zi(sos)[:, :, None] * x[0][None, None, :]
    want, _ = signal.sosfilt(sos, x, axis=0, zi=zi)
    for chunk in (1, 7, 120):
        f = kernels.CausalSos(sos, 3)
        got = np.concatenate([f.filter(x[a : a + chunk]) for a in range(0, 120, chunk)])
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="channels"):
        f.filter(np.zeros((2, 4)))
    with pytest.raises(ValueError, match="NaN"):
        f.filter(np.full((1, 3), np.nan))


def test_ring_buffer_keeps_the_last_frames() -> None:
    ring = FrameRing(5, 2)
    ring.extend(np.arange(14.0).reshape(7, 2))
    assert (ring.start, ring.end) == (2, 7)
    np.testing.assert_array_equal(ring.window(3, 6), np.arange(6.0, 12.0).reshape(3, 2))
    with pytest.raises(IndexError):
        ring.window(1, 3)


# ---------------------------------------------------------------------- replay


def _events(model: PrimitiveModel, clf: DTWClassifier | None, trial: Trial, chunk: int) -> list:
    return list(OnlinePipeline(model, clf).replay(trial, chunk=chunk))


def test_events_do_not_depend_on_the_chunk_size(fitted) -> None:
    model, clf, test = fitted
    trial = test[0]
    segs = [
        [
            e
            for e in _events(model, clf, trial, chunk)
            if isinstance(e, (SegmentClosed, MovementEnded))
        ]
        for chunk in (1, 7, 1000)
    ]
    assert trial.n_frames < 1000  # the last replay is one chunk
    assert segs[0], "no segment found"
    assert segs[0] == segs[1] == segs[2]


def test_a_motion_classifier_gives_the_final_class_of_predict(fitted, hdm05) -> None:
    model, _, test = fitted
    train = [t for t in hdm05 if not t.name.startswith("HDM_mm")]
    clf = MotionClassifier({"n_components": 6, "n_clusters": 6, "n_init": 1}).fit(
        train, [_label(t.name) for t in train], [t.name.split("_")[1] for t in train]
    )
    results = [compare_trial(model, t, clf, chunk=16) for t in test]
    # One movement per recording here: the online final class is predict's on its frames.
    assert all(r.online_class for r in results)
    assert summarise(results)["class_equal"] == 1.0
    events = [e for t in test for e in _events(model, clf, t, 7)]
    updates = [e for e in events if isinstance(e, ClassUpdate)]
    assert updates and all(0.0 <= e.confidence <= 1.0 for e in updates)
    assert {e.label for e in updates} <= set(clf.classes_.tolist())


def test_replay_agrees_with_the_offline_pipeline(fitted) -> None:
    model, clf, test = fitted
    results = [compare_trial(model, t, clf, chunk=4) for t in test]
    s = summarise(results)
    # Measured on these recordings: F1 0.9+, every final class equal (closed-end DTW of
    # the same frames is the offline cost).
    assert s["boundary_f1"] >= 0.8, s
    assert s["class_equal"] == 1.0, s
    assert s["primitive_equal"] >= 0.5, s
    assert all(np.all(r.latencies >= 0) for r in results)


def test_a_replay_with_no_online_segment_counts_every_offline_one_as_missed(fitted) -> None:
    model, _, test = fitted
    # No run travels 10,000°: the online path closes no segment, offline cuts as usual.
    r = compare_trial(model, test[0], None, chunk=16, min_travel_deg=10_000.0)
    assert r.online_segments.shape == (0, 2)
    assert r.offline_segments.shape[0] > 0
    assert r.primitives == (0, r.offline_segments.shape[0])
    assert r.boundaries[0] == 0


def test_event_stream_shape_and_json(fitted) -> None:
    model, clf, test = fitted
    events = _events(model, clf, test[1], 5)
    kinds = [type(e) for e in events]
    assert SegmentClosed in kinds and MovementEnded in kinds and ClassUpdate in kinds
    assert isinstance(events[-1], MovementEnded)
    segs = [e for e in events if isinstance(e, SegmentClosed)]
    assert all(a.end <= b.start + 1e-9 for a, b in zip(segs, segs[1:], strict=False))
    assert all(0 <= e.primitive < model.n_primitives for e in segs)
    for e in events:
        d = event_to_dict(e)
        assert json.loads(json.dumps(d)) == d


# ---------------------------------------------------------------------- memory


def _synthetic_arm(n: int, period: float = 0.034, seed: int = 0) -> Frames:
    """An arm that swings in strokes separated by pauses, n frames."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * period
    phase = np.clip(np.sin(2 * np.pi * t / 3.0) * 1.5, -1, 1)  # plateaus = pauses
    ang = 0.8 * phase + 0.01 * rng.normal(size=n)
    shoulder = np.zeros((n, 3))
    elbow = np.stack([0.3 * np.sin(ang), np.zeros(n), -0.3 * np.cos(ang)], 1)
    wrist = elbow + np.stack(
        [0.25 * np.sin(2 * ang), np.zeros(n) + 0.05, -0.25 * np.cos(2 * ang)], 1
    )
    hand = wrist + 0.05 * (wrist - elbow) / 0.25
    markers = np.stack([(shoulder + elbow) / 2, (elbow + wrist) / 2, wrist, hand], 1)
    joints = np.stack([shoulder, elbow, wrist], 1)
    return Frames(t, markers, joints)


def test_memory_stays_flat_on_a_long_stream() -> None:
    one = PrimitiveModel(n_components=4, n_clusters=3, n_init=1).fit(
        [
            Trial(f.times, f.markers, f.joints)
            for f in [_synthetic_arm(900, seed=s) for s in range(3)]
        ]
    )
    pipe = OnlinePipeline(one, max_segment=5.0)
    stream = _synthetic_arm(30_000)  # 17 minutes at 34 ms
    sizes, n_segments = [], 0
    tracemalloc.start()
    for a in range(0, 30_000, 500):
        n_segments += sum(isinstance(e, SegmentClosed) for e in pipe.push(stream.part(a, a + 500)))
        sizes.append((pipe.buffer_bytes, tracemalloc.get_traced_memory()[0]))
    tracemalloc.stop()
    assert n_segments > 100
    assert len({b for b, _ in sizes[1:]}) == 1  # the buffers never grow
    assert len(pipe.segmenter.decided) <= 1  # no list grows with the movements
    traced = np.array([m for _, m in sizes])
    # Python allocations after the first minutes stay within 1 MB of where they were.
    assert traced[10:].max() - traced[10] < 1_000_000, traced[10:].max() - traced[10]


def test_evaluate_online_writes_the_early_recognition_curve(
    shared_data: Path, tmp_path: Path
) -> None:
    from visprim.cli.main import main

    folder = shared_data / "bandai_namco_ds2"
    if not folder.is_dir():
        pytest.skip("bandai_namco_ds2 not in the shared data")
    out = tmp_path / "ev"
    assert main(["evaluate", str(folder), "--online", "--jobs", "1", "--out", str(out)]) == 0
    data = json.loads((out / "early_recognition.json").read_text())
    (result,) = data["results"]
    assert result["fractions"][0] == 0.1 and result["fractions"][-1] == 1.0
    assert all(0.0 <= a <= 1.0 for a in result["accuracy"])
    # Well above chance (4 gestures) once the whole movement is seen.
    assert result["closed_end_accuracy"] > 0.5


def test_early_confirmation_emits_inner_boundaries_sooner(fitted, hdm05) -> None:
    # confirm_frames decides when the slowest frame of a gap is emitted (that rule only).
    _, _, test = fitted
    train = [t for t in hdm05 if not t.name.startswith("HDM_mm")]
    model = PrimitiveModel(n_components=8, n_clusters=8, n_init=2, seg2_boundary="slowest").fit(
        train
    )
    early: list[float] = []
    late: list[float] = []
    for t in test:
        for confirm, latencies in ((1, early), (None, late)):
            pipe = OnlinePipeline(model, None, confirm_frames=confirm)
            events = list(pipe.replay(t, chunk=5))
            ends = {(e.movement, e.n_segments - 1) for e in events if isinstance(e, MovementEnded)}
            latencies.extend(
                e.latency
                for e in events
                if isinstance(e, SegmentClosed) and (e.movement, e.index) not in ends
            )
    assert early and late
    # Emitted once the speed is back above c, not after the next stroke's 5° of travel.
    assert np.median(early) < np.median(late), (np.median(early), np.median(late))
    with pytest.raises(ValueError, match="confirm_frames"):
        OnlinePipeline(model, None, confirm_frames=0)
