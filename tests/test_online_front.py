"""The online front end in Rust (:class:`visprim.kernels.OnlineFrontEnd`) against the Python
path it replaced, stage by stage, on shared recordings cut into chunks of 1, 7 and 64 frames.

The reference is the segmenter's former Python front end, written with the library's own
functions: :func:`visprim.ik.arm_angles_corpus` on each block as a Trial (a one-frame block
doubled), whole turns across blocks, :func:`scipy.signal.sosfilt` with its state carried,
:func:`visprim.features.from_angles`, ``z`` from :func:`numpy.gradient` over the whole
stream, the threshold from :func:`numpy.quantile` over the window, and
:func:`visprim.classify.arm_directions` for the bone directions.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import signal
from visprim import kernels
from visprim.classify import arm_directions
from visprim.features import from_angles, periodic_channels
from visprim.filtering import butterworth
from visprim.ik import DEFAULT_SINGULAR_ANGLE, arm_angles_corpus
from visprim.online import Frames, OnlinePipeline
from visprim.segment.seg2 import _ROBUST_QUANTILE, ROBUST_FRACTION, ROBUST_SLOWEST
from visprim.trial import Trial

RECORDINGS = ["HDM_bd_grabHighR_001_120.amc", "HDM_mm_throwBasketball_010_120.amc"]
BLOCK = 256  # the segmenter's block
EVERY = 8
CUTOFF = 0.25
WINDOW = 2.0  # seconds: short, so that the window slides within a recording


@pytest.fixture(scope="module")
def recordings(shared_data: Path) -> list[Trial]:
    from visprim.io import read

    folder = shared_data / "hdm05_cut_amc"
    missing = [f for f in RECORDINGS if not (folder / f).exists()]
    if missing:
        pytest.skip(f"HDM05 recordings missing: {missing}")
    trials = [read(folder / f, "both", resample=0.034) for f in RECORDINGS]
    # The same arms from the markers alone (implied joint centres, recording axes).
    bare = Trial(trials[0].times, trials[0].markers, arms=trials[0].arms, name="markers only")
    return [*trials, bare]


def _blocks(trial: Trial, chunk: int) -> list[Frames]:
    """The blocks the segmenter hands the front end: chunks, each cut into BLOCK frames."""
    out = []
    for a in range(0, trial.n_frames, chunk):
        b = min(trial.n_frames, a + chunk)
        for c in range(a, b, BLOCK):
            d = min(b, c + BLOCK)
            out.append(
                Frames(
                    trial.times[c:d],
                    trial.markers[c:d],
                    None if trial.joints is None else trial.joints[c:d],
                    None if trial.body_frame is None else trial.body_frame[c:d],
                )
            )
    return out


def _python_front(trial: Trial, features: str, chunk: int) -> dict[str, np.ndarray]:
    """Angles, values, directions and z of the former Python front end."""
    singular = 0.0 if features == "directions" else DEFAULT_SINGULAR_ANGLE
    periodic = list(periodic_channels("zyz", len(trial.arms)))
    sos = butterworth(2, CUTOFF)
    last = None
    state = None
    angles, values = [], []
    for part in _blocks(trial, chunk):
        a = arm_angles_corpus([part.as_trial(trial.arms)], singular_angle=singular)[0]
        a = np.array(a[: len(part)], dtype=np.float64)
        if last is not None:
            a[:, periodic] += 2 * np.pi * np.round((last[periodic] - a[0, periodic]) / (2 * np.pi))
        last = a[-1].copy()
        if state is None:
            state = signal.sosfilt_zi(sos)[:, :, None] * a[0][None, None, :]
        y, state = signal.sosfilt(sos, a, axis=0, zi=state)
        angles.append(a)
        values.append(from_angles(y, features))
    v = np.concatenate(values)
    z = np.sum(np.gradient(v, trial.times, axis=0) ** 2, axis=1)
    return {
        "angles": np.concatenate(angles),
        "values": v,
        "directions": arm_directions(trial),
        "z": z,
    }


def _python_threshold(z: np.ndarray, first_block: np.ndarray, c: float) -> np.ndarray:
    steps = np.diff(first_block)
    period = float(np.median(steps)) if steps.size else 1.0 / 30.0
    w = max(8, math.ceil(WINDOW / period))
    out = np.empty_like(z)
    ck = c
    for f in range(z.size):
        if f % EVERY == 0:
            s = float(np.quantile(z[max(0, f + 1 - w) : f + 1], _ROBUST_QUANTILE))
            ck = min(max(ROBUST_FRACTION * s, c / ROBUST_SLOWEST), c)
        out[f] = ck
    return out


def _rust_front(
    trial: Trial, features: str, chunk: int, c: float, adaptive: bool
) -> dict[str, np.ndarray]:
    singular = 0.0 if features == "directions" else DEFAULT_SINGULAR_ANGLE
    fe = kernels.OnlineFrontEnd(
        butterworth(2, CUTOFF),
        list(trial.arms),
        features,
        singular,
        c,
        adaptive,
        _ROBUST_QUANTILE,
        ROBUST_FRACTION,
        ROBUST_SLOWEST,
        EVERY,
        WINDOW,
    )
    out: dict[str, list[np.ndarray]] = {"angles": [], "values": [], "directions": [], "speeds": []}
    for part in _blocks(trial, chunk):
        for name, x in zip(
            out, fe.push(part.times, part.markers, part.joints, part.body_frame), strict=True
        ):
            out[name].append(x)
    out["speeds"].append(fe.finish())
    assert fe.n_frames == trial.n_frames
    return {name: np.concatenate(x) for name, x in out.items()}


@pytest.mark.parametrize("features", ["directions", "zyz"])
@pytest.mark.parametrize("chunk", [1, 7, 64])
def test_the_rust_front_end_is_the_python_one(recordings, features: str, chunk: int) -> None:
    for trial in recordings:
        want = _python_front(trial, features, chunk)
        # A constant for which the adaptive threshold moves between its bounds.
        c = 2.0 * ROBUST_FRACTION * float(np.quantile(want["z"], _ROBUST_QUANTILE))
        got = _rust_front(trial, features, chunk, c, adaptive=True)
        where = f"{trial.name}, {features}, chunks of {chunk}"
        for stage in ("angles", "values", "directions"):
            np.testing.assert_allclose(
                got[stage], want[stage], rtol=1e-9, atol=1e-10, err_msg=f"{stage}: {where}"
            )
        speeds = got["speeds"]
        assert speeds.shape == (trial.n_frames, 4), where
        np.testing.assert_allclose(speeds[:, 0], want["z"], rtol=1e-8, atol=1e-12, err_msg=where)
        np.testing.assert_array_equal(speeds[:, 1], trial.times)
        decided = np.append(trial.times[1:], trial.times[-1])
        np.testing.assert_array_equal(speeds[:, 2], decided)
        first = _blocks(trial, chunk)[0].times
        threshold = _python_threshold(want["z"], first, c)
        assert np.ptp(threshold) > 0, "the threshold should move on this recording"
        np.testing.assert_allclose(speeds[:, 3], threshold, rtol=1e-8, err_msg=where)
        fixed = _rust_front(trial, features, chunk, c, adaptive=False)["speeds"]
        np.testing.assert_array_equal(fixed[:, 3], c)
        np.testing.assert_array_equal(fixed[:, 0], speeds[:, 0])


def test_the_zyz_reference_goes_through_the_singular_cones(recordings) -> None:
    # Otherwise the comparison above would not test the interpolation of γ and α in time.
    beta = _python_front(recordings[0], "zyz", 7)["angles"][:, 1::4]
    assert np.any(beta < DEFAULT_SINGULAR_ANGLE)


def test_the_front_end_refuses_bad_chunks_and_keeps_its_state(recordings) -> None:
    trial = recordings[0]
    fe = kernels.OnlineFrontEnd(
        butterworth(2, CUTOFF), ["right", "left"], "directions", 0.0, 1.0, True,
        0.95, 0.02, 100.0, 8, 1.0,
    )  # fmt: skip
    fe.push(trial.times[:5], trial.markers[:5])
    with pytest.raises(ValueError, match="timestamps must increase"):
        fe.push(trial.times[4:6], trial.markers[4:6])
    bad = trial.markers[5:7].copy()
    bad[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        fe.push(trial.times[5:7], bad)
    with pytest.raises(ValueError, match="shape"):
        fe.push(trial.times[5:7], trial.markers[5:7, :4])
    with pytest.raises(TypeError, match="float64"):
        fe.push(trial.times[5:7].astype(np.float32), trial.markers[5:7])
    zero = np.zeros_like(trial.markers[5:7])
    with pytest.raises(ValueError, match="zero length"):
        fe.push(trial.times[5:7], zero)
    assert fe.n_frames == 5
    *_, speeds = fe.push(trial.times[5:9], trial.markers[5:9])
    assert speeds.shape == (4, 4)  # frames 4..7; frame 8 waits for its successor
    with pytest.raises(ValueError, match="features"):
        kernels.OnlineFrontEnd(
            butterworth(2, CUTOFF), ["right"], "euler", 0.0, 1.0, True, 0.95, 0.02, 100.0, 8, 1.0
        )


def test_the_pipeline_refuses_bad_frames(recordings) -> None:
    from visprim.model import PrimitiveModel

    trial = recordings[1]
    model = PrimitiveModel(n_components=2, n_clusters=2, n_init=1).fit(recordings[:2])
    pipe = OnlinePipeline(model)
    pipe.push(times=trial.times[:3], markers=trial.markers[:3])
    with pytest.raises(ValueError, match="timestamps"):
        pipe.push(times=trial.times[1:2], markers=trial.markers[1:2])
    assert pipe.segmenter.n_frames == 3
