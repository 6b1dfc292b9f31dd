"""The online engine's per-segment and per-frame shortcuts against independent references:
a closed segment's projection and primitive against ``PrimitiveModel.transform`` /
``assign``, its zero-phase values against the whole recording's zero-phase filter, and the
running class (one Rust call) against the open-end costs of a full DTW table in numpy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from visprim import kernels
from visprim.features import from_angles
from visprim.filtering import lowpass
from visprim.ik import arm_angles_corpus
from visprim.model import PrimitiveModel
from visprim.online import OnlinePipeline, SegmentClosed
from visprim.online.recogniser import OnlineRecogniser, confidence
from visprim.trial import Trial

RECORDINGS = [
    "HDM_bd_depositFloorR_001_120.amc",
    "HDM_bd_grabHighR_001_120.amc",
    "HDM_bd_throwBasketball_001_120.amc",
    "HDM_bk_depositFloorR_007_120.amc",
    "HDM_bk_grabHighR_005_120.amc",
    "HDM_dg_throwBasketball_007_120.amc",
    "HDM_dg_grabHighR_011_120.amc",
    "HDM_mm_depositFloorR_019_120.amc",
    "HDM_mm_grabHighR_017_120.amc",
    "HDM_mm_throwBasketball_010_120.amc",
]
#: Fitted on these, replayed on the others.
TRAIN = 7


@pytest.fixture(scope="module")
def trials(shared_data: Path) -> list[Trial]:
    from visprim.io import read

    folder = shared_data / "hdm05_cut_amc"
    missing = [f for f in RECORDINGS if not (folder / f).exists()]
    if missing:
        pytest.skip(f"HDM05 recordings missing: {missing[:2]}")
    return [read(folder / f, "both", resample=0.034) for f in RECORDINGS]


@pytest.fixture(scope="module")
def model(trials: list[Trial]) -> PrimitiveModel:
    return PrimitiveModel(n_components=8, n_clusters=6, n_init=2, seg2_boundary="first_stop").fit(
        trials[:TRAIN]
    )


def test_a_closed_segment_is_projected_and_assigned_as_transform_and_assign_do(
    model: PrimitiveModel, trials: list[Trial]
) -> None:
    seen: list[tuple[np.ndarray, np.ndarray]] = []
    closed: list[SegmentClosed] = []
    for trial in trials:
        pipe = OnlinePipeline(model)
        project = pipe.segmenter._project

        def spy(vectors: np.ndarray, project=project) -> np.ndarray:  # type: ignore[no-untyped-def]
            p = project(vectors)
            seen.append((vectors.copy(), p.copy()))
            return p

        pipe.segmenter._project = spy  # type: ignore[method-assign]
        closed += [e for e in pipe.replay(trial, chunk=5) if isinstance(e, SegmentClosed)]
    assert len(closed) == len(seen) >= 10
    for event, (vectors, p) in zip(closed, seen, strict=True):
        reference = model.transform(vectors)
        np.testing.assert_allclose(p, reference, rtol=0, atol=1e-12)
        labels, dist = model.assign(reference)
        assert event.primitive == int(labels[0])
        assert event.distance == pytest.approx(float(dist[0]), rel=1e-12, abs=1e-14)


def test_zero_phase_segment_values_are_those_of_the_frames_the_segment_reports(
    model: PrimitiveModel, trials: list[Trial]
) -> None:
    """The values of a segment away from the recording's end equal the zero-phase filter
    of the whole recording on the frames of its reported start..end, within the window's
    edge effects; the same frames two later (the causal filter's delay), and the causal
    filter's values, are farther."""
    errors, shifted, causal = [], [], []
    for trial in trials:
        pipe = OnlinePipeline(model)
        seg = pipe.segmenter
        got: list[tuple[np.ndarray, np.ndarray]] = []
        values_of = seg._segment_values

        def spy(a: int, b: int, upto: int, values_of=values_of, got=got, seg=seg) -> np.ndarray:  # type: ignore[no-untyped-def]
            v = values_of(a, b, upto)
            got.append((v.copy(), seg._ring.window(a, b + 1).copy()))
            return v

        pipe.segmenter._segment_values = spy  # type: ignore[method-assign]
        closed = [e for e in pipe.replay(trial, chunk=3) if isinstance(e, SegmentClosed)]
        assert len(closed) == len(got)
        # The offline reference: the whole recording's angles (bone directions exact for
        # any γ, as online), through the model's zero-phase filter.
        angles = arm_angles_corpus([trial], singular_angle=0.0)[0]
        smooth = from_angles(
            lowpass(angles, order=int(model.filter_order), cutoff=float(model.cutoff)),
            model.features,
        )
        frame = {float(t): i for i, t in enumerate(trial.times)}
        for event, (v, lagged) in zip(closed, got, strict=True):
            a, b = frame[event.start], frame[event.end]
            if b > trial.n_frames - 8:
                continue
            assert v.shape[0] == b - a + 1
            errors.append(np.abs(v - smooth[a : b + 1]).max())
            shifted.append(np.abs(v - smooth[a + 2 : b + 3]).max())
            # (aligned at the end: at the stream's first frames it holds fewer frames)
            n = min(lagged.shape[0], b - a + 1)
            causal.append(np.abs(lagged[-n:] - smooth[b + 1 - n : b + 1]).max())
    assert len(errors) >= 5, "too few segments away from the recordings' ends"
    # Unit bone vectors: the window's edge effects (measured ≤ 0.011 on these; the same
    # frames two later: 0.03–0.41).
    assert max(errors) < 0.03
    assert np.median(errors) < 0.5 * np.median(shifted)
    # The causal filter's values of the segment (segment_filter="causal") are farther.
    assert np.median(errors) < 0.5 * np.median(causal)


def _open_end_by_table(query: np.ndarray, reference: np.ndarray) -> float:
    """``min_j D(n-1, j) / (n + j + 1)`` from the full DTW table (Euclidean local cost)."""
    n, m = query.shape[0], reference.shape[0]
    d = np.sqrt(((query[:, None, :] - reference[None, :, :]) ** 2).sum(axis=2))
    table = np.full((n + 1, m + 1), np.inf)
    table[0, 0] = 0.0
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            table[i, j] = d[i - 1, j - 1] + min(
                table[i - 1, j - 1], table[i - 1, j], table[i, j - 1]
            )
    return float(np.min(table[n, 1:] / (n + np.arange(1, m + 1))))


@pytest.mark.parametrize("chunk", [1, 4])
def test_the_running_class_is_the_best_open_end_match_of_a_full_table(chunk: int) -> None:
    rng = np.random.default_rng(3)
    lengths = [5, 9, 3, 12, 7, 6, 10, 4, 8]
    refs = [rng.normal(size=(m, 4)) for m in lengths]
    labels = np.array(["a", "b", "a", "c", "b", "c", "a", "b", "c"])
    rec = OnlineRecogniser(refs, labels)
    query = rng.normal(size=(16, 4))
    for i in range(0, query.shape[0], chunk):
        rec.push_features(query[i : i + chunk])
        n = min(i + chunk, query.shape[0])
        costs = np.array([_open_end_by_table(query[:n], r) for r in refs])
        best, conf = confidence(costs, labels)
        label, got_conf, cost = rec.running()
        assert label == labels[best]
        assert got_conf == pytest.approx(conf, rel=1e-12, abs=1e-15)
        assert cost == pytest.approx(costs[best], rel=1e-12)


def test_the_running_class_refuses_codes_of_another_length() -> None:
    dtw = kernels.OnlineDtw(np.zeros((4, 2)), np.array([0, 2], dtype=np.int64))
    dtw.push(np.ones((1, 2)))
    with pytest.raises(ValueError):
        dtw.running(np.array([0, 1, 2], dtype=np.int64))
    with pytest.raises(TypeError):
        dtw.running(np.array([0.0, 1.0]))


@pytest.mark.parametrize("features", ["zyz", "directions"])
@pytest.mark.parametrize("n_arms", [1, 2])
def test_segment_channels_are_lowpass_then_from_angles(features: str, n_arms: int) -> None:
    """The closed segment's values in one Rust call against the numpy path they replace:
    the model's zero-phase filter of the window (``short="reduce"`` for short windows) then
    ``from_angles`` of the kept frames; the filter's bits, the channels within an ulp."""
    from visprim.filtering import butterworth

    rng = np.random.default_rng(5)
    for order, cutoff in [(10, 0.2), (2, 0.35)]:
        sos = butterworth(order, cutoff)
        for n in [1, 3, 12, 31, 32, 33, 120]:
            raw = np.cumsum(rng.normal(scale=0.1, size=(n, 4 * n_arms)), axis=0)
            start, stop = n // 4, n - n // 5
            want = from_angles(
                lowpass(raw, order=order, cutoff=cutoff, short="reduce")[start:stop], features
            )
            got = kernels.segment_channels(sos, raw, start, stop, features)
            assert got.shape == want.shape
            if features == "zyz":
                np.testing.assert_array_equal(got, want)
            else:
                np.testing.assert_allclose(got, want, rtol=0, atol=1e-15)


def test_segment_channels_refuses_bad_windows() -> None:
    from visprim.filtering import butterworth

    sos = butterworth(2, 0.3)
    raw = np.zeros((10, 4))
    for start, stop in [(3, 3), (4, 2), (0, 11)]:
        with pytest.raises(ValueError):
            kernels.segment_channels(sos, raw, start, stop, "zyz")
    with pytest.raises(ValueError):
        kernels.segment_channels(sos, np.zeros((10, 3)), 0, 5, "zyz")
    with pytest.raises(ValueError):
        kernels.segment_channels(sos, raw, 0, 5, "quaternions")
    bad = raw.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError):
        kernels.segment_channels(sos, bad, 0, 5, "zyz")


@pytest.mark.parametrize("offsets", ["mean", "turns"])
def test_a_closed_segments_vector_is_vectors_from_frames(trials: list[Trial], offsets: str) -> None:
    """The segmenter's shortcut to a segment vector equals
    :func:`visprim.vectors.vectors_from_frames` of the whole segment, bit for bit."""
    from visprim.features import periodic_channels
    from visprim.online.segmenter import OnlineSegmenter
    from visprim.vectors import vectors_from_frames

    model = PrimitiveModel(n_components=6, n_clusters=4, n_init=1, offsets=offsets).fit(trials[:4])
    seg = OnlineSegmenter(model)
    rng = np.random.default_rng(2)
    channels = int(model.n_channels)
    for k in [2, 3, 17, 90]:
        values = np.cumsum(rng.normal(scale=0.4, size=(k, channels)), axis=0)
        want = vectors_from_frames(
            values,
            [0.0],
            [float(k - 1)],
            trial=[0],
            starts=[0.0],
            ends=[1.0],
            n_samples=int(model.n_samples),
            periodic_channels=periodic_channels(str(model.features), len(seg.arms)),
            offsets=offsets,
        ).vectors
        np.testing.assert_array_equal(seg._vectors(values), want)
