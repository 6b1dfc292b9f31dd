"""Fuzz of every kernel's integer and size arguments (hypothesis).

Each argument is drawn from its valid range, from just outside it, and from huge or negative
integers (beyond 64 bits too). A valid value must succeed; an invalid one must raise
ValueError naming the argument, or MemoryError naming the sizes for sizes beyond memory:
never OverflowError, a Rust panic (PanicException) or a crash. Cases tried per kernel are
counted and printed at the end of the module (``pytest -s``).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from visprim import kernels as K

EXAMPLES = 60
COUNTS: Counter[str] = Counter()

HUGE = st.one_of(
    st.integers(2**63, 2**80),
    st.integers(-(2**80), -(2**63) - 1),
    st.sampled_from([2**63 - 1, 2**64, -(2**63), 2**62 + 1, 2**61 + 1, 2**32, 2**31]),
)


def ints(lo: int, hi: int) -> st.SearchStrategy[int]:
    """Valid values lo..hi, small invalid ones around them, and huge ones."""
    return st.one_of(st.integers(lo, hi), st.integers(lo - 5, lo - 1), HUGE)


@pytest.fixture(scope="module", autouse=True)
def report() -> Iterator[None]:
    yield
    total = sum(v for k, v in COUNTS.items() if k.endswith(":tried"))
    failed = sum(v for k, v in COUNTS.items() if k.endswith(":failed"))
    print(f"\nkernel fuzz: {total} cases tried, {total - failed} passed, {failed} failed")
    for key in sorted(COUNTS):
        print(f"  {key} {COUNTS[key]}")


def check(
    kernel: str, arg: str, value: int, valid: bool, call: Callable[[], Any], sizes: bool = False
) -> None:
    """``call`` must succeed when ``valid``; otherwise raise ValueError naming ``arg`` (or
    MemoryError when ``sizes``: a size beyond memory)."""
    COUNTS[f"{kernel}:tried"] += 1
    try:
        try:
            call()
        except (ValueError, MemoryError) as e:
            assert not valid, f"{kernel}({arg}={value}) raised {e!r}"
            if isinstance(e, MemoryError):
                assert sizes, f"{kernel}({arg}={value}) raised {e!r}"
            else:
                assert arg in str(e), f"{kernel}({arg}={value}): {e}"
            return
        assert valid, f"{kernel}({arg}={value}) succeeded"
    except BaseException:
        COUNTS[f"{kernel}:failed"] += 1
        raise


RNG = np.random.default_rng(0)
X = RNG.standard_normal((30, 4))
SIG = RNG.standard_normal((50, 3)).cumsum(axis=0)
SOS = K.butter_sos(4, 0.3)


@settings(max_examples=EXAMPLES, deadline=None)
@given(order=ints(1, 64))
def test_butter_order(order: int) -> None:
    check("butter_sos", "order", order, 1 <= order <= 64, lambda: K.butter_sos(order, 0.3))


@settings(max_examples=EXAMPLES, deadline=None)
@given(padlen=ints(0, 60))
def test_filter_padlen(padlen: int) -> None:
    ok = 0 <= padlen < 50
    check("sosfiltfilt", "padlen", padlen, ok, lambda: K.sosfiltfilt(SOS, SIG.T, padlen))
    check(
        "sosfiltfilt_ragged",
        "padlen",
        padlen,
        0 <= padlen < 10,  # the shortest trial has 10 frames
        lambda: K.sosfiltfilt_ragged(SOS, SIG, [0, 20, 30], padlen),
    )


@settings(max_examples=EXAMPLES, deadline=None)
@given(n=st.one_of(ints(2, 400), st.integers(2**40, 2**62)), segments=st.integers(0, 3))
def test_resample_n(n: int, segments: int) -> None:
    starts, ends = np.zeros(segments), np.full(segments, 40.5)
    small = 2 <= n <= 400
    check(
        "resample_segments",
        "n",
        n,
        small,
        lambda: K.resample_segments(SIG, starts, ends, n),
        sizes=n > 400,
    )


@settings(max_examples=EXAMPLES, deadline=None)
@given(dim=st.one_of(ints(1, 200), st.integers(2**27, 2**62)))
def test_accumulator_dim(dim: int) -> None:
    check(
        "CovarianceAccumulator",
        "dim",
        dim,
        1 <= dim <= 200,
        lambda: K.CovarianceAccumulator(dim),
        sizes=dim > 200,
    )


@settings(max_examples=EXAMPLES, deadline=None)
@given(k=ints(1, 4))
def test_eigh_k(k: int) -> None:
    c = np.cov(X, rowvar=False)
    check("eigh", "k", k, 1 <= k <= 4, lambda: K.eigh(c, k=k))


@settings(max_examples=EXAMPLES, deadline=None)
@given(k=ints(1, 30))
def test_kmeans_k(k: int) -> None:
    check("kmeans", "k", k, 1 <= k <= 30, lambda: K.kmeans(X, k))
    check("kmeans_plusplus", "k", k, 1 <= k <= 30, lambda: K.kmeans_plusplus(X, k))


@settings(max_examples=EXAMPLES, deadline=None)
@given(
    which=st.sampled_from(["n_init", "max_iter", "n_local_trials", "n_threads", "seed"]),
    data=st.data(),
)
def test_kmeans_options(which: str, data: st.DataObject) -> None:
    lo, hi, valid_hi = {
        "n_init": (1, 3, 3),
        "max_iter": (1, 50, 2**63 - 1),
        "n_local_trials": (1, 64, 64),
        "n_threads": (1, 4, 1024),
        "seed": (0, 2**64 - 1, 2**64 - 1),
    }[which]
    strategy = ints(lo, hi)
    if which == "n_init":  # every run costs time: no huge valid counts
        strategy = strategy.filter(lambda v: v <= hi or v > 2**63 - 1)
    value = data.draw(strategy, label=which)
    valid = lo <= value <= valid_hi
    check("kmeans", which, value, valid, lambda: K.kmeans(X, 3, **{which: value}))
    if which in ("n_local_trials", "n_threads", "seed"):
        check(
            "kmeans_plusplus",
            which,
            value,
            valid,
            lambda: K.kmeans_plusplus(X, 3, **{which: value}),
        )


@settings(max_examples=EXAMPLES, deadline=None)
@given(n_threads=ints(1, 3))
def test_n_threads(n_threads: int) -> None:
    ok = 1 <= n_threads <= 1024
    check("covariance", "n_threads", n_threads, ok, lambda: K.covariance(X, n_threads=n_threads))
    check(
        "kmeans_predict",
        "n_threads",
        n_threads,
        ok,
        lambda: K.kmeans_predict(X, X[:3], n_threads=n_threads),
    )
    acc = K.CovarianceAccumulator()
    check(
        "accumulator.update", "n_threads", n_threads, ok, lambda: acc.update(X, n_threads=n_threads)
    )


INDEX = st.one_of(st.integers(-3, 60), st.integers(-(2**63), 2**63 - 1))


@settings(max_examples=EXAMPLES, deadline=None)
@given(offsets=st.lists(INDEX, min_size=0, max_size=5))
def test_offsets(offsets: list[int]) -> None:
    arr = np.array(offsets, dtype=np.int64)
    valid = (
        len(offsets) > 0
        and offsets[0] == 0
        and all(b > a for a, b in zip(offsets, offsets[1:], strict=False))
        and offsets[-1] < 50
    )
    lengths = np.diff(np.append(arr, 50)) if valid else np.zeros(0)
    t = np.arange(50.0)
    check(
        "zero_velocity_crossings_ragged",
        "offsets",
        len(offsets),
        valid,
        lambda: K.zero_velocity_crossings_ragged(SIG, arr),
    )
    check(
        "sosfiltfilt_ragged",
        "offsets",
        len(offsets),
        valid,
        lambda: K.sosfiltfilt_ragged(SOS, SIG, arr, padlen=0),
    )
    check(
        "gradient_ragged",
        "offsets",
        len(offsets),
        valid and bool((lengths >= 2).all()),
        lambda: K.gradient_ragged(t, SIG, arr),
    )


@settings(max_examples=EXAMPLES, deadline=None)
@given(trial=st.lists(INDEX, min_size=1, max_size=4), channel=st.data())
def test_trial_and_channel_indices(trial: list[int], channel: st.DataObject) -> None:
    tr = np.array(trial, dtype=np.int64)
    ch = np.array(channel.draw(st.lists(INDEX, min_size=len(trial), max_size=len(trial))))
    t = np.linspace(0.0, 1.0, len(trial))
    ok_seg = all(b >= a for a, b in zip(trial, trial[1:], strict=False)) and bool((ch >= 0).all())
    bad_arg = "channel" if (ch < 0).any() else "trial"
    check("seg1_events", bad_arg, len(trial), ok_seg, lambda: K.seg1_events(tr, ch, t, 0.3))
    ok_t2f = bool(((tr >= 0) & (tr < 2)).all())
    check(
        "times_to_frames",
        "trial",
        len(trial),
        ok_t2f,
        lambda: K.times_to_frames(np.arange(50.0), [0, 20], tr, t),
    )
    check(
        "frames_to_times",
        "trial",
        len(trial),
        ok_t2f,
        lambda: K.frames_to_times(np.arange(50.0), [0, 20], tr, t),
    )
