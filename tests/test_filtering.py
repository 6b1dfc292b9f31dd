"""Corpus low-pass (visprim.filtering) against scipy.signal, and its error handling."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st
from visprim import filtering, kernels
from visprim.filtering import (
    butterworth,
    default_padlen,
    lowpass,
    lowpass_concatenated,
    lowpass_corpus,
)


def random_corpus(rng: np.random.Generator, lengths: list[int], channels: int = 4):
    return [np.cumsum(rng.normal(size=(n, channels)), axis=0) for n in lengths]


def test_defaults_are_the_methods_filter() -> None:
    np.testing.assert_allclose(
        butterworth(), scipy.signal.butter(10, 0.25, output="sos"), rtol=0, atol=1e-10
    )
    assert default_padlen(butterworth()) == 33  # 3 * (2 * 5 sections + 1)


def test_corpus_matches_scipy_per_trial() -> None:
    rng = np.random.default_rng(1)
    parts = random_corpus(rng, [90, 150, 34, 400, 120])
    out = lowpass_corpus(parts)
    sos = scipy.signal.butter(10, 0.25, output="sos")
    for x, y in zip(parts, out, strict=True):
        np.testing.assert_allclose(y, scipy.signal.sosfiltfilt(sos, x, axis=0), atol=1e-9)


def test_options_match_scipy() -> None:
    rng = np.random.default_rng(2)
    parts = random_corpus(rng, [80, 61], channels=2)
    out = lowpass_corpus(parts, order=4, cutoff=0.1, padlen=20)
    sos = scipy.signal.butter(4, 0.1, output="sos")
    for x, y in zip(parts, out, strict=True):
        np.testing.assert_allclose(
            y, scipy.signal.sosfiltfilt(sos, x, axis=0, padlen=20), atol=1e-9
        )
    one = lowpass(parts[0][:, 0], order=4, cutoff=0.1)
    np.testing.assert_allclose(one, scipy.signal.sosfiltfilt(sos, parts[0][:, 0]), atol=1e-9)


def test_whole_corpus_is_one_kernel_call(monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    real = kernels.sosfiltfilt_ragged

    def counting(*args, **kwargs):
        calls.append(args[2])
        return real(*args, **kwargs)

    monkeypatch.setattr(kernels, "sosfiltfilt_ragged", counting)
    parts = random_corpus(np.random.default_rng(3), [100] * 50)
    lowpass_corpus(parts)
    assert len(calls) == 1 and len(calls[0]) == 50


def test_short_trial_error_names_it() -> None:
    parts = random_corpus(np.random.default_rng(4), [100, 20, 100])
    with pytest.raises(ValueError, match=r"s01_m02 \(20 frames\).*short='reduce'"):
        lowpass_corpus(parts, names=["a", "s01_m02", "c"])
    with pytest.raises(ValueError, match=r"#1 \(20 frames\)"):
        lowpass_corpus(parts)


def test_short_reduce_pads_less() -> None:
    rng = np.random.default_rng(5)
    parts = random_corpus(rng, [100, 20, 12, 20, 100], channels=3)
    out = lowpass_corpus(parts, short="reduce")
    sos = scipy.signal.butter(10, 0.25, output="sos")
    for x, y in zip(parts, out, strict=True):
        pad = min(33, x.shape[0] - 1)
        np.testing.assert_allclose(
            y, scipy.signal.sosfiltfilt(sos, x, axis=0, padlen=pad), atol=1e-8
        )


@settings(max_examples=25, deadline=None)
@given(
    lengths=st.lists(st.integers(34, 120), min_size=1, max_size=6),
    order=st.integers(1, 10),
    cutoff=st.floats(0.05, 0.9),
    seed=st.integers(0, 2**32 - 1),
)
def test_property_concatenated_equals_scipy(
    lengths: list[int], order: int, cutoff: float, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    parts = random_corpus(rng, lengths, channels=2)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    out = lowpass_concatenated(np.concatenate(parts), offsets, order=order, cutoff=cutoff)
    sos = scipy.signal.butter(order, cutoff, output="sos")
    ref = np.concatenate([scipy.signal.sosfiltfilt(sos, x, axis=0) for x in parts])
    np.testing.assert_allclose(out, ref, atol=1e-8 * max(1.0, np.abs(ref).max()))


def test_bad_input() -> None:
    x = np.zeros((100, 2))
    with pytest.raises(ValueError, match="offsets"):
        lowpass_concatenated(x, [0, 50, 40])
    with pytest.raises(ValueError, match="offsets"):
        lowpass_concatenated(x, [1])
    with pytest.raises(ValueError, match=r"values must have shape"):
        lowpass_concatenated(np.zeros(100), [0])
    with pytest.raises(ValueError, match=r"trial #1: expected shape \(frames, 2\)"):
        lowpass_corpus([x, np.zeros((100, 3))])
    with pytest.raises(ValueError, match="short"):
        lowpass_corpus([x], short="skip")  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        lowpass_corpus([x], cutoff=1.5)
    assert filtering.lowpass_corpus([]) == []
