"""Segment vectors (visprim.vectors) against a per-segment numpy reference."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.vectors import (
    PERIODIC_CHANNELS,
    corpus_vectors,
    segment_vectors,
    stretch,
    time_to_frame,
    to_curves,
    to_vectors,
    turn_offsets,
    vectors_from_frames,
)

TWO_PI = 2 * np.pi


def _reference(times, angles, segments, n):
    """Per segment and channel: np.interp of the angle at n equally spaced fractional
    frame indices between the segment's ends (the documented definition)."""
    frames = np.arange(times.size, dtype=float)
    out = []
    for s, e in segments:
        fs, fe = np.interp([s, e], times, frames)
        grid = np.linspace(fs, fe, n)
        out.append(
            np.concatenate([np.interp(grid, frames, angles[:, c]) for c in range(angles.shape[1])])
        )
    return np.array(out)


def _trial(rng, n_frames, jitter=True):
    dt = 0.034
    times = np.cumsum(dt + (rng.normal(0, 3e-4, n_frames) if jitter else np.zeros(n_frames)))
    angles = np.cumsum(rng.normal(0, 0.05, (n_frames, 4)), axis=0)
    return times, angles


def test_corpus_vectors_match_reference_on_jittered_clocks():
    rng = np.random.default_rng(1)
    trials = [_trial(rng, n) for n in (57, 120, 33)]
    segs = []
    for times, _ in trials:
        cuts = np.sort(rng.uniform(times[0], times[-1], 5))
        segs.append(np.stack([cuts[:-1], cuts[1:]], axis=1))
    angles = [t for t, _ in trials], [a for _, a in trials]
    raw = corpus_vectors(*angles, segs, n_samples=100, periodic_channels=())
    ref = np.concatenate([_reference(t, a, s, 100) for (t, a), s in zip(trials, segs, strict=True)])
    assert raw.vectors.shape == (12, 400)
    np.testing.assert_allclose(raw.vectors, ref, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(raw.offsets, np.zeros((12, 4)))
    # Default: gamma and alpha of a segment whose mean is outside (-pi, pi] are shifted;
    # to_trial_angles gives the reference back.
    sv = corpus_vectors(*angles, segs, n_samples=100)
    np.testing.assert_allclose(to_vectors(sv.to_trial_angles(sv.vectors)), ref, atol=1e-12)
    np.testing.assert_array_equal(sv.trial, np.repeat([0, 1, 2], 4))
    np.testing.assert_allclose(sv.durations, np.concatenate([s[:, 1] - s[:, 0] for s in segs]))
    assert len(sv) == 12


def test_segment_vectors_endpoints_are_the_angles_at_the_segment_ends():
    rng = np.random.default_rng(2)
    times, angles = _trial(rng, 80, jitter=False)
    s, e = times[10], times[50]
    v = segment_vectors(times, angles, [[s, e]], n_samples=7, periodic_channels=())
    curves = to_curves(v)[0]
    np.testing.assert_allclose(curves[0], angles[10], atol=1e-12)
    np.testing.assert_allclose(curves[-1], angles[50], atol=1e-12)


def test_layout_is_channel_major_and_round_trips():
    x = np.arange(2 * 4 * 5, dtype=float).reshape(2, 20)
    curves = to_curves(x)
    assert curves.shape == (2, 5, 4)
    # channel 1 of vector 0 is elements 5..9
    np.testing.assert_array_equal(curves[0, :, 1], x[0, 5:10])
    np.testing.assert_array_equal(to_vectors(curves), x)
    np.testing.assert_array_equal(to_vectors(to_curves(x[0])), x[0])


def test_time_to_frame_uniform_clock():
    times = 0.5 + 0.034 * np.arange(10)
    np.testing.assert_allclose(time_to_frame(times, [0.5, 0.5 + 0.034 * 2.5]), [0.0, 2.5])
    with pytest.raises(ValueError, match="within the trial"):
        time_to_frame(times, [0.0])


def test_stretch_reproduces_a_linear_curve_on_any_clock():
    curve = np.stack([np.linspace(0, 1, 100), np.linspace(2, -2, 100)], axis=1)
    t = np.array([1.0, 1.3, 1.77, 2.0])
    out = stretch(curve, 1.0, 2.0, t)
    np.testing.assert_allclose(out[:, 0], t - 1.0, atol=1e-12)
    np.testing.assert_allclose(out[:, 1], 2 - 4 * (t - 1.0), atol=1e-12)
    with pytest.raises(ValueError, match="outside the segment"):
        stretch(curve, 1.0, 2.0, [2.5])
    with pytest.raises(ValueError, match="after its start"):
        stretch(curve, 2.0, 1.0, [1.5])


@pytest.mark.parametrize(
    ("segments", "match"),
    [
        ([[1.0, 0.5]], "ends"),
        ([[0.1, 99.0]], "within the trial"),
        ([[0.1, np.nan]], "NaN"),
        ([[0.1, 0.2, 0.3]], r"shape \(n, 2\)"),
    ],
)
def test_bad_segments_are_named(segments, match):
    times = 0.034 * np.arange(50)
    angles = np.zeros((50, 4))
    with pytest.raises(ValueError, match=match) as info:
        corpus_vectors([times], [angles], [segments], names=["trial_x"])
    assert "trial_x" in str(info.value)


def test_corpus_errors():
    times = 0.034 * np.arange(50)
    with pytest.raises(ValueError, match="differ in length"):
        corpus_vectors([times], [], [])
    with pytest.raises(ValueError, match="empty"):
        corpus_vectors([], [], [])
    with pytest.raises(ValueError, match="no segments"):
        corpus_vectors([times], [np.zeros((50, 4))], [np.zeros((0, 2))])
    with pytest.raises(ValueError, match="channels"):
        corpus_vectors(
            [times, times], [np.zeros((50, 4)), np.zeros((50, 3))], [[[0.1, 0.5]], [[0.1, 0.5]]]
        )
    with pytest.raises(ValueError, match="n_samples"):
        corpus_vectors([times], [np.zeros((50, 4))], [[[0.1, 0.5]]], n_samples=1)


def _drifting_trial(rng, n_frames=400):
    """A trial whose gamma and alpha drift over several turns (a pirouette) plus wiggles."""
    times = 0.034 * np.arange(n_frames)
    angles = np.cumsum(rng.normal(0, 0.05, (n_frames, 4)), axis=0)
    angles[:, 0] += np.linspace(0.0, 4 * TWO_PI, n_frames)  # 4 turns of gamma
    angles[:, 2] -= np.linspace(0.0, 3 * TWO_PI, n_frames)  # 3 turns back of alpha
    cuts = np.sort(rng.uniform(times[0], times[-1], 16))
    return times, angles, np.stack([cuts[:-1], cuts[1:]], axis=1)


def test_periodic_channels_are_brought_to_the_branch_of_their_mean():
    rng = np.random.default_rng(5)
    times, angles, segs = _drifting_trial(rng)
    sv = corpus_vectors([times], [angles], [segs], n_samples=50)
    ref = _reference(times, angles, segs, 50)  # unshifted, (15, 200)
    ref_curves = to_curves(ref)
    means = ref_curves.mean(axis=1)  # (15, 4)
    # Independent expectation: np.angle puts the mean into (-pi, pi]; the shift is the
    # difference, a whole number of turns.
    wrapped = np.angle(np.exp(1j * means[:, [0, 2]]))
    expected_offsets = np.zeros_like(means)
    expected_offsets[:, [0, 2]] = TWO_PI * np.round((means[:, [0, 2]] - wrapped) / TWO_PI)
    assert np.count_nonzero(expected_offsets[:, 0]) >= 10  # the test data do leave (-pi, pi]
    np.testing.assert_allclose(sv.offsets, expected_offsets, atol=1e-9)
    np.testing.assert_allclose(
        to_curves(sv.vectors), ref_curves - expected_offsets[:, None, :], atol=1e-9
    )
    got_means = to_curves(sv.vectors).mean(axis=1)
    assert np.all((got_means[:, [0, 2]] > -np.pi) & (got_means[:, [0, 2]] <= np.pi))
    # beta and the elbow are never shifted.
    np.testing.assert_array_equal(sv.offsets[:, [1, 3]], 0.0)
    assert PERIODIC_CHANNELS == (0, 2)
    # Back on the trial's clock: continuous with the trial's own angles.
    back = sv.to_trial_angles(sv.vectors)
    np.testing.assert_allclose(back, ref_curves, atol=1e-9)
    for j, (s, e) in enumerate(segs):
        inside = (times >= s) & (times <= e)
        if not inside.any():
            continue
        on_clock = stretch(back[j], s, e, times[inside])
        assert np.max(np.abs(on_clock - angles[inside])) < 0.1


@pytest.mark.parametrize(("m_gamma", "m_alpha"), [(1, 0), (0, -1), (3, -2), (-5, 7)])
def test_whole_turn_offsets_of_gamma_and_alpha_give_the_same_vectors(m_gamma, m_alpha):
    rng = np.random.default_rng(6)
    trials = [_trial(rng, n) for n in (90, 140)]
    segs = []
    for times, _ in trials:
        cuts = np.sort(rng.uniform(times[0], times[-1], 6))
        segs.append(np.stack([cuts[:-1], cuts[1:]], axis=1))
    shift = np.array([m_gamma * TWO_PI, 0.0, m_alpha * TWO_PI, 0.0])
    base = corpus_vectors([t for t, _ in trials], [a for _, a in trials], segs)
    moved = corpus_vectors([t for t, _ in trials], [a + shift for _, a in trials], segs)
    np.testing.assert_allclose(moved.vectors, base.vectors, atol=1e-12)
    np.testing.assert_allclose(moved.offsets - base.offsets, np.tile(shift, (10, 1)), atol=1e-12)
    np.testing.assert_allclose(
        moved.to_trial_angles(moved.vectors),
        base.to_trial_angles(base.vectors) + shift,
        atol=1e-12,
    )


def test_turn_offsets_boundaries_and_errors():
    n = 5
    # Channel means exactly pi and -pi: pi stays, -pi goes to pi (the branch is (-pi, pi]).
    v = np.concatenate([np.full(n, np.pi), np.zeros(n), np.full(n, -np.pi), np.zeros(n)])
    np.testing.assert_allclose(turn_offsets(v, n), [[0.0, 0.0, -TWO_PI, 0.0]])
    v2 = v + np.repeat([0.5 + 6 * np.pi, 100.0, -0.5 - 4 * np.pi, -100.0], n)
    np.testing.assert_allclose(turn_offsets(v2, n), [[4 * TWO_PI, 0.0, -3 * TWO_PI, 0.0]])
    np.testing.assert_array_equal(turn_offsets(v2, n, periodic_channels=()), np.zeros((1, 4)))
    with pytest.raises(ValueError, match=r"periodic_channels \[0, 4\].*out of range"):
        turn_offsets(v, n, periodic_channels=(0, 4))
    times = 0.034 * np.arange(50)
    with pytest.raises(ValueError, match="out of range for 2 channel"):
        corpus_vectors([times], [np.zeros((50, 2))], [[[0.1, 0.5]]])
    sv = corpus_vectors([times], [np.zeros((50, 4))], [[[0.1, 0.5]]])
    with pytest.raises(ValueError, match="one per segment"):
        sv.to_trial_angles(np.zeros((2, 400)))


def test_mean_offsets_keep_shape_apart_and_add_back_exactly():
    rng = np.random.default_rng(3)
    times, angles = _trial(rng, 80)
    angles[:, 0] += 4 * TWO_PI  # whole turns are part of the mean too
    frames = np.array([[3.0, 40.5], [20.0, 79.0]])
    args = dict(
        trial=[0, 0], starts=[0.0, 0.0], ends=[1.0, 1.0], n_samples=25, periodic_channels=(0, 2)
    )
    absolute = vectors_from_frames(angles, frames[:, 0], frames[:, 1], offsets="turns", **args)
    shape = vectors_from_frames(angles, frames[:, 0], frames[:, 1], offsets="mean", **args)
    curves = to_curves(shape.vectors, 4)
    np.testing.assert_allclose(curves.mean(axis=1), 0.0, atol=1e-12)
    np.testing.assert_allclose(
        shape.to_trial_angles(shape.vectors), absolute.to_trial_angles(absolute.vectors)
    )
    reference = _reference(np.arange(80.0), angles, frames, 25)
    np.testing.assert_allclose(shape.offsets, to_curves(reference, 4).mean(axis=1))
    with pytest.raises(ValueError, match="offsets must be one of"):
        vectors_from_frames(angles, [0.0], [5.0], **{**args, "trial": [0]}, offsets="x")


def test_amplitude_gains_are_least_squares_and_never_negative() -> None:
    from visprim.vectors import amplitude_gains

    r = np.array([[1.0, 2.0, -1.0], [0.5, 0.0, 0.5], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    s = np.array([[2.0, 4.0, -2.0], [-1.0, 0.0, -1.0], [3.0, 1.0, 0.0], [2.0, 0.0, 5.0]])
    # 2 r exactly; −2 r clipped to 0; a zero rebuild keeps gain 1; (2 + 0) / 2 = 1.
    np.testing.assert_allclose(amplitude_gains(s, r), [2.0, 0.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="must be equal"):
        amplitude_gains(s[:, :2], r)
