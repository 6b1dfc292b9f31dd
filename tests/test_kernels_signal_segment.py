"""Parity of the segmentation kernels (velocity, SEG-1 events, times to frames) with numpy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from visprim import _visprim as V
from visprim import kernels as K

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)


def ragged_clock(rng: np.random.Generator, lengths: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Jittered, strictly increasing per-trial clocks (seconds) and the trial offsets."""
    times = np.concatenate(
        [rng.uniform(-1, 1) + np.cumsum(rng.uniform(1e-3, 0.05, n)) for n in lengths]
    )
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return times, offsets


# --- gradient_ragged --------------------------------------------------------------------------


@SETTINGS
@given(
    lengths=st.lists(st.integers(2, 30), min_size=1, max_size=6),
    channels=st.integers(1, 5),
    seed=st.integers(0, 2**31),
)
def test_gradient_ragged_is_numpy_gradient_per_trial(
    lengths: list[int], channels: int, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    times, offsets = ragged_clock(rng, lengths)
    values = rng.normal(scale=3.0, size=(times.size, channels))
    got = K.gradient_ragged(times, values, offsets)
    ref = np.concatenate(
        [
            np.gradient(values[o : o + n], times[o : o + n], axis=0)
            for o, n in zip(offsets, lengths, strict=True)
        ]
    )
    # Same operations in the same order, no fused multiply-adds: bit-identical.
    np.testing.assert_array_equal(got, ref)
    one = K.gradient_ragged(times, values[:, 0].copy(), offsets)
    assert one.shape == (times.size,)
    np.testing.assert_array_equal(one, ref[:, 0])


def test_gradient_ragged_large_corpus_and_nan_propagation() -> None:
    rng = np.random.default_rng(3)
    lengths = rng.integers(2, 200, size=700).tolist()  # several parallel tasks
    times, offsets = ragged_clock(rng, lengths)
    values = rng.normal(size=(times.size, 4))
    values[10, 2] = np.nan
    got = K.gradient_ragged(times, values, offsets)
    ref = np.concatenate(
        [
            np.gradient(values[o : o + n], times[o : o + n], axis=0)
            for o, n in zip(offsets, lengths, strict=True)
        ]
    )
    np.testing.assert_array_equal(got, ref)  # NaN where numpy has NaN (assert_array_equal)
    assert np.isnan(got[9:12, 2]).all() and np.isfinite(got[:, [0, 1, 3]]).all()


def test_gradient_ragged_errors() -> None:
    t = np.arange(6.0)
    x = np.zeros((6, 2))
    with pytest.raises(TypeError, match="values must have dtype float64"):
        V.gradient_ragged(t, x.astype(np.float32), np.array([0]))
    with pytest.raises(ValueError, match=r"times must have shape \(6,\)"):
        K.gradient_ragged(t[:5], x, [0])
    with pytest.raises(ValueError, match="trial 1 has fewer than 2 frames"):
        K.gradient_ragged(t, x, [0, 5])
    with pytest.raises(ValueError, match="strictly increasing within a trial: trial 1, frame 5"):
        K.gradient_ragged(np.array([0, 1, 2, 0, 0.5, 0.5]), x, [0, 3])
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.gradient_ragged(np.array([0, 1, 2, 3, 4, np.inf]), x, [0])
    with pytest.raises(ValueError, match="offsets must be strictly increasing"):
        K.gradient_ragged(t, x, [0, 3, 3])
    with pytest.raises(ValueError, match="values is empty"):
        K.gradient_ragged(np.zeros(0), np.zeros((0, 2)), [0])


# --- seg1_events ------------------------------------------------------------------------------


def seg1_events_reference(
    trial: np.ndarray, dof: np.ndarray, time: np.ndarray, window: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Events in plain numpy: lexsort by (trial, time), single linkage, median, distinct DOFs."""
    order = np.lexsort((time, trial))
    trial, time, dof = trial[order], time[order], dof[order]
    new = np.ones(trial.size, dtype=bool)
    new[1:] = (trial[1:] != trial[:-1]) | (np.diff(time) >= window)
    event = np.cumsum(new) - 1
    m = int(event[-1]) + 1
    counts = np.bincount(event, minlength=m)
    first = np.flatnonzero(new)
    median = 0.5 * (time[first + (counts - 1) // 2] + time[first + counts // 2])
    n_dof = int(dof.max()) + 1
    n_dofs = np.bincount(np.unique(event * n_dof + dof) // n_dof, minlength=m)
    return trial[new], median, n_dofs


@SETTINGS
@given(
    n_trials=st.integers(1, 40),
    per_trial=st.integers(1, 25),
    n_dofs=st.sampled_from([1, 4, 70]),
    window=st.sampled_from([0.05, 0.3, 2.0]),
    seed=st.integers(0, 2**31),
)
def test_seg1_events_equal_numpy(
    n_trials: int, per_trial: int, n_dofs: int, window: float, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    counts = rng.integers(0, per_trial + 1, size=n_trials)
    counts[0] = max(counts[0], 1)
    trial = np.repeat(np.arange(n_trials), counts).astype(np.int64)
    dof = rng.integers(0, n_dofs, size=trial.size).astype(np.int64)
    # Times on a coarse grid (ties between DOFs, gaps exactly equal to the window).
    time = np.round(rng.uniform(0, 3, size=trial.size) / 0.05) * 0.05
    order = np.lexsort((time, dof, trial))  # as the ZVC kernel returns them
    trial, dof, time = trial[order], dof[order], time[order]
    got = K.seg1_events(trial, dof, time, window)
    ref = seg1_events_reference(trial, dof, time, window)
    for g, r in zip(got, ref, strict=True):
        np.testing.assert_array_equal(g, r)


def test_seg1_events_errors() -> None:
    with pytest.raises(ValueError, match="non-decreasing"):
        K.seg1_events([1, 0], [0, 0], [0.0, 1.0], 0.3)
    with pytest.raises(ValueError, match="window must be a positive number"):
        K.seg1_events([0], [0], [0.0], -1.0)
    with pytest.raises(ValueError, match="same length"):
        K.seg1_events([0, 0], [0], [0.0, 1.0], 0.3)
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.seg1_events([0], [0], [np.nan], 0.3)
    with pytest.raises(TypeError, match="time must have dtype float64"):
        V.seg1_events(np.zeros(1, np.int64), np.zeros(1, np.int64), np.zeros(1, np.float32), 0.3)
    trial, time, n = K.seg1_events([], [], np.zeros(0), 0.3)
    assert trial.size == time.size == n.size == 0


# --- times_to_frames --------------------------------------------------------------------------


@SETTINGS
@given(lengths=st.lists(st.integers(2, 40), min_size=1, max_size=6), seed=st.integers(0, 2**31))
def test_times_to_frames_is_interp_per_trial(lengths: list[int], seed: int) -> None:
    rng = np.random.default_rng(seed)
    times, offsets = ragged_clock(rng, lengths)
    trial = rng.integers(0, len(lengths), size=50).astype(np.int64)
    lo = times[offsets[trial]]
    hi = times[offsets[trial] + np.asarray(lengths)[trial] - 1]
    t = rng.uniform(lo - 0.1, hi + 0.1)  # some outside the trial: clamped
    t[:5] = times[offsets[trial[:5]]]  # exactly on frames
    got = K.times_to_frames(times, offsets, trial, t)
    ref = np.array(
        [
            np.interp(x, times[offsets[k] : offsets[k] + lengths[k]], np.arange(lengths[k]))
            for k, x in zip(trial, t, strict=True)
        ]
    )
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)


@SETTINGS
@given(lengths=st.lists(st.integers(2, 40), min_size=1, max_size=6), seed=st.integers(0, 2**31))
def test_frames_to_times_is_interp_per_trial(lengths: list[int], seed: int) -> None:
    rng = np.random.default_rng(seed)
    times, offsets = ragged_clock(rng, lengths)
    n = np.asarray(lengths)
    trial = rng.integers(0, len(lengths), size=50).astype(np.int64)
    frame = rng.uniform(-0.5, n[trial] - 0.5)  # some beyond either end: extrapolated
    frame[:5] = np.floor(frame[:5]).clip(0)  # exactly on frames
    got = K.frames_to_times(times, offsets, trial, frame)
    ref = []
    for k, f in zip(trial, frame, strict=True):
        tt = times[offsets[k] : offsets[k] + n[k]]
        i = int(min(max(np.floor(f), 0), n[k] - 2))
        ref.append(tt[i] + (f - i) * (tt[i + 1] - tt[i]))
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)
    # The converse of times_to_frames inside each trial.
    inside = np.clip(frame, 0, n[trial] - 1)
    back = K.times_to_frames(
        times, offsets, trial, K.frames_to_times(times, offsets, trial, inside)
    )
    np.testing.assert_allclose(back, inside, rtol=0, atol=1e-9)


def test_frames_to_times_errors() -> None:
    times = np.array([0.0, 0.1, 0.2, 0.0])
    with pytest.raises(ValueError, match=r"trial\[0\] = 2 is not a trial index"):
        K.frames_to_times(times, [0, 3], [2], [0.0])
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.frames_to_times(times, [0, 3], [0], [np.inf])
    with pytest.raises(ValueError, match="fewer than 2 frames"):
        K.frames_to_times(times, [0, 3], [1], [0.0])
    with pytest.raises(ValueError, match="same length"):
        K.frames_to_times(times, [0, 3], [0, 0], [0.0])


def test_times_to_frames_errors() -> None:
    times = np.array([0.0, 0.1, 0.2, 0.0, 0.1])
    with pytest.raises(ValueError, match=r"trial\[0\] = 2 is not a trial index"):
        K.times_to_frames(times, [0, 3], [2], [0.0])
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.times_to_frames(times, [0, 3], [0], [np.nan])
    with pytest.raises(ValueError, match="strictly increasing"):
        K.times_to_frames(np.array([0.0, 0.1, 0.1]), [0], [0], [0.05])
    with pytest.raises(ValueError, match="same length"):
        K.times_to_frames(times, [0, 3], [0, 1], [0.0])
