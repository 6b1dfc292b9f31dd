"""The online segmenter's causal low-pass (visprim.online.lowpass) against scipy's zero-phase
filter, and the latency it gives the events."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import signal
from visprim.filtering import butterworth
from visprim.model import PrimitiveModel
from visprim.online import OnlineSegmenter, SegmentClosed
from visprim.online.lowpass import FIR_LOOKAHEAD, causal_lowpass, fir_taps
from visprim.online.segmenter import frames_of
from visprim.trial import Trial


@pytest.fixture(scope="module")
def hdm05(shared_data: Path) -> list[Trial]:
    from visprim.io import read

    files = sorted((shared_data / "hdm05_cut_amc").glob("HDM_bd_*.amc"))[:12]
    if len(files) < 12:
        pytest.skip("HDM05 recordings missing")
    return [read(f, "both", resample=0.034) for f in files]


def _strokes(seed: int, n_strokes: int = 12, noise: float = 0.0) -> np.ndarray:
    """Four angle channels (rad) made of minimum-jerk strokes separated by pauses, at 34 ms
    frames: the kind of signal the filter sees."""
    rng = np.random.default_rng(seed)
    parts = []
    pos = np.zeros(4)
    for _ in range(n_strokes):
        n = int(rng.integers(15, 45))
        s = np.linspace(0.0, 1.0, n)[:, None]
        target = pos + rng.normal(0.0, 0.6, 4)
        parts.append(pos + (target - pos) * (10 * s**3 - 15 * s**4 + 6 * s**5))
        parts.append(np.repeat(target[None], int(rng.integers(3, 20)), axis=0))
        pos = target
    x = np.concatenate(parts)
    return x + rng.normal(0.0, noise, x.shape)


def test_the_taps_sum_to_one_and_reject_bad_designs() -> None:
    taps = fir_taps(10, 0.25)
    assert taps.shape == (33,)
    assert abs(taps.sum() - 1.0) < 1e-12
    # A constant passes unchanged.
    y = signal.lfilter(taps, [1.0], np.full(100, 0.7))
    assert np.allclose(y[taps.size :], 0.7, atol=1e-12)
    for bad in ({"lookahead": -1}, {"past": 0}, {"stopband_weight": -0.1}):
        with pytest.raises(ValueError):
            fir_taps(10, 0.25, **bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="cutoff"):
        fir_taps(10, 1.5)


def test_the_sections_are_the_taps() -> None:
    sos, shift = causal_lowpass("fir", 2, 0.25, 10)
    assert shift == FIR_LOOKAHEAD == 1
    x = _strokes(0)
    want = signal.lfilter(fir_taps(10, 0.25), [1.0], x, axis=0)
    got = signal.sosfilt(sos, x, axis=0)
    assert np.max(np.abs(got - want)) < 1e-8 * np.max(np.abs(x))
    with pytest.raises(ValueError, match="causal_filter"):
        causal_lowpass("median", 2, 0.25, 10)


@pytest.mark.parametrize("noise", [0.0, 0.003])
def test_the_fir_follows_the_zero_phase_filter_closer_than_the_butterworth(noise: float) -> None:
    # The reference is scipy's forward-backward filter of the model's order over the whole
    # signal; the FIR is read one frame late, the order-2 Butterworth two (its delay, 1.7
    # frames, rounded). White noise of 0.003 rad (0.17°) on the angles.
    errors: dict[str, list[float]] = {"fir": [], "butterworth": []}
    speed: dict[str, list[float]] = {"fir": [], "butterworth": []}
    for seed in range(5):
        x = _strokes(seed, noise=noise)
        ref = signal.sosfiltfilt(butterworth(10, 0.25), x, axis=0)
        for kind in errors:
            sos, shift = causal_lowpass(kind, 2, 0.25, 10)
            zi = signal.sosfilt_zi(sos)[:, :, None] * x[0]
            y, _ = signal.sosfilt(sos, x, axis=0, zi=zi)
            a, n = 40, x.shape[0]  # past the start-up of both filters
            errors[kind].append(float(np.sqrt(np.mean((y[a:] - ref[a - shift : n - shift]) ** 2))))
            dy, dref = np.diff(y, axis=0), np.diff(ref, axis=0)
            speed[kind].append(
                float(np.sqrt(np.mean((dy[a:] - dref[a - shift : n - 1 - shift]) ** 2)))
            )
    fir, bw = np.mean(errors["fir"]), np.mean(errors["butterworth"])
    assert fir < 0.95 * bw, (fir, bw)
    # Within 0.5° RMS of the zero-phase angles, for strokes of ~35° per channel.
    assert fir < np.deg2rad(0.5), np.rad2deg(fir)
    if noise == 0.0:
        # And the velocity too; with noise the FIR passes more of it (docs/online.rst).
        assert np.mean(speed["fir"]) < 0.9 * np.mean(speed["butterworth"]), speed


def test_each_segment_is_closed_three_frames_after_its_end(hdm05: list[Trial]) -> None:
    # One frame of look-ahead, the stop's successor and the velocity's central difference:
    # 3 frames (the causal Butterworth: its rounded delay of 2 frames, so 4).
    model = PrimitiveModel(n_components=8, n_clusters=6, n_init=1, seg2_boundary="first_stop").fit(
        hdm05[6:]
    )
    period = 0.034
    for kind, frames in (("fir", 3), ("butterworth", 4)):
        latencies = []
        for t in hdm05[:6]:
            seg = OnlineSegmenter(model, causal_filter=kind)
            events = seg.push(frames_of(t))
            latencies.extend(e.latency for e in events if isinstance(e, SegmentClosed))
        assert len(latencies) >= 4, (kind, latencies)
        # Every segment but those cut by max_segment (none in these recordings).
        assert np.allclose(latencies, frames * period, atol=1e-6), (kind, latencies)
    with pytest.raises(ValueError, match="causal_filter"):
        OnlineSegmenter(model, causal_filter="median")
